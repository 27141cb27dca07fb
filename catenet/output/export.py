"""A result file's states in other formats, one file per frame, through meshio
(``catenet export``): for tools that take one mesh per file.

Each frame becomes a line mesh: points at the frame's positions, one line cell per edge,
point data ``displacement`` (from the reference geometry), ``fixed`` (1.0: supported) and,
where stored, ``velocity`` (dynamic runs) or ``reaction`` (the final state); cell data
``tension`` [N], ``rest_length`` [m] and ``EA`` [N]. Moving spheres (/mesh/bodies) add
a vertex cell at each centre with cell data ``radius`` [m] (NaN on the edges; not in
XDMF, whose mixed cells meshio cannot read back). The frames are the trajectory's, or
the final state (/result) of a file without one. Every other obstacle (/mesh/obstacles,
``catenet.output.obstacles``) is a triangle surface of its own: ``STEM_obstacleJ.ext``
once for a fixed one, ``STEM_obstacleJ_K.ext`` at every exported frame for a moving one
(J its ``[[obstacle]]`` index). VTK formats also get a ParaView collection
(``STEM.pvd``) that gives every file its time, the net as part 0 and each obstacle as a
part of its own.

meshio is a dependency of every install (pyproject.toml); it is imported only here, when
a file is exported (an environment without it gets one clear message).
"""

from __future__ import annotations

import logging
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

from catenet.errors import CatenetError, ConfigError
from catenet.output.bodies import body_nodes
from catenet.output.obstacles import StoredObstacle, read_obstacles
from catenet.output.reader import (
    DAMAGED,
    Frame,
    NetMesh,
    damaged,
    is_dataset,
    open_result,
    read_mesh,
    read_result,
    trajectory_length,
)

log = logging.getLogger(__name__)

# format -> (file extension, meshio's writer name)
FORMATS = {"vtu": ("vtu", "vtu"), "vtk": ("vtk", "vtk"), "xdmf": ("xdmf", "xdmf")}
PVD = ("vtu", "vtk")  # formats that get a .pvd collection

__all__ = ["FORMATS", "Export", "export", "select_frames"]


@dataclass
class Export:
    """What ``export`` wrote: the net's files (one per frame, in order), their times, the
    ParaView collection (None: not for this format) and, per obstacle index, its files
    (one for a fixed obstacle, one per frame for a moving one)."""

    files: list[Path]
    times: list[float]
    collection: Path | None
    obstacles: dict[int, list[Path]] = field(default_factory=dict)


def _meshio():
    try:
        import meshio
    except ImportError as exc:
        raise CatenetError(
            "catenet export needs meshio, which is not installed: pip install meshio "
            f"(or pip install 'catenet[export]') ({exc})"
        ) from None
    return meshio


def select_frames(spec: str, n: int) -> list[int]:
    """The frame indices that ``--frames`` names among n: "all", "last", an index k
    (negative: from the end) or a slice "start:stop[:step]" (Python's rules)."""
    text = spec.strip().lower()
    what = f"--frames {spec!r}"
    if text == "all":
        return list(range(n))
    if text == "last":
        return [n - 1] if n else []
    if re.fullmatch(r"-?\d+", text):
        k = int(text)
        if not -n <= k < n:
            raise ConfigError(f"{what}: the file has {n} frames (0 to {n - 1})")
        return [k % n]
    m = re.fullmatch(r"(-?\d*):(-?\d*)(?::(-?\d*))?", text)
    if not m:
        raise ConfigError(f"{what}: must be all, last, an index or start:stop[:step]")
    start, stop, step = (int(g) if g else None for g in m.groups())
    if step == 0:
        raise ConfigError(f"{what}: the step must not be 0")
    picked = list(range(n))[slice(start, stop, step)]
    if not picked:
        raise ConfigError(f"{what}: selects none of the file's {n} frames")
    return picked


#: /result's datasets per node and per edge that a file of the final state carries as
#: point and cell data, where stored (rods, peaks, utilisation, form finding).
PER_NODE = ("bending_moment", "curvature", "peak_displacement")
PER_EDGE = ("utilisation", "peak_utilisation", "peak_tension", "twisting_moment", "force_density")


