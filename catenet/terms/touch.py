"""Contact between two rigid solids: a free body (``catenet.terms.rigid``) and another
free body, a ball (``catenet.terms.body``) or a fixed sphere, box, capsule or mesh.

A solid is its surface: points (a box's 8 corners, a mesh's vertices, a sphere's centre,
a capsule's axis ends), edges between them (a box's 12, a mesh's, a capsule's axis) and a
radius r the surface is grown by (a sphere's, a capsule's; 0 otherwise). Each point is
linear in the solid's nodes, y = W x (a body's point at X at t = 0: w_k = 1/4 + B_k .
(X - c0), the affine map of ``BodyFrame``; a ball's centre is its node; a fixed obstacle's
points have no weights), so every chain rule below is a constant Jacobian.

The barrier kappa b(gap) (``catenet.kernels.contact.barrier``) acts on every feature
pair of the two surfaces that decides their distance, as in incremental potential
contact (Li et al. 2020) with affine bodies (Lan et al. 2022):

- points of one solid against the other's shape grown by the points' radius: the shape's
  own barrier and exact distance (``catenet.terms.shapes``: nearest face, edge or
  vertex), seen in the other's body frame when it is a free body (``BodyContact`` on the
  points, chained through W); this holds a corner on a face, and a sphere or a
  capsule's end against anything exactly;
- edges of one against edges of the other: the strands' mollified edge-edge barrier on
  the gap d - r_a - r_b (``catenet.kernels.touch``), which holds crossing edges (two
  boxes edge on edge, a capsule across a box's edge).

Which pairs (``sides``): a sphere (body, ball or fixed) is its centre grown by its
radius, so its centre against the other's shape is the whole contact; otherwise the
points of each solid meet the other's shape unless the other is a capsule (then its
axis' edge meets the points' edges: the closest points of a segment and a polytope are
an end of the segment or on an edge), and the edges meet the edges. Two convex
polyhedra first touch vertex on face or edge on edge, so no two solids can pass through
each other (a mesh: the same for its closed surface, faces, edges, vertices).

``max_step``: the bounding spheres of the two (about each centre of points, radii
growing with the points' motion) first meet at t_b (exact, a quadratic): steps shorter
than that are free. Otherwise the points' sides cap the step (exactly by the fixed
shape's ray test; in a body's frame by BodyContact's chords of the points' quadratic
paths, exact where it does not turn, conservative otherwise), and the edge pairs within
reach of the step's motion by additive CCD up to STEP_CHECKED steps (longer ones are
refused, as in self-contact). No iterate has two solids overlapping.

Friction (``BodyTouchFriction``): the lagged Coulomb friction of the shapes
(``catenet.terms.friction``) on the points' sides, seen in a body's frame as with the
net (``BodyFriction``), chained to the pair's nodes like the barrier; the edges'
contacts (edge on edge) are frictionless.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from catenet.kernels.strands import candidates, sqdist
from catenet.kernels.touch import touch_ccd, touch_edges
from catenet.terms.base import Term, register
from catenet.terms.rigid_contact import BodyContact

#: The largest multiple of a Newton step the edges' CCD checks (longer ones are refused).
STEP_CHECKED = 4.0


class Solid:
    """One side of a contact: ``label``; the global ``nodes`` its points hang on (a
    body's four, a ball's one, none for a fixed obstacle); ``points`` (V, 3) at t = 0
    with their ``weights`` (V, len(nodes)) (y = weights @ x[nodes]; fixed points stay
    where they are); ``edges`` (E, 2) between the points; the ``radius`` the surface is
    grown by; ``kind`` ("box", "capsule", "sphere", "mesh"); ``frame``: a free body's
    BodyFrame (its shape is then seen in its body frame), else None; ``shape(nodes, kappa,
    dhat, grow)``: its shape's barrier term at t = 0 grown by ``grow`` (None: a ball,
    whose shape is its centre)."""

    def __init__(self, label, nodes, points, weights, edges, radius, kind, frame=None, shape=None):
        self.label, self.kind, self.frame, self.shape = label, kind, frame, shape
        self.nodes = np.asarray(nodes, dtype=np.int64).reshape(-1)
        self.points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        self.weights = np.asarray(weights, dtype=np.float64).reshape(len(self.points), -1)
        self.edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        self.radius = float(radius)

    def place(self, x) -> np.ndarray:
        """(V, 3) the points at the positions x (N, 3)."""
        if not len(self.nodes):
            return self.points
        return self.weights @ np.asarray(x)[self.nodes]

    def motion(self, dx) -> np.ndarray:
        if not len(self.nodes):
            return np.zeros_like(self.points)
        return self.weights @ np.asarray(dx)[self.nodes]


def sides(a: Solid, b: Solid) -> tuple[list, bool]:
    """([(points solid, shape solid), ...], whether the edges meet) for the pair (module
    docstring)."""
    if b.kind == "sphere" and (b.shape is None or a.kind != "sphere"):
        return [(b, a)], False
    if a.kind == "sphere":
        return [(a, b)], False
    out = [(p, s) for p, s in ((a, b), (b, a)) if s.kind != "capsule"]
    return out, bool(len(a.edges) and len(b.edges))


class _Side:
    """The points of ``p`` against the shape of ``s``: the shape's term on local nodes
    0..V-1 (the points), with s's frame at V..V+3 when s is a free body (``BodyContact``);
    ``M`` (V [+ 4], n) maps the local nodes to the pair's nodes."""

    def __init__(self, p: Solid, s: Solid, at: dict, kappa: float, dhat: float):
        self.p, self.s = p, s
        V = len(p.points)
        n = len(at)
        M = np.zeros((V + (4 if s.frame is not None else 0), n))
        for j, node in enumerate(p.nodes):
            M[:V, at[int(node)]] = p.weights[:, j]
        shape = s.shape(np.arange(V, dtype=np.int64), kappa, dhat, p.radius)
        if s.frame is not None:
            frame = copy.copy(s.frame)
            frame.nodes = V + np.arange(4, dtype=np.int64)
            self.term = BodyContact(shape, frame, n_nodes=V + 4, label=s.label)
            for j, node in enumerate(s.nodes):
                M[V + j, at[int(node)]] = 1.0
        else:
            self.term = shape
        self.M = M
        self.J = np.einsum("va,ij->viaj", M, np.eye(3)).reshape(len(M), 3, 3 * n)

    def riding(self, term) -> _Side:
        """This side with ``term`` in place of its barrier (its friction)."""
        out = copy.copy(self)
        out.term = term
        return out

    def local(self, x, dx=None) -> np.ndarray:
        y = self.p.place(x) if dx is None else self.p.motion(dx)
        if self.s.frame is None:
            return np.ascontiguousarray(y)
        return np.vstack([y, np.asarray(x if dx is None else dx)[self.s.nodes]])

    def gradient(self, x, gn) -> float:
        xl = self.local(x)
        gl = np.zeros_like(xl)
        energy = self.term.gradient(xl, gl)
        gn += self.M.T @ gl
        return energy

    def hessian(self, x, Hn) -> bool:
        xl = self.local(x)
        V = len(self.p.points)
        rows, cols = self.term.pattern()
        values = np.zeros(len(rows))
        if not self.term.hessian(xl, values):
            return False
        if self.s.frame is None:  # 3x3 blocks per point
            H = values.reshape(V, 3, 3)
            act = np.flatnonzero(np.any(H.reshape(V, 9) != 0.0, axis=1))
            J = self.J[act]
            Hn += np.einsum("kia,kij,kjb->ab", J, H[act], J)
            return True
        blocks = values[: 81 * V].reshape(V, 81)
        act = np.flatnonzero(np.any(blocks != 0.0, axis=1))
        Jx, Jf = self.J[act], self.J[V:].reshape(12, -1)
        xx = blocks[act, :9].reshape(-1, 3, 3)
        xp = blocks[act, 9:45].reshape(-1, 3, 12)
        Hn += np.einsum("kia,kij,kjb->ab", Jx, xx, Jx)
        cross = np.einsum("kia,kij,jb->ab", Jx, xp, Jf)
        Hn += cross + cross.T
        Hn += Jf.T @ values[81 * V :].reshape(12, 12) @ Jf
        return True

    def max_step(self, x, dx) -> float:
        return self.term.max_step(self.local(x), self.local(x, dx))


