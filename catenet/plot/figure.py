"""Figures of a result file (contract §5): the deformed net over the undeformed one, coloured
by tension, in 3D and in a side view (paper Figs. 2c-d and 4), and, for runs with a
trajectory, the deflection of the probe node against time or load factor (paper Fig. A9).

Matplotlib is imported inside the functions (never at module import) and drives the Agg
canvas directly through ``matplotlib.figure.Figure``: no pyplot, no global backend change,
no window. Bad input raises ``ConfigError`` naming the file and what is wrong with it.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError
from catenet.model.units import relabel, system
from catenet.output import read_result
from catenet.output.supports import read_supported
from catenet.plot.plan import draw_plan, draw_slack, slack_edges, wants_plan

if TYPE_CHECKING:
    from matplotlib.colors import Colormap, Normalize

    from catenet.plot.bodies import Balls
    from catenet.plot.obstacles import Obstacles
    from catenet.plot.state import Shown

log = logging.getLogger(__name__)

__all__ = ["default_output", "edge_tension", "plot_result"]

FORMATS = (".png", ".svg", ".pdf")


def edge_tension(x, edges, rest_length, EA, tension_only: bool = True) -> np.ndarray:
    """Axial forces [N] of the edges at positions x under the paper's law (0 when slack
    and tension-only): for result files that store no tensions."""
    from catenet.model import measures
    from catenet.model.laws import Law

    law = Law.uniform(len(edges), tension_only=tension_only)
    return measures.edge_tension(x, edges, rest_length, EA, law)


@dataclass
class PaperCurve:
    """One of the paper's validation plots a result file is a run of (Figs. 2e, 2f):
    catenet's points along the load steps, the closed form, and the shape of the last
    step in closed form (x along the chord from its middle, z up)."""

    title: str
    xlabel: str
    ylabel: str
    x: np.ndarray
    y: np.ndarray
    x_closed: np.ndarray
    y_closed: np.ndarray
    closed_label: str
    shape: Callable[[np.ndarray], np.ndarray]
    shape_label: str


def paper_curve(res) -> PaperCurve | None:
    """The paper's plot for a cable case of Sec. 3.1 run in load steps, else None:

    - supports moved symmetrically inward along a horizontal chord under gravity (the
      compressed catenary, Fig. 2e): delta/L against Delta L/L with Eq. 15, shape Eq. 14;
    - a downward force on the midpoint node, no gravity (Fig. 2f): delta/L against F/EA
      with Eq. 17, shape Eq. 16.

    Each load step is a frame at load factor s: the moves (and gravity) or the force
    scaled by s. Inextensible Eq. 15 does not depend on g, so the scaled gravity of the
    catenary steps does not matter there.
    """
    from catenet.validate import analytic

    case = res.case or {}
    g = case.get("geometry", {})
    if g.get("kind") != "cable" or res.series_t is None or res.method != "static":
        return None
    start, end = np.asarray(g.get("start", []), float), np.asarray(g.get("end", []), float)
    if start.shape != (3,) or end.shape != (3,) or start[2] != end[2]:
        return None
    L = float(g.get("length", np.linalg.norm(end - start)))
    chord = end - start
    unit = chord / np.linalg.norm(chord)
    s = np.asarray(res.series_t, float)
    delta = np.asarray(res.series_delta, float)
    moves = case.get("supports", {}).get("move", [])
    load = case.get("load", {})
    if len(moves) == 2 and load.get("gravity") and not load.get("point"):
        inward = [float(np.dot(m["displacement"], unit)) for m in moves]
        d = sorted(inward)
        if not (d[0] < 0 < d[1] and math.isclose(-d[0], d[1], rel_tol=1e-9)):
            return None
        dl = 2.0 * d[1] / L  # Delta L / L at load factor 1
        grid = np.linspace(0.0, dl, 200)[1:]
        sag = np.array([analytic.catenary_sag(1.0, v) for v in grid])
        return PaperCurve(
            "paper Fig. 2e: sag against shortening",
            "end shortening ΔL/L [-]",
            "mid-span sag δ/L [-]",
            s * dl,
            delta / L,
            np.concatenate([[0.0], grid]),
            np.concatenate([[0.0], sag]),
            "Eq. 15 (inextensible catenary)",
            lambda x: L * analytic.catenary_shape(np.asarray(x) / L, 1.0, dl),
            f"Eq. 14 at ΔL/L = {dl:.3g}",
        )
    points = load.get("point", [])
    if len(points) == 1 and not load.get("gravity") and not moves and res.mesh.EA is not None:
        force = np.asarray(points[0]["force"], float)
        if points[0]["node"] not in ("midpoint", res.probe) or force[:2].any() or force[2] >= 0:
            return None
        EA = float(res.mesh.EA[0])
        f_max = -force[2] / EA
        grid = np.linspace(0.0, f_max, 200)
        closed = np.array([analytic.midpoint_load_deflection(f * EA, L, EA) for f in grid])
        delta_end = analytic.midpoint_load_deflection(f_max * EA, L, EA)
        return PaperCurve(
            "paper Fig. 2f: deflection against load",
            "load F/EA [-]",
            "midpoint deflection δ/L [-]",
            s * f_max,
            delta / L,
            grid,
            closed / L,
            "Eq. 17",
            lambda x: analytic.midpoint_load_shape(np.asarray(x), delta_end, L),
            f"Eq. 16 at F/EA = {f_max:.3g}",
        )
    return None


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


def in_units(fig, units: object) -> None:
    """Names the units of every text of ``fig`` (axis labels, titles, colour bars,
    legends) as the case's ``units`` do (``catenet.model.units``: kN-m, N-mm); the
    numbers drawn are the file's, in the case's units already."""
    from matplotlib.text import Text

    units = system(units)
    if units == "SI":
        return
    for t in fig.findobj(Text):
        text = t.get_text()
        if text:
            t.set_text(relabel([text], units)[0])


def _limits(*arrays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pts = np.concatenate([a.reshape(-1, 3) for a in arrays])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = float(np.max(hi - lo)) or 1.0
    pad = 0.04 * span
    return lo - pad, hi + pad


def plot_result(
    path: str | Path,
    out: str | Path | None = None,
    *,
    dpi: int = 150,
    scale: float = 1.0,
    case: str | None = None,
    time: float | None = None,
    frame: int | None = None,
    say: Callable[[str], None] | None = None,
) -> Path:
    """Draws the figure of the result file ``path`` into ``out`` (.png, .svg or .pdf;
    default: ``path`` with the suffix .png, or RESULT-<state>.png for a chosen state)
    and returns ``out`` (see ``figure``). ``case``, ``time``, ``frame``: the state drawn
    (``catenet.plot.state.select``: a load case, combination or the envelope; the stored
    frame nearest to a time, or a frame by index); ``say`` is given the note of the frame
    that ``time`` found (when it is not at that time)."""
    from catenet.plot.state import select, state_output

    res = read_result(path)  # ConfigError for anything but a result file
    res, shown, note = select(res, case=case, time=time, frame=frame)
    if note and say is not None:
        say(note)
    if out is None:
        out = default_output(path) if shown is None else state_output(path, shown)
    out = check_output(out)
    fig = figure(res, scale=scale, shown=shown)
    in_units(fig, res.case.get("units"))
    fig.savefig(out, dpi=dpi)
    log.info("wrote %s", out)
    return out


def figure(res, *, scale: float = 1.0, shown: Shown | None = None):
    """The figure of a result (a ``catenet.output.ResultFile``), a matplotlib Figure.

    Panels: the deformed net, coloured by tension over the range of the data (colour bar
    in N), over the undeformed one (dashed grey, drawn above the grid) in 3D and in a
    side view (x-z, or y-z when the net is longer along y), supports as red dots, the
    probe node marked; displacements drawn ``scale`` times (said in the title when not 1);
    the case's obstacles in light grey (``catenet.plot.bodies``, ``catenet.plot.obstacles``).
    The 3D box keeps true proportions except that no axis is shorter than 40 % of the
    longest (then the z label says it is stretched). With a trajectory of more than one
    frame also the probe's deflection (positive down) against time (dynamic runs) or
    load factor (static runs in steps); for the paper's single-cable cases (``paper_curve``)
    that panel has the paper's axes and closed form, and the side view the closed-form
    shape. A static run's curve starts at zero load; a graph's shows how far its probe
    moves (|x - X|: a mast's top moves sideways). Slack edges (no tension, shorter
    than their rest length) are dotted in their own colour; a graph gets a plan view
    coloured by displacement with the reactions as arrows (``catenet.plot.plan``).
    ``shown``: the state drawn when it is not the final one (``catenet.plot.state``):
    said in the title, its quantity on the colour bar, its frame marked on the time panel.
    """
    if not (math.isfinite(scale) and scale > 0):
        raise ConfigError(f"--scale = {scale!r}: must be a number > 0")
    import matplotlib

    matplotlib.rcParams["svg.hashsalt"] = "catenet"  # reproducible SVG ids
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    from catenet.plot.bodies import Balls
    from catenet.plot.obstacles import Obstacles

    drawn = _Drawn.of(res, scale, Balls(res, scale), Obstacles(res))
    curve = paper_curve(res)
    series = res.series_delta is not None
    plan = wants_plan(res)
    ncols = 2 + int(series) + int(plan)
    fig = Figure(figsize=(4.6 + 5.3 * (ncols - 1), 4.8), layout="constrained")
    FigureCanvasAgg(fig)
    engine = fig.get_layout_engine()
    assert isinstance(engine, ConstrainedLayoutEngine)
    engine.set(wspace=0.12)  # room for the 3D view's z label
    ax3 = fig.add_subplot(1, ncols, 1, projection="3d")
    ax2 = fig.add_subplot(1, ncols, 2)
    _view_3d(ax3, drawn)
    lines2 = _side_view(ax2, drawn, res, curve, scale)
    colours = drawn.colours
    if colours is not None:
        cb = fig.colorbar(lines2, ax=[ax3, ax2], location="right", shrink=0.85, pad=0.02)
        what = "tension" if shown is None else shown.tension
        span = f"{colours.t_min:.6g} to {colours.t_max:.6g}"
        cb.set_label(f"{what} [N], {span}" if len(what) < 12 else f"{what} [N]\n{span}")
    marker = None if shown is None else shown.marker
    if series:
        ax_t = fig.add_subplot(1, ncols, 3)
        _deflection(ax_t, res, curve, drawn.balls, whole=plan, marker=marker)
    if plan:
        moved = None if shown is None else shown.displacement
        draw_plan(fig, fig.add_subplot(1, ncols, ncols), res, scale, displacement=moved)
    status = "" if shown is None else f": {shown.label}"
    if res.converged is False:
        status = " (NOT converged)"
    if res.from_trajectory:
        status += " (last trajectory frame)"
    if scale != 1.0:
        status += f" (displacements × {scale:g})"
    fig.suptitle(f"{res.title}{status}")
    return fig


UNDEFORMED: dict[str, Any] = {"colors": "0.35", "linewidths": 0.7, "linestyles": "--"}


@dataclass
class _Colours:
    """The edges' tensions and how they map to colours (the data's range)."""

    tension: np.ndarray
    norm: Normalize
    cmap: Colormap
    t_min: float
    t_max: float

    @classmethod
    def of(cls, res) -> _Colours | None:
        """None where the file has no finite tensions (nothing to colour by)."""
        from matplotlib import colormaps
        from matplotlib.colors import Normalize, TwoSlopeNorm

        mesh = res.mesh
        tension = res.tension
        # a file that stores no tensions (not written by catenet): computed from the mesh
        if tension is None and mesh.rest_length is not None and mesh.EA is not None:
            material = res.case.get("material", {}) if res.case else {}
            only = bool(material.get("tension_only", True))
            tension = edge_tension(res.x, mesh.edges, mesh.rest_length, mesh.EA, only)
        if tension is None or not len(tension) or not np.all(np.isfinite(tension)):
            return None
        t_min, t_max = float(tension.min()), float(tension.max())
        norm: Normalize
        if t_min < 0.0 < t_max:  # compression (bilateral edges): diverging colours
            norm, cmap = TwoSlopeNorm(0.0, t_min, t_max), colormaps["coolwarm"]
        else:  # the range of the data, not from 0: a prestressed net is not one colour
            uniform = t_max - t_min <= 1e-9 * max(abs(t_max), abs(t_min))  # round-off only
            pad = (0.05 * abs(t_max) or 1.0) if uniform else 0.0
            norm, cmap = Normalize(t_min - pad, t_max + pad), colormaps["viridis"]
        return cls(tension, norm, cmap, t_min, t_max)

    def paint(self, lines) -> None:
        lines.set_array(self.tension)
        lines.set_cmap(self.cmap)
        lines.set_norm(self.norm)


@dataclass
class _Drawn:
    """What the two views of the net draw: the undeformed and deformed edges (M, 2, 3),
    the drawn positions x (displacements scaled), the colours, the balls and obstacles,
    and the box [lo, hi] around all of them."""

    nodes: np.ndarray
    x: np.ndarray
    fixed: np.ndarray | None
    guided: np.ndarray | None  # on rollers, sliders and springs
    seg_ref: np.ndarray
    seg_def: np.ndarray
    colours: _Colours | None
    slack: np.ndarray
    balls: Balls
    obstacles: Obstacles
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def of(cls, res, scale: float, balls: Balls, obstacles: Obstacles) -> _Drawn:
        mesh = res.mesh
        nodes, edges = mesh.nodes, mesh.edges
        x = nodes + scale * (res.x - nodes)
        seg_ref = nodes[edges]  # (M, 2, 3)
        seg_def = x[edges]
        colours = _Colours.of(res)
        lo, hi = _limits(seg_ref, seg_def, *balls.extent())
        lo, hi = _limits(seg_ref, seg_def, *balls.extent(), *obstacles.extent(lo, hi))
        slack = slack_edges(res)
        guided = read_supported(res.path, len(nodes))
        return cls(
            nodes, x, mesh.fixed, guided, seg_ref, seg_def, colours, slack, balls, obstacles, lo, hi
        )

    def deformed(self, lines) -> None:
        """Colours the deformed edges by tension (one colour without tensions)."""
        if self.colours is not None:
            self.colours.paint(lines)
        else:
            lines.set_color("C0")


def _view_3d(ax3, d: _Drawn) -> None:
    """The 3D view: true proportions, but no axis shorter than 40 % of the longest (a
    flat net: its deflection would be squashed into a sliver)."""
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    ax3.add_collection3d(Line3DCollection(d.seg_ref, **UNDEFORMED))
    lines3 = Line3DCollection(d.seg_def, linewidths=1.4)
    d.deformed(lines3)
    ax3.add_collection3d(lines3)
    draw_slack(ax3, d.seg_def, d.slack, three_d=True)
    lo, hi = d.lo, d.hi
    longest = float(np.max(hi - lo))
    mid, half = 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 0.2 * longest)
    stretched = bool(half[2] > 0.5 * (hi - lo)[2] * (1 + 1e-9))
    for setter, a, b in zip(
        (ax3.set_xlim, ax3.set_ylim, ax3.set_zlim), mid - half, mid + half, strict=True
    ):
        setter(a, b)
    ax3.set_box_aspect(tuple(2.0 * half))
    for axis in (ax3.xaxis, ax3.yaxis, ax3.zaxis):
        axis.set_major_locator(MaxNLocator(4))
    if d.fixed is not None and d.fixed.any():
        f = d.x[d.fixed]
        ax3.scatter(f[:, 0], f[:, 1], f[:, 2], color="red", s=8, depthshade=False)
    if d.guided is not None:
        g = d.x[d.guided]
        ax3.scatter(g[:, 0], g[:, 1], g[:, 2], color="darkorange", marker="^", s=14)
    d.balls.draw3d(ax3)
    d.obstacles.draw3d(ax3, mid - half, mid + half)
    ax3.set_xlabel("x [m]")
    ax3.set_ylabel("y [m]")
    ax3.set_zlabel("z [m] (stretched)" if stretched else "z [m]", labelpad=1)
    ax3.set_title("3D view")


def _side_view(ax2, d: _Drawn, res, curve: PaperCurve | None, scale: float):
    """The side view along the horizontal axis in which the net is longer (with the
    closed-form shape of the paper's cable cases); returns the deformed edges' lines."""
    from matplotlib.collections import LineCollection

    nodes, x, lo, hi = d.nodes, d.x, d.lo, d.hi
    h = 0 if np.ptp(nodes[:, 0]) >= np.ptp(nodes[:, 1]) else 1
    ax2.set_axisbelow(True)  # the grid under the nets: z = 0 hides no undeformed line
    ax2.grid(True, lw=0.3, zorder=0)
    ref: Any = d.seg_ref[:, :, [h, 2]]  # (M, 2, 2): LineCollection takes the array
    ax2.add_collection(LineCollection(ref, label="undeformed", zorder=2, **UNDEFORMED))
    deformed: Any = d.seg_def[:, :, [h, 2]]
    lines2 = LineCollection(deformed, linewidths=1.4, label="deformed", zorder=3)
    d.deformed(lines2)
    ax2.add_collection(lines2)
    draw_slack(ax2, d.seg_def[:, :, [h, 2]], d.slack, three_d=False)
    if curve is not None and scale == 1.0:
        centre = 0.5 * (nodes[0] + nodes[-1])
        span = np.linspace(float(np.min(x[:, h])), float(np.max(x[:, h])), 301)
        z = curve.shape(span - centre[h]) + centre[2]
        ax2.plot(span, z, ":", color="k", lw=1.2, label=curve.shape_label, zorder=4)
    if d.fixed is not None and d.fixed.any():
        f = x[d.fixed]
        ax2.plot(f[:, h], f[:, 2], "o", color="red", ms=3, label="supports", zorder=5)
    if d.guided is not None:
        g, what = x[d.guided], "rollers, sliders, springs"
        ax2.plot(g[:, h], g[:, 2], "^", color="darkorange", ms=5, label=what, zorder=5)
    p = res.probe
    ax2.plot(
        [x[p, h]],
        [x[p, 2]],
        "x",
        color="k",
        ms=7,
        zorder=5,
        label=f"probe node {p}: δ = {res.delta:.4g} m",
    )
    d.balls.draw2d(ax2, h)
    d.obstacles.draw2d(ax2, h, lo, hi)
    ax2.update_datalim(np.column_stack([[lo[h], hi[h]], [lo[2], hi[2]]]))
    ax2.autoscale_view()
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.set_xlabel(f"{'xy'[h]} [m]")
    ax2.set_ylabel("z [m]")
    ax2.set_title("side view")
    ax2.legend(loc="best", fontsize="small")
    return lines2


def _deflection(
    ax_t, res, curve: PaperCurve | None, balls: Balls, *, whole: bool, marker: float | None = None
) -> None:
    """The probe's deflection along the trajectory (against time or load factor; a static
    run's from zero load), or the paper's plot with its closed form. ``whole``: a graph,
    whose probe's whole displacement |x - X| is drawn (a mast's top moves sideways).
    ``marker``: the time (or load factor) of the frame drawn, a vertical line."""
    if marker is not None:
        ax_t.axvline(marker, color="C3", lw=1.0, ls="--", label="frame drawn", zorder=1)
    ax_t.grid(True, lw=0.3)
    t, d = res.series_t, res.series_delta
    if curve is not None:
        ax_t.plot(curve.x_closed, curve.y_closed, "-", color="k", lw=1.0, label=curve.closed_label)
        ax_t.plot(curve.x, curve.y, "o", color="C0", ms=4, label="catenet (load steps)")
        ax_t.set_xlabel(curve.xlabel)
        ax_t.set_ylabel(curve.ylabel)
        ax_t.set_title(curve.title)
        ax_t.legend(loc="best", fontsize="small")
        return
    whole = whole and res.series_u is not None
    if whole:
        d = res.series_u
    if res.method == "static" and len(t) and t[0] > 0:  # the curve from zero load
        t, d = np.concatenate([[0.0], t]), np.concatenate([[0.0], d])
    ax_t.plot(t, d, "-", color="C0", lw=1.2, marker="." if len(t) < 60 else None)
    if res.to_rest:  # dynamic relaxation: its path to rest is not a physical motion
        ax_t.set_xlabel("pseudo-time t [s] (relaxation to rest)")
        ax_t.set_title("probe deflection on the way to rest")
    elif res.method == "dynamic":
        ax_t.set_xlabel("time t [s]")
        ax_t.set_title("probe deflection against time")
    elif res.method == "static":
        ax_t.set_xlabel("load factor [-]")
        ax_t.set_title("probe deflection against load")
    else:
        ax_t.set_xlabel("/trajectory/time")
        ax_t.set_title("probe deflection along the trajectory")
    if whole:
        ax_t.set_title(ax_t.get_title().replace("deflection", "displacement"))
        ax_t.set_ylabel(f"displacement |x - X| of node {res.probe} [m]")
    else:
        ax_t.set_ylabel(f"deflection δ of node {res.probe} [m] (down)")
    balls.draw_series(ax_t)
    if marker is not None:
        ax_t.legend(loc="best", fontsize="small")
