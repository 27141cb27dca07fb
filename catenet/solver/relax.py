"""The pseudo-time steps of dynamic relaxation to rest (``solver.t_end = "rest"``).

A run to rest follows the damped motion only as a path to the static equilibrium: its
time is pseudo-time, and the step may grow once the motion has settled into a decay.
After every accepted step the next step is set from the static residual
r_k = |grad E - f| of the free DOFs, as in switched evolution relaxation (Mulder & van
Leer 1985; pseudo-transient continuation, Kelley & Keyes 1998), and from the Newton
iterations the step took:

    h_{k+1} = h_k * max(g, min(2, r_{k-1} / r_k)),  g = 2 after at most EASY iterations, else 1,

so the step doubles while Newton converges easily, grows with the decay of the residual
otherwise and is held while the residual rises (a net still falling onto its supports:
pure SER would keep it at dt). After more than HARD iterations it is halved, never below
``dt`` by this rule, and it never exceeds ``dt * GROWTH_CAP``. A failed step is retried
with half its length, as in a run to a given end time. As h grows the
implicit Euler step tends to a Newton step on the static equilibrium (its inertia and
damping terms, M (1/h^2 + mu/h), vanish), so the run ends in a few dozen steps where
steps of ``dt`` would need thousands. ``max_steps`` bounds the accepted steps: a run
whose motion does not die out (no damping, a limit cycle) fails with a message instead
of running for ever.

The run goes through the static solve's continuations, each stage to rest loosely
(STAGE_RTOL): a net that starts slack first with its tension-only law smoothed (by mu,
the largest slack strain at the start, then mu/10 and mu/100: every edge keeps some
stiffness, so Newton does not bounce between slack and taut edges), a nearly
inextensible net with its axial stiffness scaled down
(Newton's quadratic model of a stiff chain holds only for rotations below the square
root of its strain), then obstacles whose barrier is narrower than the scene calls for
(``Obstacle.stages``) with their wider barriers first. A chain that falls onto a bed
then lands as a softer chain on a cushion instead of a barrier a fraction of a
millimetre thick, and each later stage moves it only a little.
Stages are used where nothing moves by prescription (no time history, no moving
support, obstacle or body); their steps go on growing from where they were.

Two things keep a long stiff line (a chain of 10^4 edges on a seabed) from crawling:

- Newton starts a step from the last state instead of the scheme's predictor
  x_k + h v_k where the step's potential is lower there (``TimeStepper.start_still``).
  The first step after the chain's stiffness is raised fiftyfold recoils it by metres;
  extrapolating that motion put Newton's next start metres off, where it failed within
  max_iter at every h down to 2e-4 s (from 2 s): a thousand steps of 18 iterations,
  130 s of the 10^4-edge line's run. From the last state the step converges in 7
  iterations at h = 2 s.
- The rest test holds the static residual to rtol or, where every DOF's residual is
  within it, to its round-off floor (``dynamic.at_rest``; as a static solve does): rtol
  times the load scale of that line (2e-3 N) is below the round-off of its forces
  (16 eps EA |x| / l0 = 0.02 N per DOF), and its run went on at the largest step, one
  Newton iteration each, the residual at 0.02 N, until max_steps. The inertial force
  is still held to rtol, so a state that still moves is never at rest.

With both, the 10^4-edge line comes to rest in 43 steps, to 1e-7 of the closed form's
tensions (tests/validate/test_seabed_catenary.py).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from catenet.solver.potential import Potential
    from catenet.solver.static import _Barriers

REST = "rest"  # solver.t_end's value for a run to rest
MAX_STEPS = 20_000  # solver.max_steps's default: accepted steps of a run to rest
GROWTH_CAP = 2.0**20  # the largest step is dt * GROWTH_CAP
EASY = 8  # a step that took at most this many Newton iterations doubles the next one
HARD = 16  # one that took more halves it (down to dt)


SMOOTH_STAGES = 3  # a slack start: the tension-only law smoothed by mu, mu/10, mu/100 first
STAGE_RTOL = 1e-3  # the rest test of the barrier stages before the last, times the load scale


class RestControl:
    """The step of a run to rest from t0 (the interface of ``dynamic.StepControl``, with
    ``t_end`` infinite): ``dt`` at first, then grown by ``settled`` (module docstring);
    ``failed`` halves it, down to the smallest step dt / 2**max_cuts."""

    t_end = math.inf

    def __init__(
        self,
        dt: float,
        t0: float,
        max_cuts: int,
        max_steps: int,
        stages: Iterable[Potential] = (),
    ):
        self.dt, self.t0 = dt, t0
        self.stages = list(stages)  # potentials of the barrier stages still to come
        self.h = dt
        self.h_min = dt / 2**max_cuts
        self.h_max = dt * GROWTH_CAP
        self.max_steps = max_steps
        self.previous = math.nan  # the static residual after the last accepted step
        self.planned = max_steps  # the tries are bounded by max_steps accepted steps,
        self.tries = 0  # each after at most max_cuts failed ones
        self.fails = 0

    def step(self, t: float) -> float:
        """The next step from t."""
        return self.h

    def failed(self, h_step: float) -> bool:
        """A step of ``h_step`` failed: the next try has half its length. False when that
        is below the smallest step (the run fails)."""
        self.h = 0.5 * h_step
        self.previous = math.nan  # the decay starts again from the next accepted step
        self.tries += 1
        self.fails += 1
        return not self.h < self.h_min

    def spent(self) -> bool:
        """Never: ``max_steps`` bounds a run to rest (the stepper checks it)."""
        return False

    def accepted(self) -> None:
        """A step was accepted (``settled`` sets the next one)."""
        self.tries += 1

    def settled(self, residual: float, iterations: int) -> None:
        """After an accepted step (once nothing moves by prescription): its static
        residual and the Newton iterations it took set the next step."""
        before, self.previous = self.previous, residual
        if iterations > HARD:
            self.h = max(min(self.h, self.dt), 0.5 * self.h)
            return
        factor = 2.0 if iterations <= EASY else 1.0
        if math.isfinite(before) and residual > 0.0:
            factor = max(factor, min(2.0, before / residual))
        self.h = min(self.h_max, max(min(self.h, self.dt), self.h * factor))

    def advance(self, t: float, h_step: float) -> float:
        """The time after the step (pseudo-time: plain sums)."""
        return t + h_step

    def rtol(self, rtol: float) -> float:
        """The rest test's tolerance: loose at a barrier stage before the last."""
        return max(rtol, STAGE_RTOL) if self.stages else rtol

    def next_stage(self) -> Potential:
        """The potential of the next barrier stage (the caller checks ``stages``)."""
        self.previous = math.nan
        return self.stages.pop(0)


def rest_stages(
    potential: Potential, barriers: _Barriers, factors: list[float], smooth: float = 0.0
) -> list[Potential]:
    """The potentials of a run to rest, as the static solve's continuations
    (``static.equilibrium``): with the widest barriers, the law smoothed by ``smooth``
    and its SMOOTH_STAGES tenfold reductions (none when 0) at the first stiffness, then
    the stretching scaled by each of ``factors`` (a nearly inextensible net); then the
    exact stretching with each barrier stage (``static._Barriers``); then ``potential``."""
    system = potential.system
    stretch = system.stretch
    first = stretch.scaled(factors[0]) if factors else stretch
    mus = [smooth / 10.0**k for k in range(SMOOTH_STAGES)] if smooth > 0 else []
    levels = [
        system.with_terms((first.with_law(stretch.law.smoothed(m)), *barriers(0))) for m in mus
    ]
    levels += [system.with_terms((stretch.scaled(f), *barriers(0))) for f in factors]
    levels += [system.with_terms((stretch, *barriers(k))) for k in range(barriers.count)]
    return [*(potential.with_system(s) for s in levels), potential]
