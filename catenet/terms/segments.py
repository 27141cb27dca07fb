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
outside a polyhedron (box, mesh) into it first touches it with an end (the node barrier)
or across an edge of the polyhedron (the edge barrier): a segment parallel to a face
touches it along its length, so at its end or at the face's edges. A sphere's or
capsule's distance to a segment is the distance of the centre or the axis to it, minus
R. A cylinder is the union of its core capsule (exact) and its two end bands, each
within a circumscribed prism (``catenet.scene.shapes.cylinder.Cylinder.edge_outline``;
a drum no longer than its diameter: one prism), each feature with its own radius.
Each barrier is infinite at contact; the step cap (``max_step``) is the node barrier's
exact first contact and, for the edges, the strands' additive continuous collision
detection of every pair within reach of the step's motion (a body's outline points move
linearly with its four nodes), so no step carries a segment through a thin shape or over
a corner.

Where the closest points of two edges are not unique (an edge parallel to a box's
edge), the edge-edge barrier fades out below about 1.8 degrees and the end point-edge
barriers of the same pair take over (``catenet.kernels.strands``): the energy is C1
with a Hessian exact inside each regime. A segment parallel to a face is held by its
end nodes' barrier and by the face's edges, which is the exact distance (no mollifier
needed). The barriers sum: an edge that rests across a box's edge near a node feels
both the node's and the edge's barrier (as in incremental potential contact), so it
rests a little farther out than one barrier alone would hold it, still within dhat.

