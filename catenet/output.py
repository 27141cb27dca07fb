"""Result files: the HDF5 layout of SPEC section 5 and an XDMF sidecar for ParaView.

``ResultWriter`` writes the mesh when it opens, appends trajectory frames as a run goes
and the final state (``/result``) at the end::

    /                   attrs: catenet_version, case (resolved TOML), created, software
                        versions (<name>_version), linear_backend, threads
    /mesh/nodes (N, 3), edges (M, 2), rest_length (M,), EA (M,), fixed (N,)
    /trajectory/time (T,), x (T, N, 3), v (T, N, 3) (dynamic runs), tension (T, M)
    /result/x (N, 3), tension (M,), reaction (N, 3), v (N, 3) (dynamic runs)
    /result             attrs: converged, iterations, residual, steps, wall_time,
                        equilibrium, message, time, delta, delta_over_L, probe, size,
                        max_strain, max_tension, stable (1/0; -1: not checked)

Crash safety: the file is created with ``libver=LIBVER`` and the trajectory is written
in SWMR mode (single writer, multiple readers), flushed after every frame. HDF5 then
orders its metadata writes so that the file on disk is consistent at every moment: a run
killed at any point (SIGKILL, power loss) leaves a file with every frame up to the last
flushed one. Such a file still carries HDF5's "open for writing" mark, which ordinary
readers refuse; ``open_result`` reads it in SWMR mode, and ``recover`` (or HDF5's
``h5clear -s``) turns it into an ordinary file. A run that ends, fails or is interrupted
closes the file properly. ``/result`` is written after the SWMR phase (HDF5 cannot create
objects in SWMR mode), so a killed run has no ``/result``.

Nothing non-finite is ever written: a frame or result with NaN or inf is refused with
``OutputError`` and the frames before it are kept. When writing fails mid-run (a full
disk), the writer stops writing frames and, at the end, saves the final state to a file in
the system's temporary directory, naming it in the ``OutputError`` it raises.
"""

from __future__ import annotations

import datetime
import errno
import logging
import math
import os
import platform
import re
import tempfile
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError, OutputError

log = logging.getLogger(__name__)

# SWMR needs the file format of HDF5 1.10; a newer upper bound ("latest") would let the
# HDF5 library in use write structures that the HDF5 bundled with ParaView cannot read.
LIBVER = ("v110", "v110")
# While running, the sidecar is rewritten at most once a second, and (for long runs, whose
# sidecar takes a while to write) at most 5 % of the time.
XDMF_REWRITE_SECONDS = 1.0
XDMF_SHARE = 0.05
MAX_CHUNK_BYTES = 32 * 2**20  # a trajectory chunk holds one frame, split above this size
TRAJECTORY = ("x", "v", "tension")

__all__ = [
    "Frame",
    "ResultWriter",
    "check_output_path",
    "environment",
    "open_result",
    "read_frame",
    "recover",
    "sidecar_path",
    "trajectory_length",
    "write_xdmf",
]


# --------------------------------------------------------------------------------------------
# Paths and environment
# --------------------------------------------------------------------------------------------


def sidecar_path(path: str | Path) -> Path:
    """The XDMF sidecar of a result file: ``OUT.xdmf`` next to ``OUT.h5``."""
    return Path(path).with_suffix(".xdmf")


