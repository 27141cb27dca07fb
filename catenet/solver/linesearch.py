"""The step length of a Newton step: a line search on the slope of the potential along it
(Armijo and curvature conditions; lengthened while a slack net falls freely; a secant
search inside a bracket; capped at the first contact with an obstacle)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from catenet.kernels.sparse import dot

if TYPE_CHECKING:
    from catenet.solver.potential import Evaluation, Potential
    from catenet.terms import Term

ARMIJO = 1e-4
MAX_HALVINGS = 30
MAX_EXPANSIONS = 12
REACH = 4.5  # the step cap is first sought up to this multiple of the Newton step
WOLFE = 0.9  # curvature condition: |slope at the step| <= 0.9 |slope at 0|


@dataclass(frozen=True)
class Trial:
    """Phi along the step at one length: its evaluation (None where the step touches an
    obstacle), the slope of Phi along dy there and whether it decreased enough."""

    alpha: float
    evaluation: Evaluation | None
    slope: float
    ok: bool

    @property
    def phi(self) -> float:
        return math.inf if self.evaluation is None else self.evaluation.phi


@dataclass(frozen=True)
class Searched:
    """What a line search found: the step length alpha, whether a step was taken (x then
    holds y0 + alpha dy), rho (actual over predicted decrease of Phi at the full step),
    the evaluation at alpha (its gradient a copy, the caller's to keep) and the term whose
    contact the full step would have reached (None: it reached none)."""

    alpha: float
    accepted: bool
    rho: float
    trial: Evaluation | None
    capped_by: Term | None = None


class LineSearch:
    """The line search of one Newton step along dy (free DOFs) from x, whose evaluation is
    ``start`` (Phi, its round-off level, the residual norm) and whose slope along dy is
    ``slope`` < 0; ``tol`` the residual's tolerance, ``predicted`` the decrease of Phi the
    quadratic model predicts for the full step; ``y_trial`` a buffer of the free DOFs.

    alpha = 1 when Phi decreases enough (Armijo) and its slope along dy has flattened
    (|slope| <= WOLFE |slope at 0|), as for every Newton step near the solution. While the
    slope stays steep (a slack net falling freely: only the regularisation limits the
    step) the step is lengthened fourfold at a time; once a step is too long, a secant
    search on the slope inside the bracket [lo, hi] finds a point that satisfies both
    conditions. The potential of a tension-only net is convex, so the slope along dy is
    monotone and the bracket sound; elsewhere the search falls back to bisection.
    """

    def __init__(
        self,
        potential: Potential,
        x: np.ndarray,
        dy: np.ndarray,
        *,
        start: Evaluation,
        slope: float,
        tol: float,
        predicted: float,
        y_trial: np.ndarray,
    ):
        self.potential = potential
        self.x = x
        self.dy = dy
        self.start = start
        self.slope = slope
        self.tol = tol
        self.predicted = predicted
        self.y_trial = y_trial
        self.free = potential.system.free_dofs
        self.y0 = x.reshape(-1)[self.free].copy()
        # steps this long or longer touch an obstacle, known up to ``reach`` (a step the
        # lengthening takes beyond it asks again: the search grows with the distance)
        self.reach = REACH
        self.cap = potential.max_step(x, dy, self.reach)
        self.capped_by = potential.capped_by if self.cap <= 1.0 else None
        self._x0: np.ndarray | None = None

    def at(self, alpha: float) -> Trial:
        """Phi at y0 + alpha dy (x is left there)."""
        if alpha >= self.reach and math.isinf(self.cap):
            self._look_farther(alpha)
        if alpha >= self.cap:
            return Trial(alpha, None, math.inf, False)
        np.add(self.y0, alpha * self.dy, out=self.y_trial)
        self.x.reshape(-1)[self.free] = self.y_trial
        ev = self.potential.evaluate(self.x)
        start = self.start
        finite = math.isfinite(ev.phi) and math.isfinite(ev.gnorm)
        d = float(dot(ev.g, self.dy)) if finite else math.inf
        if abs(ev.phi - start.phi) > start.phi_tol:
            ok = finite and ev.phi <= start.phi + ARMIJO * alpha * self.slope
        else:  # Phi cannot tell: the gradient norm decides
            ok = finite and (
                ev.gnorm <= (1.0 - ARMIJO * alpha) * start.gnorm or ev.gnorm <= self.tol
            )
        return Trial(alpha, ev.kept(), d, ok)

    def _look_farther(self, alpha: float) -> None:
        """The step cap known up to 4 alpha (the next lengthening's step), from x at y0."""
        self.reach = 4.0 * alpha
        x = self.x.copy()
        x.reshape(-1)[self.free] = self.y0
        self.cap = self.potential.max_step(x, self.dy, self.reach)

    def flat(self, d: float) -> bool:
        return abs(d) <= WOLFE * abs(self.slope)

    def rho(self, full: Trial) -> float:
        """Actual over predicted decrease of Phi at the full step (where Phi cannot tell:
        1 if the residual fell, else 0)."""
        ev, start = full.evaluation, self.start
        if ev is None or not math.isfinite(ev.phi):
            return 0.0
        if abs(ev.phi - start.phi) > start.phi_tol and self.predicted > 0:
            return (start.phi - ev.phi) / self.predicted
        return 1.0 if ev.gnorm < start.gnorm else 0.0

    def run(self) -> Searched:
        full = self.at(1.0)
        rho = self.rho(full)
        if full.ok and full.slope >= WOLFE * self.slope:
            return Searched(1.0, True, rho, full.evaluation, self.capped_by)
        if full.ok:  # still steep at the full step: lengthen it
            best, lo, hi = self._lengthen(full)
        else:
            best, lo, hi = None, Trial(0.0, self.start, self.slope, True), full
        if hi is not None:
            best = self._bracket(best, lo, hi)
        if best is None:
            self.x.reshape(-1)[self.free] = self.y0
            return Searched(0.0, False, rho, None, self.capped_by)
        np.add(self.y0, best.alpha * self.dy, out=self.y_trial)
        self.x.reshape(-1)[self.free] = self.y_trial
        return Searched(best.alpha, True, rho, best.evaluation, self.capped_by)

    def _lengthen(self, full: Trial) -> tuple[Trial, Trial, Trial | None]:
        """Steps 4, 16, ... times as long while Phi falls and the slope stays steep:
        the best step, and the bracket's ends (hi None: the last step is flat, or a
        longer one would overshoot by an obstacle).

        A step lengthened as a whole also lengthens its stiff directions. Away from
        solids that costs a few iterations and gains a long way (a slack net falling
        freely, a mechanism swinging through). With an obstacle within the lengthened
        step's reach, a lengthening that raises the residual above the start's is not
        taken: its stiff directions press nodes into barriers whose stiffness grows without
        bound (a frictionless rope over a box's sharp edges, 3 mm edges: 53 000 Newton
        iterations, lengthened 16-fold and pulled back again and again; about 600 now)."""
        best = lo = full
        hi = None
        for _ in range(MAX_EXPANSIONS):
            trial = self.at(4.0 * lo.alpha)
            ev = trial.evaluation
            overshoots = trial.ok and ev is not None and ev.gnorm > self.start.gnorm
            if overshoots and math.isfinite(self.cap):
                break  # the full (or last) step stands
            if trial.ok and trial.slope < 0.0:
                best = lo = trial
                if self.flat(trial.slope):
                    hi = None
                    break
                continue
            hi = trial
            if trial.ok and trial.phi < best.phi:
                best = trial
            break
        return best, lo, hi

    def _bracket(self, best: Trial | None, lo: Trial, hi: Trial) -> Trial | None:
        """A secant search on the slope inside [lo, hi] (bisection where the slopes do
        not bracket a zero): the best acceptable step found."""
        a_lo, d_lo, a_hi, d_hi = lo.alpha, lo.slope, hi.alpha, hi.slope
        for _ in range(MAX_HALVINGS):
            if math.isfinite(d_hi) and d_hi > 0.0 > d_lo:  # secant, kept off the ends
                alpha = a_lo - d_lo * (a_hi - a_lo) / (d_hi - d_lo)
                alpha = min(max(alpha, a_lo + 0.1 * (a_hi - a_lo)), a_hi - 0.1 * (a_hi - a_lo))
            else:
                alpha = 0.5 * (a_lo + a_hi)
            trial = self.at(alpha)
            if trial.ok:
                if best is None or trial.phi < best.phi:
                    best = trial
                if self.flat(trial.slope):
                    break
                if trial.slope < 0.0:
                    a_lo, d_lo = alpha, trial.slope
                else:
                    a_hi, d_hi = alpha, trial.slope
            else:
                a_hi, d_hi = alpha, trial.slope
            if best is not None and a_hi - a_lo < 1e-3 * a_hi:
                break
        return best
