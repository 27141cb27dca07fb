"""Contact along the whole edge (``solver.edge_contact``): every edge of the net is a
capsule of the contact radius r (``material.contact_radius``, default the cable's
radius) against an obstacle, a ball or a free body.

A solid is held off the capsules by two kinds of barrier, as in incremental potential
contact (Li et al. 2020):

- the nodes against the shape grown by r: the shape's own node barrier with ``offset``
  r (``catenet.terms.contact``, ``catenet.terms.shapes``; a free body's
  ``BodyContact``), exact first contact along a step;
- the edges against the shape's outline (``EdgeContact``, kernels in
  ``catenet.kernels.segments``): every outline edge against every net edge (the strands'
  mollified edge-edge barrier on the gap d - R - r) and a sphere's centre against every
  net edge (the point-segment distance minus R + r).

Guarantee: no point of any edge comes within r of the solid. A segment that moves from
outside a polyhedron (box, mesh; a cylinder's circumscribed prisms) into it first
touches it with an end (the node barrier) or across an edge of the polyhedron (the
edge barrier): a segment parallel to a face touches it along its length, so at its end
or at the face's edges. A sphere's or capsule's distance to a segment is the distance of
the centre or the axis to it, minus R. Each barrier is infinite at contact; the step
cap (``max_step``) is the node barrier's exact first contact and, for the edges, the
strands' additive continuous collision detection of every pair within reach of the
step's motion (a body's outline points move linearly with its four nodes), so no step
carries a segment through a thin shape or over a corner.

Where the closest points of two edges are not unique (an edge parallel to a box's
edge), the edge-edge barrier fades out below about 1.8 degrees and the end point-edge
barriers of the same pair take over (``catenet.kernels.strands``): the energy is C1
with a Hessian exact inside each regime. A segment parallel to a face is held by its
end nodes' barrier and by the face's edges, which is the exact distance (no mollifier
needed). The barriers sum: an edge that rests across a box's edge near a node feels
both the node's and the edge's barrier (as in incremental potential contact), so it
rests a little farther out than one barrier alone would hold it, still within dhat.

Frictionless: the friction of an obstacle (``friction``) acts at the nodes only.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from catenet.kernels.segments import (
    near_pairs,
    segment_ccd,
    segment_gaps,
    segment_gradient,
    segment_hessian,
)
from catenet.terms.base import Term, register

T_FAR = 4.0**13  # beyond the longest step a line search tries (MAX_EXPANSIONS = 12)


@register("edge_contact")
class EdgeContact(Term):
    """The barrier between the net's ``edges`` (K, 2) of ``rest`` lengths (K,) (the
    scale of the parallel edges' mollifier), capsules of radius ``r`` [m],
    and a solid's outline: ``points`` (V, 3) at t = 0 with ``weights`` (V, nb) on its
    nodes ``bnodes`` (nb: 0 for a fixed obstacle, 1 for a ball, 4 for a free body;
    points = weights @ x[bnodes]), outline ``lines`` (E, 2) and radius ``R`` (module
    docstring); stiffness ``kappa`` [N/m], activation distance ``dhat`` [m]."""

    bounds_step = True
    horizon = True
    convex = False
    role = "internal"

    def __init__(self, edges, rest, points, lines, R: float, *, r: float, kappa: float,
                 dhat: float, n_nodes: int, weights=None, bnodes=None):  # fmt: skip
        if not (math.isfinite(kappa) and kappa > 0 and math.isfinite(dhat) and dhat > 0):
            raise ValueError(f"edge_contact: kappa = {kappa!r}, dhat = {dhat!r}: must be > 0")
        if not (math.isfinite(r) and r >= 0):
            raise ValueError(f"edge_contact: contact radius {r!r}: must be >= 0")
        self.edges = np.ascontiguousarray(edges, dtype=np.int64).reshape(-1, 2)
        self.rest = np.ascontiguousarray(rest, dtype=np.float64).reshape(len(self.edges))
        self.points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        self.lines = np.ascontiguousarray(lines, dtype=np.int64).reshape(-1, 2)
        on_line = np.zeros(len(self.points), dtype=bool)
        on_line[self.lines.ravel()] = True
        self.lone = np.flatnonzero(~on_line).astype(np.int64)
        self.bnodes = np.zeros(0, np.int64) if bnodes is None else np.asarray(bnodes, np.int64)
        nb = len(self.bnodes)
        self.weights = np.ascontiguousarray(
            np.zeros((len(self.points), 0)) if weights is None else weights, dtype=np.float64
        ).reshape(len(self.points), nb)
        self.kappa, self.dhat = float(kappa), float(dhat)
        self.r = float(r) + float(R)  # the gap is d - R - r
        self.radius, self.R = float(r), float(R)
        self.n_nodes = int(n_nodes)
        self.flen = np.linalg.norm(
            self.points[self.lines[:, 1]] - self.points[self.lines[:, 0]], axis=1
        )
        self._zero = np.zeros((self.n_nodes, 3))
        self._dY = np.zeros_like(self.points)

    def narrowed(self, kappa: float, dhat: float) -> EdgeContact:
        """The same barrier with another stiffness and activation distance (a static
        solve's continuation stage, ``catenet.terms.contact.Obstacle.narrowed``)."""
        out = copy.copy(self)
        out.kappa, out.dhat, out.stages = float(kappa), float(dhat), ()
        return out

    # ---- geometry ---------------------------------------------------------------------
    def place(self, x) -> np.ndarray:
        """(V, 3) the outline's points at the positions x."""
        if not len(self.bnodes):
            return self.points
        return np.ascontiguousarray(self.weights @ np.asarray(x)[self.bnodes])

    def _motion(self, dx) -> np.ndarray:
        if not len(self.bnodes):
            return self._dY
        return np.ascontiguousarray(self.weights @ np.asarray(dx)[self.bnodes])

    def _pairs(self, x, Y) -> np.ndarray:
        reach = self.r + self.dhat
        return near_pairs(x, self._zero, self.edges, Y, self._dY, self.lines, self.lone, reach, 0.0)

    def gap(self, x) -> np.ndarray:
        """Per edge (K,): its least gap to the outline's edges and lone points, minus the
        radii (the node barrier holds its ends against the faces)."""
        out = np.empty(len(self.edges))
        x = np.ascontiguousarray(x, dtype=np.float64)
        segment_gaps(x, self.edges, self.place(x), self.lines, self.lone, self.r, out)
        return out

    # ---- energy -----------------------------------------------------------------------
    def _args(self, x):
        Y = self.place(x)
        return Y, self._pairs(x, Y), self.rest

    def gradient(self, x, grad) -> float:
        Y, pairs, rest = self._args(x)
        args = (self.lines, self.flen, self.lone, pairs, self.r, self.dhat, self.kappa, grad)
        return segment_gradient(x, self.edges, rest, Y, self.weights, self.bnodes, *args)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        nb = len(self.bnodes)
        de = (3 * self.edges[:, :, None] + np.arange(3)).reshape(-1, 6)  # (K, 6)
        db = (3 * self.bnodes[:, None] + np.arange(3)).ravel()  # (3 nb,)
        K = len(self.edges)
        ee_r, ee_c = np.repeat(de, 6, axis=1), np.tile(de, (1, 6))
        eb_r, eb_c = np.repeat(de, 3 * nb, axis=1), np.tile(db, (K, 6))
        be_r, be_c = np.tile(np.repeat(db, 6), (K, 1)), np.tile(de, (1, 3 * nb))
        rows = np.concatenate([ee_r, eb_r, be_r], axis=1).ravel()
        cols = np.concatenate([ee_c, eb_c, be_c], axis=1).ravel()
        return (
            np.concatenate([rows, np.repeat(db, 3 * nb)]),
            np.concatenate([cols, np.tile(db, 3 * nb)]),
        )

    def hessian(self, x, values) -> bool:
        Y, pairs, rest = self._args(x)
        nb = len(self.bnodes)
        args = (self.lines, self.flen, self.lone, pairs, self.r, self.dhat, self.kappa, values)
        return segment_hessian(x, self.edges, rest, Y, self.weights, nb, *args) > 0

    # ---- the step cap -----------------------------------------------------------------
    def max_step(self, x, dx) -> float:
        return self.max_step_within(x, dx, T_FAR)

    def max_step_within(self, x, dx, upto: float) -> float:
        upto = min(float(upto), T_FAR)
        Y, dY = self.place(x), self._motion(dx)
        args = (self.edges, Y, dY, self.lines, self.lone, self.r, upto)
        pairs = near_pairs(x, dx, *args)
        if not len(pairs):
            return math.inf
        return segment_ccd(x, dx, self.edges, Y, dY, self.lines, self.lone, pairs, self.r, upto)
