"""Levenberg-Marquardt within bounds, for form finding's targets.

Minimises f(s) = 1/2 |r(s)|^2 for lo <= s <= hi. Each step solves the damped least
squares min |J p + r|^2 + mu |p|^2 over the variables not held at a bound (a variable at
its bound whose gradient pushes it out is held): by the SVD of J where J is given whole,
by LSMR (each product one solve of the equilibrium) where it is a linear operator. With
mu = 0 the step is Gauss-Newton's least-norm step, which meets a reachable target with
more variables than rows (a spider's centre by its force densities) in a few steps:
SciPy's trust region methods keep such steps on their trust radius, and so converge
only linearly there. No variable moves by more than ``MAX_STEP`` in one step (log q: a
factor e); the step is clipped to the bounds. A step that does not lower f raises mu
(by 4, from a scale of J's largest singular value squared); one that does lowers it by 3
(to 0 below ``MU_MIN`` of that scale).

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
LSMR_TOL = 1e-10
LSMR_ITER = 400


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
    evaluations, mu, scale = 1, 0.0, None
    while True:
        jac = jacobian(s)
        dense = isinstance(jac, np.ndarray)
        g = jac.T @ r if dense else jac.rmatvec(r)
        held = ((s <= lo) & (g > 0)) | ((s >= hi) & (g < 0))
        if not np.any(g[~held]):
            return Ended("stationary", s, evaluations)
        sigma = None
        while True:
            if evaluations >= budget:
                return Ended("max_iter", s, evaluations)
            p, sigma = _step(jac, r, mu, held, dense, sigma)
            if scale is None:
                scale = sigma**2
            big = float(np.max(np.abs(p), initial=0.0))
            if big > MAX_STEP:
                p *= MAX_STEP / big
            trial = np.clip(s + p, lo, hi)
            r_new = residual(trial)
            evaluations += 1
            f_new = 0.5 * float(r_new @ r_new)
            if f_new < f:
                break
            mu = max(4.0 * mu, MU_FIRST * scale)
            if mu > MU_MAX * scale:
                return Ended("stationary", s, evaluations)
        done = f - f_new <= FTOL * f
        s, r, f = trial, r_new, f_new
        if done:
            return Ended("stationary", s, evaluations)
        mu = mu / 3.0 if mu / 3.0 >= MU_MIN * scale else 0.0


def _step(jac, r: np.ndarray, mu: float, held: np.ndarray, dense: bool, sigma):
    """(p, largest singular value) of min |J p + r|^2 + mu |p|^2, p = 0 where held."""
    keep = ~held
    if dense:
        j = jac[:, keep]
        u, sv, vt = np.linalg.svd(j, full_matrices=False)
        top = float(sv[0]) if sv.size else 0.0
        if mu > 0:
            inv = sv / (sv**2 + mu)
        else:
            inv = np.where(sv > 1e-12 * top, 1.0 / np.where(sv > 0, sv, 1.0), 0.0)
        p = np.zeros(len(keep))
        p[keep] = -(vt.T @ (inv * (u.T @ r)))
        return p, top
    from scipy.sparse.linalg import LinearOperator, lsmr

    mask = keep.astype(np.float64)
    op = LinearOperator(
        jac.shape,
        matvec=lambda v: jac.matvec(np.ravel(v) * mask),
        rmatvec=lambda z: jac.rmatvec(np.ravel(z)) * mask,
        dtype=np.float64,
    )
    out = lsmr(op, -r, damp=float(np.sqrt(mu)), atol=LSMR_TOL, btol=LSMR_TOL, maxiter=LSMR_ITER)
    top = sigma if sigma is not None else float(out[5]) / np.sqrt(max(min(jac.shape), 1))
    return out[0] * mask, top


__all__ = ["Ended", "levenberg"]
