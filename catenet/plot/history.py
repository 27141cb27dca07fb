"""``catenet plot RESULT.h5 --history``: a dynamic run's histories (``/history``,
``catenet.output.history``) against time, one panel each where the run has them:

- "reactions": the resultant of the reactions of all supports (x, y, z) and the
  magnitude of the resultant of each support set (a node set of the case, ``/mesh/sets``,
  all of whose nodes are supports), else |R| at the support nodes of the largest peak
  reaction (up to ``LARGEST``);
- "contact": the magnitude of the total force of each obstacle, ball or free body on
  the net (``obstacle[k]``, its kind);
- "cable end tensions": each named cable's tension at its first and at its last edge.

Matplotlib's Agg canvas as ``catenet.plot.figure``: no pyplot, no window.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.output import read_result
from catenet.output.history import History, read_history
from catenet.plot.figure import check_output, in_units

log = logging.getLogger(__name__)

__all__ = ["history_figure", "history_output", "plot_history"]

LARGEST = 4  # support nodes drawn one by one
TIME = "t [s]"


def history_output(path: str | Path) -> Path:
    """OUT-history.png next to OUT.h5."""
    path = Path(path)
    return path.with_name(f"{path.stem}-history.png")


def plot_history(path: str | Path, out: str | Path | None = None, *, dpi: int = 150) -> Path:
    """Draws the histories of the result file ``path`` into ``out`` (.png, .svg or .pdf;
    default: ``history_output``) and returns ``out``. ConfigError for a file that is not
    a result file or has no history (a static run's)."""
    res = read_result(path)  # ConfigError for anything but a result file
    hist = read_history(path)
    if hist is None or len(hist.time) == 0:
        why = (
            "a dynamic run's written before catenet kept histories"
            if res.method == "dynamic"
            else f"a {res.method or 'static'} run's"
        )
        raise ConfigError(
            f"{path}: --history: the file has no /history ({why}): histories are kept by "
            'dynamic runs (solver.method = "dynamic"); plot it without --history'
        )
    out = check_output(history_output(path) if out is None else out)
    fig = history_figure(hist, support_sets(path, hist.reaction_nodes))
    in_units(fig, res.case.get("units"))
    fig.savefig(out, dpi=dpi)
    log.info("wrote %s", out)
    return out


def support_sets(path: str | Path, supports: np.ndarray) -> dict[str, np.ndarray]:
    """The case's node sets in the file ``path`` all of whose nodes are among
    ``supports``: each as the positions of its nodes in ``supports``."""
    import h5py

    from catenet.output.netsets import read_sets

    with h5py.File(path, "r") as h5:
        sets = read_sets(h5["mesh"])
    where = {int(n): j for j, n in enumerate(supports)}
    return {
        name: np.array([where[int(n)] for n in nodes], dtype=np.int64)
        for name, nodes in sets.items()
        if len(nodes) and all(int(n) in where for n in nodes)
    }


def history_figure(hist: History, sets: dict[str, np.ndarray] | None = None):
    """The figure of a history (see the module docstring; ``sets``: the support sets,
    ``support_sets``), a matplotlib Figure."""
    import matplotlib

    matplotlib.rcParams["svg.hashsalt"] = "catenet"
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = [
        draw
        for draw, there in (
            (_reactions, hist.reaction.shape[1] > 0),
            (_contact, hist.contact.shape[1] > 0),
            (_cables, hist.cable_end_tension.shape[1] > 0),
        )
        if there
    ]
    if not panels:
        panels = [_reactions]  # a run with nothing held: its (empty) reactions' axes
    fig = Figure(figsize=(6.4, 2.9 * len(panels)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for ax, draw in zip(axes, panels, strict=True):
        draw(ax, hist, sets or {})
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", loc="best")
    axes[-1].set_xlabel(TIME)
    return fig


def _reactions(ax, hist: History, sets: dict[str, np.ndarray]) -> None:
    ax.set_label("reactions")
    ax.set_title("support reactions", fontsize="medium")
    t, r = hist.time, hist.reaction
    total = r.sum(axis=1) if r.shape[1] else np.zeros((len(t), 3))
    for j, axis in enumerate("xyz"):
        ax.plot(t, total[:, j], label=f"resultant R{axis}", lw=1.4)
    size = np.linalg.norm(r, axis=2)
    for name, at in sets.items():
        ax.plot(t, np.linalg.norm(r[:, at].sum(axis=1), axis=1), "--", lw=1.1, label=f"|R| {name}")
    if r.shape[1] > 1 and not sets:
        top = np.argsort(-size.max(axis=0, initial=0.0), kind="stable")[:LARGEST]
        for j in top:
            ax.plot(t, size[:, j], "--", lw=0.9, label=f"|R| node {hist.reaction_nodes[j]}")
    ax.set_ylabel("reaction [N]")


def _contact(ax, hist: History, sets=None) -> None:
    ax.set_label("contact")
    ax.set_title("contact force on the net", fontsize="medium")
    size = np.linalg.norm(hist.contact, axis=2)
    for j, name in enumerate(hist.names):
        ax.plot(hist.time, size[:, j], label=f"|F| {name}", lw=1.2)
    ax.set_ylabel("contact force [N]")


def _cables(ax, hist: History, sets=None) -> None:
    ax.set_label("cable end tensions")
    ax.set_title("cable end tensions", fontsize="medium")
    for j, name in enumerate(hist.cable_names):
        line = ax.plot(hist.time, hist.cable_end_tension[:, j, 0], label=f"{name}: first edge")
        ax.plot(
            hist.time,
            hist.cable_end_tension[:, j, 1],
            "--",
            color=line[0].get_color(),
            label=f"{name}: last edge",
        )
    ax.set_ylabel("tension [N]")
