"""Figures of a result file (SPEC §5): the deformed net over the undeformed one, coloured
by tension, in 3D and in a side view (paper Figs. 2c-d and 4), and, for runs with a
trajectory, the deflection of the probe node against time or load factor (paper Fig. A9).

Matplotlib is imported inside the functions (never at module import) and drives the Agg
canvas directly through ``matplotlib.figure.Figure``: no pyplot, no global backend change,
no window. Bad input raises ``ConfigError`` naming the file and what is wrong with it.
"""

from __future__ import annotations

import logging
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError

log = logging.getLogger(__name__)

__all__ = [
    "ResultFile",
    "default_output",
    "edge_tension",
    "plot_result",
    "probe_node",
    "read_result",
]

FORMATS = (".png", ".svg", ".pdf")
REQUIRED = ("/mesh/nodes", "/mesh/edges")


@dataclass
class ResultFile:
    """What a figure needs from a result file.

    nodes (N, 3) reference positions, edges (M, 2), x (N, 3) final positions, tension (M,)
    [N] (None when neither stored nor computable), fixed (N,) bool or None, probe: node
    whose deflection is reported, series_t / series_delta: trajectory time (or load factor)
    and the probe's deflection (positive down) when the trajectory has more than one frame,
    method: the case's solver.method ("static", "dynamic" or None when unknown).
    """

    path: Path
    nodes: np.ndarray
    edges: np.ndarray
    x: np.ndarray
    tension: np.ndarray | None
    fixed: np.ndarray | None
    probe: int
    case: dict = field(default_factory=dict)
    converged: bool | None = None
    method: str | None = None
    series_t: np.ndarray | None = None
    series_delta: np.ndarray | None = None
    from_trajectory: bool = False  # x is the last trajectory frame (no /result/x)

    @property
    def title(self) -> str:
        title = self.case.get("title") if isinstance(self.case.get("title"), str) else ""
        return title or self.path.name

    @property
    def delta(self) -> float:
        """Final deflection of the probe node [m], positive downward."""
        return float(self.nodes[self.probe, 2] - self.x[self.probe, 2])


def _dataset(h5, name: str, path: Path, shape_tail: tuple, dtype, problems: list[str]):
    obj = h5.get(name)
    if obj is None:
        return None
    if not hasattr(obj, "shape"):
        problems.append(f"{path}: {name} is a group: must be a dataset")
        return None
    arr = np.asarray(obj[()])
    if arr.ndim != 1 + len(shape_tail) or tuple(arr.shape[1:]) != shape_tail:
        want = "(n" + "".join(f", {k}" for k in shape_tail) + ")"
        problems.append(f"{path}: {name} has shape {arr.shape}: must be {want}")
        return None
    try:
        return arr.astype(dtype)
    except (TypeError, ValueError):
        problems.append(f"{path}: {name} is not numeric")
        return None


def probe_node(nodes: np.ndarray, fixed: np.ndarray | None = None) -> int:
    """The node whose deflection is reported when the file does not say: the free node
    nearest the centre of the x-y bounding box (the midpoint of a cable with an odd node
    count, the centre of a square net)."""
    lo, hi = nodes[:, :2].min(axis=0), nodes[:, :2].max(axis=0)
    dist = np.hypot(*(nodes[:, :2] - 0.5 * (lo + hi)).T)
    if fixed is not None and not fixed.all():
        dist = np.where(fixed, np.inf, dist)
    return int(np.argmin(dist))


def edge_tension(x, edges, rest_length, EA, tension_only: bool = True) -> np.ndarray:
    """Axial forces EA (|e|/l0 - 1) [N] of the edges at positions x (0 when slack)."""
    length = np.linalg.norm(x[edges[:, 1]] - x[edges[:, 0]], axis=1)
    t = EA * (length / rest_length - 1.0)
    return np.maximum(t, 0.0) if tension_only else t


