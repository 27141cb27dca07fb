"""Barrier contact between the net's nodes and a free rigid body (``catenet.terms.rigid``).

The body's shape is a fixed obstacle term (box, capsule, sphere, mesh) built at the
body's pose at t = 0; a node x is seen there at X = c0 + A^T (x - c), with (c, A) the
body's pose, linear in its four nodes p (``BodyFrame.state``). With g, H the shape's
gradient and Hessian at X and u = x - c:

    dE/dx = A g,   dE/dc = -A g,   dE/dA = u g^T,

and the Hessian in q = (x, c, a1, a2, a3) (a_m the columns of A) is L^T H L + S, with
L = [A^T, -A^T, e_1 u^T, e_2 u^T, e_3 u^T] the Jacobian of X and S the second
derivative of X weighted by g: g_m 1 between a_m and x, -g_m 1 between a_m and c. The
chain to the body's nodes is the constant kron(T, 1) of ``BodyFrame.chain``. Per contact
node the values are its (x, x) block (9), (x, p) (36) and (p, x) (36), then the
body's (p, p) block (144) summed over the nodes.

``max_step``: along the step, a node's body-frame point follows the quadratic path
X(t) = X0 + t V + t^2 W (V = A^T du + dA^T u, W = dA^T du, du = dx - dc). On a piece
[t, t + h] the path stays within |W| h^2 / 4 of its chord, so when that is at most
delta, a path that enters the shape has its chord enter the shape grown by delta no
later: the chords' exact first contact with the grown shape (the kernels' own ray tests,
the offset grown) is a safe cap, exact for W = 0 (a body that does not turn in the
step). delta is CA_SHARE of the smallest gap (at most dhat / 2, within a mesh's grid),
so no iterate reaches the shape; the pieces go on to beyond every step a line search
tries (inf).

The cap keeps every node at least ``floor`` off the shape (the shape is grown by it as
well): FLOOR_SHARE of dhat, and no less than ROUNDOFF round-offs of the body-frame
coordinates (a node's X carries an error of eps |X|). A line search may go as near the
cap as it likes, and where the barrier cannot hold a node off (a body spun so fast that
its inertia dwarfs every contact force) Newton's iterates would otherwise close in on
the surface until a node sat on it within round-off, its barrier infinite: a state, and
a failed run's kept state, with a node on the body. A node at the floor (or nearer, a
start placed so) keeps room to move: the floor stays SLACK of its gap below it, so each
iteration that ends at the cap brings it at most that share nearer (10^4 such iterations
per e-fold; a run fails long before, and a run the barrier holds never gets there).

Candidates (``candidates=True``: a box or capsule on a net, in time steps): only the nodes
that may come within dhat in a step enter the gradient, the Hessian and the pattern, so
the work and the factorisation's border of the body's 12 unknowns follow the nodes near
the body, not the whole net. At each step's start x, a node's radius is REACH_SHARE of
the net's shortest edge (at least dhat) plus twice its body-frame motion in the last step
(doubled, until a node joins, when the same step is tried again after a radius held its
last Newton step back: ``TimeStepper.widened`` retries such a step at its length), and it is a
candidate where its gap is below dhat plus its radius. The others keep their body-frame
point within gap - dhat of where it was (their step cap: |X0 - Xb| + t |V| + t^2 |W|
<= gap - dhat): the gap is 1-Lipschitz in X, so they stay beyond dhat, where the barrier
is exactly zero, and leaving them out changes no energy, force or stiffness. The pattern
keeps every candidate it has had (no rebuild when one comes back) until they outnumber
PATTERN_SLACK times the present ones (at least FEWEST): a net of no more than
PATTERN_SLACK x FEWEST contact nodes keeps them all, without candidates. Every node is a
candidate until the first time step, and again in a static solve (``begin_step`` without
a time: a load path's dynamic relaxation rung narrows the set, the static solves after it
take every node, ``static.solve_static`` rebuilding the pattern). The body's friction
(``BodyFriction``) follows the same set: a node pressed on the body at the lagged state
is within the barrier, so a candidate.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.bodycap import body_paths, body_room, body_step_cap
from catenet.kernels.rigid import (
    frame_contact_gradient,
    frame_contact_hessian,
    frame_contact_hessian_shape,
    frame_friction_gradient,
    frame_friction_hessian,
    frame_local,
)
from catenet.kernels.shapes import shape_gap
from catenet.terms.base import Term, register
from catenet.terms.rigid import CA_ITER, CA_SHARE, BodyFrame
from catenet.terms.shapes import BoxBarrier, CapsuleBarrier

T_FAR = 4.0**13  # beyond the longest step a line search tries (MAX_EXPANSIONS = 12)
FLOOR_SHARE = 1e-6  # no node comes nearer the body than this share of dhat ...
ROUNDOFF = 1e4  # ... nor than this many round-offs of its body-frame coordinates
SLACK = 1e-4  # a node at the floor may come this share of its gap nearer (docstring)
EPS = np.finfo(np.float64).eps
REACH_SHARE = 0.1  # a candidate's radius: this share of the shortest edge (>= dhat) ...
PATTERN_SLACK = 4  # ... the pattern's nodes, at most this many times the candidates
FEWEST = 32  # ... or than this many: a net of at most PATTERN_SLACK x FEWEST contact
#              nodes keeps them all (no candidates: the set could never shrink)


@register("body_contact")
class BodyContact(Term):
    """The barrier of ``shape`` (a fixed obstacle term on the net's contact nodes, built
    at the body's pose at t = 0) riding on the body ``frame``."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    role = "internal"
    convex = False
    widens = True  # a step its radii held back is tried again, wider (``begin_step``)
    width = math.inf  # the body's smallest extent [m], where the scene gives it

    def __init__(
        self,
        shape,
        frame: BodyFrame,
        *,
        n_nodes: int,
        label: str = "a free body",
        candidates: bool = False,
        edge: float = 0.0,
    ):
        self.shape, self.frame = shape, frame
        self.nodes = shape.nodes  # every contact node (``gap`` is in their order)
        self.kappa, self.dhat = getattr(shape, "kappa", 0.0), getattr(shape, "dhat", 0.0)
        self.n_nodes = int(n_nodes)
        self.label = label
        self.c0 = frame.center.copy()
        self._buf = np.zeros((n_nodes, 3))
        self._g = np.zeros((n_nodes, 3))
        self._chain = np.ascontiguousarray(frame.chain())
        self.project = False  # safeguarded: each contact's block projected (``safeguard``)
        # Candidates (module docstring): a box's or capsule's kernels on the nodes near it.
        many = len(self.nodes) > PATTERN_SLACK * FEWEST
        self.grows = bool(candidates) and _kernel(shape) and self.dhat > 0.0 and many
        self.reach = max(REACH_SHARE * float(edge), self.dhat)
        self.known = self.nodes  # the pattern's nodes: every one until the first time step
        self._inside = np.ones(len(self.nodes), dtype=bool)  # which contact nodes they are
        self._pattern: tuple[np.ndarray, np.ndarray] | None = None
        self._far = np.zeros(0, dtype=np.int64)  # the others, and the room each has
        self._far_X = np.zeros((0, 3))
        self._room = np.zeros(0)
        self._radius: np.ndarray | None = None  # per contact node, from the last step
        self._base: np.ndarray | None = None  # x at the last step's start
        self._base_X = np.zeros((0, 3))  # every contact node's body-frame point there
        self.held = False  # a radius cut the last step asked about short (``_roomy``)

    def safeguard(self, on: bool) -> None:
        """While on, each contact node's 15 x 15 block (the node, the body's centre and
        frame) enters the Hessian with its negative eigenvalues set to 0: the barrier's
        curvature round a box's edges and the frame's second derivative S make the exact
        block indefinite, and Newton's step along such a direction may throw a node
        metres (a light net's node pressed on the box, its cords slack: 28 m in one
        step of a 21 x 21 net at 10 ms). Gradient and energy are unchanged."""
        self.project = bool(on)

    # ---- evaluation -------------------------------------------------------------------
    def _local(self, x):
        frame = self.frame
        c, A, U, X = frame_local(x, self.nodes, frame.nodes, frame.B, self.c0)
        self._buf[self.nodes] = X
        return c, A, U

    def gap(self, x):
        self._local(x)
        return self.shape.gap(self._buf)

    def _shape_gradient(self):
        g = self._g
        energy = self.shape.gradient(self._buf, g)
        out = g[self.nodes].copy()
        g[self.nodes] = 0.0
        return energy, out

    def energy(self, x):
        self._local(x)
        return self.shape.energy(self._buf)

    def gradient(self, x, grad):
        shape, frame = self.shape, self.frame
        if _kernel(shape):  # a box or capsule: one kernel, on the candidates
            return float(
                frame_contact_gradient(shape.kind, shape.geom, self.kappa, self.dhat, x,
                                       self.known, frame.nodes, frame.B, self.c0, grad)
            )  # fmt: skip
        _, A, U = self._local(x)
        energy, g = self._shape_gradient()
        if not math.isfinite(energy):  # a node in the shape: no step, no gradient to add
            return energy
        fx = g @ A.T
        grad[self.nodes] += fx
        gA = U.T @ g
        grad[self.frame.nodes] += -0.25 * fx.sum(axis=0) + self.frame.B @ gA.T
        return energy

    def pattern(self):
        if self._pattern is None:  # kept until the candidates change
            self._pattern = self._entries()
        return self._pattern

    def _entries(self):
        dn = 3 * self.known[:, None] + np.arange(3)  # (K, 3)
        db = self.frame.dofs()  # (12,)
        K = len(self.known)
        ii_r = np.repeat(dn, 3, axis=1)
        ii_c = np.tile(dn, (1, 3))
        ip_r = np.repeat(dn, 12, axis=1)
        ip_c = np.tile(db, (K, 3))
        pi_r = np.tile(np.repeat(db, 3), (K, 1))
        pi_c = np.tile(dn, (1, 12))
        rows = np.concatenate([ii_r, ip_r, pi_r], axis=1).ravel()
        cols = np.concatenate([ii_c, ip_c, pi_c], axis=1).ravel()
        return np.concatenate([rows, np.repeat(db, 12)]), np.concatenate([cols, np.tile(db, 12)])

    def hessian(self, x, values):
        shape, frame = self.shape, self.frame
        if _kernel(shape):  # a box or capsule: one kernel, on the candidates
            if values.size != 81 * len(self.known) + 144:
                raise RuntimeError(
                    f"{self.label}: the contact's candidates changed since the system was "
                    "built: Workspace.refresh() rebuilds it"
                )
            return (
                frame_contact_hessian_shape(shape.kind, shape.geom, self.kappa, self.dhat, x,
                                            self.known, frame.nodes, frame.B, self.c0,
                                            self._chain, values, self.project) > 0
            )  # fmt: skip
        _, A, U = self._local(x)
        K = len(self.nodes)
        hv = np.zeros(9 * K)
        self.shape.hessian(self._buf, hv)
        H = hv.reshape(K, 3, 3)
        _, g = self._shape_gradient()
        values[:] = 0.0
        act = np.flatnonzero(np.any(H.reshape(K, 9) != 0.0, axis=1) | np.any(g != 0.0, axis=1))
        if act.size == 0:
            return False
        blocks = values[: 81 * K].reshape(K, 81)
        frame_contact_hessian(A, U, H, g, self._chain, act, blocks, values[81 * K :], self.project)
        return True

    def stiffness(self):
        s = np.zeros(self.n_nodes)
        s[self.frame.nodes] = self.kappa
        return s

    # ---- candidates (module docstring) ------------------------------------------------
    def begin_step(self, x, time, start=None) -> None:
        """The candidates of the time step from x; a static solve takes every node again
        (its pattern rebuilt once, where a dynamic run had narrowed it)."""
        if not self.grows:
            return
        if time is None:
            self._everyone()
            return
        frame = self.frame
        X = frame_local(x, self.nodes, frame.nodes, frame.B, self.c0)[3]
        if self._base is not None and np.array_equal(x, self._base):
            if self.held and self._radius is not None:  # the same step again: wider
                self._radius = self._wider(X, self._radius)
        elif self._base is not None:
            moved = np.sqrt(np.einsum("ij,ij->i", X - self._base_X, X - self._base_X))
            self._radius = self.reach + 2.0 * moved
        self.held = False
        self._base = np.array(x, dtype=np.float64, copy=True)
        self._base_X = X
        if self._radius is None:  # the first time step: every node
            return
        gap = np.empty(len(self.nodes))
        self._buf[self.nodes] = X
        shape_gap(self.shape.kind, self._buf, self.nodes, self.shape.geom, gap)
        near = gap < self.dhat + self._radius
        count = int(np.count_nonzero(near))
        inside = self._inside
        if int(np.count_nonzero(inside)) > PATTERN_SLACK * max(count, FEWEST):  # stale
            inside = near
        elif np.any(near & ~inside):
            inside = inside | near
        if inside is not self._inside:
            self._inside = inside
            self.known, self._pattern, self.grew = self.nodes[inside], None, True
        out = ~inside
        self._far = np.ascontiguousarray(self.nodes[out])
        self._far_X = X[out]
        self._room = gap[out] - self.dhat  # > the radius: no candidate

    def _everyone(self) -> None:
        """Every contact node a candidate again, as before the first time step."""
        if not self._inside.all():
            self._inside = np.ones(len(self.nodes), dtype=bool)
            self.known, self._pattern, self.grew = self.nodes, None, True
        self._far = np.zeros(0, dtype=np.int64)
        self._far_X, self._room = np.zeros((0, 3)), np.zeros(0)
        self._radius = self._base = None

    def _wider(self, X: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """The radii doubled until a node that is no candidate becomes one (a radius held
        a step back: the retry must take in more), at most 2^20 times."""
        gap = np.empty(len(self.nodes))
        self._buf[self.nodes] = X
        shape_gap(self.shape.kind, self._buf, self.nodes, self.shape.geom, gap)
        out = ~self._inside
        for _ in range(20):
            radius = 2.0 * radius
            if np.any(gap[out] < self.dhat + radius[out]):
                break
        return radius

    def _roomy(self, x, dx) -> float:
        """The largest multiple of dx that keeps every node that is no candidate within
        its room of its body-frame point at the step's start (module docstring); a share
        below 1 means a radius held the step back (``held``: of the last step asked
        about, so a solve that fails is retried wider only where the radii held back its
        last iteration, not one of its first, wild steps: the 101 x 101 net's 10 ms step
        was tried four times over, 27 iterations each, to the same failure)."""
        frame = self.frame
        out = float(
            body_room(x, dx, self._far, frame.nodes, frame.B, self.c0, self._far_X, self._room)
        )  # (the least t > 0 with |W| t^2 + |V| t = room - |X0 - start|; none: inf)
        if out < 0.0:  # a node already beyond its room
            self.held = True
            return 0.0
        self.held = out < 1.0
        return out

    # ---- the step cap -----------------------------------------------------------------
    horizon = True  # its search walks the step in pieces: as far as asked, no farther

    def max_step(self, x, dx):
        return self.max_step_within(x, dx, T_FAR)

    def max_step_within(self, x, dx, upto: float) -> float:
        far = min(float(upto), T_FAR)
        if _kernel(self.shape):  # one kernel, on the candidates; the others by their room
            frame = self.frame
            X0, V, W, scale = body_paths(x, dx, self.known, frame.nodes, frame.B, self.c0)
            t = float(
                body_step_cap(self.shape.kind, self.shape.geom, X0, V, W, scale, self.dhat,
                              CA_SHARE, CA_ITER, FLOOR_SHARE, ROUNDOFF, SLACK, far)
            )  # fmt: skip
            if not len(self._far):
                self.held = False
                return t
            return min(t, self._roomy(x, dx))
        c, A, U = self._local(x)
        X0 = self._buf[self.nodes].copy()
        dc, dA = self.frame.state(dx)
        dU = np.asarray(dx)[self.nodes] - dc
        V = dU @ A + U @ dA
        W = dU @ dA
        if not (np.any(V) or np.any(W)):
            return math.inf
        return self._advance(X0, V, W, self._floor(X0, U), far)

    def _floor(self, X0, U) -> float:
        """The nearest a node may come to the shape along a step from X0 (module
        docstring): FLOOR_SHARE dhat, at least ROUNDOFF round-offs of the coordinates,
        and below the smallest gap now by SLACK of it."""
        self._buf[self.nodes] = X0
        gap = float(self.shape.gap(self._buf).min())
        scale = max(float(np.abs(X0).max()), float(np.abs(U).max()), float(np.abs(self.c0).max()))
        floor = max(FLOOR_SHARE * self.dhat, ROUNDOFF * EPS * scale)
        return min(floor, (1.0 - SLACK) * gap) if gap > 0.0 else 0.0

    def _advance(self, X0, V, W, floor: float = 0.0, far: float = T_FAR) -> float:
        """The first contact along the quadratic paths X0 + t V + t^2 W (module
        docstring) with the shape grown by ``floor``: over pieces [t, t + h] (the step
        [0, 1], then doubling t) whose chords stay within |W| h^2 / 4 <= delta of the
        paths, each chord's exact first contact with the shape grown by that deviation
        too, a contact no later than the true one (exact where W = 0); inf where none
        comes before ``far`` (the line search asks again to look farther)."""
        w = float(np.linalg.norm(W, axis=1).max())
        t = 0.0
        for _ in range(CA_ITER):
            P = X0 + t * V + t * t * W
            self._buf[self.nodes] = P
            gap = self.shape.gap(self._buf)
            delta = min(CA_SHARE * (float(gap.min()) - floor), 0.5 * self.dhat)
            if not delta > 0.0:  # a node at the floor already (round-off of a body turning
                return t  # at an extreme rate, or NaN): no further advance is safe
            h = min(max(1.0, t), far - t)  # pieces of the step, then doubling
            if w > 0.0:
                h = min(h, 2.0 * math.sqrt(delta / w))
            chord = h * V + (2.0 * t * h + h * h) * W  # X(t + h) - X(t)
            s = self._ray(P, chord, 0.25 * w * h * h + floor)
            if s <= 1.0:
                return t + s * h
            t += h
            if t >= far:
                return math.inf
        return t  # still short of a contact: capped where the pieces got

    def _ray(self, P, D, grow: float) -> float:
        """The first contact of the nodes' segments P + s D (s in [0, 1]) with the shape
        grown by ``grow`` (inf, or a value beyond 1: none)."""
        x, dx = self._buf, self._g
        x[self.nodes] = P
        dx[self.nodes] = D
        try:
            return self.shape.first_hit(x, dx, grow, 1.0)
        finally:
            dx[self.nodes] = 0.0


@register("body_friction")
class BodyFriction(BodyContact):
    """Coulomb friction between the net and a free body: the lagged friction term
    (``catenet.terms.friction.Friction``) of the body's shape, evaluated in the body
    frame like the barrier it rides on (``contact``), so its normals and anchors ride
    with the body and the friction force acts on both the node and the body (equal and
    opposite, no net torque). A static load step re-lags it (``relag``)."""

    bounds_step = False
    lagged = True

    def __init__(self, friction, contact: BodyContact):
        super().__init__(friction, contact.frame, n_nodes=contact.n_nodes, label=contact.label)
        self.rides_on = contact
        self.contact = contact
        self.grows = contact.grows  # on the contact's candidates (``_follow``)
        self.touching = False  # a node pressed on the body at the lagged state
        self._lag = (friction.anchor, friction.normal, friction.weight)  # on ``known``

    def begin_step(self, x, time, start=None) -> None:
        self._local(x)
        self.shape.begin_step(self._buf, None)
        self._follow()

    def relag(self, x) -> float:
        self._local(x)
        change = self.shape.relag(self._buf)
        self._follow()
        return float(change)

    def _follow(self) -> None:
        """The lagged state on the contact's candidates (after its ``begin_step``): a
        node pressed on the body is within its barrier, so a candidate; one that is not
        carries no friction (and is taken in, should its weight say otherwise)."""
        f = self.shape
        if self.grows:
            inside = self.contact._inside | (f.weight > 0.0)
            if not np.array_equal(inside, self._inside):
                self._inside = inside
                self.known, self._pattern, self.grew = self.nodes[inside], None, True
            sub = self._inside
            self._lag = (f.anchor[sub], f.normal[sub], f.weight[sub])
        else:
            self._lag = (f.anchor, f.normal, f.weight)
        self.touching = bool(np.any(self._lag[2] > 0.0))

    # With no node pressed on the body (every lagged normal force 0: a net in flight
    # towards it) the friction's energy, gradient and Hessian are zero: not evaluated.
    # Else one kernel each, on the nodes' body-frame points (as a box's barrier).
    def gradient(self, x, grad):
        if not self.touching:
            return 0.0
        frame, (anchor, normal, weight) = self.frame, self._lag
        return float(
            frame_friction_gradient(x, self.known, frame.nodes, frame.B, self.c0, anchor,
                                    normal, weight, self.shape.slip, grad)
        )  # fmt: skip

    def hessian(self, x, values):
        if not self.touching:
            return False
        if values.size != 81 * len(self.known) + 144:
            raise RuntimeError(
                f"{self.label}: the friction's nodes changed since the system was built: "
                "Workspace.refresh() rebuilds it"
            )
        frame, (anchor, normal, weight) = self.frame, self._lag
        return (
            frame_friction_hessian(x, self.known, frame.nodes, frame.B, self.c0, anchor,
                                   normal, weight, self.shape.slip, self._chain, values) > 0
        )  # fmt: skip

    def gap(self, x):
        return self.rides_on.gap(x)

    def stiffness(self):
        return None


def _kernel(shape) -> bool:
    """Whether ``shape`` has the body kernels (a box or a capsule)."""
    return isinstance(shape, (BoxBarrier, CapsuleBarrier))