@register("body_touch")
class BodyTouch(Term):
    """The barrier between the solids ``a`` (a free body) and ``b`` (module docstring):
    stiffness ``kappa`` [N/m], activation distance ``dhat`` [m]."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    role = "internal"
    convex = False

    def __init__(self, a: Solid, b: Solid, *, kappa: float, dhat: float, n_nodes: int):
        if not (math.isfinite(kappa) and kappa > 0 and math.isfinite(dhat) and dhat > 0):
            raise ValueError(f"body_touch: kappa = {kappa!r}, dhat = {dhat!r}: must be > 0")
        self.a, self.b = a, b
        self.kappa, self.dhat, self.n_nodes = float(kappa), float(dhat), int(n_nodes)
        self.label = f"{a.label} and {b.label}"
        self.nodes = np.concatenate([a.nodes, b.nodes])
        at = {int(node): j for j, node in enumerate(self.nodes)}
        pairs, meet = sides(a, b)
        self.sides = [_Side(p, s, at, self.kappa, self.dhat) for p, s in pairs]
        self.meet = meet
        if meet:  # the edges of both, their points stacked (a's first)
            n = len(self.nodes)
            W = np.zeros((len(a.points) + len(b.points), n))
            for solid, first in ((a, 0), (b, len(a.points))):
                for j, node in enumerate(solid.nodes):
                    W[first : first + len(solid.points), at[int(node)]] = solid.weights[:, j]
            self.W = W
            self.edges = np.concatenate([a.edges, b.edges + len(a.points)])
            ends = np.concatenate([a.points, b.points])
            self.rest = np.linalg.norm(ends[self.edges[:, 1]] - ends[self.edges[:, 0]], axis=1)
            self.n_a = len(a.edges)
            self.r = a.radius + b.radius

    # ---- evaluation -------------------------------------------------------------------
    def _stack(self, x, dx=None):
        if dx is None:
            return np.ascontiguousarray(np.vstack([self.a.place(x), self.b.place(x)]))
        return np.ascontiguousarray(np.vstack([self.a.motion(dx), self.b.motion(dx)]))

    def _pairs(self, Y, grow) -> np.ndarray:
        """The edge pairs (one of each solid) within reach: dhat + r + grow of the two."""
        pairs = candidates(Y, self.edges, grow, self.dhat + self.r)
        keep = (pairs[:, 0] < self.n_a) != (pairs[:, 1] < self.n_a)
        return np.ascontiguousarray(pairs[keep])

    def _bounds(self, Y):
        """(centre, radius) of each solid's points at Y, the radius grown by its own."""
        split = len(self.a.points)
        out = []
        for part, solid in ((Y[:split], self.a), (Y[split:], self.b)):
            c = part.mean(axis=0)
            out.append((c, float(np.linalg.norm(part - c, axis=1).max()) + solid.radius))
        return out

    def _near(self, x) -> bool:
        """Whether the two may be within dhat at x (their bounding spheres)."""
        (ca, ra), (cb, rb) = self._bounds(self._stack(x))
        return float(np.linalg.norm(ca - cb)) < ra + rb + self.dhat

    def _evaluate(self, x, want: bool):
        n = len(self.nodes)
        gn, Hn = np.zeros((n, 3)), np.zeros((3 * n, 3 * n))
        if not self._near(x):
            return 0.0, gn, Hn, False
        energy = 0.0
        acted = False
        for side in self.sides:
            energy += side.gradient(x, gn)
            if want:
                acted = side.hessian(x, Hn) or acted
        if self.meet:
            Y = self._stack(x)
            pairs = self._pairs(Y, np.zeros(len(self.edges)))
            args = (self.r, self.dhat, self.kappa, gn, Hn, want)
            energy += touch_edges(Y, self.W, self.edges, self.rest, pairs, *args)
            acted = acted or bool(np.any(Hn))
        return energy, gn, Hn, acted

    def energy(self, x):
        return self._evaluate(x, False)[0]

    def gradient(self, x, grad):
        energy, gn, _, _ = self._evaluate(x, False)
        grad[self.nodes] += gn
        return energy

    def pattern(self):
        d = (3 * self.nodes[:, None] + np.arange(3)).ravel()
        return np.repeat(d, len(d)), np.tile(d, len(d))

    def hessian(self, x, values):
        _, _, Hn, acted = self._evaluate(x, True)
        values[:] = Hn.ravel()
        return acted

    def stiffness(self):
        s = np.zeros(self.n_nodes)
        s[self.nodes] = self.kappa
        return s

    def gap(self, x) -> float:
        """The smallest gap [m] of the pair's features at x (inf: beyond reach)."""
        if not self._near(x):
            return math.inf
        gaps = [
            float(np.min(side.term.gap(side.local(x)), initial=math.inf)) for side in self.sides
        ]
        if self.meet:
            Y = self._stack(x)
            pairs = self._pairs(Y, np.zeros(len(self.edges)))
            for a, b in pairs:
                P = Y[[*self.edges[a], *self.edges[b]]]
                gaps.append(_segments(P) - self.r)
        return min(gaps, default=math.inf)

    # ---- the step cap -----------------------------------------------------------------
    def max_step(self, x, dx):
        Y, dY = self._stack(x), self._stack(x, dx)
        t_b = self._first_reach(Y, dY)
        if t_b > STEP_CHECKED:
            return t_b
        t = min((side.max_step(x, dx) for side in self.sides), default=math.inf)
        if self.meet:
            speed = np.linalg.norm(dY, axis=1)
            grow = STEP_CHECKED * np.maximum(speed[self.edges[:, 0]], speed[self.edges[:, 1]])
            pairs = self._pairs(Y, grow)
            t = min(t, touch_ccd(Y, dY, self.edges, pairs, self.r, STEP_CHECKED), STEP_CHECKED)
        return t

    def _first_reach(self, Y, dY) -> float:
        """The first t >= 0 at which the bounding spheres, each growing by its points'
        largest speed about its centre, touch along Y + t dY (inf: never)."""
        (ca, ra), (cb, rb) = self._bounds(Y)
        split = len(self.a.points)
        spread = []
        for part in (dY[:split], dY[split:]):
            spread.append(float(np.linalg.norm(part - part.mean(axis=0), axis=1).max()))
        d0 = ca - cb
        e = dY[:split].mean(axis=0) - dY[split:].mean(axis=0)
        R0, s = ra + rb, spread[0] + spread[1]
        f0 = float(d0 @ d0) - R0 * R0
        if f0 <= 0.0:
            return 0.0
        qa, qb = float(e @ e) - s * s, float(d0 @ e) - R0 * s
        disc = qb * qb - qa * f0
        if qa > 0.0:  # the distance outgrows the radii: a root only when closing
            return (-qb - math.sqrt(disc)) / qa if qb < 0.0 and disc >= 0.0 else math.inf
        if qa == 0.0:
            return -0.5 * f0 / qb if qb < 0.0 else math.inf
        return (-qb - math.sqrt(max(disc, 0.0))) / qa  # the radii outgrow: one root ahead


