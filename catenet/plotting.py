"""Figures of a result file (SPEC §5): the deformed net over the undeformed one, coloured
by tension, in 3D and in a side view (paper Figs. 2c-d and 4), and, for runs with a
trajectory, the deflection of the probe node against time or load factor (paper Fig. A9).

Matplotlib is imported inside the functions (never at module import) and drives the Agg
canvas directly through ``matplotlib.figure.Figure``: no pyplot, no global backend change,
no window. Bad input raises ``ConfigError`` naming the file and what is wrong with it.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.output import read_result

log = logging.getLogger(__name__)

__all__ = ["default_output", "edge_tension", "plot_result"]

FORMATS = (".png", ".svg", ".pdf")


def edge_tension(x, edges, rest_length, EA, tension_only: bool = True) -> np.ndarray:
    """Axial forces [N] of the edges at positions x under the paper's law (0 when slack
    and tension-only): for result files that store no tensions."""
    from catenet import measures
    from catenet.laws import Law

    law = Law.uniform(len(edges), tension_only=tension_only)
    return measures.edge_tension(x, edges, rest_length, EA, law)


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
    res = read_result(path)  # ConfigError for anything but a result file
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

    mesh = res.mesh
    nodes, x, edges, fixed = mesh.nodes, res.x, mesh.edges, mesh.fixed
    seg_ref = nodes[edges]  # (M, 2, 3)
    seg_def = x[edges]
    tension = res.tension
    # a file that stores no tensions (not written by catenet): computed from the mesh
    if tension is None and mesh.rest_length is not None and mesh.EA is not None:
        only = bool(res.case.get("material", {}).get("tension_only", True)) if res.case else True
        tension = edge_tension(x, edges, mesh.rest_length, mesh.EA, only)
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
    if fixed is not None and fixed.any():
        f = x[fixed]
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
    if fixed is not None and fixed.any():
        f = x[fixed]
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
