"""The time steps of a dynamic run with a fixed dt (``StepControl``): a failed step
halved, a shortened one grown back, every time an exact multiple of the smallest step
after t0, and the work a run may take before it fails rather than run on for hours."""

from __future__ import annotations

import math

MAX_CUTS = 20  # the smallest step is dt / 2**MAX_CUTS
GROW_AFTER = 4
#: The work a run may take: SLOWDOWN times the steps dt plans from t0 to t_end, plus
#: ALLOWANCE tries (the cut-backs of a hard start or of a few impacts). A run whose steps
#: stay short beyond that fails rather than run on for hours.
SLOWDOWN = 4  # the examples take at most 2.2x (tether_capture: 532 tries for 240 steps)
ALLOWANCE = 100
#: Of these, at most half the steps dt plans plus FAIL_ALLOWANCE may fail (a failed try
#: costs max_iter Newton iterations; a start cut down to the smallest step still fits).
FAIL_ALLOWANCE = MAX_CUTS + 4


class StepControl:
    """The time step of a run from t0 to t_end: ``dt`` while steps converge; a failed step
    is retried with half its length (``failed`` says whether that is still at least the
    smallest step, dt / 2**MAX_CUTS); after GROW_AFTER accepted steps in a row a shortened
    step doubles, back up to dt. ``advance`` gives the time after a step: exact multiples
    of the smallest step after t0 (t0 + k dt with one rounding while the step is dt), not
    sums of the steps' round-off. The tries (accepted and failed steps) are bounded:
    ``spent`` says when they exceed SLOWDOWN times the steps dt plans plus ALLOWANCE, or
    the failed ones half the steps dt plans plus FAIL_ALLOWANCE."""

    def __init__(self, dt: float, t0: float, t_end: float):
        self.dt, self.t0, self.t_end = dt, t0, t_end
        self.quantum = dt / 2**MAX_CUTS  # every step is a multiple of it (but one at t_end)
        self.h = dt  # the next step's length
        self.good = 0  # steps accepted since the last change of h
        self.planned = max(1, math.ceil((t_end - t0) / dt - 1e-9))
        self.budget = SLOWDOWN * self.planned + ALLOWANCE
        self.fail_budget = self.planned // 2 + FAIL_ALLOWANCE
        self.tries = 0  # steps tried, accepted or failed
        self.fails = 0

    def step(self, t: float) -> float:
        """The next step from t: h, cut short at t_end."""
        return min(self.h, self.t_end - t)

    def failed(self, h_step: float) -> bool:
        """A step of ``h_step`` failed: the next try has half its length. False when that
        is below the smallest step (the run fails)."""
        self.h = 0.5 * h_step
        self.good = 0
        self.tries += 1
        self.fails += 1
        return not self.h < self.dt / 2**MAX_CUTS

    def spent(self) -> bool:
        """Whether the tries so far, or the failed ones, exceed the run's budget (the run
        fails)."""
        return self.tries > self.budget or self.fails > self.fail_budget

    def spent_message(self, t: float) -> str:
        """Why a run whose budget is spent stops at time t."""
        mean = (t - self.t0) / max(1, self.tries - self.fails)
        return (
            f"dynamic run stopped at t = {t:.6g} s of solver.t_end = {self.t_end:g} s: "
            f"{self.tries} steps tried ({self.fails} failed) where solver.dt = {self.dt:g} s "
            f"plans {self.planned}; its steps stay about {self.dt / max(mean, self.quantum):.0f}x"
            f" shorter than dt and would not finish in reasonable time (a model too stiff or"
            f" too fast for this dt: try a smaller solver.dt, a larger solver.max_iter, or"
            f" check the stiffness, masses and velocities); the last failed step"
        )

    def accepted(self) -> None:
        """A step was accepted: after GROW_AFTER of them a shortened step doubles."""
        self.tries += 1
        self.good += 1
        if self.h < self.dt and self.good >= GROW_AFTER:
            self.h = min(self.dt, 2.0 * self.h)
            self.good = 0

    def advance(self, t: float, h_step: float) -> float:
        """The time after the step of ``h_step`` from t."""
        return _advance(t, h_step, self.t0, self.t_end, self.quantum)


def _advance(t: float, h: float, t0: float, t_end: float, quantum: float) -> float:
    """t + h without accumulated round-off: t_end when the step ends there, else, for a
    step of a whole number of quanta (every step but one cut short by t_end), the grid
    point t0 + k quantum next to t + h."""
    if h == t_end - t:
        return t_end
    if (h / quantum).is_integer():
        return t0 + round((t + h - t0) / quantum) * quantum
    return t + h
