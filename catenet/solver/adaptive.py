"""Time steps chosen by accuracy (``solver.tolerance``, a run with a number for t_end): each step's
local error is estimated by the scheme (``estimate``: the difference between the step's
solution and the polynomial through the last states, extrapolated), measured against the
tolerance, and the step is accepted where that error is within it and retried shorter
where not; the next step is sized so that its error comes out at SAFETY of the tolerance.

The error of a step is the largest of

    |error in x| / (tolerance X),   |error in strain| / (tolerance S),
    |error in a body's momentum| / (MOMENTUM tolerance P),
    |error in a free body's spin| / (MOMENTUM tolerance max(P, its largest spin)),
    |energy the integrator creates or removes in the step| / (its allowance)

with X the motion's reach (the largest mass-weighted RMS displacement from the start so
far, over the free DOFs; at least FLOOR of the net's size L, its bounding box's
diagonal), S the largest strain of an edge so far (at least STRAIN_FLOOR) and P each free
body's or ball's largest momentum |sum m v| so far (at least its mass times FLOOR of
sqrt(|g| L) or L / (t_end - t0) until anything moves, then at least FLOOR of the
largest momentum the run's parts carry, the sum of every free node's |m v|: an 8 t
target at rest, struck by a net thrown at 2 m/s, measures its error against the net's
momentum, not against 1 % of its own mass at the scene's speed); a spin is |sum m r x
v| / rho, about the body's centre over its radius of gyration (catenet/solver/scales.py).
The strain error of
an edge is the positions' error projected on the edge over its rest length; its RMS
over the edges taut at the step's end
(or within their error of it; every edge that is not tension-only), weighted by their
rest lengths, counts: the tensions of the loaded ropes. (The largest edge's error instead
took 1215 steps on the drop at 1e-3, against 360.) The net's velocities are left out:
their error is that of its light nodes ringing across the ropes (100 to 1000 times the
rest on an impact), which no design value depends on and which set every step (the drop
took 783 steps at 1e-3 with them); a transverse swing changes no strain to first order,
and the positions' error keeps the net's motion within the tolerance of its reach. A
body's momentum is where an impact's error shows first, and its errors add up over the
tens of steps of a contact: it is held to MOMENTUM of the tolerance (at the tolerance
itself, a ball dropped 1 m on the ground rebounded 3.6 % slow and two boxes colliding head
on 10 %; at a tenth, the ball's bounce keeps its period to 0.02 %, the boxes their speed
within 5 %). A lumped mass (``[[mass]]``) HEAVY times a typical free node's or more
(catenet/solver/scales.py) is such a body: a weight dropped on a slack rope, undamped,
gained 1 to 2.4 % of its energy where only the positions' error chose the steps (bdf2's
velocities carried the rope's pull on for a few steps after it went slack, where the
jerk drops from k v / m to 0) and the run stopped; with its momentum held, 0.03 % at the
default (tests/solver/test_rope_snap.py). So the default tolerance, 3e-3, asks every
step to keep its positions within 0.3 % of how far the motion has gone, the strains (the
tensions) within 0.3 % of the largest and each body's momentum within 3e-4 of its
largest. (At 5e-3 the drop
below took about 120 steps for 1.4 %, but the ball of tests/solver/test_accuracy.py
lost 4.3 % of its bounce's period, under 1 % at 3e-3, when the estimate chose the steps
through its 0.4 ms bounce; they are now a 64th of it, catenet/solver/strikes.py.)

The energy a step lets the integrator create or remove on its own (the balance's
remainder, catenet/solver/energy.py: ``Ledger.change`` before the step is taken) is
held where no barrier touches at its start or end (or where nodes only rest on fixed
obstacles, ``scales.resting``): the run may move ENERGY (5 %) of the
motion's energy at the default tolerance, in proportion to the tolerance, spread evenly
over its span with what earlier steps saved, and each step at least LEAST of the run's
allowance (``scales.Energy``). The positions' error is local: bdf2 damps within a few
steps a mode it does not resolve, whose error is small from then on, so the steps never
come back to it. A 10 m wire at 10 kN struck by a 20 N step at midspan came out 13.5 %
low at the default (22 steps; 5.8 % at 1e-4) with 130 % of its motion's energy gone; 0.3
% in 980 steps now (tests/solver/test_energy_steps.py), and a roof net's gust peak 5 %
low, now within 1 % (tests/run/test_integrator_loss.py). Where the nodes a barrier holds
carry the motion they chatter on it, a loss no step resolves (the drop below and a rod
landing on the ground, judged there, shrank their steps to round-off): such contact is
left to the momenta and to the strikes. Nodes resting on fixed obstacles are judged
(``scales.resting``: a chain lying on the seabed), a landing's fall not (``landing``).

The corners of what the case prescribes are landed on too: every point of a load's,
gravity's, a support's, a vessel's, an obstacle's or a turned rod end's history, and the
end of a support's ramp (``motions.corners``, ``Term.corners``). A step takes a history at
its end only: one across a corner smooths it, and one across a pulse steps over it whole
(a 20 ms pulse on a hanging weight, at rest before it: the steps had grown to 0.3 s and
the weight never moved, tests/solver/test_corners.py). The scheme restarts its supports'
velocities there (``Scheme.corner``); the step after a corner is judged as any other
(the estimate through it is what shortens the steps where the motion turns). A
prescribed sine (a support's, a vessel's, a wave's) of period T is followed by steps of at most
T / (SINE_STEPS sqrt(TOLERANCE / tolerance)): the error estimate sees the net's
response, not the motion that drives it, and a response too small to matter against the
net's size (a taut wire shaken by 0.5 mm at one end) let the steps grow to 30 periods and
sample the sine (its amplitude 64 % low; within 1 % now, tests/solver/test_corners.py).
bdf2's error in a forced steady state falls with (h / T)^2. For the same reason a
piece of a load's history that changes the factor by its whole range is taken in
RAMP_STEPS steps (a smaller change in proportion fewer, at least one):
the steps grown over a rest took a pulse's rise in one, which takes the load
at its end, so its rising half twice (a weight struck after 1 s at rest 2.2 % fast, a
string 41 % too far; 0.05 % now).

Contact events (a first touch, a release) are landed on (catenet/solver/events.py): a
converged step across one is tried again ending there, before its error is judged, so
that the impact is resolved from its first instant. Nodes that strike a free body or a
ball bringing momentum of their own are resolved through their bounce on its barrier
(catenet/solver/strikes.py): the step is taken again to end just before the strike and
the steps through the bounce are constant, a sixteenth of its length, where the error
estimate, filtered, would let the bounce be damped and the body take too little. No ball
or body near the net moves a quarter of its width in a step (``Strikes.crossing``).

A run starts with ``first`` (``solver.dt`` where given, else FIRST_SHARE of the run's span,
at most ``dt_max``): the scheme's first steps, before it has the states to estimate its
error from, are taken at that length. Steps stay within
[``dt_min``, ``dt_max``]; a step that fails to converge (Newton) is retried at half its
length, as with fixed steps, and the run fails where that is below ``dt_min``; a step at
``dt_min`` whose error is still beyond the tolerance is accepted (the run warns once). A
run that takes more than MAX_TRIES steps fails (a tolerance too tight for it).
The positions' estimate is filtered through the step's own matrix as a first-order
system, (I - b J)^-1 applied to the estimate in positions and velocities (``filtered``;
Hairer & Wanner II, IV.8; Shampine's filter of stiff ODE codes): a mode the step
resolves keeps its error, a stiff one it cannot (a free body's rigidity, a rope's axial
ringing, a node chattering on a barrier) is damped as bdf2 and implicit Euler damp it on
the next steps, so it does not set the steps. The bodies' momenta are not filtered: a
barrier's stiffness is the bounce itself (filtered, two boxes colliding head on at the
default lost 6.4 % of their speed, 4.2 % raw; a ball's bounce on the ground 0.9 % of its
period, 0.8 % raw), and a body's rigidity does not change its momentum. A body's
momentum error counts the momentum of the net's nodes in its barrier with its own
(``Bodies.hold``): a box's held nodes chattering on it pass momentum to and fro, no
error of the motion, which set the steps of the drop below through its contact when
counted on the box alone.

Measured (``python -m benchmarks accuracy``; docs/howto/dynamic-runs.md) on the drop of
benchmarks/peers/mujoco_drop.toml without its dt (the box's momentum at 0.4 s; bdf2 at
fixed 0.31 ms steps: 16.17 kg m/s, at 39 us 16.53): 153 steps, 16.26 kg m/s (150 and
16.27 before its spin was held; 182 steps, 16.22, with the body's momentum error counted
without the nodes it holds); on the
safety net of benchmarks/safety_net.toml and two other drop tests.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError, ConvergenceError
from catenet.model import motions
from catenet.solver.energy import ROUNDOFF
from catenet.solver.events import Events
from catenet.solver.integrators import BDF2, ImplicitEuler
from catenet.solver.scales import ENERGY, FLOOR, Bodies, Edges, Energy, landing, resting
from catenet.solver.stepping import ALLOWANCE
from catenet.solver.strikes import Strikes, Watch

if TYPE_CHECKING:
    from catenet.solver.newton import NewtonResult
    from catenet.solver.stepper import TimeStepper

log = logging.getLogger(__name__)

TOLERANCE = 3e-3  # ErrorControl's default (docs/howto/dynamic-runs.md: what it costs and gives)
SAFETY = 0.9  # the next step aims at SAFETY^(p+1) of the tolerance (Hairer & Wanner)
GROW_MAX = 2.0  # a step at most doubles (bdf2 is zero-stable below 1 + sqrt 2)
SHRINK_MIN = 0.2  # a rejected step shrinks at most fivefold
FIRST_SHARE = 1e-3  # the first step, of the run's span (t_end - t0)
ADAPTIVE = ("implicit_euler", "bdf2")  # the schemes that estimate their error
STRAIN_FLOOR = 1e-4  # S at least this strain (0.01 %)
SINE_STEPS = 64  # the fewest steps a period of a prescribed sine at the default tolerance
RAMP_STEPS = 16  # the fewest steps a load history's changing piece at the default tolerance
MOMENTUM = 0.1  # a body's momentum error against this share of the tolerance
MAX_TRIES = 100_000  # a run that needs more steps fails (a tolerance too tight for it)


def filtered(
    stepper: TimeStepper, b: float, ex: np.ndarray, ev: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The local error (ex, ev) of a step (free DOFs) through the step's own matrix:
    (I - b J)^-1 (ex, ev), J the motion's Jacobian as a first-order system, which is

        ex' = (w + K)^-1 (w ex + M ev / b),   ev' = (ex' - ex) / b

    with W = w + K the step's Newton matrix, w = M (1/b^2 + mu/b) its inertia (the
    filter of stiff ODE codes: Hairer & Wanner, Solving ODEs II, IV.8; Shampine 1984).
    A mode the step resolves (omega b << 1) keeps its error, a stiff one (a rope's
    axial ringing, a free body's rigidity, a node chattering on a barrier) is damped:
    an oscillating one by 1 / sqrt(1 + (omega b)^2) (the eigenvalues of I - b J are
    1 -+ i omega b), as the scheme itself damps it on the next steps."""
    w, m = stepper.inertia.w, stepper.m_free
    fx = stepper.potential.solver.solve(w * ex + (m / b) * ev)
    return fx, (fx - ex) / b


