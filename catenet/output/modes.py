"""Natural modes in a result file (``catenet modes``): the /modes group, its animation
frames and their place in the XDMF sidecar.

::

    /modes/frequency (K,) [Hz], period (K,) [s], omega2 (K,) [1/s^2]
    /modes/shape (K, N, 3)            mass-normalised (phi^T M phi = 1) [1/sqrt(kg)]
    /modes/effective_mass (K, 3) [kg], participation (K, 3) [sqrt(kg)]
    /modes/direction_share (K, 3)     each mode's kinetic energy share along x, y, z
    /modes/twist_share (K,)           ... and in the rods' twist (> 0.5: torsional)
    /modes/twist (K, M)               where rods' twist angles are DOFs: each edge's
                                      twist angle [rad/sqrt(kg m^2)] (mass-normalised)
    /modes/polar_inertia (M,)         ... and its rotational inertia rho J_p l0 [kg m^2]
    /modes                attrs: count, zero_modes, zero_message, total_mass (3,) [kg],
                          sigma, method, backend, seconds, residual, amplitude [m],
                          frames (per period), animated (modes with frames)
    /modes/frames/<k>/<f> (N, 3) float32: mode k at phase f / frames of its period,
                          x + amplitude sin(2 pi f / frames) phi_k / max|phi_k|

The lumped masses M the modes are taken with are the file's /mesh/mass (N,) [kg], which
every result file has (``catenet.output.writer``).

The frames make each mode a time series that ParaView animates (the sidecar's Temporal
collection "mode k", times are the phase in periods, 0 to 1) and that ``catenet export
--mode k`` writes like a trajectory's frames. They cost 12 bytes per node per frame, so
only the lowest modes within ANIMATION_BYTES get them. The file is rewritten whole (a
copy, then one rename): a reader never sees it half-written.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.output.files import copy_atomically
from catenet.output.reader import LIBVER
from catenet.output.xdmf import _attribute, _grid, _hdf_item, sidecar_path

FRAMES = 16  # animation frames per period
ANIMATION_BYTES = 256 * 2**20  # at most this much of animation frames in a file
AMPLITUDE = 0.05  # the largest displacement of an animation frame, a share of the size

__all__ = ["StoredModes", "read_modes", "write_modes"]


@dataclass
class StoredModes:
    """The /modes group of a result file (see the module docstring)."""

    frequency: np.ndarray
    period: np.ndarray
    shape: np.ndarray
    effective_mass: np.ndarray
    participation: np.ndarray
    direction_share: np.ndarray
    x: np.ndarray
    attrs: dict
    twist_share: np.ndarray | None = None  # (K,); None: a file written before it

    @property
    def count(self) -> int:
        return int(self.frequency.size)

    def frame(self, k: int, f: int) -> np.ndarray:
        """Positions (N, 3) of mode k at phase f / frames, as stored for the animation."""
        a = float(self.attrs["amplitude"])
        top = float(np.max(np.abs(self.shape[k]))) or 1.0
        phase = 2 * math.pi * f / int(self.attrs["frames"])
        return self.x + (a * math.sin(phase) / top) * self.shape[k]


def animated_count(count: int, n_nodes: int, frames: int = FRAMES) -> int:
    """How many of the lowest modes get animation frames within ANIMATION_BYTES."""
    per_mode = 12 * n_nodes * frames
    return int(min(count, max(1, ANIMATION_BYTES // max(per_mode, 1))))


def write_modes(
    path: str | Path, scene, modes, *, frames: int = FRAMES, about: str | None = None
) -> None:
    """Adds /modes to the result file ``path`` of ``scene`` and the
    modes' animations to its XDMF sidecar where it has one. ``about``: the load case or
    combination whose state the modes are about (attribute ``load_case``; None: the
    base state, /result)."""
    import h5py

    path = Path(path)
    tmp = path.with_name(f".{path.name}.modes.{os.getpid()}")
    copy_atomically(path, tmp)
    animated = animated_count(modes.count, scene.net.n_nodes, frames)
    amplitude = AMPLITUDE * float(scene.size)
    try:
        with h5py.File(tmp, "r+", libver=LIBVER) as h5:
            _write_group(h5, scene, modes, frames, animated, amplitude)
            if about is not None:
                h5["modes"].attrs["load_case"] = about
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    side = sidecar_path(path)
    if side.is_file():
        add_to_sidecar(side, path.name, scene.net.n_nodes, scene.net.n_edges, animated, frames)


def _write_group(h5, scene, modes, frames: int, animated: int, amplitude: float) -> None:
    if "modes" in h5:
        del h5["modes"]
    g = h5.create_group("modes")
    g.create_dataset("frequency", data=modes.frequency)
    g.create_dataset("period", data=modes.period)
    g.create_dataset("omega2", data=modes.omega2)
    g.create_dataset("shape", data=modes.shape, compression="gzip", shuffle=True)
    g.create_dataset("effective_mass", data=modes.effective_mass)
    g.create_dataset("participation", data=modes.participation)
    g.create_dataset("direction_share", data=modes.direction_share())
    g.create_dataset("twist_share", data=modes.twist_share())
    if modes.twist is not None:
        g.create_dataset("twist", data=modes.twist, compression="gzip", shuffle=True)
        g["twist"].attrs["unit"] = "rad/sqrt(kg m^2) (mass-normalised)"
        g.create_dataset("polar_inertia", data=modes.inertia)
        g["polar_inertia"].attrs["unit"] = "kg m^2"
    g.create_dataset("x", data=modes.x)
    stats = modes.stats
    attrs = {
        "count": modes.count,
        "zero_modes": int(modes.zero_modes),
        "zero_message": modes.zero_message,
        "total_mass": modes.total_mass,
        "sigma": float(modes.sigma),
        "method": str(stats.get("method", "")),
        "backend": str(stats.get("backend", "")),
        "seconds": float(stats.get("seconds", -1.0)),
        "residual": float(stats.get("residual", math.nan)),
        "amplitude": amplitude,
        "frames": int(frames),
        "animated": int(animated),
    }
    for key, value in attrs.items():
        g.attrs[key] = value
    g["frequency"].attrs["unit"] = "Hz"
    g["shape"].attrs["unit"] = "1/sqrt(kg) (mass-normalised)"
    stored = StoredModes(
        modes.frequency, modes.period, modes.shape, modes.effective_mass,
        modes.participation, modes.direction_share(), modes.x, attrs,
    )  # fmt: skip
    for k in range(animated):
        _shape_view(g, k, modes.shape.shape)
        group = g.require_group(f"frames/{k}")
        for f in range(frames):
            group.create_dataset(str(f), data=stored.frame(k, f).astype(np.float32))


def _shape_view(g, k: int, shape: tuple) -> None:
    """/modes/shape_views/<k>: mode k of /modes/shape as a dataset of its own (a
    virtual view of the same file, for the sidecar: meshio reads whole datasets only)."""
    import h5py

    layout = h5py.VirtualLayout(shape=shape[1:], dtype="f8")
    layout[:] = h5py.VirtualSource(".", "/modes/shape", shape=shape)[k]
    g.require_group("shape_views").create_virtual_dataset(str(k), layout, fillvalue=np.nan)


def read_modes(path: str | Path) -> StoredModes | None:
    """The /modes group of a result file, or None where it has none."""
    import h5py

    with h5py.File(path, "r") as h5:
        if "modes" not in h5:
            return None
        g = h5["modes"]

        def array(name: str) -> np.ndarray:
            return np.asarray(g[name][()])

        return StoredModes(
            array("frequency"), array("period"), array("shape"), array("effective_mass"),
            array("participation"), array("direction_share"), array("x"),
            attrs={k: _plain(v) for k, v in g.attrs.items()},
            twist_share=array("twist_share") if "twist_share" in g else None,
        )  # fmt: skip


def _plain(value):
    """An attribute as Python has it: a NumPy scalar (or 0-d array) as its Python value."""
    scalar = isinstance(value, (np.generic, np.ndarray)) and np.ndim(value) == 0
    return value.item() if scalar else value


def add_to_sidecar(side: Path, h5name: str, n_nodes: int, n_edges: int, count: int, frames: int):
    """Puts a Temporal collection "mode k" per animated mode into the sidecar, before
    the net's own grids (meshio's time-series reader takes the last collection: the
    trajectory stays the one it reads). Times are phases (0 to 1 period)."""
    tree = ET.parse(side)
    domain = tree.getroot().find("Domain")
    assert domain is not None, f"{side}: the sidecar catenet wrote has a Domain"
    net = [g for g in domain if g.get("Name") in ("trajectory", "result")]
    at = list(domain).index(net[0]) if net else len(domain)
    for old in [g for g in domain if (g.get("Name") or "").startswith("mode ")]:
        domain.remove(old)
    for k in reversed(range(count)):
        series = ET.Element("Grid", Name=f"mode {k + 1}", GridType="Collection",
                            CollectionType="Temporal")  # fmt: skip
        for f in range(frames):
            grid = _grid(series, f"mode {k + 1} frame {f}", h5name, n_edges)
            geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            item = _hdf_item(geom, h5name, f"/modes/frames/{k}/{f}", (n_nodes, 3))
            item.set("Precision", "4")
            ET.SubElement(grid, "Time", Value=repr(f / frames))
            att = _attribute(grid, "shape", "Node", "Vector")
            _hdf_item(att, h5name, f"/modes/shape_views/{k}", (n_nodes, 3))
        domain.insert(at, series)
    ET.indent(tree.getroot(), space=" ")
    text = '<?xml version="1.0" ?>\n' + ET.tostring(tree.getroot(), encoding="unicode") + "\n"
    tmp = side.with_name(f".{side.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, side)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise
