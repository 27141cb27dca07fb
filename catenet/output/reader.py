"""Reading result files (contract §5), also those of killed runs: the one module that
knows where a result file keeps what.

- ``read_result(path)`` -> ``ResultFile``: mesh, attributes, final state (``/result``, or
  the last complete frame of a run that stopped before writing it) and trajectory access,
  with every layout problem reported at once (``catenet plot``).
- ``read_frame(path, index)`` -> ``Frame``: one stored state (``--restart``, tests).
- ``read_mesh(path)`` -> ``NetMesh``: the net a file was written for (``--restart``).
- ``open_result`` and ``trajectory_length``: the h5py file and its complete frames, for
  tools that look at the datasets themselves (``catenet.output.repair`` rewrites a file
  that needs it as an ordinary one).

The writer only ever replaces a result file whole, so a killed run's file is an ordinary
HDF5 file. Files written in place (by earlier catenet versions, in SWMR mode) carry HDF5's
"open for writing" mark after a kill: ``open_result`` reads them in SWMR mode, as they
were at their last flush. Frames that never fully reached the disk (shorter datasets, or
NaN, the datasets' fill value) are not counted.
"""

from __future__ import annotations

import logging
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.model import measures
from catenet.model.limits import MAGNITUDE
from catenet.output.files import read_text
from catenet.output.heaps import check_heaps

log = logging.getLogger(__name__)

# SWMR needs the file format of HDF5 1.10; a newer upper bound ("latest") would let the
# HDF5 library in use write structures that the HDF5 bundled with ParaView cannot read.
LIBVER = ("v110", "v110")
# per-frame datasets of /trajectory, besides time (energy: a dynamic run's balance, [J])
TRAJECTORY = ("x", "v", "a", "tension", "energy")
REQUIRED = ("/mesh/nodes", "/mesh/edges")

__all__ = [
    "LIBVER",
    "Frame",
    "NetMesh",
    "ResultFile",
    "open_result",
    "probe_node",
    "read_frame",
    "read_mesh",
    "read_result",
    "trajectory_length",
]


# --------------------------------------------------------------------------------------------
# The HDF5 file and its complete frames
# --------------------------------------------------------------------------------------------


def open_result(path: str | Path):
    """Opens a result file for reading with h5py: normally, or, for the file of a run that
    was killed while writing in place (HDF5 refuses it: "file is already open for write"),
    in SWMR read mode, which reads it as it was at its last flush. A truncated or damaged
    file raises OSError at once (``check_heaps``: a damaged heap of strings, which HDF5
    would read for ever)."""
    import h5py

    if Path(path).is_file() and Path(path).stat().st_size > 0:
        check_heaps(path)
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        # Only a file that HDF5 calls open for write is read in SWMR mode: a truncated or
        # damaged one would make SWMR's reader retry its metadata for ever.
        if "already open for write" not in str(exc):
            raise
        try:
            return h5py.File(path, "r", libver=LIBVER, swmr=True)
        except OSError:
            raise exc from None


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
    except DAMAGED:  # data beyond the end of a truncated file, or not numbers
        return False


#: What h5py and NumPy raise for a damaged file or datasets of the wrong kind: a group
#: where a dataset belongs, strings where numbers belong, chunks that fail to decode.
DAMAGED = (OSError, RuntimeError, TypeError, ValueError, KeyError, AttributeError, IndexError)


def is_dataset(obj) -> bool:
    """Whether ``obj`` (what an open file holds at a name, or None) is a dataset."""
    import h5py

    return isinstance(obj, h5py.Dataset)


def damaged(path, exc: BaseException) -> ConfigError:
    """The ConfigError for a result file that is damaged or not laid out as catenet's."""
    if isinstance(exc, ConfigError):
        return exc
    reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return ConfigError(f"{path}: damaged or not a catenet result file ({reason})")


# --------------------------------------------------------------------------------------------
# One stored state
# --------------------------------------------------------------------------------------------