def _scene(stepper: TimeStepper) -> tuple[float, float]:
    """A run's size L (its nodes' bounding box's diagonal) and |g|."""
    nodes, gravity = stepper.net.nodes, stepper.loads.gravity
    size = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0)))
    return size, 0.0 if gravity is None else float(np.linalg.norm(gravity))


def _speed(size: float, gravity: float, span: float) -> float:
    """V's floor: FLOOR of sqrt(|g| L) or L / span, the larger (L = 1 for no size)."""
    size = size if size > 0 else 1.0
    return FLOOR * max(math.sqrt(gravity * size), size / span)


def watch(stepper: TimeStepper, t0: float, t_end: float) -> Watch | None:
    """The strikes on free bodies, balls and fixed obstacles that fixed steps step over,
    said once (catenet/solver/strikes.py); None for a run without any."""
    bodies = Bodies(stepper, _speed(*_scene(stepper), t_end - t0))
    strikes = Strikes.of(stepper.system.terms, bodies, stepper.net.mass, ground=True)
    return None if strikes is None else Watch(strikes, bodies, stepper.free)


def _rms(a: np.ndarray, mass: np.ndarray) -> float:
    """sqrt(sum m a^2 / sum m): a mass-weighted RMS over the free DOFs."""
    total = float(np.sum(mass))
    return math.sqrt(float(np.dot(mass, a * a)) / total) if total > 0 else 0.0


