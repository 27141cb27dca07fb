"""Material laws as strain energy densities: w(eps), w'(eps), w''(eps) per unit EA and rest length.

An edge of law ``law`` stores U = EA l0 w(eps); its axial force is N = EA w'(eps) and its
axial stiffness (EA/l0) w''(eps). Every law has w(0) = w'(0) = 0 and w''(0) = 1, so EA is
the small-strain stiffness of every law and each reduces to the paper's at small strain.
With the stretch lambda = 1 + eps:

- linear (the paper's):   w = eps^2 / 2,                       N = EA eps
- neo_hookean (1D, incompressible, E = 3 mu):
                          w = (lambda^2/2 + 1/lambda - 3/2) / 3,  N = EA (lambda - lambda^-2) / 3
- hencky (logarithmic strain):
                          w = (ln lambda)^2 / 2 / ... per reference length: w = (ln lambda)^2/2,
                          N = EA ln(lambda) / lambda
- table (piecewise linear N(eps) through user points; EA is the first segment's slope):
                          w' = N(eps)/EA, w'' its slope, w its integral from 0 (exact,
                          piecewise quadratic); linear beyond the last point with the last
                          slope, and below 0 with the first.

``strain_energy`` composes a law with the tension-only switch: w(s(eps)) with
s = max(eps, 0), or the smooth s(eps) = (eps + sqrt(eps^2 + mu^2))/2 of the static solver's
continuation, which tends to max(eps, 0) as mu -> 0 and keeps every edge slightly taut.

Tables live in one array ``table`` (K, 3) of rows (eps, N/EA, w) shared by all edges; a
table edge's ``params`` are (first row, number of rows). A new law is one function here and
one branch in ``density`` (its id), plus its entry in ``catenet.model.laws.LAWS``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.law_ids import HENCKY, LINEAR, NEO_HOOKEAN, TABLE


@njit(cache=True, error_model="numpy")
def linear(eps):
    """The paper's law: w = eps^2 / 2 (tension EA eps)."""
    return 0.5 * eps * eps, eps, 1.0


@njit(cache=True, error_model="numpy")
def neo_hookean(eps):
    """Incompressible neo-Hookean bar in 1D (nominal stress mu (lambda - lambda^-2), E = 3 mu);
    infinite energy as lambda -> 0."""
    lam = 1.0 + eps
    if lam <= 0.0:
        return np.inf, -np.inf, np.inf
    inv = 1.0 / lam
    w = (0.5 * lam * lam + inv - 1.5) / 3.0
    dw = (lam - inv * inv) / 3.0
    ddw = (1.0 + 2.0 * inv * inv * inv) / 3.0
    return w, dw, ddw


@njit(cache=True, error_model="numpy")
def hencky(eps):
    """Hencky (logarithmic) strain: w = (ln lambda)^2 / 2, N = EA ln(lambda)/lambda; the
    force peaks at lambda = e (eps = 1.72), beyond which the bar softens."""
    lam = 1.0 + eps
    if lam <= 0.0:
        return np.inf, -np.inf, np.inf
    h = np.log(lam)
    return 0.5 * h * h, h / lam, (1.0 - h) / (lam * lam)


@njit(cache=True, error_model="numpy")
def tabulated(eps, first, rows, table):
    """Piecewise-linear N/EA through table rows (eps_k, n_k, w_k) starting at (0, 0, 0)."""
    lo = first
    hi = first + rows - 1
    if eps <= table[lo, 0]:  # below the first point: the first segment's slope (1)
        slope = (table[lo + 1, 1] - table[lo, 1]) / (table[lo + 1, 0] - table[lo, 0])
        d = eps - table[lo, 0]
        n = table[lo, 1] + slope * d
        return table[lo, 2] + table[lo, 1] * d + 0.5 * slope * d * d, n, slope
    k = lo
    while k < hi - 1 and eps > table[k + 1, 0]:
        k += 1
    slope = (table[k + 1, 1] - table[k, 1]) / (table[k + 1, 0] - table[k, 0])
    d = eps - table[k, 0]
    n = table[k, 1] + slope * d
    return table[k, 2] + table[k, 1] * d + 0.5 * slope * d * d, n, slope