def _segments(P) -> float:
    """The distance of the segments P[0]-P[1] and P[2]-P[3] (4, 3)."""
    g, H = np.empty(12), np.empty((12, 12))
    return math.sqrt(sqdist(np.ascontiguousarray(P).ravel(), 0, g, H, False))


@register("body_touch_friction")
class BodyTouchFriction(Term):
    """Coulomb friction (coefficient ``mu``, slip distance ``slip`` [m]) riding on the
    barrier ``touch`` between two solids: on each of its points' sides the shape's
    lagged friction (module docstring); frictionless edge on edge."""

    lagged = True
    role = "internal"
    convex = False

    def __init__(self, touch: BodyTouch, *, mu: float, slip: float):
        from catenet.terms.friction import Friction
        from catenet.terms.rigid_contact import BodyFriction

        self.rides_on = touch
        self.nodes, self.n_nodes = touch.nodes, touch.n_nodes
        self.sides = []
        for side in touch.sides:
            if isinstance(side.term, BodyContact):
                term = BodyFriction(Friction(side.term.shape, mu=mu, slip=slip), side.term)
            else:
                term = Friction(side.term, mu=mu, slip=slip)
            self.sides.append(side.riding(term))

    def begin_step(self, x, time, start=None) -> None:
        for side in self.sides:
            side.term.begin_step(side.local(x), time, start)

    def relag(self, x) -> float:
        return max((side.term.relag(side.local(x)) for side in self.sides), default=0.0)

    def pattern(self):
        return self.rides_on.pattern()

    def gradient(self, x, grad):
        gn = np.zeros((len(self.nodes), 3))
        energy = sum(side.gradient(x, gn) for side in self.sides)
        grad[self.nodes] += gn
        return float(energy)

    def energy(self, x):
        return self.gradient(x, np.zeros_like(np.asarray(x)))

    def hessian(self, x, values):
        n = len(self.nodes)
        Hn = np.zeros((3 * n, 3 * n))
        acted = False
        for side in self.sides:
            acted = side.hessian(x, Hn) or acted
        values[:] = Hn.ravel()
        return acted