def read_result(path: str | Path) -> ResultFile:
    """Reads what the figures need from a result file, checking the SPEC §5 layout.

    /result/x may be missing (a run that stopped before writing it): the last trajectory
    frame stands in. Tensions come from /result/tension, else from /trajectory/tension,
    else from /mesh/rest_length and /mesh/EA.
    """
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
    from catenet.output import open_result, trajectory_length

    problems: list[str] = []
    try:
        with open_result(path) as h5:  # also the file of a killed run
            missing = [name for name in REQUIRED if name not in h5]
            nodes = _dataset(h5, "/mesh/nodes", path, (3,), np.float64, problems)
            edges = _dataset(h5, "/mesh/edges", path, (2,), np.int64, problems)
            fixed = _dataset(h5, "/mesh/fixed", path, (), bool, problems)
            x = _dataset(h5, "/result/x", path, (3,), np.float64, problems)
            tension = _dataset(h5, "/result/tension", path, (), np.float64, problems)
            rest = _dataset(h5, "/mesh/rest_length", path, (), np.float64, problems)
            EA = _dataset(h5, "/mesh/EA", path, (), np.float64, problems)
            time = _dataset(h5, "/trajectory/time", path, (), np.float64, problems)
            traj = h5.get("/trajectory/x")
            n_frames = 0
            if traj is not None and hasattr(traj, "shape") and traj.ndim == 3:
                n_frames = min(traj.shape[0], trajectory_length(h5))
            elif traj is not None:
                problems.append(f"{path}: /trajectory/x must have shape (T, N, 3)")
            from_trajectory = False
            if x is None and "/result/x" not in h5:
                if n_frames > 0:
                    x = np.asarray(traj[n_frames - 1], dtype=np.float64)
                    from_trajectory = True
                    t_traj = h5.get("/trajectory/tension")
                    if tension is None and t_traj is not None and t_traj.ndim == 2:
                        if t_traj.shape[0] >= n_frames:
                            tension = np.asarray(t_traj[n_frames - 1], dtype=np.float64)
                else:
                    missing.append("/result/x")
            if missing:
                problems.insert(
                    0,
                    f"{path}: missing {', '.join(missing)}: not a catenet result file "
                    "(layout of SPEC §5: /mesh/nodes, /mesh/edges, /result/x, ...)",
                )
            if problems:
                raise ConfigError(problems)
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
            case = _case(h5.attrs.get("case"), path)
            method = case.get("solver", {}).get("method") if case else None
            attrs = h5["/result"].attrs if "/result" in h5 else {}
            converged = bool(attrs["converged"]) if "converged" in attrs else None
            probe = None
            if "probe" in attrs:
                try:
                    probe = int(attrs["probe"])
                except (TypeError, ValueError):
                    probe = None
                if probe is not None and not 0 <= probe < n:
                    probe = None
            if probe is None:
                probe = probe_node(nodes, fixed)
            series_t = series_delta = None
            if n_frames > 1 and traj.shape[1:] == (n, 3):
                z = np.asarray(traj[:n_frames, probe, 2], dtype=np.float64)
                series_delta = nodes[probe, 2] - z
                if time is not None and len(time) >= n_frames:
                    series_t = time[:n_frames]
                else:
                    series_t = np.arange(n_frames, dtype=np.float64)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read as HDF5: {exc}") from exc
    if tension is None and rest is not None and EA is not None:
        only = bool(case.get("material", {}).get("tension_only", True)) if case else True
        tension = edge_tension(x, edges, rest, EA, only)
    return ResultFile(
        path=path,
        nodes=nodes,
        edges=edges,
        x=x,
        tension=tension,
        fixed=fixed,
        probe=probe,
        case=case,
        converged=converged,
        method=method if isinstance(method, str) else None,
        series_t=series_t,
        series_delta=series_delta,
        from_trajectory=from_trajectory,
    )


def _case(text, path: Path) -> dict:
    if text is None:
        return {}
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    try:
        return tomllib.loads(str(text))
    except tomllib.TOMLDecodeError as exc:
        log.warning("%s: the case attribute is not valid TOML (%s); plotting without it", path, exc)
        return {}


def default_output(path: str | Path) -> Path:
    """OUT.png next to OUT.h5."""
    return Path(path).with_suffix(".png")


def check_output(out: str | Path) -> Path:
    out = Path(out)
    if out.suffix.lower() not in FORMATS:
        raise ConfigError(
            f"--output = {str(out)!r}: the format must be one of {', '.join(FORMATS)}"
        )
    if not out.resolve().parent.is_dir():
        raise ConfigError(f"--output = {str(out)!r}: its directory does not exist")
    return out


