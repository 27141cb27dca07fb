"""Moving rigid spheres: a ball whose centre is a node of the net, two-way coupled.

A rigid ball (``[[obstacle]] kind = "sphere"`` with ``mass``) is one node appended to
the net (``Net.bodies``: no edges, the ball's mass lumped there, so gravity and inertia
act on it as on any node). ``Ball`` is the log-barrier of the fixed sphere
(``catenet.terms.contact``) between every free net node and that centre: the contact
force acts on both, the implicit step integrates net and ball together, and the line
search is capped at the first contact of the relative motion (``max_step``), so no node
is ever inside the ball, at any step size. The paper's mass-proportional damping mu
acts on the net only (``catenet.solver.dynamic``): a ball flies free and loses its energy to
the damped net it lands on.

A ball on a prescribed path (a sphere with ``velocity`` and no ``mass``) is the same
node, held on its path c(t) by ``Guide``, a stiff spring k |x_c - c(t)|^2 / 2 whose
anchor moves at every time step (``begin_step``). The ball is never teleported: each
step moves it within the same Newton solve as the net, capped at the first contact, so
nodes cannot be swallowed; where the net resists, the ball lags its path by
force / k (``Guide.lag``). The path does work on the net through that spring, which
the energy balance books as external work (``Guide.driven_work``), so a run with a
ball on a path is judged by its balance like any other.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.body import pair_gap, pair_gradient, pair_hessian, pair_max_step
from catenet.terms.base import Term, node_block_pattern, register


@register("ball")
class Ball(Term):
    """Barrier contact of ``nodes`` with the ball of ``radius`` centred at node ``center``
    (kappa [N/m], activation distance dhat [m]); ``n_nodes`` of the net with the ball."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    label = "a ball"  # the ball in messages (its obstacle's key path)

    role = "internal"
    convex = False  # as the fixed sphere: indefinite near contact

    def __init__(self, nodes, center: int, radius: float, *, kappa, dhat, n_nodes: int):
        if not (math.isfinite(kappa) and kappa > 0 and math.isfinite(dhat) and dhat > 0):
            raise ValueError(f"ball: kappa = {kappa!r}, dhat = {dhat!r}: must be > 0")
        if not (math.isfinite(radius) and radius > 0):
            raise ValueError(f"ball: radius = {radius!r}: must be > 0")
        self.nodes = np.ascontiguousarray(nodes, dtype=np.int64)
        self.center = int(center)
        if self.center in set(self.nodes.tolist()):
            raise ValueError("ball: the centre node must not be one of the contact nodes")
        self.radius = float(radius)
        self.kappa = float(kappa)
        self.dhat = float(dhat)
        self.n_nodes = int(n_nodes)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        dof = np.arange(3)
        ni = 3 * self.nodes[:, None] + dof  # (K, 3)
        nc = np.broadcast_to(3 * self.center + dof, ni.shape)
        blocks = []
        for r, c in ((ni, ni), (ni, nc), (nc, ni)):
            blocks.append((np.repeat(r, 3, axis=1), np.tile(c, (1, 3))))  # (K, 9) each
        rows = np.concatenate([b[0] for b in blocks], axis=1).ravel()
        cols = np.concatenate([b[1] for b in blocks], axis=1).ravel()
        rc, cc = node_block_pattern(np.array([self.center]))
        return np.concatenate([rows, rc]), np.concatenate([cols, cc])

    def gradient(self, x, grad):
        args = (x, self.nodes, self.center, self.radius, self.kappa, self.dhat, grad)
        return pair_gradient(*args)

    def energy(self, x):
        return self.gradient(x, np.zeros_like(x))

    def hessian(self, x, values):
        args = (x, self.nodes, self.center, self.radius, self.kappa, self.dhat, values)
        return pair_hessian(*args) > 0

    def stiffness(self) -> np.ndarray:
        k = np.zeros(self.n_nodes)
        k[self.center] = self.kappa  # the ball's scale, for the regularisation
        return k

    def gap(self, x) -> np.ndarray:
        """Each contact node's distance to the ball's surface (> 0 outside)."""
        out = np.empty(len(self.nodes))
        x = np.ascontiguousarray(x, dtype=np.float64)
        pair_gap(x, self.nodes, self.center, self.radius, out)
        return out

    def max_step(self, x, dx) -> float:
        return pair_max_step(x, dx, self.nodes, self.center, self.radius)