def check_output_path(path: str | Path, *, what: str = "output file") -> Path:
    """Checks, without creating anything, that ``path`` can be written: it is not a
    directory, an existing file there is writable, and its nearest existing parent is a
    writable directory (missing directories are created when the file is opened).
    Raises ConfigError naming the path; returns the path."""
    p = Path(path)
    text = str(path)
    if not text.strip():
        raise ConfigError(f"{what} = {text!r}: must be a file path")
    if p.is_dir():
        raise ConfigError(f"{what} {text!r}: is a directory: give a file path such as out/run.h5")
    if p.suffix.lower() == ".xdmf":
        raise ConfigError(
            f"{what} {text!r}: .xdmf is the name of the ParaView sidecar: give the HDF5 file, "
            "such as out/run.h5"
        )
    if p.exists() or p.is_symlink():
        if not p.is_file():
            raise ConfigError(f"{what} {text!r}: exists and is not a regular file")
        if not os.access(p, os.W_OK):
            raise ConfigError(
                f"{what} {text!r}: exists and cannot be overwritten (permission denied)"
            )
    parent = p.absolute().parent
    while not parent.exists():
        if parent.is_symlink():  # a dangling link
            raise ConfigError(f"{what} {text!r}: {parent} is a broken symbolic link")
        parent = parent.parent
    if not parent.is_dir():
        raise ConfigError(f"{what} {text!r}: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ConfigError(f"{what} {text!r}: cannot write in {parent} (permission denied)")
    return p


def environment() -> dict[str, str]:
    """Versions of catenet, Python and the libraries it runs on ('' where missing)."""
    from importlib.metadata import PackageNotFoundError, version

    import catenet

    out = {"catenet": catenet.__version__, "python": platform.python_version()}
    for name in ("numpy", "scipy", "numba", "h5py", "click", "pypardiso", "mkl"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = ""
    try:
        import h5py

        out["hdf5"] = h5py.version.hdf5_version
    except ImportError:  # pragma: no cover - h5py is a dependency
        out["hdf5"] = ""
    return out


def describe(exc: BaseException) -> str:
    """A one-line account of an I/O error (HDF5's messages span lines and name buffers)."""
    text = str(exc)
    m = re.search(r"errno = (\d+), error message = '([^']*)'", text)
    if m:
        return f"{m.group(2)} (errno {m.group(1)})"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return text.splitlines()[0] if text else type(exc).__name__


def _check_finite(name: str, value, t: float) -> None:
    arr = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise OutputError(
            f"refusing to write a non-finite state at t = {t:.6g}: {name} has {bad} NaN or "
            "infinite values (the solution diverged); the frames before it are kept"
        )


# --------------------------------------------------------------------------------------------
# Reading (also files of killed runs)
# --------------------------------------------------------------------------------------------


def open_result(path: str | Path):
    """Opens a result file for reading with h5py: normally, or, for the file of a run that
    was killed or whose disk filled up while writing (HDF5 refuses it: "file is already
    open for write", "truncated file"), in SWMR read mode, which reads it as it was at its
    last flush."""
    import h5py

    try:
        return h5py.File(path, "r")
    except OSError as exc:
        try:
            return h5py.File(path, "r", libver=LIBVER, swmr=True)
        except OSError:
            raise exc from None


@dataclass
class Frame:
    """One stored state: time (or load factor), positions, velocities (None: not
    stored), and where it came from ("trajectory" frame ``index`` or "result")."""

    t: float
    x: np.ndarray
    v: np.ndarray | None
    source: str
    index: int


def trajectory_length(h5) -> int:
    """Complete frames in a file: the shortest of the trajectory datasets (a killed run
    may have extended one dataset more than the others), less trailing frames that never
    fully reached the disk (they read as NaN, the datasets' fill value)."""
    g = h5.get("trajectory")
    if g is None or "time" not in g:
        return 0
    names = [name for name in ("time", *TRAJECTORY) if name in g]
    n = min(g[name].shape[0] for name in names)
    while n > 0 and not _complete(g, names, n - 1):
        n -= 1
    return n


def _complete(g, names, k: int) -> bool:
    try:
        return all(np.all(np.isfinite(g[name][k])) for name in names)
    except (OSError, RuntimeError):  # data beyond the end of a truncated file
        return False


def read_frame(path: str | Path, index: int = -1) -> Frame:
    """A stored state of a result file: trajectory frame ``index`` (default: the last),
    else, for a file without a trajectory, ``/result``. Raises ConfigError for a file that
    is missing, not HDF5 or holds no state."""
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{path}: no such result file")
    try:
        h5 = open_result(p)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read as an HDF5 result file: {exc}") from None
    with h5:
        n = trajectory_length(h5)
        if n > 0:
            k = index if index >= 0 else n + index
            if not 0 <= k < n:
                raise ConfigError(f"{path}: has {n} frames: frame {index} does not exist")
            g = h5["trajectory"]
            v = np.asarray(g["v"][k], dtype=np.float64) if "v" in g else None
            return Frame(
                float(g["time"][k]), np.asarray(g["x"][k], dtype=np.float64), v, "trajectory", k
            )
        if "result" in h5 and "x" in h5["result"]:
            r = h5["result"]
            v = np.asarray(r["v"], dtype=np.float64) if "v" in r else None
            return Frame(
                float(r.attrs.get("time", 0.0)),
                np.asarray(r["x"], dtype=np.float64),
                v,
                "result",
                -1,
            )
    raise ConfigError(f"{path}: holds no stored state (no trajectory frame and no /result)")


def recover(path: str | Path, out: str | Path | None = None) -> Path:
    """Copies the readable part of a result file (in particular one left by a killed run,
    which ordinary HDF5 readers refuse) into a clean file, ``out`` or ``path`` itself,
    and rewrites the XDMF sidecar to match. Returns the clean file's path."""
    import h5py

    src = Path(path)
    dst = src if out is None else Path(out)
    tmp = dst.with_name(f".{dst.name}.recover-{os.getpid()}")
    with open_result(src) as h5, h5py.File(tmp, "w", libver=LIBVER) as clean:
        for key, value in h5.attrs.items():
            clean.attrs[key] = value
        n = trajectory_length(h5)
        for name in h5:
            if name == "trajectory":
                g = clean.create_group("trajectory")
                for key, ds in h5["trajectory"].items():
                    copy = g.create_dataset(
                        key,
                        data=ds[:n],
                        maxshape=(None, *ds.shape[1:]),
                        chunks=ds.chunks,
                        compression=ds.compression,
                        shuffle=ds.shuffle,
                    )
                    for attr, value in ds.attrs.items():
                        copy.attrs[attr] = value
            else:
                h5.copy(h5[name], clean, name=name)
    os.replace(tmp, dst)
    _write_sidecar_for(dst)
    return dst


def _write_sidecar_for(path: Path) -> None:
    with open_result(path) as h5:
        n_nodes, n_edges = len(h5["mesh/nodes"]), len(h5["mesh/edges"])
        n = trajectory_length(h5)
        times = list(np.asarray(h5["trajectory/time"][:n], dtype=float)) if n else []
        has_v = "trajectory" in h5 and "v" in h5["trajectory"]
        has_result = "result" in h5 and "x" in h5["result"]
    if times or has_result:
        write_xdmf(
            sidecar_path(path),
            path.name,
            n_nodes=n_nodes,
            n_edges=n_edges,
            times=times,
            velocities=has_v,
        )


# --------------------------------------------------------------------------------------------
# XDMF
# --------------------------------------------------------------------------------------------


def _hdf_item(parent, h5name: str, dataset: str, dims: Iterable[int], number: str = "Float"):
    item = ET.SubElement(
        parent,
        "DataItem",
        Format="HDF",
        NumberType=number,
        Precision="8",
        Dimensions=" ".join(map(str, dims)),
    )
    item.text = f"{h5name}:{dataset}"
    return item


def _slab(parent, h5name: str, dataset: str, k: int, full: tuple[int, ...]):
    """Frame k of a (T, ...) dataset as an XDMF HyperSlab."""
    rest = full[1:]
    count = (1, *rest)
    slab = ET.SubElement(
        parent,
        "DataItem",
        ItemType="HyperSlab",
        Dimensions=" ".join(map(str, count)),
        Type="HyperSlab",
    )
    sel = ET.SubElement(
        slab, "DataItem", Dimensions=f"3 {len(full)}", Format="XML", NumberType="Int"
    )
    start = (k, *(0 for _ in rest))
    stride = tuple(1 for _ in full)
    sel.text = " ".join(" ".join(map(str, row)) for row in (start, stride, count))
    _hdf_item(slab, h5name, dataset, full)
    return slab


def _grid(parent, name: str, h5name: str, n_nodes: int, n_edges: int):
    grid = ET.SubElement(parent, "Grid", Name=name, GridType="Uniform")
    topo = ET.SubElement(
        grid,
        "Topology",
        TopologyType="Polyline",
        NodesPerElement="2",
        NumberOfElements=str(n_edges),
    )
    _hdf_item(topo, h5name, "/mesh/edges", (n_edges, 2), number="Int")
    return grid


def _attribute(grid, name: str, center: str, kind: str):
    return ET.SubElement(grid, "Attribute", Name=name, AttributeType=kind, Center=center)


def write_xdmf(
    path: str | Path,
    h5name: str,
    *,
    n_nodes: int,
    n_edges: int,
    times: list[float],
    velocities: bool = False,
) -> None:
    """Writes the XDMF 3 sidecar of a result file (atomically: a temporary file renamed).

    With ``times`` (the trajectory's frames): a Temporal collection with one Polyline grid
    per frame, geometry and tension read from frame k of /trajectory/x and
    /trajectory/tension by HyperSlab. Without: one grid of /result/x and /result/tension.
    ``h5name`` is the HDF5 file as the sidecar names it (relative to the sidecar).
    """
    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    n_t = len(times)
    if n_t:
        series = ET.SubElement(
            domain, "Grid", Name="trajectory", GridType="Collection", CollectionType="Temporal"
        )
        for k, t in enumerate(times):
            grid = _grid(series, f"frame {k}", h5name, n_nodes, n_edges)
            ET.SubElement(grid, "Time", Value=repr(float(t)))
            geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            _slab(geom, h5name, "/trajectory/x", k, (n_t, n_nodes, 3))
            att = _attribute(grid, "tension", "Cell", "Scalar")
            _slab(att, h5name, "/trajectory/tension", k, (n_t, n_edges))
            if velocities:
                att = _attribute(grid, "velocity", "Node", "Vector")
                _slab(att, h5name, "/trajectory/v", k, (n_t, n_nodes, 3))
    else:
        grid = _grid(domain, "result", h5name, n_nodes, n_edges)
        geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
        _hdf_item(geom, h5name, "/result/x", (n_nodes, 3))
        att = _attribute(grid, "tension", "Cell", "Scalar")
        _hdf_item(att, h5name, "/result/tension", (n_edges,))
        att = _attribute(grid, "reaction", "Node", "Vector")
        _hdf_item(att, h5name, "/result/reaction", (n_nodes, 3))
    ET.indent(root, space=" ")
    text = '<?xml version="1.0" ?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise


# --------------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------------


class ResultWriter:
    """Writes a run's result file (and its XDMF sidecar) while the run goes on.

    ``every``: the run keeps every k-th step as a trajectory frame (0: only the final
    state, and the file has no /trajectory group). The writer stores what it is given:
    ``frame`` appends (the caller picks which steps, see ``wants``), ``result`` writes
    /result. ``velocities`` (default: dynamic cases) adds /trajectory/v and /result/v;
    ``attrs`` are extra root attributes.

    Use it as a context manager; the file is complete and closed on exit, also when the
    block raises (frames kept, no /result unless ``result`` was called).
    """

    def __init__(
        self,
        path: str | Path,
        scene,
        *,
        every: int,
        xdmf: bool = True,
        velocities: bool | None = None,
        attrs: dict | None = None,
    ):
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 0:
            raise ConfigError(f"output.every = {every!r}: must be an integer >= 0")
        self.path = Path(path)
        self.scene = scene
        self.every = int(every)
        self.xdmf = bool(xdmf)
        if velocities is None:
            solver = getattr(getattr(scene, "case", None), "solver", None)
            velocities = getattr(solver, "method", "static") == "dynamic"
        self.velocities = bool(velocities)
        self.attrs = dict(attrs or {})
        self.frames = 0
        self.times: list[float] = []
        self.error: BaseException | None = None  # a failed write: frames stop there
        self.saved_to: Path | None = None  # where the result went instead
        self._h5 = None
        self._datasets: dict = {}
        self._swmr = False
        self._result_written = False
        self._next_xdmf = -math.inf

    # --- context ---------------------------------------------------------------------------
    def __enter__(self) -> ResultWriter:
        self.open()
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        self.close()
        return False

    @property
    def has_result(self) -> bool:
        """Whether /result was written (to this file)."""
        return self._result_written

    @property
    def sidecar(self) -> Path:
        return sidecar_path(self.path)

    def wants(self, step: int) -> bool:
        """Whether step ``step`` (0 = the initial state) is a trajectory frame."""
        return self.every > 0 and step % self.every == 0

    # --- opening ---------------------------------------------------------------------------
    def open(self) -> None:
        """Creates the file (and missing parent directories) and writes the mesh."""
        import h5py

        check_output_path(self.path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ConfigError(
                f"output file {str(self.path)!r}: cannot create its directory: "
                f"{exc.strerror or exc}"
            ) from None
        try:
            self._h5 = h5py.File(self.path, "w", libver=LIBVER)
        except OSError as exc:
            hint = ""
            if "lock" in str(exc).lower():
                hint = " (is it open in another program, such as ParaView or HDFView?)"
            raise ConfigError(
                f"output file {str(self.path)!r}: cannot be created{hint}: {exc}"
            ) from None
        try:
            self._write_header(self._h5)
            if self.every > 0:
                self._create_trajectory(self._h5)
                # Dataset objects live as long as the file: a temporary one closed while
                # writes fail would make HDF5 keep its identifier (see _detach).
                g = self._h5["trajectory"]
                self._datasets = {name: g[name] for name in g}
                self._h5.swmr_mode = True
                self._swmr = True
            self._h5.flush()
        except OSError as exc:
            self._abandon()
            raise OutputError(f"{self.path}: cannot be written: {describe(exc)}") from None
        # A sidecar left from an earlier run of this file would now lie: remove it.
        if self.xdmf:
            self.sidecar.unlink(missing_ok=True)

    def _abandon(self) -> None:
        """Closes and removes a file that could not even get its header."""
        try:
            if self._h5 is not None:
                self._h5.close()
        except Exception:  # best effort: the file is being removed
            pass
        self._h5 = None
        self.path.unlink(missing_ok=True)

    def _write_header(self, h5) -> None:
        scene = self.scene
        net = scene.net
        env = environment()
        h5.attrs["catenet_version"] = env["catenet"]
        h5.attrs["case"] = scene.case.to_toml() if scene.case is not None else ""
        h5.attrs["created"] = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        title = getattr(scene.case, "title", "")
        if title:
            h5.attrs["title"] = title
        for name, ver in env.items():
            if name != "catenet" and ver:
                h5.attrs[f"{name}_version"] = ver
        for key, value in self.attrs.items():
            h5.attrs[key] = value
        mesh = h5.create_group("mesh")
        mesh.create_dataset("nodes", data=np.asarray(net.nodes, dtype=np.float64))
        mesh.create_dataset("edges", data=np.asarray(net.edges, dtype=np.int64))
        mesh.create_dataset("rest_length", data=np.asarray(net.rest_length, dtype=np.float64))
        mesh.create_dataset("EA", data=np.asarray(net.EA, dtype=np.float64))
        mesh.create_dataset("fixed", data=np.asarray(net.fixed, dtype=bool))
        mesh.attrs["probe"] = int(scene.probe)
        mesh.attrs["size"] = float(scene.size)

    def _create_trajectory(self, h5) -> None:
        n, m = self.scene.net.n_nodes, self.scene.net.n_edges
        g = h5.create_group("trajectory")
        # Fill value NaN: a frame that never fully reached the disk (the writer failed or
        # was killed in the middle of it) reads as NaN, and readers skip it.
        g.create_dataset(
            "time", shape=(0,), maxshape=(None,), dtype="f8", chunks=(1024,), fillvalue=np.nan
        )
        shapes = {"x": (n, 3), "tension": (m,)}
        if self.velocities:
            shapes["v"] = (n, 3)
        for name in TRAJECTORY:
            if name not in shapes:
                continue
            tail = shapes[name]
            chunk = list(tail)
            while 8 * math.prod(chunk) > MAX_CHUNK_BYTES:
                chunk[0] = max(1, chunk[0] // 2)
            g.create_dataset(
                name,
                shape=(0, *tail),
                maxshape=(None, *tail),
                dtype="f8",
                chunks=(1, *chunk),
                compression="gzip",
                compression_opts=4,
                shuffle=True,
                fillvalue=np.nan,
            )
        g["time"].attrs["unit"] = "s (dynamic) or load factor (static)"

    # --- frames ----------------------------------------------------------------------------
    def frame(self, t: float, x, v=None, tension=None) -> None:
        """Appends a frame and flushes it to disk. ``v`` None stores zeros (when the file
        keeps velocities); ``tension`` None is computed from x. Raises OutputError for a
        non-finite frame (not written). A failed write (a full disk) is remembered, and
        frames stop: the run goes on and ``result`` saves the final state elsewhere."""
        if self.every == 0 or self.error is not None:
            return
        if self._h5 is None:
            raise OutputError(f"{self.path}: the writer is not open")
        net = self.scene.net
        x = np.asarray(x, dtype=np.float64)
        if x.shape != net.nodes.shape:
            raise OutputError(f"frame x: shape {x.shape}: must be {net.nodes.shape}")
        if tension is None:
            tension = _tension(net, x)
        data = {"x": x, "tension": np.asarray(tension, dtype=np.float64)}
        if self.velocities:
            data["v"] = np.zeros_like(x) if v is None else np.asarray(v, dtype=np.float64)
        if not math.isfinite(float(t)):
            raise OutputError(f"refusing to write a frame at t = {t!r}: the time must be finite")
        for name, arr in data.items():
            _check_finite(name, arr, float(t))
        k = self.frames
        try:
            for name, arr in data.items():
                ds = self._datasets[name]
                ds.resize(k + 1, axis=0)
                ds[k] = arr
            ds = self._datasets["time"]
            ds.resize((k + 1,))
            ds[k] = float(t)  # last: the frame counts once its time is there
            self._h5.flush()
        except (OSError, RuntimeError) as exc:  # ENOSPC, EFBIG, EIO, quota ...
            self._fail(exc)
            return
        self.frames += 1
        self.times.append(float(t))
        if self.xdmf and time.monotonic() >= self._next_xdmf:
            self._write_sidecar()

    def _fail(self, exc: BaseException) -> None:
        self.error = exc
        log.warning(
            "%s: writing failed after %d frames (%s); the run goes on, its final state will "
            "be saved to a temporary file",
            self.path,
            self.frames,
            describe(exc),
        )
        h5, self._h5 = self._h5, None
        if h5 is not None:
            _detach(h5)
            self._datasets = {}
            try:
                h5.close()
            except Exception:  # the file is broken already
                pass

    def _write_sidecar(self) -> None:
        if not self.xdmf:
            return
        net = self.scene.net
        start = time.monotonic()
        try:
            write_xdmf(
                self.sidecar,
                self.path.name,
                n_nodes=net.n_nodes,
                n_edges=net.n_edges,
                times=self.times,
                velocities=self.velocities,
            )
        except OSError as exc:
            log.warning("%s: cannot write the XDMF sidecar: %s", self.sidecar, exc)
        now = time.monotonic()
        self._next_xdmf = now + max(XDMF_REWRITE_SECONDS, (now - start) / XDMF_SHARE)

    # --- result ----------------------------------------------------------------------------
    def result(self, res, **attrs) -> None:
        """Writes /result (final state and its attributes; ``attrs`` add to them). After a
        failed write, saves root attributes, mesh and /result to a temporary file and
        raises OutputError naming it (with ``.result`` and ``.saved_to`` set)."""
        _check_finite("x", res.x, float(getattr(res, "time", 0.0)))
        if self.error is None:
            try:
                self._reopen_for_result()
                self._write_result(self._h5, res, attrs)
                self._h5.flush()
                self._result_written = True
                return
            except (OSError, RuntimeError) as exc:
                self._fail(exc)
        # Writing failed: keep the result in a temporary file.
        first = self.error
        try:
            self.saved_to = self._save_elsewhere(res, attrs)
        except Exception as exc:
            err = OutputError(
                f"{self.path}: writing failed ({describe(first)}); saving the result to the "
                f"temporary directory {tempfile.gettempdir()} failed as well ({describe(exc)}): "
                "the result exists only in memory"
            )
            err.result = res
            err.saved_to = None
            raise err from None
        kept = f" (it keeps {self.frames} trajectory frames)" if self.frames else ""
        err = OutputError(
            f"{self.path}: writing failed ({describe(first)}){kept}; the final state was "
            f"saved to {self.saved_to} instead"
        )
        err.result = res
        err.saved_to = self.saved_to
        raise err

    def _reopen_for_result(self) -> None:
        """HDF5 creates no objects in SWMR mode: close that phase and reopen."""
        import h5py

        if self._h5 is None:
            raise OSError(errno.EBADF, "the result file is not open", str(self.path))
        if self._swmr:
            self._close_file()
            self._h5 = h5py.File(self.path, "r+", libver=LIBVER)

    def _write_result(self, h5, res, attrs: dict) -> None:
        scene = self.scene
        net = scene.net
        if "result" in h5:
            del h5["result"]
        g = h5.create_group("result")
        g.create_dataset("x", data=np.asarray(res.x, dtype=np.float64))
        tension = res.tension if res.tension is not None else _tension(net, res.x)
        g.create_dataset("tension", data=np.asarray(tension, dtype=np.float64))
        reaction = res.reaction if res.reaction is not None else np.zeros_like(res.x)
        g.create_dataset("reaction", data=np.asarray(reaction, dtype=np.float64))
        v = getattr(res, "v", None)
        if self.velocities and v is not None and np.all(np.isfinite(v)):
            g.create_dataset("v", data=np.asarray(v, dtype=np.float64))
        for key, value in result_attrs(res, scene).items():
            g.attrs[key] = value
        for key, value in attrs.items():
            g.attrs[key] = value

    def _save_elsewhere(self, res, attrs: dict) -> Path:
        import h5py

        fd, name = tempfile.mkstemp(prefix=f"{self.path.stem}-", suffix=".h5")
        os.close(fd)
        tmp = Path(name)
        try:
            with h5py.File(tmp, "w", libver=LIBVER) as h5:
                self._write_header(h5)
                h5.attrs["note"] = (
                    f"saved here because writing {self.path} failed ({describe(self.error)}); "
                    f"the trajectory ({self.frames} frames) is in that file"
                )
                self._write_result(h5, res, attrs)
        except Exception:
            tmp.unlink(missing_ok=True)
            raise
        return tmp

    # --- closing ---------------------------------------------------------------------------
    def _close_file(self) -> None:
        """Flushes and closes the file. When that fails, the file is detached (see
        ``_detach``) and closed all the same, and the error re-raised."""
        h5 = self._h5
        try:
            h5.flush()
            self._datasets = {}
            h5.close()
        except (OSError, RuntimeError):
            _detach(h5)
            self._datasets = {}
            try:
                h5.close()
            except Exception:  # closed as far as it goes
                pass
            raise
        finally:
            self._h5 = None
            self._swmr = False

    def close(self) -> None:
        """Closes the file and writes the final sidecar (consistent with the file)."""
        if self._h5 is not None:
            try:
                self._close_file()
            except (OSError, RuntimeError) as exc:  # a broken file: nothing more to save
                self.error = self.error or exc
                log.warning("%s: closing failed: %s", self.path, describe(exc))
            if self.xdmf and self.error is None and (self.frames or self._result_written):
                self._write_sidecar()


def _detach(h5) -> None:
    """Points HDF5's file descriptor of a file whose writes fail at /dev/null.

    HDF5 retries the failed writes when the file and its datasets are closed; when those
    fail again, it keeps their identifiers and crashes at interpreter exit. Writing the
    rest to /dev/null lets the close succeed, while the file on disk keeps what was
    flushed before the failure (consistent, thanks to SWMR).
    """
    try:
        fd = h5.id.get_vfd_handle()
        null = os.open(os.devnull, os.O_RDWR)
    except Exception:  # another file driver, or no /dev/null: leave it be
        return
    try:
        os.dup2(null, fd)
    except OSError:
        pass
    finally:
        os.close(null)


def result_attrs(res, scene) -> dict:
    """The /result attributes of a Result: SPEC section 5 plus what a user reads first."""
    net = scene.net
    probe = int(scene.probe)
    delta = -float(res.x[probe, 2] - net.nodes[probe, 2])
    tension = np.asarray(res.tension) if res.tension is not None else np.zeros(0)
    residual = float(res.residual)
    strain = float(res.max_strain)
    return {
        "converged": bool(res.converged),
        "iterations": int(res.iterations),
        "residual": residual if not math.isnan(residual) else math.inf,
        "steps": int(res.steps),
        "wall_time": float(res.wall_time),
        "equilibrium": bool(res.equilibrium),
        "message": str(res.message or ""),
        "time": float(res.time),
        "delta": delta,
        "delta_over_L": delta / float(scene.size),
        "probe": probe,
        "size": float(scene.size),
        "max_strain": strain if math.isfinite(strain) else 0.0,
        "max_tension": float(np.max(tension, initial=0.0)),
        # bilateral nets: 1 stable, 0 unstable equilibrium; -1 not checked (tension-only)
        "stable": -1 if getattr(res, "stable", None) is None else int(bool(res.stable)),
    }


def _tension(net, x: np.ndarray) -> np.ndarray:
    """EA * eps of every edge at x (0 when slack and tension-only)."""
    e = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    eps = np.linalg.norm(e, axis=1) / net.rest_length - 1.0
    t = net.EA * eps
    return np.maximum(t, 0.0) if net.tension_only else t