class ErrorControl:
    """Steps from t0 to t_end chosen by the error estimate (module docstring): ``step``
    the next one, ``judge`` after a converged step (whether to accept it, and the next
    step's length), ``failed`` after a step whose Newton failed, ``advance`` the time after
    a step; ``spent`` where the tries exceed the run's budget."""

    adaptive = True

    def __init__(
        self,
        t0: float,
        t_end: float,
        *,
        order: int,
        tolerance: float = TOLERANCE,
        first: float | None = None,
        dt_max: float | None = None,
        dt_min: float | None = None,
        size: float = 1.0,
        gravity: float = 0.0,
    ):
        span = t_end - t0
        self.size = float(size) if size > 0 else 1.0  # L
        self.reach = FLOOR * self.size  # X: grows with the motion's displacements
        self.speed = _speed(self.size, gravity, span)  # V, grows
        self.strain = STRAIN_FLOOR  # S: grows with the largest strain
        self.edges: Edges | None = None  # the net's (``of``): no strain error without
        self.bodies: Bodies | None = None  # the free bodies and balls (``of``)
        self.energy: Energy | None = None  # the integrator's own energy (``of``)
        self.events: Events | None = None  # contact events landed on (``of``)
        self.strikes: Strikes | None = None  # nodes striking bodies, resolved (``of``)
        self.crossing = math.inf  # the longest step no solid passes a strand in (``ahead``)
        self.corners = np.empty(0)  # times a prescribed motion or load turns a corner (``of``)
        self.ramps = np.empty((0, 3))  # the loads' changing pieces, resolved (``of``)
        self.scheme: ImplicitEuler | BDF2 | None = None  # told of each corner (``of``)
        self.t0, self.t_end, self.order = t0, t_end, int(order)
        self.tolerance = float(tolerance)
        self.dt_max = span if dt_max is None else float(dt_max)
        self.dt_min = span / 2.0**40 if dt_min is None else float(dt_min)
        self.h = FIRST_SHARE * span if first is None else float(first)
        self.h = min(self.dt_max, max(self.dt_min, self.h))  # within the bounds
        self.dt = self.h  # the first step (messages; the budget)
        self.quantum = 0.0  # no grid: times are sums of the steps
        self.tries = 0
        self.fails = 0
        self.rejected = 0  # steps that converged but whose error was beyond the tolerance
        self.beyond = 0  # steps accepted at dt_min with their error beyond the tolerance
        self.landed = 0  # steps tried again to end at a contact event
        self.again = False  # the last try was rejected: the next step is not longer
        self.least = self.dt_min  # the shortest the next step may be (``step``)
        self.planned = max(1, math.ceil(span / self.dt_max - 1e-9))
        self.budget = MAX_TRIES + ALLOWANCE  # many short steps may be what the tolerance asks

    @classmethod
    def of(
        cls,
        stepper: TimeStepper,
        first: float,
        t0: float,
        t_end: float,
        tolerance: float,
        dt_max: float | None,
        dt_min: float | None,
    ) -> ErrorControl:
        """The control of a TimeStepper's run (``catenet.solver.dynamic``): its scheme's
        order, the net's size and gravity. ConfigError for a scheme without an estimate."""
        scheme = stepper.scheme
        if not isinstance(scheme, (ImplicitEuler, BDF2)):  # the schemes of ADAPTIVE
            raise ConfigError(
                f"solver.tolerance: steps chosen by accuracy take integrator = 'bdf2' or "
                f"'implicit_euler', not {scheme.name!r} (give solver.dt for fixed steps)"
            )
        if stepper.ledger is not None:
            from catenet.solver.energy import ADAPTIVE_REMEDY

            stepper.ledger.remedy = ADAPTIVE_REMEDY
        scheme.keep = True
        net = stepper.net
        size, gravity = _scene(stepper)
        waves = [p for term in stepper.system.terms for p in term.periods()]
        sines = np.concatenate([motions.periods(stepper.loads), waves])
        if len(sines):  # followed, not sampled (module docstring)
            longest = float(np.min(sines)) / (SINE_STEPS * math.sqrt(TOLERANCE / tolerance))
            dt_max = longest if dt_max is None else min(dt_max, longest)
        out = cls(
            t0, t_end, order=scheme.order, tolerance=tolerance, first=first, dt_max=dt_max,
            dt_min=dt_min, size=size, gravity=gravity,
        )  # fmt: skip
        out.edges = Edges(net, stepper.free)
        out.energy = Energy(t0, t_end, ENERGY * tolerance / TOLERANCE)
        out.scheme = scheme
        out.bodies = Bodies(stepper, out.speed)
        out.strain = max(STRAIN_FLOOR, out.edges.strain(stepper.x))
        g = stepper.loads.gravity  # bends a fall's predicted first touch
        pull = None if g is None else np.where(net.fixed[:, None], 0.0, g)
        out.events = Events(stepper.system.terms, stepper.x, pull)
        corners = [t for term in stepper.system.terms for t in term.corners()]
        corners.extend(motions.corners(stepper.loads))
        every = np.unique(np.asarray(corners, dtype=np.float64))
        out.corners = every[(every > t0) & (every < t_end)]
        ramps = motions.ramps(stepper.loads)
        out.ramps = ramps[(ramps[:, 1] > t0) & (ramps[:, 0] < t_end)]
        spacing = float(np.median(net.rest_length)) if net.n_edges else 0.0
        out.strikes = Strikes.of(stepper.system.terms, out.bodies, net.mass, spacing, True)
        out.ahead(stepper.x, stepper.v)
        return out

    def within(self, stepper: TimeStepper, h_step: float, newton: NewtonResult) -> bool:
        """Whether the converged step of ``h_step`` of a TimeStepper (in its x_trial) is
        within the tolerance, its estimate filtered through the step's matrix (module
        docstring): else the next try is shorter, and ConvergenceError where the run's
        tries are spent."""
        if self.lands(stepper, h_step) or self.strikes_short(stepper, h_step):
            self.tries += 1
            return False
        held = math.inf if self.strikes is None else self.strikes.cap(stepper.t)
        if h_step >= held * (1.0 - 1e-9):  # a bounce's steps: constant, resolving it
            self.tries += 1
            self.h = held
            return True
        free = stepper.free
        y_k, v_k = stepper.x.reshape(-1)[free], stepper.v.reshape(-1)[free]
        y_new = stepper.x_trial.reshape(-1)[free]
        scheme = stepper.scheme
        assert isinstance(scheme, (ImplicitEuler, BDF2))  # ``of`` takes no other
        estimate = scheme.estimate(y_new, y_k, v_k, h_step)
        error = None
        if estimate is not None:
            if newton.iterations == 0:  # no step matrix factorised yet: the filter's
                stepper.potential.factorize(stepper.x_trial, 0.0)
            if self.bodies is not None:
                self.bodies.hold(stepper.x, stepper.x_trial)
            ex, _ = filtered(stepper, scheme.b, *estimate)  # the momenta raw (docstring)
            error = self.error(ex, estimate[1], stepper.m_free, stepper.x_trial)
            error = max(error, self.energy_error(stepper, h_step))
        if self.judge(h_step, error):
            return True
        log.info("t = %.6g: step %.3g beyond the tolerance (%.3g); retrying with %.3g",
                 stepper.t, h_step, error, self.h)  # fmt: skip
        if self.spent():  # (the message ends "the last failed step": this one)
            raise ConvergenceError(
                f"{self.spent_message(stepper.t)}: {h_step:.3g} s, its error {error:.3g} times "
                "the tolerance", iterations=stepper.iterations, state=stepper.x.copy(),
            )  # fmt: skip
        return False

    def energy_error(self, stepper: TimeStepper, h_step: float) -> float:
        """The energy the converged step of ``h_step`` would let its integrator create or
        remove, over its allowance (``Energy``; module docstring); 0 where no balance is
        kept or a barrier touches whose nodes do not rest on fixed obstacles (``resting``);
        a loss up to the energy of nodes landing on them is theirs (``landing``)."""
        ledger, scheme = stepper.ledger, stepper.scheme
        if self.energy is None or ledger is None or not ledger.judged:
            return 0.0
        touching = [] if self.events is None else self.events.touching(stepper.x_trial)
        assert isinstance(scheme, (ImplicitEuler, BDF2))  # ``of`` takes no other
        x, x_new = stepper.x, stepper.x_trial
        v_new = scheme.velocities(x_new, x, stepper.v, stepper.free, h_step)
        if touching and not resting(touching, stepper.net.mass, x_new, v_new):
            return 0.0
        change, motion = ledger.change(stepper, x, x_new, v_new, h_step)
        if touching and change < 0.0:  # (stepper.v: the landing nodes' speed at the start)
            change = min(0.0, change + landing(touching, stepper.net.mass, x, x_new, stepper.v))
        noise = max(ledger.floor, ROUNDOFF * ledger.largest)
        spent = float(ledger.row[-1])
        return self.energy.error(change, motion, spent, noise, stepper.t, h_step, ledger.headroom)

    def lands(self, stepper: TimeStepper, h_step: float) -> bool:
        """Whether the converged step of ``h_step`` crosses a contact event it should end
        at (catenet/solver/events.py): then the next try is that short."""
        if self.events is None:
            return False
        share = self.events.landing(stepper.x, stepper.v, stepper.x_trial, h_step)
        if share is None or share * h_step < self.least:
            return False
        self.h = share * h_step
        self.landed += 1
        return True

    def strikes_short(self, stepper: TimeStepper, h_step: float) -> bool:
        """Whether the converged step of ``h_step`` holds strikes on a body or a fixed
        obstacle that it is too long to resolve (catenet/solver/strikes.py): then the next
        try, and the steps for one bounce after it, are that short."""
        if (bodies := self.bodies) is None or self.strikes is None:
            return False
        strike = self.strikes.step(stepper.x, stepper.v, stepper.x_trial, h_step,
                                   bodies.largest, self.tolerance, bodies.flow)  # fmt: skip
        if strike is None:
            return False
        longest = max(strike.longest, self.least)
        entry = strike.at * h_step  # the first strike, from the step's start
        since = stepper.t + entry - longest  # one resolving step before the strike
        self.strikes.hold(since, stepper.t + entry + strike.tau, longest)
        if h_step <= longest * (1.0 + 1e-9):
            return False
        self.h = max(longest, min(entry - longest, 0.5 * h_step))  # to since, or halved
        return True

    def saw(self, x: np.ndarray, u: np.ndarray, v: np.ndarray, mass: np.ndarray) -> None:
        """The state x (N, 3) of an accepted step with its displacements from the start
        and velocities (free DOFs, their masses): X and V grow to the largest
        mass-weighted RMS of each (V of the bodies'), S to the largest strain."""
        if len(v):
            self.reach = max(self.reach, _rms(u, mass))
            if self.bodies is not None:
                self.bodies.saw(v, x)
        if self.edges is not None:
            self.strain = max(self.strain, self.edges.strain(x))
        if self.events is not None:
            self.events.take(x)

    def error(
        self, ex: np.ndarray, ev: np.ndarray, mass: np.ndarray, x: np.ndarray | None = None
    ) -> float:
        """A step's error over the tolerance from its estimates in x and v (free DOFs,
        their masses) at its end state x (N, 3): the positions' mass-weighted RMS (a
        light node rattling in contact does not set the steps of a heavy body's motion),
        the largest strain error of a taut edge, the bodies' velocities' RMS (module
        docstring)."""
        if not len(ex):
            return 0.0
        ratio = _rms(ex, mass) / (self.tolerance * self.reach)
        if self.edges is not None and x is not None:
            ratio = max(ratio, self.edges.error(x, ex) / (self.tolerance * self.strain))
        if self.bodies is not None:
            ratio = max(ratio, self.bodies.error(ev) / (MOMENTUM * self.tolerance))
        return ratio

    def ahead(self, x: np.ndarray, v: np.ndarray) -> None:
        """The next step's start (x, v) (N, 3): how long it may be before a ball or body
        could pass a strand within it (catenet/solver/strikes.py's ``crossing``)."""
        if self.strikes is not None:
            self.crossing = max(self.dt_min, self.strikes.crossing(x, v, self.h))

    def _corner(self, t: float) -> float | None:
        """The first corner of a prescribed motion or load after t (None: none)."""
        k = int(np.searchsorted(self.corners, t + self._near(t), side="right"))
        return float(self.corners[k]) if k < len(self.corners) else None

    def _ramp(self, t: float) -> float:
        """The longest step from t within a piece of a load's history along which it
        changes: RAMP_STEPS of them over a piece that changes the load by its whole
        range at the default tolerance, in proportion fewer for a smaller change (one
        step of a record's sample that hardly changes), more at a tighter tolerance;
        never below dt_min; inf outside such pieces."""
        near = self._near(t)
        on = (self.ramps[:, 0] <= t + near) & (t + near < self.ramps[:, 1])
        if not on.any():
            return math.inf
        pieces = self.ramps[on]
        steps = RAMP_STEPS * pieces[:, 2] * math.sqrt(TOLERANCE / self.tolerance)
        longest = float(np.min((pieces[:, 1] - pieces[:, 0]) / np.maximum(steps, 1.0)))
        return max(self.dt_min, longest)

    def _near(self, t: float) -> float:
        """How close to a corner a time lies on it (round-off of the times' sums)."""
        return 1e-12 * max(abs(t), self.t_end - self.t0)

    def step(self, t: float) -> float:
        """The next step from t: h, cut short at t_end or at the next corner of a
        prescribed motion or load (landed on: the step across a fairlead's stop took the
        chain's jolt within it), or half what is left where h would leave a sliver
        shorter than itself."""
        corner = self._corner(t)
        left = (self.t_end if corner is None else corner) - t
        self.h = min(self.h, self.crossing, self._ramp(t))  # (no solid past a strand)
        if self.strikes is not None:  # a bounce goes on: its steps resolve it
            self.h = min(self.h, self.strikes.cap(t))
        self.least = self.dt_min  # the shortest this step may be (judge)
        if 2.0 * self.h > left and 0.5 * left < self.dt_min:
            self.least = left  # what is left, in one step: no shorter one fits
        if self.h >= left:
            return left
        return 0.5 * left if 2.0 * self.h > left and self.least < left else self.h

    def judge(self, h_step: float, error: float | None) -> bool:
        """A step of ``h_step`` converged with ``error`` (its estimate over the tolerance;
        None: the scheme cannot estimate it yet): whether it is accepted; the next step's
        length either way."""
        self.tries += 1
        if error is None or not math.isfinite(error):
            if error is not None:  # a NaN estimate: shorten, as for a failure
                self.h = max(self.dt_min, 0.5 * h_step)
                self.rejected += 1
                return False
            return True  # the scheme's start: keep h
        factor = SAFETY * error ** (-1.0 / (self.order + 1)) if error > 0 else GROW_MAX
        if error > 1.0:  # never longer than 0.9 h
            self.rejected += 1
            self.h = max(self.dt_min, h_step * max(SHRINK_MIN, min(factor, 0.9)))
            self.again = True
            if h_step <= self.least * (1.0 + 1e-9):  # taken: no shorter step (said once)
                self.beyond += 1
                self.rejected -= 1
                if self.beyond == 1:
                    log.warning(
                        "a step at solver.dt_min = %.3g s has an error %.3g times "
                        "solver.tolerance = %g: taken, as every such step (a tolerance "
                        "tighter than dt_min allows: a smaller dt_min, or a larger "
                        "tolerance)", self.dt_min, error, self.tolerance,
                    )  # fmt: skip
                return True
            return False
        if self.again:  # just after a rejection: not longer (Hairer & Wanner)
            factor = min(factor, 1.0)
        self.h = min(self.dt_max, max(self.dt_min, h_step * min(GROW_MAX, factor)))
        self.again = False
        return True

    def failed(self, h_step: float) -> bool:
        """A step of ``h_step`` failed to converge: the next try has half its length.
        False when that is below ``dt_min`` (the run fails)."""
        self.h = 0.5 * h_step
        self.tries += 1
        self.fails += 1
        self.again = True
        return not self.h < self.dt_min

    def accepted(self) -> None:
        """Nothing to count beyond ``judge``."""

    def spent(self) -> bool:
        return self.tries > self.budget

    def spent_message(self, t: float) -> str:
        return (
            f"dynamic run stopped at t = {t:.6g} s of solver.t_end = {self.t_end:g} s: "
            f"{self.tries} steps tried ({self.fails} failed, {self.rejected} beyond "
            f"solver.tolerance = {self.tolerance:g}) would not finish in reasonable time "
            "(a model too stiff or too fast for this tolerance: try a larger "
            "solver.tolerance or solver.dt_min); the last failed step"
        )

    def advance(self, t: float, h_step: float) -> float:
        """The time after the step of ``h_step`` from t (t_end exactly at the end)."""
        end = t + h_step
        if h_step == self.t_end - t or end >= self.t_end * (1 - 1e-12):
            return self.t_end
        corner = self._corner(t)
        if corner is None or abs(end - corner) > self._near(t):
            return end
        if self.scheme is not None:  # its supports' velocities restart there
            self.scheme.corner()
        return corner