Friction (``EdgeFriction``, a fixed obstacle's ``friction``): the nodes' lagged Coulomb
friction (``catenet.terms.friction``) at the point of the edge where each outline
feature pushes it, that material point y = (1 - s) x_i + s x_j held with s, the normal
force and the normal lagged from the step's start: convex within the step, its force
never above mu times the edge's normal force, opposing the slip of the edge's material
over the solid (a rope sliding lengthwise over a box's edge, or sideways). On a free
body: ``catenet.terms.body_segments.BodyEdgeFriction``; a ball is frictionless.
"""

from __future__ import annotations

import copy
import math
from typing import TYPE_CHECKING

import numpy as np

from catenet.kernels.friction import friction_gradient, friction_hessian
from catenet.kernels.segments import (
    near_pairs,
    pair_forces,
    segment_ccd,
    segment_gaps,
    segment_gradient,
    segment_hessian,
)
from catenet.terms.base import Term, register

if TYPE_CHECKING:
    from catenet.terms.moving import Moving

T_FAR = 4.0**13  # beyond the longest step a line search tries (MAX_EXPANSIONS = 12)


@register("edge_contact")
class EdgeContact(Term):
    """The barrier between the net's ``edges`` (K, 2) of ``rest`` lengths (K,) (the
    scale of the parallel edges' mollifier), capsules of radius ``r`` [m],
    and a solid's outline: ``points`` (V, 3) at t = 0 with ``weights`` (V, nb) on its
    nodes ``bnodes`` (nb: 0 for a fixed obstacle, 1 for a ball, 4 for a free body;
    points = weights @ x[bnodes]), outline ``lines`` (E, 2) and radius ``R`` (module
    docstring): one for every feature, or one per feature (the lines, then the points on
    no line in their order: a cylinder's core capsule beside its prisms' edges);
    stiffness ``kappa`` [N/m], activation distance ``dhat`` [m]."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    horizon = True
    convex = False
    role = "internal"

    def __init__(self, edges, rest, points, lines, R, *, r: float, kappa: float,
                 dhat: float, n_nodes: int, weights=None, bnodes=None):  # fmt: skip
        if not (math.isfinite(kappa) and kappa > 0 and math.isfinite(dhat) and dhat > 0):
            raise ValueError(f"edge_contact: kappa = {kappa!r}, dhat = {dhat!r}: must be > 0")
        if not (math.isfinite(r) and r >= 0):
            raise ValueError(f"edge_contact: contact radius {r!r}: must be >= 0")
        self.edges = np.ascontiguousarray(edges, dtype=np.int64).reshape(-1, 2)
        self.nodes = np.unique(self.edges)  # the nodes it reads (an obstacle's motion)
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
        n_features = len(self.lines) + len(self.lone)
        self.R = np.broadcast_to(np.asarray(R, dtype=np.float64), (n_features,)).copy()
        self.radius = float(r)
        self.rf = np.ascontiguousarray(self.R + self.radius)  # the gap is d - R - r
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
        reach = self.rf + self.dhat
        return near_pairs(x, self._zero, self.edges, Y, self._dY, self.lines, self.lone, reach, 0.0)

    def gap(self, x) -> np.ndarray:
        """Per edge (K,): its least gap to the outline's edges and lone points, minus the
        radii (the node barrier holds its ends against the faces)."""
        out = np.empty(len(self.edges))
        x = np.ascontiguousarray(x, dtype=np.float64)
        segment_gaps(x, self.edges, self.place(x), self.lines, self.lone, self.rf, out)
        return out

    # ---- energy -----------------------------------------------------------------------
    def _args(self, x):
        Y = self.place(x)
        return Y, self._pairs(x, Y), self.rest

    def gradient(self, x, grad) -> float:
        Y, pairs, rest = self._args(x)
        args = (self.lines, self.flen, self.lone, pairs, self.rf, self.dhat, self.kappa, grad)
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
        args = (self.lines, self.flen, self.lone, pairs, self.rf, self.dhat, self.kappa, values)
        return segment_hessian(x, self.edges, rest, Y, self.weights, nb, *args) > 0

    # ---- the step cap -----------------------------------------------------------------
    def max_step(self, x, dx) -> float:
        return self.max_step_within(x, dx, T_FAR)

    def max_step_within(self, x, dx, upto: float) -> float:
        upto = min(float(upto), T_FAR)
        Y, dY = self.place(x), self._motion(dx)
        args = (self.edges, Y, dY, self.lines, self.lone, self.rf, upto)
        pairs = near_pairs(x, dx, *args)
        if not len(pairs):
            return math.inf
        return segment_ccd(x, dx, self.edges, Y, dY, self.lines, self.lone, pairs, self.rf, upto)


def pushes(contact: EdgeContact, x) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(pairs, normal forces, unit normals, shares) of the pairs of ``contact`` that push
    the net's edges at x: the pair (edge, feature), the size and direction of the force
    on the edge and where along it it acts (the share on its second node)."""
    c = contact
    Y = c.place(x)
    pairs = c._pairs(x, Y)
    force = np.zeros((len(pairs), 3))
    share = np.zeros(len(pairs))
    args = (c.lines, c.flen, c.lone, pairs, c.rf, c.dhat, c.kappa, force, share)
    pair_forces(x, c.edges, c.rest, Y, *args)
    size = np.linalg.norm(force, axis=1)
    on = size > 0.0
    return pairs[on], size[on], force[on] / size[on, None], share[on]


@register("edge_friction")
class EdgeFriction(Term):
    """Coulomb friction ``mu`` with slip distance ``slip`` [m] where the outline of
    ``contact`` (a fixed obstacle's ``EdgeContact``, or one on a prescribed motion: a
    ``catenet.terms.moving_edges.MovingEdges``) pushes the net's edges (module
    docstring): per pushing pair, lagged at the step's start, its normal force, normal
    and the edge's material point s; anchors kept per pair from step to step (a pair
    that sticks stays within ``slip`` of where it stuck). On a moving obstacle they are
    taken with the obstacle at its pose at the step's start and ride with it to its pose
    at the step's end (as ``catenet.terms.friction.Friction``'s): friction acts against
    the edge's slip over the obstacle's surface, and a pair that sticks is carried."""

    lagged = True
    role = "internal"
    convex = True

    def __init__(self, contact: EdgeContact | Moving, *, mu: float, slip: float):
        if not (math.isfinite(mu) and mu >= 0 and math.isfinite(slip) and slip > 0):
            raise ValueError(f"edge_friction: mu = {mu!r}, slip = {slip!r}: must be >= 0, > 0")
        self.obstacle: Moving | None = None
        edge = contact
        if not isinstance(edge, EdgeContact):  # the outline in its body frame
            self.obstacle, edge = edge, edge.shape
        if len(edge.bnodes):
            raise ValueError("edge_friction: on a fixed or moving obstacle only, not a body")
        self.contact: EdgeContact = edge
        self.rides_on = contact
        self.mu, self.slip = float(mu), float(slip)
        self.pairs = np.zeros((0, 2), dtype=np.int64)
        self.share = np.zeros(0)
        self.normal = np.zeros((0, 3))
        self.weight = np.zeros(0)
        self.anchor = np.zeros((0, 3))
        self._anchors: dict[tuple[int, int], np.ndarray] = {}
        self._start: np.ndarray | None = None  # the accepted state of the step (begin_step)
        self._carry: tuple | None = None  # a moving obstacle's (c0, c1, turn) over the step

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        de = (3 * self.contact.edges[:, :, None] + np.arange(3)).reshape(-1, 6)
        return np.repeat(de, 6, axis=1).ravel(), np.tile(de, (1, 6)).ravel()

    def _pushes(self, x) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        obs = self.obstacle
        if obs is None:
            return pushes(self.contact, x)
        pairs, lam, normal, share = pushes(self.contact, obs._body(x))
        return pairs, lam, np.asarray(normal @ obs.R.T), share  # the normals in the world

    def _points(self, x) -> np.ndarray:
        e = self.contact.edges[self.pairs[:, 0]]
        s = self.share[:, None]
        return np.ascontiguousarray((1.0 - s) * x[e[:, 0]] + s * x[e[:, 1]])

    def begin_step(self, x, time, start=None) -> None:
        """The pushing pairs, their lagged normal forces and normals at the accepted
        state x, and where each holds the edge: a pair that sticks keeps its material
        point s and anchor (a rope sliding lengthwise moves its material over the
        contact, which stays where it is in space); one whose material point slid
        farther than ``slip`` takes the contact's point now and drags its anchor to
        ``slip`` behind it; a new pair anchors where it touches. On a moving obstacle,
        at its pose at ``start``, then carried with it to its pose at ``time``."""
        obs = self.obstacle if time is not None and start is not None else None
        if obs is not None:
            obs.set_pose(start)  # the pose of the accepted state
        pairs, lam, normal, share = self._pushes(x)
        keys = [(int(e), int(f)) for e, f in pairs.tolist()]
        held = [self._anchors.get(k) for k in keys]
        was = np.array([h is not None for h in held], dtype=bool)
        s = share.copy()
        anchor = np.zeros((len(keys), 3))
        for i, h in enumerate(held):
            if h is not None:
                anchor[i], s[i] = h[:3], h[3]
        self.pairs, self.normal = pairs, np.ascontiguousarray(normal)
        self.weight = self.mu * lam
        self.share = s
        u = self._points(x) - anchor
        u -= np.sum(u * normal, axis=1)[:, None] * normal
        slid = np.linalg.norm(u, axis=1)
        moved = was & (slid > self.slip)
        self.share = np.where(moved | ~was, share, s)
        y = self._points(x)
        anchor[~was] = y[~was]
        behind = self.slip / np.where(moved, slid, 1.0)
        anchor[moved] = y[moved] - behind[moved, None] * u[moved]
        self.anchor = np.ascontiguousarray(anchor)
        self._start, self._carry = np.array(x, dtype=np.float64), None
        if obs is not None:  # the obstacle's rigid motion over the step
            c0, R0 = obs.pose(start)
            c1, R1 = obs.pose(time)
            turn = R1 @ R0.T
            self._carry = (c0, c1, turn)
            self.anchor = np.ascontiguousarray(c1 + (self.anchor - c0) @ turn.T)
            self.normal = np.ascontiguousarray(self.normal @ turn.T)
            obs.set_pose(time)  # where the step is solved
        self._remember(keys)

    def _started(self, pairs: np.ndarray, share: np.ndarray) -> np.ndarray:
        """Where the material points (edge, s) of ``pairs`` were at the step's start (on a
        moving obstacle, carried with it over the step, as the anchors are): a pair first
        pushing at a static step's equilibrium slid there from that point."""
        e = self.contact.edges[pairs[:, 0]]
        x0 = self._start
        assert x0 is not None  # begin_step came first
        y0 = (1.0 - share[:, None]) * x0[e[:, 0]] + share[:, None] * x0[e[:, 1]]
        if self._carry is not None:
            c0, c1, turn = self._carry
            y0 = c1 + (y0 - c0) @ turn.T
        return np.ascontiguousarray(y0)

    def _remember(self, keys: list) -> None:
        rows = np.concatenate([self.anchor, self.share[:, None]], axis=1)
        self._anchors = dict(zip(keys, rows, strict=True))

    def relag(self, x) -> float:
        """Normal forces and normals taken at x (the pairs that push there; the anchors
        and material points of the known pairs kept, a new pair's anchor where its
        material point was at the step's start, as a node's is: it slid from there, and
        friction acts against that slip; anchored where it is, a rope first pressed on a
        solid in a static step kept its frictionless equilibrium, friction or not): the
        largest change of a pair's normal force, relative to the largest one."""
        before = {(int(e), int(f)): w for (e, f), w in zip(self.pairs, self.weight, strict=True)}
        top = float(self.weight.max(initial=0.0))
        pairs, lam, normal, share = self._pushes(x)
        keys = [(int(e), int(f)) for e, f in pairs.tolist()]
        self.pairs, self.normal = pairs, np.ascontiguousarray(normal)
        self.weight = self.mu * lam
        self.share = share.copy()
        anchor = self._started(pairs, self.share) if self._start is not None else self._points(x)
        for i, k in enumerate(keys):
            h = self._anchors.get(k)
            if h is not None:
                anchor[i], self.share[i] = h[:3], h[3]
        self.anchor = np.ascontiguousarray(anchor)
        self._remember(keys)
        now = dict(zip(keys, self.weight, strict=True))
        change = max(
            (abs(now.get(k, 0.0) - before.get(k, 0.0)) for k in {*now, *before}), default=0.0
        )
        top = max(top, float(self.weight.max(initial=0.0)))
        return change / top if top > 0.0 else 0.0

    def gradient(self, x, grad) -> float:
        if not len(self.pairs):
            return 0.0
        y = self._points(x)
        g = np.zeros_like(y)
        idx = np.arange(len(y), dtype=np.int64)
        energy = friction_gradient(y, idx, self.anchor, self.normal, self.weight, self.slip, g)
        e = self.contact.edges[self.pairs[:, 0]]
        s = self.share[:, None]
        np.add.at(grad, e[:, 0], (1.0 - s) * g)
        np.add.at(grad, e[:, 1], s * g)
        return float(energy)

    def hessian(self, x, values) -> bool:
        values[:] = 0.0
        if not len(self.pairs):
            return False
        y = self._points(x)
        blocks = np.zeros(9 * len(y))
        idx = np.arange(len(y), dtype=np.int64)
        args = (self.anchor, self.normal, self.weight, self.slip, blocks)
        if friction_hessian(y, idx, *args) == 0:
            return False
        s = self.share
        w = np.stack([1.0 - s, s], axis=1)  # (K, 2): the two nodes' weights
        H = blocks.reshape(-1, 3, 3)
        per = np.einsum("ka,kb,kij->kaibj", w, w, H).reshape(-1, 36)
        np.add.at(values.reshape(-1, 36), self.pairs[:, 0], per)
        return True