@dataclass
class Frame:
    """One stored state: time (or load factor), positions, velocities (None: not
    stored), where it came from ("trajectory" frame ``index`` or "result"), the
    tensions stored with it and the integrator's acceleration state (newmark runs; None:
    not stored); /result's reactions and contact forces (``catenet export``; None: not
    read); the mode shape (N, 3) of a mode's animation frame (``catenet export --mode``;
    None otherwise)."""

    t: float
    x: np.ndarray
    v: np.ndarray | None
    source: str
    index: int
    tension: np.ndarray | None = None
    a: np.ndarray | None = None
    reaction: np.ndarray | None = None
    contact_force: np.ndarray | None = None
    shape: np.ndarray | None = None
    per_node: dict[str, np.ndarray] = field(default_factory=dict)  # /result's, by name
    per_edge: dict[str, np.ndarray] = field(default_factory=dict)


def _array(g, name: str) -> np.ndarray | None:
    return np.asarray(g[name], dtype=np.float64) if name in g else None


def _trajectory_frame(h5, k: int) -> Frame:
    g = h5["trajectory"]
    v = np.asarray(g["v"][k], dtype=np.float64) if "v" in g else None
    tension = np.asarray(g["tension"][k], dtype=np.float64) if "tension" in g else None
    x = np.asarray(g["x"][k], dtype=np.float64)
    a = np.asarray(g["a"][k], dtype=np.float64) if "a" in g else None
    return Frame(float(g["time"][k]), x, v, "trajectory", k, tension, a)


def _frame_index(path, n: int, index: int) -> int:
    k = index if index >= 0 else n + index
    if not 0 <= k < n:
        raise ConfigError(f"{path}: has {n} frames: frame {index} does not exist")
    return k


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
    try:
        with h5:
            n = trajectory_length(h5)
            if n > 0:
                return _trajectory_frame(h5, _frame_index(path, n, index))
            if "result" in h5 and "x" in h5["result"]:
                r = h5["result"]
                t = float(r.attrs.get("time", 0.0))
                x = np.asarray(r["x"], dtype=np.float64)
                v, tension, a = _array(r, "v"), _array(r, "tension"), _array(r, "a")
                return Frame(t, x, v, "result", -1, tension, a)
    except DAMAGED as exc:
        raise damaged(path, exc) from None
    raise ConfigError(f"{path}: holds no stored state (no trajectory frame and no /result)")


def read_peaks(path: str | Path, t: float) -> dict[str, np.ndarray] | None:
    """The run's peaks in /result (``peak_tension``, ``peak_tension_time``,
    ``least_tension``, ``peak_displacement``, ``peak_displacement_time``) when /result is
    the state at time ``t`` (a restart from its last frame goes on with them); else None."""
    names = (
        "peak_tension",
        "peak_tension_time",
        "least_tension",
        "peak_displacement",
        "peak_displacement_time",
    )
    try:
        with open_result(Path(path)) as h5:
            r = h5.get("result")
            if r is None or float(r.attrs.get("time", np.nan)) != t:
                return None
            if not all(name in r for name in names):
                return None
            return {name: np.asarray(r[name], dtype=np.float64) for name in names}
    except DAMAGED as exc:  # a file damaged there: bad input, not peaks silently lost
        raise damaged(path, exc) from None


# --------------------------------------------------------------------------------------------
# The net a file was written for
# --------------------------------------------------------------------------------------------


@dataclass
class NetMesh:
    """The net of a result file (/mesh): nodes (N, 3) reference positions [m], edges (M, 2)
    node indices, rest_length and EA (M,) [m], [N], fixed (N,) bool pinned nodes. In a
    ``ResultFile`` the last three are None when a file does not hold them (in the right
    shape); ``read_mesh`` requires all but EA."""

    nodes: np.ndarray
    edges: np.ndarray
    rest_length: np.ndarray | None
    EA: np.ndarray | None
    fixed: np.ndarray | None


