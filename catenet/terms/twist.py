"""Twist of isotropic rods: E = sum over twisted segments of (Theta(x) - Theta_0 + Phi)^2
/ (2 C), the twist eliminated quasistatically (``catenet.kernels.twist`` derives it and
its exact derivatives; ``catenet.model.twist`` says which chains twist).

Guarantee: the energy, gradient and Hessian are exact (the gradient and Hessian of the
total twist Theta by parallel transport, checked against finite differences) for every
state where no two consecutive tangents of a segment (nor an end edge and its clamp)
fold back on each other, and where a segment ending at a rigid joint does not have its
partner member turned onto its axis; there the twist is undefined and the energy is inf. The twist
has no rotational inertia here (it is uniform along a segment at every instant: torsional
waves, far faster than bending ones in a slender rod, are not resolved); the modes keep
the twist angles with their inertia (``catenet.model.torsion``). Theta is
tracked continuously from the last accepted state (``begin_step``), so a rod twisted by
many turns keeps its count; the term is not convex. A static run imposes the twist Phi
in full from its start (a straight rod is an equilibrium under any twist: where it
buckles, that equilibrium turns unstable); a dynamic run takes it along each end's
history.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np

from catenet.kernels.twist import twist_angles, twist_frames, twist_gradient, twist_hessian
from catenet.model.histories import History
from catenet.model.twist import Twists
from catenet.terms.base import Term, register
from catenet.terms.bending import dense_blocks

#: The clamps' turn [rad] of ``Twist.end_moments``' central differences.
TURN = 1e-5
#: (segment, angle [rad], history or None) of each turned clamp.
Imposed = tuple[int, float, History | None]


def _mean_edge(x: np.ndarray, nodes: np.ndarray, closed: bool) -> float:
    """The mean edge length of a chain of nodes (a ring's closing edge included)."""
    chain = np.concatenate([nodes, nodes[:1]]) if closed else nodes
    return float(np.mean(np.linalg.norm(np.diff(x[chain], axis=0), axis=1)))


def _turn(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation matrix of ``angle`` about the unit ``axis`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


@register("twist")
class Twist(Term):
    """The rods' twist energy (module docstring)."""

    role = "internal"
    convex = False
    structural = True
    driven = True  # a turned end's history does work (the energy balance counts it)

    def __init__(
        self, twists: Twists, n_nodes: int, x0: np.ndarray, imposed: Sequence[Imposed] = ()
    ):
        self.twists = twists
        self.n_nodes = int(n_nodes)
        self.imposed = tuple(imposed)
        self._time: float | None = None  # a dynamic step's end (None: static, all of Phi)
        self._start: float | None = None  # ... and its start
        self._run: float | None = None  # a dynamic run's start time (static solves in it)
        n_edges = len(twists.edges)
        self._ref = np.zeros((n_edges, 3))
        self._tau = np.zeros((n_edges, 3))
        x0 = np.ascontiguousarray(x0, dtype=np.float64)
        self._theta = np.zeros(len(twists))
        bounds = zip(twists.start[:-1], twists.start[1:], twists.closed, strict=True)
        self._lbar = np.array([_mean_edge(x0, twists.nodes[a:b], c) for a, b, c in bounds])
        self._frames(x0, self._theta)
        self.offset = self._angles(x0)  # untwisted as given (a ring: its holonomy)
        self._theta = self.offset.copy()
        self._frames(x0, self._theta)

    def _geometry(self):
        t = self.twists
        return t.nodes, t.start, t.closed, t.head, t.tail

    def _frames(self, x: np.ndarray, theta: np.ndarray) -> None:
        t = self.twists
        twist_frames(
            x, *self._geometry(), t.head_dir, theta, self._ref, self._tau, t.first,
            t.partner, t.phase,
        )  # fmt: skip

    def _angles(self, x: np.ndarray, **turned: np.ndarray) -> np.ndarray:
        """Theta per segment at x; ``turned``: head, tail, head_dir or tail_dir in place
        of the clamps' own (``end_moments``)."""
        t = self.twists
        out = np.zeros(len(t))
        frames = {"head": t.head, "tail": t.tail, "head_dir": t.head_dir, "tail_dir": t.tail_dir}
        frames.update(turned)
        twist_angles(
            np.ascontiguousarray(x, dtype=np.float64),
            t.nodes,
            t.start,
            t.closed,
            frames["head"],
            frames["tail"],
            frames["head_dir"],
            frames["tail_dir"],
            self._ref,
            self._tau,
            t.first,
            t.partner,
            t.phase,
            out,
        )
        return out

    def end_moments(self, x: np.ndarray) -> np.ndarray:
        """(S, 2, 3) the moment [N m] each open segment's clamps exert on it at x, its first
        end's and its last's: dE/dphi for a turn phi of the clamp (its tangent and director
        together), M dTheta/dphi, with dTheta/dphi by central differences of Theta over
        turns of TURN rad (to about 1e-9 of M). About the rod's axis it is the twisting
        moment, -M at the first end and +M at the last (the end's tangent along the
        chain); across it, what the clamp adds where the end edge leaves its held
        direction. A ring's rows are 0 (no support holds it)."""
        t = self.twists
        x = np.ascontiguousarray(x, dtype=np.float64)
        m = self.moments(x)
        out = np.zeros((len(t), 2, 3))
        for end, (tangent, director) in enumerate(((t.head, t.head_dir), (t.tail, t.tail_dir))):
            for axis in range(3):
                theta = []
                for sign in (1.0, -1.0):
                    turn = _turn(np.eye(3)[axis], sign * TURN)
                    turned = {"head" if end == 0 else "tail": tangent @ turn.T}
                    turned["head_dir" if end == 0 else "tail_dir"] = director @ turn.T
                    theta.append(self._angles(x, **turned))
                out[:, end, axis] = m * (theta[0] - theta[1]) / (2.0 * TURN)
        out[t.closed] = 0.0
        out[t.partner >= 0] = 0.0  # an end on a rigid joint: no support
        return out

    def joint_members(self) -> frozenset:
        """(joint node, member's other node) of every segment end on a rigid joint: the
        members whose twist their joint holds."""
        t = self.twists
        out = set()
        for s in np.flatnonzero((t.partner >= 0).any(axis=1) & ~t.closed):
            lo, hi = int(t.start[s]), int(t.start[s + 1])
            if t.partner[s, 0] >= 0:
                out.add((int(t.nodes[lo]), int(t.nodes[lo + 1])))
            if t.partner[s, 1] >= 0:
                out.add((int(t.nodes[hi - 1]), int(t.nodes[hi - 2])))
        return frozenset(out)

    def imposed_twist(self, time: float | None = None) -> np.ndarray:
        """Phi per segment [rad] at ``time`` (None: now): each turned end's angle, in full
        (static) or times its history (dynamic; a static solve in a dynamic run, such as
        its equilibrium start, at the run's start time)."""
        if time is None:
            time = self._time if self._time is not None else self._run
        phi = np.zeros(len(self.twists))
        for s, angle, history in self.imposed:
            if time is None or history is None:
                phi[s] += angle
            else:
                phi[s] += angle * history(time)
        return phi

    def moments(self, x: np.ndarray, time: float | None = None) -> np.ndarray:
        """The twisting moment M [N m] of every segment at x (> 0: right-handed), at
        ``time`` (None: now)."""
        twist = self._angles(x) - self.offset + self.imposed_twist(time)
        return twist / self.twists.compliance

    def begin_run(self, x: np.ndarray, t: float) -> None:
        """A dynamic run's start at time t: the turned ends where their histories are."""
        self._time = self._start = self._run = float(t)

    def settle_time(self) -> float:
        """The last point of the turned ends' histories (0: none)."""
        return max([h.end for _, _, h in self.imposed if h is not None], default=0.0)

    def corners(self) -> tuple[float, ...]:
        """The points of the turned ends' histories."""
        return tuple(t for _, _, h in self.imposed if h is not None for t in h.times)

    def driven_work(self, x_old: np.ndarray, x_new: np.ndarray, commit: bool = True) -> float:
        """1/2 (M_n + M_n+1) (Phi_n+1 - Phi_n), summed over the segments, for the step of
        the last ``begin_step``."""
        if self._start is None or self._time is None:
            return 0.0
        before, after = self.imposed_twist(self._start), self.imposed_twist(self._time)
        m = self.moments(x_old, self._start) + self.moments(x_new, self._time)
        return float(0.5 * np.sum(m * (after - before)))

    def begin_step(self, x: np.ndarray, time: float | None, start: float | None = None) -> None:
        """The frames carried to the last accepted state x, keeping the twist's count."""
        self._time, self._start = time, start
        x = np.ascontiguousarray(x, dtype=np.float64)
        theta = self._angles(x)
        if np.all(np.isfinite(theta)):
            self._theta = theta
            self._frames(x, theta)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._pattern

    @cached_property
    def _pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """Every segment's dense block of its nodes' DOFs, row-major: its chain's, then
        the partners of its ends on rigid joints."""
        return dense_blocks(self.local_nodes(s) for s in range(len(self.twists)))

    def local_nodes(self, s: int) -> np.ndarray:
        """Segment s's nodes as its kernels order them: its chain's, then the partners
        of its ends on rigid joints (``catenet.kernels.twist.segment_gradient``)."""
        t = self.twists
        chain = t.nodes[t.start[s] : t.start[s + 1]]
        return np.concatenate([chain, t.partner[s][t.partner[s] >= 0]])

    def energy(self, x: np.ndarray) -> float:
        m = self.moments(x)
        return float(0.5 * np.sum(self.twists.compliance * m * m))

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        m = self.moments(x)
        x = np.ascontiguousarray(x, dtype=np.float64)
        twist_gradient(x, *self._geometry(), self.twists.partner, m, grad)
        return float(0.5 * np.sum(self.twists.compliance * m * m))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        m = self.moments(x)
        twist_hessian(
            np.ascontiguousarray(x, dtype=np.float64),
            *self._geometry(),
            self.twists.partner,
            m,
            self.twists.compliance,
            values,
        )

    @cached_property
    def _scale(self) -> np.ndarray:
        """Per node, the scale of its Hessian diagonal [N/m]: the segment's mean GJ over
        its mean edge length squared, count / (C lbar)."""
        t = self.twists
        out = np.zeros(self.n_nodes)
        for s in range(len(t)):
            nodes = t.nodes[t.start[s] : t.start[s + 1]]
            count = len(nodes) - (0 if t.closed[s] else 1)
            out[nodes] += count / (t.compliance[s] * self._lbar[s] ** 2)
        return out

    def stiffness(self) -> np.ndarray:
        return self._scale

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """A coordinate error eps |x| moves a node's force by its stiffness times it;
        Theta, a sum of V angles, carries V eps: the energy M V eps (levels in units of
        eps)."""
        size = float(np.max(np.abs(x)))
        level = float(np.linalg.norm(self._scale)) * size
        t = self.twists
        vertices = np.diff(t.start) + 1 - 2 * t.closed
        m = self.moments(x)
        finite = np.isfinite(m)
        return level, abs(energy) + float(np.sum(np.abs(m[finite]) * vertices[finite]))

    def node_roundoff(self, x: np.ndarray, energy: float) -> np.ndarray:
        return self._scale * float(np.max(np.abs(x)))