def _results(group, names: tuple[str, ...], count: int) -> dict[str, np.ndarray]:
    """The datasets ``names`` of ``group`` that are numbers, one (or a row) per item of
    ``count``."""
    out = {}
    for name in names:
        ds = group.get(name)
        if not is_dataset(ds) or ds.dtype.kind not in "fiub" or not ds.shape:
            continue
        if ds.shape[0] == count and len(ds.shape) <= 2:
            out[name] = np.asarray(ds, dtype=np.float64)
    return out


def _final_results(h5, frame: Frame, n: int) -> None:
    """/result's per-node and per-edge datasets on ``frame`` when it is the run's last
    stored frame and that is /result's state."""
    r = h5.get("result")
    if frame.index != n - 1 or r is None or not is_dataset(r.get("x")):
        return
    if r["x"].shape != frame.x.shape or not np.array_equal(r["x"][()], frame.x):
        return
    frame.per_node = _results(r, PER_NODE, len(frame.x))
    if frame.tension is not None:
        frame.per_edge = _results(r, PER_EDGE, len(frame.tension))


def _frames(path: Path, spec: str) -> list[Frame]:
    with open_result(path) as h5:
        n = trajectory_length(h5)
        if n:
            g = h5["trajectory"]
            out = []
            for k in select_frames(spec, n):
                v = np.asarray(g["v"][k], dtype=np.float64) if "v" in g else None
                tension = np.asarray(g["tension"][k], dtype=np.float64)
                x = np.asarray(g["x"][k], dtype=np.float64)
                out.append(Frame(float(g["time"][k]), x, v, "trajectory", k, tension))
            _final_results(h5, out[-1], n)
            return out
        if "result" in h5 and "x" in h5["result"]:
            r = h5["result"]
            select_frames(spec, 1)  # checks the spec
            frame = Frame(
                float(r.attrs.get("time", 1.0)),
                np.asarray(r["x"], dtype=np.float64),
                np.asarray(r["v"], dtype=np.float64) if "v" in r else None,
                "result",
                -1,
                np.asarray(r["tension"], dtype=np.float64) if "tension" in r else None,
            )
            frame.reaction = np.asarray(r["reaction"]) if "reaction" in r else None
            frame.contact_force = np.asarray(r["contact_force"]) if "contact_force" in r else None
            frame.per_node = _results(r, PER_NODE, len(frame.x))
            if frame.tension is not None:
                frame.per_edge = _results(r, PER_EDGE, len(frame.tension))
            return [frame]
    raise ConfigError(f"{path}: holds no stored state (no trajectory frame and no /result)")


def _check_shapes(path: Path, mesh: NetMesh, states: list[Frame]) -> None:
    """ConfigError when a stored state does not fit the mesh (a damaged file)."""
    n, m = len(mesh.nodes), len(mesh.edges)
    for f in states:
        for name, value, shape in (
            ("x", f.x, (n, 3)),
            ("v", f.v, (n, 3)),
            ("tension", f.tension, (m,)),
        ):
            if value is not None and np.shape(value) != shape:
                raise ConfigError(
                    f"{path}: {name} of {f.source} frame {f.index} has shape "
                    f"{np.shape(value)}: the mesh needs {shape} (a damaged file)"
                )
    for name, value, size in (
        ("rest_length", mesh.rest_length, m),
        ("EA", mesh.EA, m),
        ("fixed", mesh.fixed, n),
    ):
        if value is None:
            continue
        value = np.asarray(value)
        if value.shape != (size,) or value.dtype.kind not in "biuf":
            raise ConfigError(
                f"{path}: /mesh/{name} holds {value.dtype} of shape {value.shape}: must be "
                f"({size},) numbers (a damaged file)"
            )