def read_mesh(path: str | Path, *, what: str | None = None) -> NetMesh:
    """The mesh of a result file, all of nodes, edges, rest lengths and supports present.
    Raises ConfigError naming ``what`` (default: the path) for a file without them."""
    what = str(path) if what is None else what
    try:
        with open_result(path) as h5:
            if "mesh" not in h5:
                raise ConfigError(f"{what}: has no /mesh: not a catenet result file")
            mesh = h5["mesh"]
            try:
                nodes = np.asarray(mesh["nodes"])
                edges = np.asarray(mesh["edges"])
                rest = np.asarray(mesh["rest_length"])
                fixed = np.asarray(mesh["fixed"])
            except KeyError as exc:
                raise ConfigError(f"{what}: /mesh lacks {exc}: not a catenet result file") from None
            EA = np.asarray(mesh["EA"]) if "EA" in mesh else None
    except OSError as exc:
        raise ConfigError(f"{what}: cannot be read: {exc}") from None
    except DAMAGED as exc:
        raise damaged(what, exc) from None
    return NetMesh(nodes, edges, rest, EA, fixed)


# --------------------------------------------------------------------------------------------
# The whole file, checked
# --------------------------------------------------------------------------------------------


@dataclass
class ResultFile:
    """A result file as read by ``read_result``.

    mesh: the net (``NetMesh``); attrs: the root attributes (the resolved case as TOML,
    versions, ...), case: that TOML parsed ({} when missing or invalid), result_attrs:
    those of /result ({} without). x (N, 3): the final positions, /result/x, or the last
    complete trajectory frame for a run that stopped before writing it
    (``from_trajectory``); tension (M,) [N]: the tensions stored with them (None: not
    stored); converged: /result's flag (None: unknown); probe: the node whose deflection
    is reported (/result's attribute, else ``probe_node``). times: the times (or load
    factors) of the complete trajectory frames, ``frame(k)`` reads one; series_t /
    series_delta: time and probe deflection (positive down) when there is more than one.
    """

    path: Path
    mesh: NetMesh
    x: np.ndarray
    tension: np.ndarray | None
    probe: int
    attrs: dict = field(default_factory=dict)
    case: dict = field(default_factory=dict)
    result_attrs: dict = field(default_factory=dict)
    converged: bool | None = None
    times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    series_t: np.ndarray | None = None
    series_delta: np.ndarray | None = None
    from_trajectory: bool = False  # x is the last trajectory frame (no /result/x)
    reaction: np.ndarray | None = None  # (N, 3) /result/reaction [N] (None: not stored)
    series_u: np.ndarray | None = None  # |x - X| of the probe along series_t [m]

    @property
    def title(self) -> str:
        title = self.case.get("title") if isinstance(self.case.get("title"), str) else ""
        return title or self.path.name

    @property
    def method(self) -> str | None:
        """The case's solver.method ("static", "dynamic"; None when unknown)."""
        method = self.case.get("solver", {}).get("method") if self.case else None
        return method if isinstance(method, str) else None

    @property
    def to_rest(self) -> bool:
        """Whether the run was dynamic relaxation to rest (solver.t_end = "rest"): its
        time is pseudo-time."""
        solver = self.case.get("solver", {}) if self.case else {}
        return self.method == "dynamic" and solver.get("t_end") == "rest"

    @property
    def delta(self) -> float:
        """Final deflection of the probe node [m], positive downward."""
        return measures.deflection(self.mesh.nodes, self.x, self.probe)

    @property
    def n_frames(self) -> int:
        """Complete trajectory frames."""
        return len(self.times)

    def frame(self, index: int) -> Frame:
        """Trajectory frame ``index`` (negative: from the end)."""
        k = _frame_index(self.path, self.n_frames, index)
        try:
            with open_result(self.path) as h5:
                return _trajectory_frame(h5, k)
        except DAMAGED as exc:
            raise damaged(self.path, exc) from None


def probe_node(nodes: np.ndarray, fixed: np.ndarray | None = None) -> int:
    """The node whose deflection is reported when the file does not say: the free node
    nearest the centre of the x-y bounding box (the midpoint of a cable with an odd node
    count, the centre of a square net)."""
    lo, hi = nodes[:, :2].min(axis=0), nodes[:, :2].max(axis=0)
    dist = np.hypot(*(nodes[:, :2] - 0.5 * (lo + hi)).T)
    if fixed is not None and not fixed.all():
        dist = np.where(fixed, np.inf, dist)
    return int(np.argmin(dist))


