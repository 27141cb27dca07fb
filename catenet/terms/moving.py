"""Obstacles on a prescribed rigid motion: a box, a capsule or a mesh that translates
with ``velocity`` and turns with ``angular_velocity`` about its reference point (a
tumbling piece of debris), as a wrapper around the fixed shape's term.

The pose at time t is c(t) = c0 + v F(t), R(t) = exp(F(t) [w]x) (Rodrigues), F the
integral of the history factor (F(t) = t without one). The wrapped shape stays where it
was built (its pose at t = 0) and works in that body frame: a point x is seen there as
x_b = c0 + R^T (x - c); gradients turn back as R g_b and the Hessian's node blocks as
R H_b R^T (the pattern is the shape's). ``begin_step(x, time)`` sets the pose at the
step's end, so every Newton iterate of a step sees one fixed obstacle and the barrier
and the exact first contact of ``max_step`` keep their guarantee within the step.

Between steps the obstacle jumps from pose(t_n) to pose(t_n+1), which could swallow a
node near it. ``carry`` (called by the time stepping before its predictor is cut back to
the first contact) moves every free node that the obstacle may reach in the step
rigidly with it from the point the cut-back starts from: rigid motion keeps a node's
gap, so every step starts with every node outside. Newton starts a carried node there,
or at its predictor (its own motion) where the obstacle translates and the node's
straight path to it, relative to the obstacle, is clear (``_predicted``). A node is
carried by one obstacle at most, and the contacts of a carried rigid ball (or the ball
resting on a carried node) come along (``catenet.terms.collide.spread``). A node or edge
that a second moving obstacle reaches in the same step is watched over it and carried
by a blend of the two motions (``catenet.terms.pinch``). A support the obstacle reaches
stops the run (ConvergenceError naming obstacle and node).

The obstacle's motion does work on the net (``driven_work``, booked by the energy
balance as external work): over a step from t_n to t_n+1, the trapezoid of the barrier's
forces f on the nodes times the rigid motion's displacement D of the obstacle's points
where the nodes are, -1/2 (g(x_n; pose_n) . D_n + g(x_n+1; pose_n+1) . D_n+1), g the
barrier's gradient (the work rate of a barrier E(x_b(x, t)) is -grad_x E . u(x), u the
obstacle's velocity field). ``catenet.terms.moving_edges`` moves the edges' barrier
(``solver.edge_contact``) the same way.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.errors import ConvergenceError
from catenet.terms.base import Term
from catenet.terms.body import Path
from catenet.terms.collide import SWEEP_SAFETY, spread
from catenet.terms.probe import Only


def rotation_vector(w, angle: float) -> np.ndarray:
    """exp(angle [w/|w|]x): the rotation by ``angle`` about the unit vector of w."""
    from catenet.terms.shapes import rotation

    return np.eye(3) if angle == 0.0 else rotation(w, angle)


class Moving(Term):
    """The obstacle term ``shape`` (built at its pose at t = 0) moving rigidly: its
    reference point ``origin`` translates with ``velocity`` [m/s] and the body turns
    with ``angular_velocity`` [rad/s] about that point, both scaled by ``history``
    (a ``catenet.model.histories.History``; None: 1). ``reach``: the largest distance from the
    origin to a point of the obstacle [m]."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    moving = True
    driven = True  # its motion's work on the net (``driven_work``)

    role = "internal"
    convex = False
    #: Whether ``carry`` stops the run at a support the obstacle reaches (False for a
    #: ball's centre against it: the shape grown by the ball's radius is no obstacle to
    #: the supports; the net's own term guards them).
    guards_supports = True

    def __init__(
        self,
        shape,
        origin,
        velocity=None,
        angular_velocity=None,
        history=None,
        *,
        reach: float,
        label: str = "a moving obstacle",
    ):
        self.shape = shape
        self.nodes = shape.nodes
        self.kappa, self.dhat = shape.kappa, shape.dhat
        self.origin = np.asarray(origin, dtype=np.float64).copy()
        v = np.zeros(3) if velocity is None else np.asarray(velocity, dtype=np.float64)
        w = np.zeros(3) if angular_velocity is None else np.asarray(angular_velocity, float)
        if not (np.all(np.isfinite(v)) and np.all(np.isfinite(w)) and math.isfinite(reach)):
            raise ValueError("moving obstacle: velocity and angular velocity must be finite")
        self.velocity, self.omega = v, w
        self.path = Path(self.origin, v, history)
        self.reach = float(reach)
        self.label = label
        self.center, self.R = self.pose(0.0)
        # body-frame buffers: positions and displacements (_local), the gradient
        self._x: np.ndarray | None = None
        self._dx: np.ndarray | None = None
        self._g: np.ndarray | None = None
        self._span: tuple[float, float] | None = None  # the last step's (start, end)

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(c(t), R(t)): the origin's place and the body's rotation at time t."""
        return self._pose(self.path.distance(t))

    def _pose(self, f: float) -> tuple[np.ndarray, np.ndarray]:
        """The pose after the motion's integral ``f`` (F(t), t without a history)."""
        spin = float(np.linalg.norm(self.omega))
        return self.origin + self.velocity * f, rotation_vector(self.omega, spin * f)

    def set_pose(self, t: float) -> None:
        self.center, self.R = self.pose(t)

    def begin_step(self, x, time, start=None) -> None:
        self._span = None
        if time is not None:
            self.set_pose(time)
            if start is not None:
                self._span = (float(start), float(time))
        self.shape.begin_step(self._body(x), time, start)

    def begin_run(self, x, t: float) -> None:
        self.set_pose(t)

    def settle_time(self) -> float:
        return 0.0  # a run with a moving obstacle goes to its t_end (not to rest)

    def corners(self) -> tuple[float, ...]:
        return self.path.corners()

    def driven_work(self, x_old, x_new, commit=True) -> float:
        """The work [J] of the obstacle's motion on the net over the last step (module
        docstring): the trapezoid of the barrier's forces times the displacement of the
        obstacle's points where the nodes are, at the step's start and end."""
        if self._span is None:
            return 0.0
        t0, t1 = self._span
        keep = self.center, self.R
        nodes = self.nodes
        try:
            ahead = self.rigid(x_old[nodes], t0, t1) - x_old[nodes]
            behind = x_new[nodes] - self.rigid(x_new[nodes], t1, t0)
            work = self._work(x_old, t0, ahead) + self._work(x_new, t1, behind)
        finally:
            self.center, self.R = keep
        return 0.5 * work

    def drive(self, x_old, x_new) -> np.ndarray | None:
        """(N, 3) the displacement of the obstacle's points where the nodes are over the
        last step (the mean of the rigid motion's at x_old and at x_new, as in
        ``driven_work``): its friction's work on the net is f . drive, the rest of the
        friction's f . dx is dissipated (None: no step yet)."""
        if self._span is None:
            return None
        t0, t1 = self._span
        ahead = self.rigid(x_old, t0, t1) - x_old
        behind = x_new - self.rigid(x_new, t1, t0)
        return 0.5 * (ahead + behind)

    def _work(self, x, t: float, shift: np.ndarray) -> float:
        """f . shift at x with the obstacle at its pose at t (f = -grad: on the nodes)."""
        self.set_pose(t)
        g = np.zeros(np.shape(x))
        if not np.isfinite(self.gradient(x, g)):
            return 0.0
        return -float(np.sum(g[self.nodes] * shift))

    def _body(self, x, center=None, R=None) -> np.ndarray:
        """Points x (N, 3) in the body frame (the shape's pose at t = 0)."""
        c = self.center if center is None else center
        R = self.R if R is None else R
        return self.origin + (np.asarray(x) - c) @ R

    def world(self, p) -> np.ndarray:
        """Body-frame points p (K, 3) where the obstacle has them now."""
        return self.center + (np.asarray(p) - self.origin) @ self.R.T

    def pattern(self):
        return self.shape.pattern()

    def _local(self, x, turn_only: bool = False) -> np.ndarray:
        """The rows of x (N, 3) at the obstacle's nodes in the body frame (``turn_only``:
        a displacement, turned only), in a buffer kept across evaluations (one for
        positions, one for displacements); the shape's kernels read no other row. Saves a
        full (N, 3) copy per Newton evaluation."""
        buf = self._dx if turn_only else self._x
        if buf is None or buf.shape != np.shape(x):
            buf = np.zeros(np.shape(x))
            if turn_only:
                self._dx = buf
            else:
                self._x = buf
        rows = np.asarray(x)[self.nodes]
        if turn_only:
            buf[self.nodes] = rows @ self.R
        else:
            buf[self.nodes] = self.origin + (rows - self.center) @ self.R
        return buf

    def gap(self, x):
        return self.shape.gap(self._local(x))

    def gradient(self, x, grad):
        if self._g is None or self._g.shape != np.shape(x):
            self._g = np.zeros(np.shape(x))
        g = self._g
        energy = self.shape.gradient(self._local(x), g)
        grad[self.nodes] += g[self.nodes] @ self.R.T
        g[self.nodes] = 0.0  # the shape adds at its nodes only: the buffer is zero again
        return energy

    def energy(self, x):
        return self.shape.energy(self._local(x))

    def hessian(self, x, values):
        active = self.shape.hessian(self._local(x), values)
        if np.any(self.omega):  # R H_b R^T per node (R = 1 where it only translates)
            H = values.reshape(-1, 3, 3)
            H[:] = self.R @ H @ self.R.T
        return active

    def max_step(self, x, dx):
        return self.shape.max_step(self._local(x), self._local(dx, turn_only=True))

    def sweep(self, t0: float, t1: float) -> float:
        """The largest displacement of any point of the obstacle from t0 to t1 [m]."""
        f = abs(self.path.distance(t1) - self.path.distance(t0))
        return f * (
            float(np.linalg.norm(self.velocity)) + float(np.linalg.norm(self.omega)) * self.reach
        )

    def carry(self, base, trial, t0: float, t1: float, fixed, moved=None, index=0) -> int:
        """Moves the free nodes the obstacle may reach from t0 to t1 (gap at pose(t0)
        below SWEEP_SAFETY times its sweep plus the activation distance) rigidly with it,
        in ``base`` (the step's start, as the cut-back sees it) and ``trial`` (its
        predictor), in place; returns how many. ``moved`` (per node, the ``index`` of
        the obstacle that carried it, -1: none) skips nodes carried already and records
        these. Raises ConvergenceError when a support (``fixed``, a mask of all nodes) is
        inside or on the obstacle at t1."""
        c1, R1 = self.pose(t1)
        self.center, self.R = c1, R1
        supports = np.flatnonzero(fixed) if self.guards_supports else np.empty(0, np.int64)
        if supports.size:
            hit = self._reaches(trial, supports, t0, t1)
            if hit is not None:
                i, t_hit = hit
                where = ", ".join(f"{v:.6g}" for v in trial[i])
                raise ConvergenceError(
                    f"{self.label} reaches support node {i} at [{where}] "
                    f"at t = {t_hit:.6g} s: a moving obstacle must not run over a "
                    "support; change its motion or the supports"
                )
        move = self.sweep(t0, t1)
        if move == 0.0:
            return 0
        c0, R0 = self.pose(t0)
        gap = self.shape.gap(self._body(base, c0, R0))
        near = self.nodes[gap < SWEEP_SAFETY * move + self.dhat]
        near = near[~self.stays(near[:, None], base, t0, t1)]
        return int(self._carry_nodes(near, base, trial, t0, t1, moved, index).size)

    def stays(self, items, base, t0: float, t1: float) -> np.ndarray:
        """Per item (its nodes: rows of ``items``, (K, m), as the shape's gap takes them)
        whether it may stay where it is over the step rather than ride with the obstacle:
        the obstacle translates (no spin), so relative to it each item moves on a straight
        line, along which no item meets it (the shape's own first contact) and each keeps
        at the end at least half of the smaller of its gap at the start and dhat (a belt
        running along its face under a rope: carried, the rope was pulled along the belt
        and its end edges strained at every step's start). None stays where the obstacle
        turns or where a path that would keep its gap at the end meets the obstacle."""
        stay = np.zeros(len(items), dtype=bool)
        if np.any(self.omega) or not len(items):
            return stay
        c0, R0 = self.pose(t0)
        c1, _ = self.pose(t1)
        x = self._body(base, c0, R0)
        dx = np.broadcast_to((c0 - c1) @ R0, x.shape).copy()
        probe = Only(self.shape, items)
        stay = probe.gap(x + dx) >= 0.5 * np.minimum(probe.gap(x), self.dhat)
        if stay.any() and not Only(self.shape, items[stay]).max_step(x, dx) >= 1.0:
            stay[:] = False
        return stay

    def _carry_nodes(self, nodes, base, trial, t0: float, t1: float, moved, index: int):
        """``nodes`` that no other obstacle carried this step (``moved``: -1, then marked
        ``index``) moved rigidly with this one from t0 to t1 in ``base`` and ``trial``;
        returns them."""
        if moved is not None:
            nodes = nodes[moved[nodes] < 0]
            moved[nodes] = index
        if nodes.size:
            riding = self.rigid(base[nodes], t0, t1)
            keep = self._predicted(nodes, base, trial, t0, t1)
            trial[nodes] = np.where(keep[:, None], trial[nodes], riding)
            base[nodes] = riding
        return nodes

    def node_shape(self):
        """The barrier of the obstacle's nodes (this term's shape)."""
        return self.shape

    def _predicted(self, nodes, base, trial, t0: float, t1: float) -> np.ndarray:
        """Per node, whether its predictor (``trial``: where its own motion takes it) is
        kept: the obstacle translates, and relative to it the node's straight path from
        its start (``base``) to its predictor meets it nowhere (the nodes' barrier's own
        first contact) and keeps at the end at least half the smaller of its gap at the
        start and dhat. Else the node's start rides with the obstacle. (Carrying the
        predictor instead counted a riding node's motion twice: a rope pushed by a paddle
        at 2.5 mm a step started each step with the nodes in front 2.5 mm ahead of their
        neighbours, hundreds of newtons out of balance, and its steps shrank elevenfold.)"""
        keep = np.zeros(len(nodes), dtype=bool)
        shape = self.node_shape()
        if np.any(self.omega) or shape is None:
            return keep
        c0, R0 = self.pose(t0)
        c1, R1 = self.pose(t1)
        x0 = self._body(base, c0, R0)
        dx = np.zeros_like(x0)
        dx[nodes] = self._body(trial[nodes], c1, R1) - x0[nodes]
        probe = Only(shape, nodes[:, None])
        keep = probe.gap(x0 + dx) >= 0.5 * np.minimum(probe.gap(x0), self.dhat)
        pending = [np.flatnonzero(keep)]
        while pending:  # the straight paths, by halves where one of a group meets it
            group = pending.pop()
            if not group.size or Only(shape, nodes[group, None]).max_step(x0, dx) >= 1.0:
                continue
            if group.size == 1:
                keep[group] = False
            else:
                pending += [group[: group.size // 2], group[group.size // 2 :]]
        return keep

    def rigid(self, points, t0: float, t1: float) -> np.ndarray:
        """Points (K, 3) moved rigidly with the obstacle from pose(t0) to pose(t1)."""
        c0, R0 = self.pose(t0)
        c1, R1 = self.pose(t1)
        return c1 + (points - c0) @ (R1 @ R0.T).T

    def _reaches(self, x, supports, t0: float, t1: float):
        """(node, time) of the first support (at its place in x) the obstacle reaches
        between t0 and t1, else None (``first_touch``)."""
        hit = self.first_touch(Only(self.shape, supports[:, None]), x, t0, t1)
        return None if hit is None else (int(supports[hit[0]]), hit[1])

    def first_touch(self, probe, x, t0: float, t1: float, max_iter: int = 200):
        """(k, time) of the first of ``probe``'s items (its ``gap`` per item of body-frame
        points, x held where it is, or ``x(c, R)`` the points with the obstacle at the
        pose c, R: some riding with it) that the obstacle reaches between t0 and t1, else
        None: conservative advancement, every point moving at most ``sweep`` over the step
        relative to the obstacle, so it advances by gap / rate at a time: an item thinner
        than the obstacle's travel in the step is not passed over."""
        f0, f1 = self.path.distance(t0), self.path.distance(t1)
        rate = self.sweep(t0, t1)  # per unit of the step's fraction s
        s = 1.0 if rate == 0.0 else 0.0
        for _ in range(max_iter):
            c, R = self._pose(f0 + s * (f1 - f0))
            gap = probe.gap(self._body(x(c, R) if callable(x) else x, c, R))
            k = int(np.argmin(gap))
            if not gap[k] > 1e-9 * max(self.reach, self.dhat):
                return k, t0 + s * (t1 - t0)
            if s >= 1.0:
                return None
            s = min(1.0, s + float(gap[k]) / rate)
        c, R = self._pose(f1)  # grazing for max_iter advances: the end pose decides
        gap = probe.gap(self._body(x(c, R) if callable(x) else x, c, R))
        k = int(np.argmin(gap))
        return (k, t1) if not gap[k] > 0.0 else None


def carry(potential, base, trial, t0: float, t1: float, fixed) -> np.ndarray:
    """``base`` (the step's start) with the nodes every moving obstacle of the potential
    may reach from t0 to t1 carried along with it, in a copy, and in ``trial`` in place
    (``Moving.carry``; then the contacts of carried balls, ``collide.spread``); ``base``
    itself when there is none."""
    movers = [t for t in potential.system.terms if isinstance(t, Moving)]
    if not movers:
        return base
    start, base = base, base.copy()
    before = trial.copy() if len(movers) > 1 else trial
    moved = np.full(len(base), -1, dtype=np.int64)
    for k, term in enumerate(movers):
        term.carry(base, trial, t0, t1, fixed, moved, k)
    if len(movers) > 1:  # a node or edge two obstacles reach: catenet/terms/pinch.py
        from catenet.terms.pinch import share

        share(movers, start, base, trial, before, moved, t0, t1)
    spread(potential.system.terms, movers, start, base, trial, moved, t0, t1)
    return base


def moves(potential, t0: float = 0.0) -> bool:
    """Whether any obstacle of the potential is on a prescribed motion; puts each at
    its pose at ``t0`` (a run's start)."""
    movers = [t for t in potential.system.terms if isinstance(t, Moving)]
    for term in movers:
        term.set_pose(t0)
    return bool(movers)
