"""A dynamic run's history (``catenet.output.history``): at its start and at every accepted
time step, the reaction at each support node, the total force of each obstacle, ball and
free body on the net, and the tension of each named cable's end edges, computed by
``catenet.model.measures`` as /result's reaction and contact force are.

The reaction of a support node (fixed, on a roller or a slider, or on a spring) is what
/result/reaction is at that state; the force of obstacle k on the net is minus the
gradient, at the net's own nodes, of the terms that are its part (``Term.owner``): its
barrier and friction, a ball's or a free body's barrier with the net and its friction (a
body's pairs with other solids act on the solids only). So, at every step of an implicit
Euler run, the change of the momentum of the net and its bodies over the step is the
step times the applied loads, the reactions and the fixed obstacles' contact forces at
its end (``tests/run/test_history.py``).

A restarted run (``--restart OLD.h5``) begins with OLD.h5's rows up to its restart time
where the two histories have the same columns; its own rows follow.
"""

from __future__ import annotations

import logging

import numpy as np

from catenet.model import measures
from catenet.model.lines import Lines, line_paths
from catenet.output.history import HistoryLayout, read_history

log = logging.getLogger(__name__)

__all__ = ["Recorder", "layout"]


def layout(scene) -> HistoryLayout:
    """The columns of ``scene``'s history: its fixed nodes, its obstacles, balls and free
    bodies by index (``obstacle[k]``), its named cables with their first and last edge."""
    net = scene.net
    kinds = {k: shape.kind for k, shape, _ in scene.obstacles}
    kinds.update({m.index: m.shape.kind for m in scene.movers})
    owned = sorted(kinds)
    names: tuple[str, ...] = ()
    ends = np.zeros((0, 2), dtype=np.int64)
    line = lines_of(scene)
    if line is not None:
        names, edge = line
        rows = []
        for c in range(len(names)):
            mine = np.flatnonzero(edge == c)
            rows.append((mine[0], mine[-1]) if mine.size else (0, 0))
        ends = np.asarray(rows, dtype=np.int64).reshape(-1, 2)
    return HistoryLayout(
        reaction_nodes=np.flatnonzero(net.supported).astype(np.int64),
        obstacles=tuple(owned),
        names=tuple(f"obstacle[{k}]" for k in owned),
        kinds=tuple(kinds[k] for k in owned),
        cable_names=names,
        cable_edges=ends,
        grounds=bool(owned),
    )


def lines_of(scene) -> tuple[tuple[str, ...], np.ndarray] | None:
    """(names, each edge's line (-1: none)): the named cables, or a net that is one
    open path of edges (a single cable) as the line "cable"; None: no line."""
    cables = scene.cables
    if cables is not None and len(cables.names):
        return tuple(cables.names), np.asarray(cables.edge)
    net = scene.net
    edges = np.asarray(net.edges)
    if not len(edges):
        return None
    degree = np.bincount(edges.ravel(), minlength=net.n_nodes)
    path = len(edges) == np.count_nonzero(degree) - 1 and degree.max() <= 2
    chained = path and all(set(edges[k]) & set(edges[k + 1]) for k in range(len(edges) - 1))
    return (("cable",), np.zeros(len(edges), dtype=np.int64)) if chained else None


