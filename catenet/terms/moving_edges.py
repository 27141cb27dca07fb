"""The edges' barrier (``solver.edge_contact``, ``catenet.terms.segments.EdgeContact``)
against an obstacle on a prescribed rigid motion, as ``catenet.terms.moving.Moving``
moves the nodes' barrier: the obstacle's outline stays where it was built (its pose at
t = 0) and the net's edges are seen in that body frame, x_b = c0 + R^T (x - c), with
the pose at the step's end set by ``begin_step``. Within a step the obstacle is fixed,
so the capsules' barrier and the continuous collision detection of every edge against
the outline (``max_step``, the step cap) keep their guarantee: no point of an edge comes
within the contact radius of the obstacle. Gradients turn back as R g_b and each edge's
6 x 6 Hessian block as diag(R, R) H_b diag(R, R)^T.

Between steps the obstacle jumps from pose(t_n) to pose(t_n+1), which could swallow the
middle of an edge whose nodes are far from it. ``carry`` moves both nodes of every edge
the obstacle may reach in the step (its gap at pose(t_n) below SWEEP_SAFETY times the
obstacle's sweep plus the activation distance) rigidly with it from the point the
step's cut-back starts from (Newton's start as ``Moving._predicted`` chooses it, by the
nodes' barrier of the same obstacle): a rigid motion keeps the edge's distance to the
obstacle, so every step starts with every edge outside. An edge held at a support
that the obstacle reaches stops the run (ConvergenceError naming the edge): an edge
with both nodes fixed (no barrier moves it: ``guard``), and one with a node fixed and
the other riding with the obstacle, is swept over the step by conservative advancement
(``Moving.first_touch``, as the supports are), so an obstacle thinner than its travel
in one step does not pass it unseen. The energy
balance books the obstacle's work on the edges as on the nodes (``Moving.driven_work``).
"""

from __future__ import annotations

import math

import numpy as np

from catenet.errors import ConvergenceError
from catenet.terms.collide import SWEEP_SAFETY
from catenet.terms.moving import Moving
from catenet.terms.probe import Only


class MovingEdges(Moving):
    """An ``EdgeContact`` (built at the obstacle's pose at t = 0) on the obstacle's
    prescribed motion (``Moving``'s arguments)."""

    horizon = True
    guards_supports = False  # the nodes' barrier of the same obstacle guards them
    guard = None  # the edges with both nodes fixed (an EdgeContact), only watched
    twin: Moving | None = None  # the nodes' barrier of the same obstacle

    def hessian(self, x, values):
        active = self.shape.hessian(self._local(x), values)
        if np.any(self.omega):  # diag(R, R) H_b diag(R, R)^T (R = 1 where it only translates)
            H = values.reshape(-1, 2, 3, 2, 3)  # each edge's row-major 6 x 6 block
            blocks = H.transpose(0, 1, 3, 2, 4)  # (K, 2, 2, 3, 3): its 3 x 3 blocks
            H[:] = (self.R @ blocks @ self.R.T).transpose(0, 1, 3, 2, 4)
        return active

    def node_shape(self):
        """The nodes' barrier of the same obstacle (None: none)."""
        return None if self.twin is None else self.twin.shape

    def max_step(self, x, dx):
        return self.max_step_within(x, dx, math.inf)

    def max_step_within(self, x, dx, upto: float) -> float:
        return float(
            self.shape.max_step_within(self._local(x), self._local(dx, turn_only=True), upto)
        )

    def carry(self, base, trial, t0: float, t1: float, fixed, moved=None, index=0) -> int:
        """Moves both free nodes of every edge the obstacle may reach from t0 to t1
        rigidly with it, in ``base`` and ``trial`` in place (module docstring); returns
        how many nodes. ``moved`` as ``Moving.carry``'s (a node carried by another
        obstacle stays). ConvergenceError where an edge held at a support would be
        inside the obstacle at t1."""
        c1, R1 = self.pose(t1)
        self.center, self.R = c1, R1
        move = self.sweep(t0, t1)
        if move == 0.0:
            return 0
        edges = self.shape.edges
        if self.guard is not None and len(self.guard.edges):  # cannot give way: swept
            hit = self.first_touch(self.guard, trial, t0, t1)
            if hit is not None:
                self._stop_at(self.guard.edges, np.array([hit[0]]), hit[1])
        c0, R0 = self.pose(t0)
        near = self.shape.gap(self._body(base, c0, R0)) < SWEEP_SAFETY * move + self.dhat
        reach = np.flatnonzero(near)
        near[reach[self.stays(edges[reach], base, t0, t1)]] = False
        if not near.any():
            return 0
        start = base.copy()
        nodes = np.unique(edges[near])
        nodes = self._carry_nodes(nodes[~fixed[nodes]], base, trial, t0, t1, moved, index)
        held = np.flatnonzero(near & (fixed[edges[:, 0]] | fixed[edges[:, 1]]))
        if held.size:  # its free node rides with the obstacle, its fixed one stays: swept

            def riding(c, R):
                out = start.copy()
                out[nodes] = c + (start[nodes] - c0) @ (R @ R0.T).T
                return out

            hit = self.first_touch(Only(self.shape, edges[held]), riding, t0, t1)
            if hit is not None:
                self._stop_at(edges, held[hit[0] : hit[0] + 1], hit[1])
        return int(nodes.size)

    def _stop_at(self, edges, hit: np.ndarray, t1: float) -> None:
        """ConvergenceError naming the first of the edges ``hit``, held at a support."""
        if hit.size:
            i, j = edges[hit[0]]
            raise ConvergenceError(
                f"{self.label} reaches the edge {i}-{j}, held at a support, at "
                f"t = {t1:.6g} s: a moving obstacle must not run over an edge at a "
                "support; change its motion or the supports"
            )


def moving_edges(edge, term: Moving, guard=None) -> MovingEdges:
    """The edges' barrier ``edge`` on the motion of the obstacle whose nodes' barrier
    is ``term`` (a ``Moving``); ``guard``: the barrier of the edges with both nodes
    fixed (not in ``edge``), only to stop the run where the obstacle reaches one."""
    out = MovingEdges(
        edge,
        term.origin,
        term.velocity,
        term.omega,
        term.path.history,
        reach=term.reach,
        label=term.label,
    )
    out.guard = guard
    out.twin = term  # the same obstacle's motion (catenet/terms/pinch.py)
    return out
