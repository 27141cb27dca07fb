"""Time steps chosen by accuracy (``solver.tolerance``, a run with a number for t_end): each step's
local error is estimated by the scheme (``estimate``: the difference between the step's
solution and the polynomial through the last states, extrapolated), measured against the
tolerance, and the step is accepted where that error is within it and retried shorter
where not; the next step is sized so that its error comes out at SAFETY of the tolerance.

The error of a step is the larger of

    |error in x| / (tolerance X)   and   |error in v| / (tolerance V)

in the mass-weighted RMS over the free DOFs (so that a light node rattling in contact
does not set the steps of a heavy body), with X and V the motion's own scales: the largest
mass-weighted RMS displacement from the start and speed of the run so far, at least FLOOR
of the net's size L (its bounding box's diagonal) and of sqrt(|g| L) or L / (t_end - t0).
So a tolerance of 1e-3 asks every step to keep its positions within 1e-3 of how far the
motion has gone and its velocities within 1e-3 of how fast.

A run starts with ``first`` (``solver.dt`` where given, else FIRST_SHARE of the run's span,
at most ``dt_max``): the scheme's first steps, before it has the states to
estimate its error from, are taken at that length. Steps stay within
[``dt_min``, ``dt_max``]; a step that fails to converge (Newton) is retried at half its
length, as with fixed steps, and the run fails where that is below ``dt_min``; a step at
``dt_min`` whose error is still beyond the tolerance is accepted (the run warns once). A
run that takes more than MAX_TRIES steps fails (a tolerance too tight for it).
Each estimate is filtered through the step's own matrix (W^-1 w e, W = w + K the Newton
matrix, w the inertia weights): a component the step resolves keeps its size, a stiff one
it cannot (a free body's rigidity, a barrier's) is damped as bdf2 and implicit Euler damp
it, so it does not set the steps (Shampine's filter, as in stiff ODE codes).

Measured on the drop of benchmarks/peers/mujoco_drop.toml (the box's momentum at 0.4 s;
bdf2 at fixed 0.31 ms steps: 16.17 kg m/s): tolerance 1e-2, 31 steps, 16.54 (+2.3 %);
3e-3, 185 steps, 16.44 (+1.7 %); 1e-3, 783 steps, 16.18 (+0.03 %); fixed 10 ms steps:
40 steps, 16.29 (+0.8 %). Where the contact phase is short against the free flight, a
tolerance above 1e-3 steps over part of it: adaptive steps are not yet the default.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError, ConvergenceError
from catenet.solver.integrators import BDF2, ImplicitEuler
from catenet.solver.stepping import ALLOWANCE

if TYPE_CHECKING:
    from catenet.solver.stepper import TimeStepper

log = logging.getLogger(__name__)

TOLERANCE = 1e-3  # ErrorControl's default
SAFETY = 0.8  # the share of the tolerance the next step aims at
GROW_MAX = 2.0  # a step at most doubles
SHRINK_MIN = 0.2  # a rejected step shrinks at most fivefold
FIRST_SHARE = 1e-3  # the first step, of the run's span (t_end - t0)
ADAPTIVE = ("implicit_euler", "bdf2")  # the schemes that estimate their error
FLOOR = 1e-2  # X and V at least this share of L and of sqrt(|g| L), L / (t_end - t0)
MAX_TRIES = 100_000  # a run that needs more steps fails (a tolerance too tight for it)


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
        self.speed = FLOOR * max(math.sqrt(gravity * self.size), self.size / span)  # V, grows
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
        nodes, gravity = stepper.net.nodes, stepper.loads.gravity
        return cls(
            t0, t_end, order=scheme.order, tolerance=tolerance, first=first, dt_max=dt_max,
            dt_min=dt_min, size=float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0))),
            gravity=0.0 if gravity is None else float(np.linalg.norm(gravity)),
        )  # fmt: skip

    def within(self, stepper: TimeStepper, h_step: float) -> bool:
        """Whether the converged step of ``h_step`` of a TimeStepper (in its x_trial) is
        within the tolerance, its estimate filtered through the step's matrix (module
        docstring): else the next try is shorter, and ConvergenceError where the run's
        tries are spent."""
        free = stepper.free
        y_k, v_k = stepper.x.reshape(-1)[free], stepper.v.reshape(-1)[free]
        y_new = stepper.x_trial.reshape(-1)[free]
        scheme = stepper.scheme
        assert isinstance(scheme, (ImplicitEuler, BDF2))  # ``of`` takes no other
        estimate = scheme.estimate(y_new, y_k, v_k, h_step)
        error = None
        if estimate is not None:
            w, solve = stepper.inertia.w, stepper.potential.solver.solve
            error = self.error(solve(w * estimate[0]), solve(w * estimate[1]), stepper.m_free)
        if self.judge(h_step, error):
            return True
        log.info("t = %.6g: step %.3g beyond the tolerance (%.3g); retrying with %.3g",
                 stepper.t, h_step, error, self.h)  # fmt: skip
        if self.spent():
            raise ConvergenceError(
                self.spent_message(stepper.t), iterations=stepper.iterations,
                state=stepper.x.copy(),
            )  # fmt: skip
        return False

    def saw(self, u: np.ndarray, v: np.ndarray, mass: np.ndarray) -> None:
        """The displacements from the start and velocities of an accepted step (free
        DOFs, their masses): X and V grow to the largest mass-weighted RMS of each."""
        if len(v):
            self.reach = max(self.reach, _rms(u, mass))
            self.speed = max(self.speed, _rms(v, mass))

    def error(self, ex: np.ndarray, ev: np.ndarray, mass: np.ndarray) -> float:
        """A step's error over the tolerance from its estimates in x and v (free DOFs,
        their masses: mass-weighted RMS, so that a light node rattling in contact does
        not set the steps of a heavy body's motion)."""
        if not len(ex):
            return 0.0
        ratio_x = _rms(ex, mass) / (self.tolerance * self.reach)
        ratio_v = _rms(ev, mass) / (self.tolerance * self.speed)
        return max(ratio_x, ratio_v)

    def step(self, t: float) -> float:
        """The next step from t: h, cut short at t_end, or half what is left where h would
        leave a sliver shorter than itself."""
        left = self.t_end - t
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
        if error > 1.0:
            self.rejected += 1
            self.h = max(self.dt_min, h_step * max(SHRINK_MIN, min(factor, 0.9)))
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
        self.h = min(self.dt_max, h_step * min(GROW_MAX, max(1.0, factor)))
        return True

    def failed(self, h_step: float) -> bool:
        """A step of ``h_step`` failed to converge: the next try has half its length.
        False when that is below ``dt_min`` (the run fails)."""
        self.h = 0.5 * h_step
        self.tries += 1
        self.fails += 1
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
        return self.t_end if h_step == self.t_end - t or end >= self.t_end * (1 - 1e-12) else end
