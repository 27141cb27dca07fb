"""Levenberg-Marquardt within bounds, for form finding's targets.

Minimises f(s) = 1/2 |r(s)|^2 for lo <= s <= hi. Each step solves the damped least
squares min |J p + r|^2 + mu |p|^2 over the variables not held at a bound (a variable at
its bound whose gradient pushes it out is held): where J is given whole, by Cholesky on
J J^T + mu (or J^T J + mu, the smaller); else by conjugate residuals on the smaller of
the two with J's products (``catenet.formfind.krylov``) to a relative residual eta (an
inexact Levenberg-Marquardt), or, where they do not get there, by one sparse
factorisation of the saddle-point system that holds J without forming it
(``catenet.formfind.adjoint.SparseJacobian``). The forcing term eta = ``ETA_PATH`` |r_0|
/ |r| (within ``ETA_MIN`` .. ``ETA_MAX``) holds every step's residual to the same small
fraction of the first misses: the first, large steps are the exact steps to about
ETA_PATH (and so is the path, which decides which force densities are found where the
targets leave them free), the last, small ones are not solved beyond what they change.
With mu small the step is Gauss-Newton's least-norm step, which meets a reachable target
with more variables than rows (a spider's centre by its force densities) in a few steps:
SciPy's trust region methods keep such steps on their trust radius, and so converge only
linearly there. mu starts at ``MU_FIRST`` of the square of J's Frobenius norm (or of its
largest singular value, by power iterations, for the sparse form), grows by 4 after a
step that does not lower f and falls by 3 after one that does (never below ``MU_MIN`` of
that scale), each time relative to the scale of the J the step is taken with. No
variable moves by more than ``MAX_STEP`` in one step (log q: a factor e); the step is
clipped to the bounds. After a refused trial (until a step is taken at its first trial)
a whole Jacobian's step gets its geodesic acceleration (``_accelerated``: one more
residual along the step), which bends Gauss-Newton's steps along a narrow curved valley
of the misses instead of out of it.

It ends when ``residual`` raises (the caller's test: every target met), when the
evaluations reach ``budget``, or when no step lowers f by more than ``FTOL`` of it (or
mu exceeds ``MU_MAX`` of the scale): the least-squares compromise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

MAX_STEP = 1.0
FTOL = 1e-12
MU_FIRST, MU_MIN, MU_MAX = 1e-6, 1e-12, 1e8
ETA_PATH, ETA_MIN, ETA_MAX = 1e-6, 1e-10, 0.3  # the iterative step's forcing term
GEO_H, GEO_ALPHA = 0.1, 0.75  # geodesic acceleration: the probe along the step, its bound


@dataclass
class Ended:
    """How the search ended: ``why`` ("max_iter" or "stationary"), at ``s``."""

    why: str
    s: np.ndarray
    evaluations: int


def levenberg(
    residual: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[np.ndarray], Any],
    s: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    budget: int,
) -> Ended:
    """The search from s (see the module docstring); ``residual`` may raise to stop."""
    lo, hi = bounds
    r = residual(s)
    f = 0.5 * float(r @ r)
    evaluations, rel, top = 1, MU_FIRST, None
    first = float(np.linalg.norm(r))
    eta = ETA_PATH
    refused = False  # the last iteration's first trial was refused (a valley)
    while True:
        jac = jacobian(s)
        dense = isinstance(jac, np.ndarray)
        g = jac.T @ r if dense else jac.rmatvec(r)
        held = ((s <= lo) & (g > 0)) | ((s >= hi) & (g < 0))
        if not np.any(g[~held]):
            return Ended("stationary", s, evaluations)
        # mu relative to this J's size (its Frobenius norm, or its largest singular value
        # by power iterations from the last one's vector), squared: a scale kept from the
        # first J held a search from a start far off (a weighing cable's depth a
        # thousand times its target) to steps of gradient descent as J shrank a
        # hundred-thousandfold
        if dense:
            scale = float(np.linalg.norm(jac)) ** 2 or 1.0
        else:
            size, top = _largest(jac, top)
            scale = size**2 or 1.0
        mu = rel * scale
        tries = 0
        while True:
            if evaluations >= budget:
                return Ended("max_iter", s, evaluations)
            tries += 1
            p = _step(jac, r, mu, ~held, dense, eta)
            if p is not None and dense and refused and evaluations + 1 < budget:
                p, probed = _accelerated(residual, jac, s, r, p, mu, ~held, bounds)
                evaluations += probed
            if p is not None:
                big = float(np.max(np.abs(p), initial=0.0))
                if big > MAX_STEP:
                    p *= MAX_STEP / big
                trial = np.clip(s + p, lo, hi)
                r_new = residual(trial)
                evaluations += 1
                f_new = 0.5 * float(r_new @ r_new)
                if f_new < f:
                    break
            refused = True
            mu *= 4.0
            if mu > MU_MAX * scale:
                return Ended("stationary", s, evaluations)
        rel = mu / scale
        done = f - f_new <= FTOL * f
        eta = min(
            max(ETA_PATH * first / max(float(np.linalg.norm(r_new)), 1e-300), ETA_MIN), ETA_MAX
        )
        s, r, f = trial, r_new, f_new
        refused = tries > 1  # (steps taken at once: no valley, no acceleration)
        if done:
            return Ended("stationary", s, evaluations)
        rel = max(rel / 3.0, MU_MIN)


def _step(
    jac, r: np.ndarray, mu: float, keep: np.ndarray, dense: bool, eta: float = ETA_MIN
) -> np.ndarray | None:
    """The p of min |J p + r|^2 + mu |p|^2 with p = 0 where not ``keep`` (a sparse J's
    to the relative residual ``eta``); None where the system is singular."""
    if not dense:
        from catenet.errors import SingularSystemError

        try:
            return jac.damped(r, mu, keep, eta)
        except SingularSystemError:
            return None
    from scipy.linalg import LinAlgError, cho_factor, cho_solve

    j = jac[:, keep]
    p = np.zeros(len(keep))
    try:
        if j.shape[0] <= j.shape[1]:  # p = -J^T (J J^T + mu)^-1 r: the rows' system
            gram = j @ j.T
            gram[np.diag_indices_from(gram)] += mu
            p[keep] = -(j.T @ cho_solve(cho_factor(gram), r))
        else:  # (J^T J + mu) p = -J^T r
            gram = j.T @ j
            gram[np.diag_indices_from(gram)] += mu
            p[keep] = -cho_solve(cho_factor(gram), j.T @ r)
    except LinAlgError:  # (not positive definite in round-off: more damping)
        return None
    return p if np.all(np.isfinite(p)) else None


def _accelerated(residual, jac, s, r, v, mu: float, keep, bounds) -> tuple[np.ndarray, int]:
    """The step v with its geodesic acceleration (Transtrum and Sethna 2012): the
    residual's second derivative along v by one more residual at s + GEO_H v, r_vv =
    2 / h ((r(s + h v) - r) / h - J v), and a = the damped step for r_vv; v + a / 2 where
    |a| <= GEO_ALPHA |v| / 2 (the path bends little within the step), else v. Where the
    residual curves along a narrow valley (two variables that move the targets almost
    alike), Gauss-Newton's steps leave it and are refused; the acceleration bends them
    along it. (the step, the evaluations it took: 0 or 1)."""
    lo, hi = bounds
    probe = s + GEO_H * v
    if np.any(probe < lo) or np.any(probe > hi):
        return v, 0
    r_h = residual(probe)
    if not np.all(np.abs(r_h) < 1e149):  # (no state there)
        return v, 1
    rvv = (2.0 / GEO_H) * ((r_h - r) / GEO_H - jac @ v)
    a = _step(jac, rvv, mu, keep, True)
    if a is None or 2.0 * float(np.linalg.norm(a)) > GEO_ALPHA * float(np.linalg.norm(v)):
        return v, 1
    return v + 0.5 * a, 1


def _largest(jac, start: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """J's largest singular value, by power iterations on J^T J: 8 from a random vector,
    2 from ``start`` (the last J's top vector: a step changes J little); and the vector."""
    if start is None or len(start) != jac.shape[1]:
        count, v = 8, np.random.default_rng(0).standard_normal(jac.shape[1])
    else:
        count, v = 2, start.copy()
    top = 0.0
    for _ in range(count):
        v /= np.linalg.norm(v) or 1.0
        w = jac.rmatvec(jac.matvec(v))
        top = float(np.sqrt(np.linalg.norm(w)))
        v = w
    return top, v / (np.linalg.norm(v) or 1.0)


__all__ = ["Ended", "levenberg"]
