"""Strands inside solids: where the net meets obstacles, balls and free bodies at its nodes
only (no ``solver.edge_contact``), the barriers keep every node out, but the straight edge
between two nodes may cut into a solid, or the solid may pass between the nodes: a 0.24 m
ball dropped on a net of 0.22 m cells pushed the cell's nodes aside and fell on through
it at nearly free-fall speed, "converged", and nothing said so.

``EdgeWatch`` follows a run's states (every time step, every load step and the end) and
measures, at SAMPLES points inside every edge (and REFINE more round the deepest of an
edge near its limit), how deep the edge lies in each solid (the solid's own signed
distance, at its pose then: a free body's from its nodes, a ball's centre node, a moving
obstacle's pose at the time). An edge deeper than DEEP of its
length, or than DEEP_WIDTH of the solid's width (a thin plate cut through), is a crossing:
the run warns once per solid, with the deepest point, when, and in how many states. A
chord of a net draped on a sphere of radius R lies l^2 / (8 R) inside it between its
nodes, below DEEP for edges shorter than 0.4 R: the polyhedral net's own shape, not
warned. Planes need nothing (a segment whose ends are outside a half-space is
outside). Load cases are watched from the base state on (``catenet.run.cases``).

A step can also carry the net through a solid, whatever meets it: each state keeps them
apart, but the step's solution lies on the solid's far side (a 4 cm ball at 2 m/s given
2 cm steps ended below the strand it should bounce off, with ``solver.edge_contact``; a
slack cord loaded in one load step came to hang under a sphere it should lie on). The
watch looks at the straight way between two states (time steps or load steps) at the
points the contact holds off (along every edge with edge contact, the nodes without): a
point outside the solid at both states that goes deeper than PASS of the solid's width
on the way, and comes out on its other side (the solid's outward directions at the point
at the two states more than 90 degrees apart), is a pass, warned once per solid (with
contact at the nodes, where a node went through). A node carried round a box's corner
or a sphere's quarter in one step turns by 90 degrees at most: not a pass.
"""

from __future__ import annotations

import math

import numpy as np

#: Points inside each edge at which its depth in a solid is measured.
SAMPLES = 7
#: An edge deeper in a solid than this share of its own length is a crossing.
DEEP = 0.05
#: ... or deeper than this share of the solid's width (a thin solid cut through).
DEEP_WIDTH = 0.25
#: An edge whose deepest sample is beyond this share of its limit is measured closer ...
CLOSE = 0.5
#: ... at this many more points on either side of that sample.
REFINE = 8
#: Points farther from a solid's origin than its reach times this are not measured.
MARGIN = 1.01
#: Between two states, a node moves at most this share of a solid's width (or of the
#: median edge) relative to it from one measured state to the next ...
SUBSTEP = 0.25
#: ... in at most this many states between two.
MAX_SUBSTEPS = 64
#: A point deeper in a solid than this share of its width on the straight way between
#: two states, and outside it on its other side at both, is a pass.
PASS = 0.05
#: The points along each edge, its ends included, at which passes are looked for where
#: the whole edge meets the solids; where its nodes only do, at its ends.
PASS_ALONG = np.linspace(0.0, 1.0, SAMPLES + 2)[None, :, None]
PASS_ENDS = np.array([0.0, 1.0])[None, :, None]

ALONG = (np.arange(1, SAMPLES + 1) / (SAMPLES + 1.0))[None, :, None]


class _Worst:
    """The deepest of a kind of event seen: how deep, which edge, when; in how many
    steps."""

    def __init__(self):
        self.depth, self.edge, self.when, self.steps = 0.0, -1, 0.0, 0
        self.node = -1  # the node of the edge that went deepest (-1: a point inside it)

    def keep(self, depth: float, edge: int, when: float, node: int = -1) -> None:
        if depth > self.depth:
            self.depth, self.edge, self.when, self.node = depth, edge, when, node

    @property
    def what(self) -> str:
        return f"node {self.node}" if self.node >= 0 else f"edge {self.edge}"