class Recorder:
    """Computes a state's history row and gives it to the writer (``ResultWriter.record``)."""

    def __init__(self, scene, ws, writer, shape: HistoryLayout):
        self.scene, self.ws, self.writer, self.layout = scene, ws, writer, shape
        self.last: float | None = None  # the time of the last row (a restart's seed)
        slot = {k: j for j, k in enumerate(shape.obstacles)}
        # each term once a row: an obstacle's into its own array, the supports' springs
        # into theirs (-2), the others' together (-1)
        self.terms = [
            (term, -2 if term.holds else slot.get(term.owner, -1)) for term in ws.system.terms
        ]
        self.held = any(term.holds for term in ws.system.terms)
        n = scene.net.n_nodes
        self.grad = np.zeros((n, 3))
        self.springs = np.zeros((n, 3))
        self.owned = np.zeros((len(slot), n, 3))
        self.n_net = scene.net.n_net
        self.cables = bool(shape.cable_names)
        self.lines = Lines([])
        line = lines_of(scene)
        if self.cables and line is not None:
            net = scene.net
            paths = line_paths(net.nodes, net.edges, net.rest_length, line[1])
            self.lines = Lines(paths + [None] * (len(line[0]) - len(paths)))

    def row(self, t: float, x: np.ndarray) -> dict[str, np.ndarray]:
        """The history's row of state x at time t."""
        net, grad, owned, springs = self.scene.net, self.grad, self.owned, self.springs
        grad.fill(0.0)
        owned.fill(0.0)
        springs.fill(0.0)
        for term, j in self.terms:  # the system's gradient, by owner
            term.gradient(x, grad if j == -1 else springs if j == -2 else owned[j])
        grad += owned.sum(axis=0)
        grad += springs
        force = self.scene.loads.external_force(net, time=t)
        support = self.layout.reaction_nodes
        held = None
        if self.held:  # the springs' force on the net, as the reactions count it
            held = np.zeros_like(springs)
            for term, j in self.terms:
                if j == -2:
                    term.held_force(x, held)
        out = {"reaction": measures.reaction(net, grad, force, held)[support]}
        out["contact"] = -owned[:, : self.n_net].sum(axis=1)  # on the net's own nodes
        if self.cables:
            tension = self.ws.system.tension(x)
            out["cable_end_tension"] = tension[self.layout.cable_edges]
            out.update(self._lines(x, tension, owned))
        return out

    def _lines(self, x: np.ndarray, tension: np.ndarray, owned: np.ndarray) -> dict:
        """Each line's least and largest tension, uplift angle at its anchor and
        touchdown point (``catenet.model.lines.Lines``)."""
        lines = self.lines
        out = {
            "cable_tension_range": lines.tension_range(tension),
            "anchor_uplift": lines.uplift(x),
        }
        if self.layout.grounds:
            out["touchdown"] = lines.touchdown(np.any(owned != 0.0, axis=(0, 2)))
        return out

    def record(self, t: float, x: np.ndarray) -> None:
        """Writes the row of state x at time t (once per time)."""
        if self.last is not None and t <= self.last:
            return
        self.writer.record(t, self.row(t, x))
        self.last = t

    def seed(self, path, t: float) -> None:
        """Begins with the rows of the earlier run in ``path`` up to time t (a restart),
        where its history has the same columns; else says why it begins anew."""
        try:
            old = read_history(path)
        except Exception as exc:  # an unreadable history: this run's own rows only
            log.info("--restart: %s; the history begins at t = %.6g", exc, t)
            return
        lay = self.layout
        same = old is not None and (
            np.array_equal(old.reaction_nodes, lay.reaction_nodes)
            and list(old.obstacles) == list(lay.obstacles)
            and old.cable_names == list(lay.cable_names)
        )
        if not same or old is None:
            log.info("--restart: %s has no history of the same columns: it begins anew", path)
            return
        keep = np.flatnonzero(old.time <= t * (1.0 + 1e-12) + 1e-300)
        columns = {
            "reaction": old.reaction,
            "contact": old.contact,
            "cable_end_tension": old.cable_end_tension,
            "cable_tension_range": old.cable_tension_range,
            "anchor_uplift": old.anchor_uplift,
        }
        if old.touchdown is not None:
            columns["touchdown"] = old.touchdown
        for name, shape in lay.shapes().items():  # a column missing, cut or not finite
            column = columns.get(name)
            if column is None or column.shape[1:] != shape or column.shape[0] < keep.size:
                log.info("--restart: %s: its history's %s is not this run's", path, name)
                return
            if not np.all(np.isfinite(column[keep])):
                log.info("--restart: %s: its history's %s is not finite", path, name)
                return
        for i in keep:
            self.writer.record(float(old.time[i]), {name: c[i] for name, c in columns.items()})
        if keep.size:
            self.last = float(old.time[keep[-1]])
            log.info("--restart: the history goes on from the %d rows of %s", keep.size, path)
