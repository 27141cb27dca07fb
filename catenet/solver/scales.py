"""What the error of a step chosen by accuracy is measured against (catenet/solver/adaptive.py,
whose docstring says why): the net's edges, for the error in strain, the free bodies,
balls and heavy lumped masses, for the error in momentum, and the motion's energy, for
the energy the integrator creates or removes."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.model.motions import drive_speed

if TYPE_CHECKING:
    from catenet.model.net import Net
    from catenet.solver.stepper import TimeStepper
    from catenet.terms import Term

FLOOR = 1e-2  # X and V at least this share of L and of sqrt(|g| L), L / (t_end - t0)
STILL = 1e-6  # a body's momentum scale at least this share of its mass times V's floor
HEAVY = 10.0  # a node's lumped mass this many times a typical node's: a body (``_heavy``)
ENERGY = 5e-2  # the integrator's own energy over a run, of the motion's, at the default
LEAST = 1e-3  # a step's energy allowance at least this share of the run's (``Energy``)


class Edges:
    """A net's edges for the strain error (catenet/solver/adaptive.py): node pairs
    (M, 2), rest lengths, which are tension-only; ``free`` maps a free DOF's error into
    the net's (N * 3) flat positions."""

    def __init__(self, net: Net, free: np.ndarray):
        self.i, self.j = net.edges[:, 0], net.edges[:, 1]
        self.l0 = np.asarray(net.rest_length, dtype=np.float64)
        self.only = np.asarray(net.law.tension_only, dtype=bool)
        self.free = free
        self.n = len(net.nodes)

    def strain(self, x: np.ndarray) -> float:
        """The largest strain of an edge in state x (N, 3), 0 for none."""
        if not len(self.l0):
            return 0.0
        d = x[self.j] - x[self.i]
        return max(0.0, float(np.max(np.sqrt(np.einsum("ij,ij->i", d, d)) / self.l0 - 1.0)))

    def error(self, x: np.ndarray, ex: np.ndarray) -> float:
        """The RMS error in strain along the edges taut in state x (N, 3) (weighted by
        their rest lengths), from the error ``ex`` of the free DOFs' positions."""
        if not len(self.l0):
            return 0.0
        full = np.zeros(3 * self.n)
        full[self.free] = ex
        e = full.reshape(-1, 3)
        d = x[self.j] - x[self.i]
        length = np.sqrt(np.einsum("ij,ij->i", d, d))
        length[length == 0.0] = 1.0
        de = np.abs(np.einsum("ij,ij->i", d, e[self.j] - e[self.i])) / (length * self.l0)
        taut = ~self.only | (length / self.l0 - 1.0 + de > 0.0)
        w = self.l0 * taut  # the RMS along the taut rope
        tot = float(w.sum())
        return math.sqrt(float(np.dot(w, de * de)) / tot) if tot > 0 else 0.0


GAIN = 0.5  # a step may create at most this share of what the energy verdict leaves


class Energy:
    """The energy a run's steps chosen by accuracy may let the integrator create or
    remove (catenet/solver/adaptive.py): ``share`` of the motion's energy over the run
    (ENERGY at the default tolerance, in proportion to the tolerance), spent no faster
    than evenly over its span, except what earlier steps left unspent; each step at
    least LEAST of a span's allowance, so that a loss that no shorter step makes much
    smaller (a cord that snaps taut within the step) does not shrink the steps to
    nothing. The motion's energy is the largest kinetic energy so far and what damping,
    drag and friction took (the warning's, ``catenet.run.integrator_advice``)."""

    def __init__(self, t0: float, t_end: float, share: float):
        self.t0, self.span, self.share = float(t0), float(t_end - t0), float(share)
        self.start: float | None = None  # the remainder at the first step judged

    def error(self, change: float, motion: float, spent: float, noise: float, t: float,
              h: float, headroom: float = math.inf) -> float:  # fmt: skip
        """A step's energy error over its allowance: ``change`` the energy it creates
        (< 0: removes), ``motion`` the motion's energy after it, ``spent`` what the run's
        integrator created or removed before it (the balance's remainder; what it held
        at the first step judged is the scheme's start's, not counted), ``noise`` the
        energies' round-off (no error below it), the step from t of h."""
        if self.start is None:  # the scheme's start (implicit Euler's first step) is
            self.start = spent  # not spent: a ball falling from rest lost a quarter of
        spent -= self.start  # its motion in it, and the next steps shrank to 4 us
        if not abs(change) > noise:
            return 0.0
        run = self.share * motion
        evenly = run * max(h / self.span, LEAST)
        saved = run * (t + h - self.t0) / self.span - abs(spent)
        ratio = abs(change) / max(evenly, saved, noise)
        if change > 0.0:  # never more than the verdict leaves (``Ledger.headroom``): a
            ratio = max(ratio, change / max(GAIN * headroom, noise))  # line let go in
        return ratio  # water gained 2.4 % of its energy at 0.14 s steps and was stopped