class _Solid:
    """One solid of the scene as the watch measures it: its label, width, a barrier of
    its shape (its signed distance, at its pose at t = 0 or its own), how to bring world
    points into that barrier's frame, and the deepest crossing seen."""

    def __init__(self, index: int, label: str, shape, width: float, local, origin):
        self.index = index  # its obstacle[k]
        self.label, self.width = label, width
        self.barrier = shape.barrier(np.zeros(0, dtype=np.int64), kappa=1.0, dhat=1e-3 * width)
        self.reach = MARGIN * shape.reach + 1e-12
        self.origin = origin  # (x, t) -> the solid's origin in the world at the state x
        self.local = local  # (points, x, t) -> the points in the barrier's frame
        self.cut = _Worst()  # the deepest crossing: an edge inside it (module docstring)
        self.passed = _Worst()  # the deepest pass

    def near(
        self, x0: np.ndarray, x1: np.ndarray, edges: np.ndarray, t0: float, t1: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The edges that may come within the solid's reach between the states x0 and
        x1 (each node's distance from the solid's origin, moving linearly, is at least
        the smaller of its two less its move; an edge's points at least that less its
        length), and the largest move of their nodes relative to the solid."""
        o0, o1 = self.origin(x0, t0), self.origin(x1, t1)
        r0, r1 = x0 - o0, x1 - o1
        move = np.linalg.norm(r1 - r0, axis=1)
        low = np.minimum(np.linalg.norm(r0, axis=1), np.linalg.norm(r1, axis=1)) - move
        long = np.maximum(
            np.linalg.norm(x0[edges[:, 1]] - x0[edges[:, 0]], axis=1),
            np.linalg.norm(x1[edges[:, 1]] - x1[edges[:, 0]], axis=1),
        )
        ends = np.minimum(low[edges[:, 0]], low[edges[:, 1]])
        return np.flatnonzero(ends - long <= self.reach), move

    def see(
        self, t: float, x: np.ndarray, edges: np.ndarray, which: np.ndarray, between: bool
    ) -> bool:
        """The state x at time t: the depth of the points inside the edges ``which``;
        whether one is a crossing. A state ``between`` two that the run reached is the
        straight way from one to the other: an edge whose end nodes it takes into the
        solid (a node sliding round its corner, cut short) is not measured there."""
        if between:
            ends = np.concatenate([x[edges[which, 0]], x[edges[which, 1]]])
            held = self._depth(ends, x, t).reshape(2, -1).max(axis=0) <= 0.0
            which = which[held]
            if not which.size:
                return False
        a, b = x[edges[which, 0]], x[edges[which, 1]]
        points = (a[:, None, :] + ALONG * (b - a)[:, None, :]).reshape(-1, 3)
        depth = self._depth(points, x, t).reshape(-1, SAMPLES)
        limit = np.minimum(DEEP * np.linalg.norm(b - a, axis=1), DEEP_WIDTH * self.width)
        close = np.flatnonzero(depth.max(axis=1) > CLOSE * limit)
        if not close.size:
            return False
        best = self._refined(a[close], b[close], depth[close], x, t)
        over = best > limit[close]
        if not over.any():
            return False
        k = int(np.argmax(np.where(over, best, -np.inf)))
        self.cut.keep(float(best[k]), int(which[close[k]]), float(t))
        return True

    def _refined(self, a, b, depth, x, t: float) -> np.ndarray:
        """Each edge's largest depth: twice REFINE more points on either side of its
        deepest point so far, within the samples' spacing, then within theirs (a straight
        edge's depth in a convex solid has one peak, which seven points alone missed by up
        to a quarter)."""
        at = (np.argmax(depth, axis=1) + 1.0) / (SAMPLES + 1.0)
        best = depth.max(axis=1)
        half = 1.0 / (SAMPLES + 1.0)
        for _ in range(2):
            u = np.clip(at[:, None] + np.linspace(-half, half, 2 * REFINE + 1)[None, :], 0, 1)
            points = (a[:, None, :] + u[:, :, None] * (b - a)[:, None, :]).reshape(-1, 3)
            more = self._depth(points, x, t).reshape(len(a), -1)
            at = u[np.arange(len(a)), np.argmax(more, axis=1)]
            best = np.maximum(best, more.max(axis=1))
            half /= REFINE
        return best

    def passes(
        self, x0: np.ndarray, x1: np.ndarray, t0: float, t1: float, n: int,
        edges: np.ndarray, which: np.ndarray, along: np.ndarray, between: bool,
    ) -> bool:  # fmt: skip
        """Whether the straight way from x0 (at t0) to x1 (at t1), measured at the ``n``
        - 1 states between them, carries a point of the edges ``which`` (at ``along``
        their length) through the solid (module docstring); the deepest such point kept,
        at its time on the way (``between``: a motion) or at t1 (load steps)."""
        if n < 2:
            return False
        ends = edges[which]
        p0 = x0[ends[:, 0]][:, None, :] + along * (x0[ends[:, 1]] - x0[ends[:, 0]])[:, None, :]
        p1 = x1[ends[:, 0]][:, None, :] + along * (x1[ends[:, 1]] - x1[ends[:, 0]])[:, None, :]
        p0, p1 = p0.reshape(-1, 3), p1.reshape(-1, 3)
        out = (self._depth(p0, x0, t0) < 0.0) & (self._depth(p1, x1, t1) < 0.0)
        if not out.any():
            return False
        p0, p1, index = p0[out], p1[out], np.flatnonzero(out)
        deepest, when = np.full(len(p0), -np.inf), np.zeros(len(p0))
        for k in range(1, n):
            s = k / n
            t = t0 + s * (t1 - t0)
            depth = self._depth((1.0 - s) * p0 + s * p1, (1.0 - s) * x0 + s * x1, t)
            deeper = depth > deepest
            deepest[deeper], when[deeper] = depth[deeper], t if between else t1
        deep = np.flatnonzero(deepest > PASS * self.width)
        if not deep.size:
            return False
        turned = np.sum(self._outward(p0[deep], x0, t0) * self._outward(p1[deep], x1, t1), axis=1)
        through = deep[turned < 0.0]
        if not through.size:
            return False
        k = through[np.argmax(deepest[through])]
        edge, point = divmod(int(index[k]), along.shape[1])
        u = float(along[0, point, 0])
        node = int(ends[edge, 0]) if u == 0.0 else int(ends[edge, 1]) if u == 1.0 else -1
        self.passed.keep(float(deepest[k]), int(which[edge]), when[k], node)
        return True

    def _outward(self, points: np.ndarray, x: np.ndarray, t: float) -> np.ndarray:
        """The solid's outward direction at each world point outside it (the gradient of
        its distance, by central differences)."""
        h = 1e-5 * self.width
        grad = np.empty_like(points)
        for i in range(3):
            step = np.zeros(3)
            step[i] = h
            grad[:, i] = self._depth(points - step, x, t) - self._depth(points + step, x, t)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        return grad / np.where(norm > 0.0, norm, 1.0)

    def _depth(self, points: np.ndarray, x: np.ndarray, t: float) -> np.ndarray:
        """How deep each world point lies in the solid at the state x at time t (< 0:
        outside)."""
        self.barrier.nodes = np.arange(len(points), dtype=np.int64)
        return -self.barrier.gap(np.ascontiguousarray(self.local(points, x, t)))


class EdgeWatch:
    """Follows a run's states (``see``) and says where edges went into solids or a step
    carried the net through one (``warnings``; module docstring). Where every edge meets
    the solids (edge contact: ``apart``), only the way between two states is looked at.
    Empty where the scene has no solid but planes."""

    def __init__(self, scene, terms=(), dynamic: bool = False):
        from catenet.scene.shapes import solid_width

        self.dynamic = dynamic
        self.apart = scene.edge_radius is not None  # every state keeps the edges out
        self.edges = np.asarray(scene.net.edges)[: scene.net.n_edges]
        self.solids: list[_Solid] = []
        self.last: tuple[np.ndarray, float] | None = None
        if not len(self.edges):
            return
        ends = scene.net.nodes[self.edges]
        self.median = float(np.median(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)))
        moving = {getattr(t, "owner", None): t for t in terms if type(t).__name__ == "Moving"}
        for k, shape, _ in scene.obstacles:
            if shape.kind == "plane":
                continue
            width = solid_width(shape)
            if not (math.isfinite(width) and width > 0.0):
                continue  # its extent lost to round-off where it lies (1e19 m off): unmeasured
            label = f"obstacle[{k}] (a {shape.kind})"
            term = moving.get(k)
            if term is None:
                solid = _Solid(k, label, shape, width, _as_is, _fixed(shape.origin))
            else:
                label = f"obstacle[{k}] (a moving {shape.kind})"
                solid = _Solid(k, label, shape, width, _moved(term), _moving(term))
            self.solids.append(solid)
        self._bodies(scene)

    def _bodies(self, scene) -> None:
        from catenet.scene.shapes import solid_width
        from catenet.scene.shapes.sphere import Sphere

        for ball in scene.bodies:
            sphere = Sphere(center=np.zeros(3), radius=ball.radius)
            label = f"obstacle[{ball.obstacle}] (a moving sphere)"  # (as before the run)
            node = ball.node
            self.solids.append(
                _Solid(
                    ball.obstacle,
                    label,
                    sphere,
                    2.0 * ball.radius,
                    _ball(node),
                    lambda x, t, n=node: x[n],
                )
            )
        shapes = {m.index: m.shape for m in scene.movers if m.free}
        for body in scene.rigid:
            shape = shapes.get(body.obstacle)
            if shape is None or shape.kind == "plane":
                continue
            label = f"obstacle[{body.obstacle}] (a free {shape.kind})"
            frame = body.frame
            self.solids.append(
                _Solid(
                    body.obstacle,
                    label,
                    shape,
                    solid_width(shape),
                    _body(frame),
                    _body_origin(frame, shape),
                )
            )

    def __bool__(self) -> bool:
        return bool(self.solids)

    def see(self, t: float, x) -> None:
        """A state x (N, 3) at time (or load factor) t; in a dynamic run, also the way to
        it from the last one seen: straight, at as many states between as keep each
        node's move relative to a solid below SUBSTEP of the solid's width or of the
        median edge (a ball that passes between the nodes within one step is inside the
        edges on its way)."""
        if not self.solids:
            return
        x = np.array(x, dtype=np.float64)
        if self.last is not None and self.last[1] == t and np.array_equal(self.last[0], x):
            return  # (the end, seen as the last step already: counted once)
        x0, t0 = (x, t) if self.last is None else self.last
        self.last = (x, t)
        for solid in self.solids:
            which, move = solid.near(x0, x, self.edges, t0, t)
            if not which.size:
                continue
            size = SUBSTEP * min(solid.width, self.median)
            farthest = float(move[self.edges[which].ravel()].max())
            n = int(min(MAX_SUBSTEPS, max(1, math.ceil(farthest / size))))
            held = PASS_ALONG if self.apart else PASS_ENDS  # the points the contact holds off
            solid.passed.steps += solid.passes(
                x0, x, t0, t, n, self.edges, which, held, self.dynamic
            )
            if self.apart:
                continue
            crossed = False
            for k in range(1, n if self.dynamic else 1):  # (load steps are no motion)
                s = k / n
                xs = (1.0 - s) * x0 + s * x
                crossed |= solid.see(t0 + s * (t - t0), xs, self.edges, which, True)
            crossed |= solid.see(t, x, self.edges, which, False)
            solid.cut.steps += crossed

    def met(self) -> dict[int, list[str]]:
        """Per obstacle index, how the net met the solid where no barrier saw it: "cut"
        (edges went into it), "through" (a step carried them through each other), or
        both; obstacles with neither are left out."""
        out = {}
        for s in self.solids:
            kinds = [k for k, w in (("cut", s.cut), ("through", s.passed)) if w.edge >= 0]
            if kinds:
                out[s.index] = kinds
        return out

    def warnings(self) -> list[str]:
        """Per solid, one warning where a step carried the net through it and one where
        an edge went into it (none: neither)."""
        out = []
        for s in self.solids:
            c = s.cut
            if s.passed.edge >= 0:
                out.append(self._passed(s))
            if c.edge < 0:
                continue
            at = f"t = {c.when:.6g} s" if self.dynamic else f"load factor {c.when:.6g}"
            many = f", in {c.steps} step{'s' if c.steps != 1 else ''}" if self.dynamic else ""
            deep = _down(c.depth)  # (never shown deeper than it was)
            out.append(
                f"edges cut {deep:.3g} m deep into {s.label} between the nodes it holds "
                f"off (edge {c.edge} at {at}{many}): the net meets solids at its nodes "
                "only, so the strands between them can cut into a solid or let it pass "
                "between the nodes; set solver.edge_contact = true "
                "(docs/guide/edge-contact.md), or refine the net well below the solid's width"
            )
        return out

    def _passed(self, s: _Solid) -> str:
        """The warning of a solid that a step carried the net through."""
        p = s.passed
        many = f"{p.steps} step{'s' if p.steps != 1 else ''}"
        if self.dynamic:
            return (
                f"{p.what} and {s.label} went through each other between two time "
                f"steps (near t = {p.when:.6g} s, {_down(p.depth):.3g} m deep on the "
                f"straight way from one to the next, in {many}): each state keeps them "
                "apart, but the step is too long to follow the motion there, and its "
                "solution lies on the solid's far side; give a shorter solver.dt, or leave "
                "it out (steps chosen by accuracy move a solid near the net by at most a "
                "quarter of its width) (docs/guide/edge-contact.md)"
            )
        return (
            f"the equilibrium at load factor {p.when:.6g} lies on the far side of "
            f"{s.label} from the state before it (the straight way between them takes "
            f"{p.what} {_down(p.depth):.3g} m deep through it, in {many}): load "
            "steps are no motion, and the net may not get there round the solid; check "
            "with a damped run to rest (solver.method = 'dynamic', solver.t_end = 'rest') "
            "or more load steps (solver.steps) (docs/guide/edge-contact.md)"
        )


def _down(value: float) -> float:
    """value rounded down to three significant digits."""
    if not value > 0.0:
        return value
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    return math.floor(value / scale * (1.0 + 1e-12)) * scale


def _as_is(points, x, t):
    return points


def _fixed(origin):
    o = np.asarray(origin, dtype=np.float64)
    return lambda x, t: o


def _ball(node: int):
    return lambda points, x, t: points - x[node]


def _moved(term):
    """World points in a moving obstacle's body frame at its pose at time t."""

    def local(points, x, t):
        center, R = term.pose(t)
        return term.origin + (points - center) @ R

    return local


def _moving(term):
    """Where a moving obstacle's origin is at time t."""
    return lambda x, t: term.pose(t)[0]


def _body(frame):
    """World points in a free body's frame at t = 0: X = c0 + A^T (p - c)."""
    from catenet.kernels.rigid import frame_state

    def local(points, x, t):
        c, A = frame_state(x, frame.nodes, frame.B)
        return frame.center + (points - c) @ A

    return local


def _body_origin(frame, shape):
    """Where a free body's shape origin is now (its pose from its nodes)."""
    from catenet.kernels.rigid import frame_state

    offset = np.asarray(shape.origin, dtype=np.float64) - frame.center

    def origin(x, t):
        c, A = frame_state(x, frame.nodes, frame.B)
        return c + A @ offset

    return origin