@njit(cache=True, error_model="numpy")
def density(law, params, table, eps):
    """w, w', w'' of law id ``law`` with parameters ``params`` at strain eps (NaN for an
    unknown id: the solvers' finite checks reject it)."""
    if law == LINEAR:
        return linear(eps)
    if law == NEO_HOOKEAN:
        return neo_hookean(eps)
    if law == HENCKY:
        return hencky(eps)
    if law == TABLE:
        return tabulated(eps, int(params[0]), int(params[1]), table)
    return np.nan, np.nan, np.nan


@njit(cache=True, error_model="numpy")
def edge_density(law, params, table, k, eps):
    """w, w', w'' of edge k: ``law`` holds the law id of every edge, or is None where
    every edge follows the linear law. Numba prunes the branch on None when it compiles,
    so a net of linear edges compiles (and loads) none of the other laws."""
    if law is None:
        return linear(eps)
    return density(law[k], params[k], table, eps)


@njit(cache=True, error_model="numpy")
def strain_energy(law, params, table, k, eps, tension_only, smooth):
    """w, w' and w'' (derivatives by eps) of edge k's law (``edge_density``) composed with
    the tension-only switch."""
    if not tension_only:
        return edge_density(law, params, table, k, eps)
    if smooth > 0.0:
        r = np.sqrt(eps * eps + smooth * smooth)
        s = 0.5 * (eps + r)
        ds = 0.5 * (1.0 + eps / r)
        dds = 0.5 * smooth * smooth / (r * r * r)
    elif eps < 0.0:
        return 0.0, 0.0, 0.0
    else:
        return edge_density(law, params, table, k, eps)
    w, dw, ddw = edge_density(law, params, table, k, s)
    return w, dw * ds, ddw * ds * ds + dw * dds


@njit(cache=True, error_model="numpy")
def strain_for_force(law, params, table, target):
    """The strain at which the law carries N/EA = ``target`` (NaN where none does): Newton
    on w'(eps) = target, safeguarded by bisection on a bracket grown from 0. The linear
    law's w'(eps) = eps gives the strain at once."""
    if target == 0.0:
        return 0.0
    if law == LINEAR:
        return target
    lo, hi = 0.0, 0.0
    step = abs(target) if abs(target) < 0.5 else 0.5
    if target > 0.0:
        hi = step
        for _ in range(200):
            if density(law, params, table, hi)[1] >= target:
                break
            lo, hi = hi, 2.0 * hi + 1.0
        else:
            return np.nan
    else:
        lo = -step
        for _ in range(200):
            if density(law, params, table, lo)[1] <= target:
                break
            hi = lo
            lo = -1.0 + 0.5 * (1.0 + lo) if lo > -1.0 + 1e-300 else lo * 2.0
            if lo <= -1.0:
                return np.nan
        else:
            return np.nan
    eps = 0.5 * (lo + hi)
    for _ in range(200):
        _, f, df = density(law, params, table, eps)
        r = f - target
        if r > 0.0:
            hi = eps
        else:
            lo = eps
        new = eps - r / df if df > 0.0 else 0.5 * (lo + hi)
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
        if abs(new - eps) <= 1e-15 * max(1.0, abs(eps)):
            return new
        eps = new
    return eps


@njit(cache=True, error_model="numpy")
def strains_for_forces(kind, params, table, tension_only, tension, EA):
    """Per edge, ``strain_for_force`` of tension / EA (NaN for a compression in a
    tension-only edge): one compiled loop over the edges."""
    out = np.empty(len(kind))
    for k in range(len(kind)):
        if tension_only[k] and tension[k] < 0.0:
            out[k] = np.nan
        else:
            out[k] = strain_for_force(kind[k], params[k], table, tension[k] / EA[k])
    return out