def _mode_frames(path: Path, mode: int, spec: str) -> list[Frame]:
    """The animation frames of mode ``mode`` (1 = the lowest) of a ``catenet modes``
    file (``catenet.output.modes``): times are phases (0 to 1 period), tensions the
    equilibrium's, and each frame carries the shape as ``shape``."""
    from catenet.output.modes import read_modes

    stored = read_modes(path)
    if stored is None:
        raise ConfigError(f"--mode {mode}: {path} holds no modes (write it with catenet modes)")
    animated = int(stored.attrs.get("animated", 0))
    if not 1 <= mode <= animated:
        raise ConfigError(
            f"--mode {mode}: {path} has animation frames for modes 1 to {animated} "
            f"(of {stored.count})"
        )
    count = int(stored.attrs["frames"])
    with open_result(path) as h5:
        tension = np.asarray(h5["result/tension"]) if "result/tension" in h5 else None
        g = h5[f"modes/frames/{mode - 1}"]
        out = []
        for f in select_frames(spec, count):
            frame = Frame(f / count, np.asarray(g[str(f)], dtype=np.float64), None, "mode", f,
                          tension, shape=stored.shape[mode - 1])  # fmt: skip
            out.append(frame)
    return out


@dataclass(frozen=True)
class _Target:
    """Where and how ``export`` writes its files: meshio, the directory, the extension,
    meshio's writer name and the digits of a frame index in a file's name."""

    meshio: ModuleType
    out: Path
    ext: str
    writer: str
    width: int

    def name(self, stem: str, f: Frame) -> str:
        """The file name (no extension) of state ``f``: STEM_K, STEM_result for /result."""
        return f"{stem}_{f.index:0{self.width}d}" if f.index >= 0 else f"{stem}_result"

    def write(self, name: str, mesh) -> Path:
        """Writes ``mesh`` as ``name`` in the directory; returns its path."""
        target = self.out / f"{name}.{self.ext}"
        self.meshio.write(target, mesh, file_format=self.writer)
        return target