class Bodies:
    """The free bodies, balls and heavy lumped masses (``_heavy``) of a run for the
    momentum error (catenet/solver/adaptive.py): each one's free-DOF positions (k, 3) in
    the free DOFs' vector (a free body's four frame nodes, a ball's or a mass's node),
    its masses, and its momentum
    scale ``largest``: the largest momentum |sum m v| it has had, at least FLOOR of the
    run's largest ``flow`` (the sum of every free node's |m v|: the momentum its parts
    carry), and before anything moves ``floor`` times its mass; never below STILL of
    that (a body resting on a net from its static equilibrium: round-off's motion alone,
    whose momentum error no step length can bring below round-off's). A body's momentum
    error counts with it the net's nodes inside its barrier (``hold``): momentum passing
    to and fro between a body and the nodes it holds (a box's net chattering on its
    barrier) is no error of the motion.

    A free body's spin is held as its momentum is: its angular momentum about its centre
    of mass over its radius of gyration, |sum m r x v| / rho (rho^2 = sum m |r|^2 / sum
    m, r from the centre: a momentum), its error against ``turning``, the larger of its
    largest spin so far and its momentum's scale (a box dropped flat, which never spins,
    took 424 steps against 150 with its spin's error measured against FLOOR of
    ``flow``). A pipe dropped across a net with edge contact, yawed by the cords, spun
    on at the default tolerance with three times the energy of its converged spin and
    rebounded 12 % slow, where only its momentum was held (tests/solver/test_spin.py).

    Where supports move on a prescribed path, a body's momentum scale is never below
    FLOOR of its mass times the path's speed (``motions.drive_speed``): a weight hung at
    rest from its static equilibrium (its scale round-off's) whose support started to
    rise through a dashpot, or was shaken by a sine, had its first steps' momentum error
    measured against round-off, and the steps shrank until the run failed."""

    def __init__(self, stepper: TimeStepper, floor: float):
        from catenet.terms.body import Ball
        from catenet.terms.rigid import Rigidity
        from catenet.terms.rigid_contact import BodyContact

        net, free = stepper.net, stepper.free
        where = np.full(3 * len(net.nodes), -1)
        where[free] = np.arange(len(free))
        frames = [
            np.asarray(t.frame.nodes) for t in stepper.system.terms if isinstance(t, Rigidity)
        ]
        framed = set(int(k) for nodes in frames for k in nodes)
        balls = [np.array([k]) for k in range(net.n_net, len(net.nodes)) if k not in framed]
        balls += [np.array([k]) for k in _heavy(net, free, framed)]
        self.dofs = []
        self.heads: list[int] = []  # each one's first node (a frame's centre, a ball's)
        for nodes in frames + balls:
            dofs = where[3 * nodes[:, None] + np.arange(3)]
            if np.all(dofs >= 0):
                self.dofs.append(dofs)
                self.heads.append(int(nodes[0]))
        m = stepper.m_free
        self.mass = [m[d] for d in self.dofs]
        self.m_free, self.where, self.free = m, where, free
        self.y: np.ndarray | None = None  # the free DOFs' positions at the step's end
        self.barriers: list[list[Any]] = [[] for _ in self.dofs]  # each one's, with the net
        for t in stepper.system.terms:
            head = -1
            if isinstance(t, BodyContact) and t.dhat > 0:
                head = int(np.asarray(t.frame.nodes)[0])
            elif isinstance(t, Ball):
                head = int(t.center)
            if head in self.heads:
                self.barriers[self.heads.index(head)].append(t)
        self.held = [np.zeros(0, dtype=np.int64) for _ in self.dofs]  # (``hold``)
        drive = drive_speed(stepper.loads, net)  # the supports' prescribed speed
        self.largest = [floor * float(ms[:, 0].sum()) for ms in self.mass]
        self.least = [
            max(STILL * p, FLOOR * drive * float(ms[:, 0].sum()))
            for p, ms in zip(self.largest, self.mass, strict=True)
        ]
        self.largest = [max(p, q) for p, q in zip(self.largest, self.least, strict=True)]
        self.own = [0.0] * len(self.dofs)  # each one's largest |sum m v| so far
        self.spun = [0.0] * len(self.dofs)  # ... and spin, |sum m r x v| / rho
        self.turning = list(self.largest)  # the spins' scale, as ``largest`` the momenta's
        self.flow = 0.0  # the largest sum of the free nodes' |m v| so far
        self.node_mass = m[::3]  # (the free DOFs come in threes, a node's x, y, z)

    def momenta(self, v: np.ndarray) -> list[float]:
        """|sum m v| of each body from the free DOFs' velocities (or their errors) v."""
        return [
            float(np.linalg.norm(np.sum(ms * v[d], axis=0)))
            for d, ms in zip(self.dofs, self.mass, strict=True)
        ]

    def spins(self, v: np.ndarray, y: np.ndarray) -> list[float]:
        """|sum m r x v| / rho of each body of more than one node (0 for a ball) from
        the free DOFs' velocities v at positions y."""
        return [
            _spin(ms, y[d], v[d]) if len(d) > 1 else 0.0
            for d, ms in zip(self.dofs, self.mass, strict=True)
        ]

    def saw(self, v: np.ndarray, x: np.ndarray | None = None) -> None:
        """The velocities v (free DOFs) of an accepted step at x (N, 3): the scales grow."""
        self.own = [max(a, b) for a, b in zip(self.own, self.momenta(v), strict=True)]
        if x is not None:
            spins = self.spins(v, x.reshape(-1)[self.free])
            self.spun = [max(a, b) for a, b in zip(self.spun, spins, strict=True)]
        speeds = np.sqrt(np.einsum("ij,ij->i", v.reshape(-1, 3), v.reshape(-1, 3)))
        self.flow = max(self.flow, float(np.dot(self.node_mass, speeds)))
        if self.flow > 0.0:
            self.largest = [
                max(p, FLOOR * self.flow, q) for p, q in zip(self.own, self.least, strict=True)
            ]
            self.turning = [max(p, q) for p, q in zip(self.spun, self.largest, strict=True)]

    def hold(self, x0: np.ndarray, x1: np.ndarray) -> None:
        """The free DOFs (k, 3) of the net's nodes within each body's barrier (dhat) at
        a step's start x0 or end x1 (N, 3): the nodes it holds (``error``)."""
        self.y = x1.reshape(-1)[self.free]
        for k, terms in enumerate(self.barriers):
            near = [np.asarray(t.nodes)[(t.gap(x0) < t.dhat) | (t.gap(x1) < t.dhat)] for t in terms]
            nodes = np.unique(np.concatenate(near)) if near else np.zeros(0, dtype=np.int64)
            dofs = self.where[3 * nodes[:, None] + np.arange(3)]
            self.held[k] = dofs[np.all(dofs >= 0, axis=1)]

    def error(self, ev: np.ndarray) -> float:
        """The largest error in a body's momentum, with the nodes it holds (``hold``),
        over its largest momentum so far, and in its spin over its ``turning``."""
        out, y = 0.0, self.y
        bodies = zip(self.dofs, self.mass, self.held, self.largest, self.turning, strict=True)
        for d, ms, held, scale, turning in bodies:
            mh = self.m_free[held]
            moved = np.sum(ms * ev[d], axis=0) + np.sum(mh * ev[held], axis=0)
            out = max(out, float(np.linalg.norm(moved)) / scale)
            if y is not None and len(d) > 1:  # its spin, with the nodes it holds
                centre, rho = _centre(ms[:, 0], y[d])
                spin = _turn(ms, y[d], ev[d], centre) + _turn(mh, y[held], ev[held], centre)
                out = max(out, float(np.linalg.norm(spin)) / rho / turning)
        return out