#: The datasets of node positions, whose every value a run keeps within MAGNITUDE.
POSITIONS = ("/mesh/nodes", "/result/x")


def _dataset(h5, name: str, path: Path, shape_tail: tuple, dtype, problems: list[str]):
    obj = h5.get(name)
    if obj is None:
        return None
    if not is_dataset(obj):
        problems.append(f"{path}: {name} is a group: must be a dataset")
        return None
    arr = np.asarray(obj[()])
    if arr.ndim != 1 + len(shape_tail) or tuple(arr.shape[1:]) != shape_tail:
        want = "(n" + "".join(f", {k}" for k in shape_tail) + ")"
        problems.append(f"{path}: {name} has shape {arr.shape}: must be {want}")
        return None
    try:
        arr = arr.astype(dtype)
    except (TypeError, ValueError):
        problems.append(f"{path}: {name} is not numeric")
        return None
    if name in POSITIONS and arr.size and not np.all(np.abs(arr) <= MAGNITUDE):
        problems.append(  # no run writes such positions: flipped bytes (a NaN, 7e307)
            f"{path}: {name} holds positions beyond +-{MAGNITUDE:.0e} m or not finite: damaged"
        )
        return None
    return arr


def read_result(path: str | Path) -> ResultFile:
    """Reads a result file, checking the contract §5 layout; raises ConfigError listing every
    problem found.

    /result/x may be missing (a run that stopped before writing it): the last complete
    trajectory frame stands in, with its tensions. /mesh/fixed of the wrong shape counts
    as missing.
    """
    path = _hdf5_file(path)
    problems: list[str] = []
    try:
        with open_result(path) as h5:  # also the file of a killed run
            missing = [name for name in REQUIRED if name not in h5]
            nodes = _dataset(h5, "/mesh/nodes", path, (3,), np.float64, problems)
            edges = _dataset(h5, "/mesh/edges", path, (2,), np.int64, problems)
            fixed = _dataset(h5, "/mesh/fixed", path, (), bool, problems)
            x = _dataset(h5, "/result/x", path, (3,), np.float64, problems)
            tension = _dataset(h5, "/result/tension", path, (), np.float64, problems)
            reaction = h5.get("/result/reaction")
            reaction = (
                np.asarray(reaction, dtype=np.float64)
                if nodes is not None and is_dataset(reaction) and reaction.shape == (len(nodes), 3)
                else None
            )
            rest = _dataset(h5, "/mesh/rest_length", path, (), np.float64, problems)
            EA = _dataset(h5, "/mesh/EA", path, (), np.float64, problems)
            time = _dataset(h5, "/trajectory/time", path, (), np.float64, problems)
            traj = h5.get("/trajectory/x")
            n_frames = 0
            if is_dataset(traj) and traj.ndim == 3:
                n_frames = min(traj.shape[0], trajectory_length(h5))
            elif traj is not None:
                problems.append(f"{path}: /trajectory/x must have shape (T, N, 3)")
            from_trajectory = False
            if x is None and "/result/x" not in h5:
                if n_frames > 0:  # the last complete frame stands in, with its tensions
                    x, tension = _last_frame(h5, traj, n_frames, tension)
                    from_trajectory = True
                else:
                    missing.append("/result/x")
            if missing:
                problems.insert(
                    0,
                    f"{path}: missing {', '.join(missing)}: not a catenet result file "
                    "(the result file layout: /mesh/nodes, /mesh/edges, /result/x, ...)",
                )
            if problems:
                raise ConfigError(problems)
            fixed = _check_shapes(path, nodes, edges, x, fixed, tension, rest, EA)
            attrs = dict(h5.attrs)
            case = _case(attrs.get("case"), path)
            result_attrs = dict(h5["/result"].attrs) if "/result" in h5 else {}
            converged = bool(result_attrs["converged"]) if "converged" in result_attrs else None
            probe = _probe(result_attrs, nodes, fixed)
            times = time[:n_frames] if n_frames and time is not None else np.zeros(0)
            series = _series(traj, time, n_frames, nodes, probe)
    except ConfigError:
        raise
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read as HDF5: {exc}") from exc
    except DAMAGED as exc:
        raise damaged(path, exc) from None
    return ResultFile(
        path=path,
        mesh=NetMesh(nodes, edges, rest, EA, fixed),
        x=x,
        tension=tension,
        probe=probe,
        attrs=attrs,
        case=case,
        result_attrs=result_attrs,
        converged=converged,
        times=times,
        series_t=series[0],
        series_delta=series[1],
        from_trajectory=from_trajectory,
        reaction=reaction,
        series_u=series[2],
    )