def _limits(*arrays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pts = np.concatenate([a.reshape(-1, 3) for a in arrays])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = float(np.max(hi - lo)) or 1.0
    pad = 0.04 * span
    return lo - pad, hi + pad


def plot_result(path: str | Path, out: str | Path | None = None, *, dpi: int = 150) -> Path:
    """Draws the figure of the result file ``path`` into ``out`` (.png, .svg or .pdf;
    default: ``path`` with the suffix .png) and returns ``out``.

    Panels: the deformed net (coloured by tension, colour bar in N) over the undeformed
    one (grey) in 3D and in a side view (x-z, or y-z when the net is longer along y),
    supports as red dots, the probe node marked; with a trajectory of more than one frame
    also the probe's deflection (positive down) against time (dynamic runs) or load
    factor (static runs in steps).
    """
    res = read_result(path)
    out = check_output(default_output(path) if out is None else out)

    import matplotlib

    matplotlib.rcParams["svg.hashsalt"] = "catenet"  # reproducible SVG ids
    from matplotlib import colormaps
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize, TwoSlopeNorm
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    nodes, x, edges = res.nodes, res.x, res.edges
    seg_ref = nodes[edges]  # (M, 2, 3)
    seg_def = x[edges]
    tension = res.tension
    if tension is not None and len(tension) and np.all(np.isfinite(tension)):
        t_min, t_max = float(tension.min()), float(tension.max())
        if t_min < 0.0 < t_max:  # compression (bilateral edges): diverging colours
            norm, cmap = TwoSlopeNorm(0.0, t_min, t_max), colormaps["coolwarm"]
        else:
            lo, hi = min(t_min, 0.0), max(t_max, 0.0)
            norm, cmap = Normalize(lo, hi if hi > lo else lo + 1.0), colormaps["viridis"]
    else:
        tension, norm, cmap = None, None, None

    series = res.series_delta is not None
    fig = Figure(figsize=(15.5 if series else 11.0, 4.8), layout="constrained")
    FigureCanvasAgg(fig)
    fig.get_layout_engine().set(wspace=0.12)  # room for the 3D view's z label
    ncols = 3 if series else 2
    ax3 = fig.add_subplot(1, ncols, 1, projection="3d")
    ax2 = fig.add_subplot(1, ncols, 2)

    # 3D view
    ax3.add_collection3d(Line3DCollection(seg_ref, colors="0.75", linewidths=0.6, linestyles="--"))
    lines3 = Line3DCollection(seg_def, linewidths=1.4)
    if tension is not None:
        lines3.set_array(tension)
        lines3.set_cmap(cmap)
        lines3.set_norm(norm)
    else:
        lines3.set_color("C0")
    ax3.add_collection3d(lines3)
    lo, hi = _limits(seg_ref, seg_def)
    # true proportions, but no axis thinner than 30 % of the longest (a cable in a plane,
    # a flat net): its box would collapse and its tick labels pile up
    mid, half = 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 0.15 * float(np.max(hi - lo)))
    for setter, a, b in zip(
        (ax3.set_xlim, ax3.set_ylim, ax3.set_zlim), mid - half, mid + half, strict=True
    ):
        setter(a, b)
    ax3.set_box_aspect(tuple(2.0 * half))
    for axis in (ax3.xaxis, ax3.yaxis, ax3.zaxis):
        axis.set_major_locator(MaxNLocator(4))
    if res.fixed is not None and res.fixed.any():
        f = x[res.fixed]
        ax3.scatter(f[:, 0], f[:, 1], f[:, 2], color="red", s=8, depthshade=False)
    ax3.set_xlabel("x [m]")
    ax3.set_ylabel("y [m]")
    ax3.set_zlabel("z [m]", labelpad=1)
    ax3.set_title("3D view")

    # side view: the horizontal axis along which the net is longer
    h = 0 if np.ptp(nodes[:, 0]) >= np.ptp(nodes[:, 1]) else 1
    ax2.add_collection(
        LineCollection(
            seg_ref[:, :, [h, 2]],
            colors="0.75",
            linewidths=0.6,
            linestyles="--",
            label="undeformed",
        )
    )
    lines2 = LineCollection(seg_def[:, :, [h, 2]], linewidths=1.4, label="deformed")
    if tension is not None:
        lines2.set_array(tension)
        lines2.set_cmap(cmap)
        lines2.set_norm(norm)
    else:
        lines2.set_color("C0")
    ax2.add_collection(lines2)
    if res.fixed is not None and res.fixed.any():
        f = x[res.fixed]
        ax2.plot(f[:, h], f[:, 2], "o", color="red", ms=3, label="supports")
    p = res.probe
    ax2.plot(
        [x[p, h]], [x[p, 2]], "x", color="k", ms=7, label=f"probe node {p}: δ = {res.delta:.4g} m"
    )
    ax2.update_datalim(np.column_stack([[lo[h], hi[h]], [lo[2], hi[2]]]))
    ax2.autoscale_view()
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.set_xlabel(f"{'xy'[h]} [m]")
    ax2.set_ylabel("z [m]")
    ax2.set_title("side view")
    ax2.legend(loc="best", fontsize="small")
    ax2.grid(True, lw=0.3)

    if tension is not None:
        cb = fig.colorbar(lines2, ax=[ax3, ax2], location="right", shrink=0.85, pad=0.02)
        cb.set_label("tension [N]")

    if series:
        ax_t = fig.add_subplot(1, ncols, 3)
        t, d = res.series_t, res.series_delta
        ax_t.plot(t, d, "-", color="C0", lw=1.2, marker="." if len(t) < 60 else None)
        if res.method == "dynamic":
            ax_t.set_xlabel("time t [s]")
            ax_t.set_title("probe deflection against time")
        elif res.method == "static":
            ax_t.set_xlabel("load factor [-]")
            ax_t.set_title("probe deflection against load")
        else:
            ax_t.set_xlabel("/trajectory/time")
            ax_t.set_title("probe deflection along the trajectory")
        ax_t.set_ylabel(f"deflection δ of node {p} [m] (down)")
        ax_t.grid(True, lw=0.3)

    status = ""
    if res.converged is False:
        status = " (NOT converged)"
    if res.from_trajectory:
        status += " (last trajectory frame)"
    fig.suptitle(f"{res.title}{status}")
    fig.savefig(out, dpi=dpi)
    log.info("wrote %s", out)
    return out