def _centre(m: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    """The centre of mass of nodes of masses m (k,) at y (k, 3), and their radius of
    gyration about it (never 0)."""
    centre = m @ y / m.sum()
    r = y - centre
    rho = math.sqrt(float(m @ np.einsum("ij,ij->i", r, r)) / float(m.sum()))
    return centre, max(rho, 1e-300)


def _turn(ms: np.ndarray, y: np.ndarray, v: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """sum m (y - centre) x v (3,) of DOFs of masses ms (k, 3) at y with velocities v."""
    r = y - centre
    ry, rz, vy, vz = r[:, 1], r[:, 2], v[:, 1], v[:, 2]  # (``np.cross``'s set-up costs
    rx, vx = r[:, 0], v[:, 0]  # more than its arithmetic, once per step and body)
    turn = np.array([ry * vz - rz * vy, rz * vx - rx * vz, rx * vy - ry * vx])
    out: np.ndarray = np.einsum("ij,ji->j", ms, turn)
    return out


def _spin(ms: np.ndarray, y: np.ndarray, v: np.ndarray) -> float:
    """A body's spin |sum m r x v| / rho from its DOFs' masses ms (k, 3), positions y
    and velocities v (k, 3)."""
    centre, rho = _centre(ms[:, 0], y)
    return float(np.linalg.norm(_turn(ms, y, v, centre))) / rho


def _heavy(net: Net, free: np.ndarray, framed: set[int]) -> list[int]:
    """The net's nodes whose lumped mass (``[[mass]]``) is HEAVY times a typical moving
    node's mass or more (the lower median of the free nodes' masses; for a net with one
    free node, its own cables' share): a weight on a rope, a net's corner masses, each a
    body for the momentum error (catenet/solver/adaptive.py). A mass added to every node
    is the net's own."""
    if net.point_mass is None:
        return []
    moving = np.unique(free // 3)
    moving = moving[moving < net.n_net]
    if not len(moving):
        return []
    mass, point = net.mass[moving], net.point_mass[moving]
    typical = float(np.sort(mass)[(len(mass) - 1) // 2]) if len(mass) > 1 else mass[0] - point[0]
    heavy = (point > 0.0) & (point >= HEAVY * typical)
    return [int(k) for k, h in zip(moving, heavy, strict=True) if h and int(k) not in framed]


#: nodes on fixed obstacles carrying at most this share of the kinetic energy (``resting``)
RESTING = 0.1


def resting(touching: list[Term], mass: np.ndarray, x: np.ndarray, v: np.ndarray) -> bool:
    """Whether the barriers ``touching`` hold nodes at rest on fixed obstacles: each a
    fixed obstacle, the nodes within its reach at x (N, 3) carrying at most RESTING of
    the kinetic energy (velocities v, masses ``mass``): a chain lying on the seabed,
    where the energy is judged (its snatch came out 28 % low without), not a rod
    landing on the ground or a box on a net, whose nodes chatter on the barrier."""
    from catenet.terms.contact import Obstacle  # (a run without contact never loads it)

    kinetic = mass * np.einsum("ij,ij->i", v, v)
    held = np.zeros(len(mass), dtype=bool)
    for term in touching:
        if not isinstance(term, Obstacle) or term.driven:
            return False
        held[term.nodes[term.gap(x) < term.dhat]] = True
    return float(kinetic[held].sum()) <= RESTING * float(kinetic.sum())


def landing(
    touching: list[Term], mass: np.ndarray, x: np.ndarray, x_new: np.ndarray, v: np.ndarray
) -> float:
    """The kinetic energy of the nodes that land on the fixed obstacles ``touching`` in
    the step from x to x_new (N, 3): sum 1/2 m a^2 over the nodes within reach at x_new,
    a their speed toward the obstacle at the step's start (the rate of their gap along
    v). A node's landing on a barrier is a bounce the steps do not resolve, and bdf2
    takes its fall's energy: a chain landing on the seabed at tolerance 3e-4 lost a
    quarter to half a joule in every step however short, its node 1e-6 m above the
    plane at 0.37 m/s (the log barrier's stiffness grows as the gap shrinks), and the
    steps shrank to round-off. Up to this energy, a step's loss is the landing's."""
    from catenet.terms.contact import Obstacle

    out = 0.0
    for term in touching:
        assert isinstance(term, Obstacle)  # (``resting``: fixed obstacles only)
        near = term.gap(x_new) < term.dhat
        if not near.any():
            continue
        nodes = term.nodes[near]
        speed = float(np.max(np.abs(v[nodes]), initial=0.0))
        if not speed > 0.0:
            continue
        s = 1e-6 * term.dhat / speed  # a probe of a millionth of the reach
        moved = x.copy()
        moved[nodes] += s * v[nodes]
        rate = (term.gap(moved)[near] - term.gap(x)[near]) / s
        approach = np.maximum(-rate, 0.0)
        out += 0.5 * float(np.sum(mass[nodes] * approach * approach))
    return out
