"""The step length of a Newton step: a line search on the slope of the potential along it
(Armijo and curvature conditions; lengthened while a slack net falls freely; a secant
search inside a bracket; capped at the first contact with an obstacle)."""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.sparse import dot, norm

ARMIJO = 1e-4
MAX_HALVINGS = 30
MAX_EXPANSIONS = 12
WOLFE = 0.9  # curvature condition: |slope at the step| <= 0.9 |slope at 0|


def line_search(potential, x, y0, dy, phi, slope, gnorm, phi_tol, tol, predicted, y_trial):
    """Step length along dy.

    alpha = 1 when Phi decreases enough (Armijo) and its slope along dy has flattened
    (|slope| <= WOLFE |slope at 0|), as for every Newton step near the solution. While the
    slope stays steep (a slack net falling freely: only the regularisation limits the
    step) the step is lengthened fourfold at a time; once a step is too long, a secant
    search on the slope inside the bracket [lo, hi] finds a point that satisfies both
    conditions. The potential of a tension-only net is convex, so the slope along dy is
    monotone and the bracket sound; elsewhere the search falls back to bisection.

    Returns (alpha, accepted, rho, evaluation at alpha); x holds y0 + alpha dy if accepted.
    """
    free = potential.system.free_dofs
    xf = x.reshape(-1)
    cap = potential.max_step(x, dy)  # steps of this length or longer touch an obstacle
    refused = (math.inf, None, 0.0, 0.0, 0.0, math.inf), math.inf, False

    def at(alpha):
        if alpha >= cap:
            return refused
        np.add(y0, alpha * dy, out=y_trial)
        xf[free] = y_trial
        phi_t, g_t, scale_t, floor_t, phi_tol_t = potential.evaluate(x)
        gnorm_t = float(norm(g_t.reshape(-1)))
        finite = math.isfinite(phi_t) and math.isfinite(gnorm_t)
        d_t = float(dot(g_t, dy)) if finite else math.inf
        if abs(phi_t - phi) > phi_tol:
            ok = finite and phi_t <= phi + ARMIJO * alpha * slope
        else:  # Phi cannot tell: the gradient norm decides
            ok = finite and (gnorm_t <= (1.0 - ARMIJO * alpha) * gnorm or gnorm_t <= tol)
        return (phi_t, g_t.copy(), scale_t, floor_t, phi_tol_t, gnorm_t), d_t, ok

    def flat(d):
        return abs(d) <= WOLFE * abs(slope)

    ev, d, ok = at(1.0)
    rho = 0.0
    if math.isfinite(ev[0]):
        if abs(ev[0] - phi) > phi_tol and predicted > 0:
            rho = (phi - ev[0]) / predicted
        else:
            rho = 1.0 if ev[5] < gnorm else 0.0
    if ok and (d >= WOLFE * slope):
        return 1.0, True, rho, ev
    best = None  # (alpha, evaluation)
    if ok:  # still steep at the full step: lengthen it
        best = (1.0, ev)
        lo, d_lo, hi, d_hi = 1.0, d, None, None
        for _ in range(MAX_EXPANSIONS):
            alpha = 4.0 * lo
            ev, d, ok = at(alpha)
            if ok and d < 0.0:
                best, lo, d_lo = (alpha, ev), alpha, d
                if flat(d):
                    hi = None
                    break
                continue
            hi, d_hi = alpha, d
            if ok and ev[0] < best[1][0]:
                best = (alpha, ev)
            break
    else:
        lo, d_lo, hi, d_hi = 0.0, slope, 1.0, d
    if hi is not None:
        for _ in range(MAX_HALVINGS):
            if math.isfinite(d_hi) and d_hi > 0.0 > d_lo:  # secant, kept off the ends
                alpha = lo - d_lo * (hi - lo) / (d_hi - d_lo)
                alpha = min(max(alpha, lo + 0.1 * (hi - lo)), hi - 0.1 * (hi - lo))
            else:
                alpha = 0.5 * (lo + hi)
            ev, d, ok = at(alpha)
            if ok:
                if best is None or ev[0] < best[1][0]:
                    best = (alpha, ev)
                if flat(d):
                    break
                if d < 0.0:
                    lo, d_lo = alpha, d
                else:
                    hi, d_hi = alpha, d
            else:
                hi, d_hi = alpha, d
            if best is not None and hi - lo < 1e-3 * hi:
                break
    if best is None:
        xf[free] = y0
        return 0.0, False, rho, None
    alpha, ev = best
    np.add(y0, alpha * dy, out=y_trial)
    xf[free] = y_trial
    return alpha, True, rho, ev