def export(
    path: str | Path,
    fmt: str,
    out_dir: str | Path | None = None,
    frames="all",
    mode: int | None = None,
) -> Export:
    """Writes the frames of a result file (``frames``: see ``select_frames``) in format
    ``fmt`` (one of ``FORMATS``) into ``out_dir`` (default: ``STEM-FMT`` beside the
    file), as ``STEM_K.ext`` with K the frame's index; returns what was written.
    ``mode`` k: the animation frames of mode k of a ``catenet modes`` file instead
    (``STEM_modek_F.ext``, times the phase in periods; point data ``shape``)."""
    path = Path(path)
    if fmt not in FORMATS:
        raise ConfigError(f"--to {fmt!r}: must be one of {', '.join(FORMATS)}")
    if not path.is_file():
        raise ConfigError(f"{path}: no such result file")
    meshio = _meshio()
    read_result(path)  # the layout checked first: every problem at once
    try:
        mesh = read_mesh(path)
        if mode is None:
            states, stem = _frames(path, str(frames)), path.stem
        else:
            states, stem = _mode_frames(path, int(mode), str(frames)), f"{path.stem}_mode{mode}"
        _check_shapes(path, mesh, states)
        body, radius = body_nodes(path)  # moving spheres: a vertex cell each, with its radius
        obstacles = read_obstacles(path)
    except DAMAGED as exc:
        raise damaged(path, exc) from None
    out = Path(out_dir) if out_dir is not None else path.with_name(f"{stem}-{fmt}")
    if out.exists() and not out.is_dir():
        raise ConfigError(f"-o {out}: exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    width = max(4, len(str(max(f.index for f in states))))
    target = _Target(meshio, out, *FORMATS[fmt], width)
    if fmt == "xdmf":  # meshio reads no vertex cells back from its mixed XDMF topology
        body = body[:0]
    files = _net_files(target, stem, mesh, states, body, radius)
    times = [f.t for f in states]
    solids = _obstacles(target, path, obstacles, states)
    parts = [files] + [w if len(w) == len(files) else w * len(files) for w in solids.values()]
    collection = _write_pvd(out / f"{stem}.pvd", parts, times) if fmt in PVD else None
    log.info("%s: %d frames written to %s", path, len(files), out)
    return Export(files, times, collection, solids)


def _net_files(
    target: _Target, stem: str, mesh: NetMesh, states: list[Frame], body, radius
) -> list[Path]:
    """Writes the net at every state, with a vertex cell per moving sphere's centre
    (``body``, its ``radius``); returns the files in order."""
    meshio = target.meshio
    cells = [("line", np.asarray(mesh.edges, dtype=np.int64))]
    if body.size:
        cells.append(("vertex", body[:, None]))
    files = []
    for f in states:
        point_data = _point_data(mesh, f)
        cell_data = _cell_data(mesh, f, body, radius)
        mesh_f = meshio.Mesh(f.x, cells, point_data=point_data, cell_data=cell_data)
        files.append(target.write(target.name(stem, f), mesh_f))
    return files


def _point_data(mesh: NetMesh, f: Frame) -> dict[str, np.ndarray]:
    """The point data of the net at state ``f``: displacement, fixed and whichever of
    velocity, reaction, contact_force, shape and /result's per-node datasets it holds."""
    point_data = {
        "displacement": f.x - mesh.nodes,
        "fixed": np.asarray(mesh.fixed, dtype=np.float64),  # VTK reads no int types
    }
    if f.v is not None:
        point_data["velocity"] = f.v
    if f.reaction is not None:
        point_data["reaction"] = f.reaction
    if f.contact_force is not None:
        point_data["contact_force"] = f.contact_force
    if f.shape is not None:
        point_data["shape"] = f.shape
    point_data.update(f.per_node)
    return point_data


def _cell_data(mesh: NetMesh, f: Frame, body, radius) -> dict[str, list[np.ndarray]]:
    """The cell data of the net at state ``f``, a block per cell type (the edges, then
    the moving spheres' vertices): tension, rest_length, EA and /result's per-edge
    datasets where stored (NaN on the vertices), and the spheres' radius (NaN on the
    edges)."""
    cell_data = {}
    for key, value in (
        ("tension", f.tension),
        ("rest_length", mesh.rest_length),
        ("EA", mesh.EA),
        *f.per_edge.items(),
    ):
        if value is not None:
            cell_data[key] = [np.asarray(value, dtype=np.float64)]
            if body.size:
                cell_data[key].append(np.full(body.size, np.nan))
    if body.size:
        cell_data["radius"] = [np.full(len(mesh.edges), np.nan), radius]
    return cell_data


def _obstacles(
    target: _Target, path: Path, obstacles: list[StoredObstacle], states: list[Frame]
) -> dict[int, list[Path]]:
    """Writes every obstacle's surface: once for a fixed one, at every state for a
    moving one (its frame's surface, or /result's for the final state); returns the
    files per obstacle index."""
    meshio = target.meshio
    written: dict[int, list[Path]] = {}
    for o in obstacles:
        stem = f"{path.stem}_obstacle{o.index}"
        if not o.moving:
            surface = meshio.Mesh(o.vertices, [("triangle", o.triangles)])
            written[o.index] = [target.write(stem, surface)]
            continue
        files = []
        for f in states:
            if f.index >= 0:
                stored = o.frames
                points = None if stored is None else stored[f.index]
            else:
                points = o.final
            if points is None:  # a file of an older catenet: no surface at this state
                break
            surface = meshio.Mesh(points, [("triangle", o.frame_triangles)])
            files.append(target.write(target.name(stem, f), surface))
        if len(files) == len(states):
            written[o.index] = files
    return written


def _write_pvd(target: Path, parts: list[list[Path]], times: list[float]) -> Path:
    """ParaView's collection: at each time, the files of every part (the net is part 0)."""
    root = ET.Element("VTKFile", type="Collection", version="0.1")
    coll = ET.SubElement(root, "Collection")
    for k, t in enumerate(times):
        for part, files in enumerate(parts):
            rel = os.path.relpath(files[k], target.parent)
            ET.SubElement(coll, "DataSet", timestep=repr(float(t)), part=str(part), file=rel)
    ET.indent(root, space=" ")
    target.write_text('<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n")
    return target