class Path:
    """The centre c(t) = c0 + velocity * integral_0^t f of a ball on a prescribed path,
    with f the ``history`` factor (1 without one): the velocity at t is velocity f(t)."""

    def __init__(self, start, velocity, history=None):
        self.start = np.asarray(start, dtype=np.float64)
        self.velocity = np.asarray(velocity, dtype=np.float64)
        self.history = history

    def distance(self, t: float) -> float:
        """integral_0^t f (exact for the piecewise linear factor)."""
        h = self.history
        if h is None:
            return t
        ts = np.concatenate([[0.0], h.times[(h.times > 0.0) & (h.times < t)], [t]])
        fs = np.interp(ts, h.times, h.factors)
        return float(np.sum(0.5 * (fs[1:] + fs[:-1]) * np.diff(ts)))

    def __call__(self, t: float) -> np.ndarray:
        return self.start + self.velocity * self.distance(t)

    def corners(self) -> tuple[float, ...]:
        """The times its velocity turns a corner: the history's points."""
        return () if self.history is None else tuple(self.history.times)


@register("guide")
class Guide(Term):
    """The spring k |x_c - anchor|^2 / 2 holding node ``center`` on ``path``: the anchor is
    path(t) at the end of every time step; static load steps keep it where it is."""

    role = "internal"
    convex = True
    driven = True  # the path's work on the net (``driven_work``)

    def __init__(self, center: int, path: Path, stiffness: float, *, n_nodes: int):
        if not (math.isfinite(stiffness) and stiffness > 0):
            raise ValueError(f"guide: stiffness = {stiffness!r}: must be > 0")
        self.center = int(center)
        self.path = path
        self.k = float(stiffness)
        self.anchor = path(0.0).copy()
        self.n_nodes = int(n_nodes)
        self._span: tuple[float, float] | None = None  # the last step's (start, end)
        self._loaded = True  # a step of the run booked (``begin_run``: not yet)

    def begin_run(self, x, t: float) -> None:
        self.anchor = self.path(t)
        self._span = None
        self._loaded = False  # the spring at the run's start holds nothing yet

    def settle_time(self) -> float:
        return 0.0  # as before: the path's end decides nothing of a run to rest

    def corners(self) -> tuple[float, ...]:
        return self.path.corners()

    def begin_step(self, x, time, start=None) -> None:
        self._span = None
        if time is not None:
            self.anchor = self.path(time)
            if start is not None:
                self._span = (float(start), float(time))

    def driven_work(self, x_old, x_new, commit=True) -> float:
        """The path's work [J] on the net over the last step: the spring's force on the
        ball times the anchor's displacement, the trapezoid of the step's start and end
        (the work rate of k |x_c - c(t)|^2 / 2 is -k (x_c - c) . c'(t)), as an obstacle
        on a prescribed motion books its own (``catenet.terms.moving``). In a run's first
        step the end's force alone: at the start the spring holds nothing (the ball sits
        on its anchor), and within a step's first instants it takes up the ball's
        weight and the net's push, so the trapezoid would count half of them."""
        if self._span is None:
            return 0.0
        a0, a1 = self.path(self._span[0]), self.path(self._span[1])
        f1 = -self.k * (x_new[self.center] - a1)
        if not self._loaded:  # the first step: its end's force throughout
            self._loaded = commit
            return float(f1 @ (a1 - a0))
        f0 = -self.k * (x_old[self.center] - a0)
        return 0.5 * float((f0 + f1) @ (a1 - a0))

    def pattern(self):
        return node_block_pattern(np.array([self.center]))

    def gradient(self, x, grad):
        u = x[self.center] - self.anchor
        grad[self.center] += self.k * u
        return 0.5 * self.k * float(u @ u)

    def energy(self, x):
        u = x[self.center] - self.anchor
        return 0.5 * self.k * float(u @ u)

    def hessian(self, x, values):
        values[:] = 0.0
        values[0::4] = self.k  # the 3x3 identity, row-major: entries 0, 4, 8
        return True

    def roundoff(self, x, energy):
        return self.k * float(np.abs(self.anchor).max() + np.abs(x[self.center]).max()), abs(energy)

    def stiffness(self) -> np.ndarray:
        k = np.zeros(self.n_nodes)
        k[self.center] = self.k
        return k

    def lag(self, x) -> float:
        """How far the ball is behind its path [m]."""
        return float(np.linalg.norm(x[self.center] - self.anchor))