def _hdf5_file(path: str | Path) -> Path:
    """``path`` as a Path once it names an HDF5 file; ConfigError saying why not."""
    import h5py

    path = Path(path)
    if not path.exists():
        raise ConfigError(f"{path}: no such file or directory")
    if not path.is_file():
        raise ConfigError(f"{path}: not a file")
    try:
        is_h5 = h5py.is_hdf5(path)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read: {exc}") from exc
    if not is_h5:
        raise ConfigError(f"{path}: not an HDF5 file (expected a catenet result file)")
    return path


def _last_frame(h5, traj, n_frames: int, tension):
    """(x, tension) of the last complete trajectory frame (the tension given, else the
    frame's where stored)."""
    x = np.asarray(traj[n_frames - 1], dtype=np.float64)
    t_traj = h5.get("/trajectory/tension")
    if tension is None and t_traj is not None and t_traj.ndim == 2:
        if t_traj.shape[0] >= n_frames:
            tension = np.asarray(t_traj[n_frames - 1], dtype=np.float64)
    return x, tension


def _check_shapes(path: Path, nodes, edges, x, fixed, tension, rest, EA):
    """``fixed`` (None where its shape is wrong: it counts as missing) once the arrays
    agree in size; ConfigError listing every disagreement."""
    problems = []
    n, m = len(nodes), len(edges)
    if x.shape != nodes.shape:
        problems.append(f"{path}: /result/x has shape {x.shape}: must be {nodes.shape}")
    if m and (edges.min() < 0 or edges.max() >= n):
        problems.append(f"{path}: /mesh/edges: node indices must be in 0..{n - 1}")
    if fixed is not None and fixed.shape != (n,):
        fixed = None
    for name, arr in (("tension", tension), ("rest_length", rest), ("EA", EA)):
        if arr is not None and arr.shape != (m,):
            problems.append(f"{path}: {name} has {len(arr)} values: must be {m}")
    if problems:
        raise ConfigError(problems)
    return fixed


def _probe(result_attrs: dict, nodes, fixed) -> int:
    """The probe node /result names (an index among the nodes), else the geometry's."""
    probe = None
    if "probe" in result_attrs:
        try:
            probe = int(result_attrs["probe"])
        except (TypeError, ValueError):
            probe = None
        if probe is not None and not 0 <= probe < len(nodes):
            probe = None
    return probe_node(nodes, fixed) if probe is None else probe


def _series(traj, time, n_frames: int, nodes, probe: int) -> tuple:
    """(t, delta, |u|) of the probe over the trajectory's frames (None each without two
    frames of the net's shape); t the frame index where times are missing."""
    if not (n_frames > 1 and traj.shape[1:] == (len(nodes), 3)):
        return None, None, None
    xp = np.asarray(traj[:n_frames, probe : probe + 1], dtype=np.float64)
    delta = measures.deflection(nodes[probe : probe + 1], xp, 0)
    u = np.linalg.norm(xp[:, 0, :] - nodes[probe], axis=1)
    if time is not None and len(time) >= n_frames:
        return time[:n_frames], delta, u
    return np.arange(n_frames, dtype=np.float64), delta, u


def _case(text, path: Path) -> dict:
    if text is None:
        return {}
    try:
        return tomllib.loads(read_text(text))
    except tomllib.TOMLDecodeError as exc:
        log.warning("%s: the case attribute is not valid TOML (%s); plotting without it", path, exc)
        return {}
