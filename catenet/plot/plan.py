"""The parts of ``catenet plot`` that read a net as an engineer does: slack edges in
their own colour, and for graphs (masts, roofs, nets) a plan view coloured by how far
each node moved, with the supports' reactions as arrows.

Matplotlib is imported by the caller (``catenet.plot.figure``); nothing here imports it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from catenet.output.reader import ResultFile

SLACK_COLOUR = "darkorange"


def slack_edges(res: ResultFile) -> np.ndarray:
    """Edges that are slack in the result (bool (M,)): no tension and shorter than their
    rest length (a strut in compression carries a negative tension: not slack)."""
    mesh = res.mesh
    if res.tension is None or mesh.rest_length is None or len(mesh.edges) == 0:
        return np.zeros(len(mesh.edges), bool)
    e = res.x[mesh.edges[:, 1]] - res.x[mesh.edges[:, 0]]
    shorter = np.linalg.norm(e, axis=1) < mesh.rest_length
    return shorter & (res.tension == 0.0)


def wants_plan(res: ResultFile) -> bool:
    """A plan view for graphs (any net not the paper's square net or single cable)."""
    kind = res.case.get("geometry", {}).get("kind") if res.case else None
    return kind == "graph"


def draw_plan(fig, ax, res: ResultFile, scale: float, displacement=None) -> None:
    """Plan view (x-y): the deformed net coloured by each edge's mean displacement |x - X|
    [m] (``displacement`` (N,): those values instead, the envelope's largest over the
    cases), the undeformed net dashed, supports as red dots, each support's reaction as an
    arrow of its horizontal part (the largest drawn at 15 % of the net's span), the node
    that moves most marked."""
    from matplotlib import colormaps
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    mesh = res.mesh
    nodes, edges, fixed = mesh.nodes, mesh.edges, mesh.fixed
    envelope = displacement is not None
    u = np.linalg.norm(res.x - nodes, axis=1) if not envelope else np.asarray(displacement)
    x = nodes + scale * (res.x - nodes)
    ax.set_axisbelow(True)
    ax.grid(True, lw=0.3, zorder=0)
    ref = LineCollection(nodes[edges][:, :, :2], colors="0.6", linewidths=0.6, linestyles="--")
    ax.add_collection(ref)
    colour = 0.5 * (u[edges[:, 0]] + u[edges[:, 1]])
    top = float(u.max()) or 1.0
    lines = LineCollection(x[edges][:, :, :2], linewidths=1.5, cmap=colormaps["plasma"])
    lines.set_array(colour)
    lines.set_norm(Normalize(0.0, top))
    ax.add_collection(lines)
    cb = fig.colorbar(lines, ax=ax, location="bottom", shrink=0.8, pad=0.02)
    if envelope:
        cb.set_label(f"largest displacement of the cases [m], up to {top:.4g}")
    else:
        cb.set_label(f"displacement |x - X| [m], largest {top:.4g} m")
    span = float(np.max(np.ptp(nodes[:, :2], axis=0))) or 1.0
    if fixed is not None and fixed.any():
        f = x[fixed]
        ax.plot(f[:, 0], f[:, 1], "o", color="red", ms=3, zorder=5, label="supports")
        r = res.reaction
        if r is not None:
            r = r[fixed]
            size = np.linalg.norm(r, axis=1)
            biggest = float(size.max()) if len(size) else 0.0
            horizontal = r[:, :2]
            if biggest > 0 and np.any(np.linalg.norm(horizontal, axis=1) > 1e-9 * biggest):
                k = 0.15 * span / biggest
                ax.quiver(
                    f[:, 0],
                    f[:, 1],
                    k * horizontal[:, 0],
                    k * horizontal[:, 1],
                    angles="xy",
                    scale_units="xy",
                    scale=1.0,
                    color="C3",
                    width=0.004,
                    zorder=6,
                    label=f"reactions (horizontal part; largest |R| {biggest:.4g} N)",
                )
    free = np.flatnonzero(~fixed) if fixed is not None else np.arange(len(nodes))
    if free.size:
        k = int(free[np.argmax(u[free])])
        ax.plot(
            [x[k, 0]],
            [x[k, 1]],
            "x",
            color="k",
            ms=7,
            zorder=7,
            label=f"node {k} moves most: {u[k]:.4g} m",
        )
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("plan view")
    ax.legend(loc="best", fontsize="small")


def draw_slack(ax, segments: np.ndarray, slack: np.ndarray, three_d: bool) -> None:
    """The slack edges over the deformed net, dotted in their own colour."""
    if not slack.any():
        return
    label = f"slack edges ({int(slack.sum())})"
    if three_d:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection

        ax.add_collection3d(
            Line3DCollection(segments[slack], colors=SLACK_COLOUR, linewidths=1.6, linestyles=":")
        )
        return
    from matplotlib.collections import LineCollection

    ax.add_collection(
        LineCollection(
            segments[slack],
            colors=SLACK_COLOUR,
            linewidths=1.8,
            linestyles=":",
            zorder=4,
            label=label,
        )
    )
