"""Material laws as strain energy densities: w(eps), w'(eps), w''(eps) per unit EA and rest length.

An edge of law ``law`` stores U = EA l0 w(eps); its axial force is EA w'(eps) and its axial
stiffness (EA/l0) w''(eps). Every law has w(0) = w'(0) = 0 and w''(0) = 1, so EA is the
small-strain stiffness of every law. ``strain_energy`` composes a law with the tension-only
switch: w(s(eps)) with s = max(eps, 0), or the smooth s(eps) = (eps + sqrt(eps^2 + mu^2))/2
of the static solver's continuation, which tends to max(eps, 0) as mu -> 0 and keeps every
edge slightly taut.

A new law is one function here and one branch in ``density`` (its id), plus its entry in
``catenet.laws.LAWS``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.laws import LINEAR


@njit(cache=True, error_model="numpy")
def linear(eps):
    """The paper's law: w = eps^2 / 2 (tension EA eps)."""
    return 0.5 * eps * eps, eps, 1.0


@njit(cache=True, error_model="numpy")
def density(law, params, eps):
    """w, w', w'' of law id ``law`` with parameters ``params`` at strain eps (NaN for an
    unknown id: the solvers' finite checks reject it)."""
    if law == LINEAR:
        return linear(eps)
    return np.nan, np.nan, np.nan


@njit(cache=True, error_model="numpy")
def strain_energy(law, params, eps, tension_only, smooth):
    """w, w' and w'' (derivatives by eps) of a law composed with the tension-only switch."""
    if not tension_only:
        return density(law, params, eps)
    if smooth > 0.0:
        r = np.sqrt(eps * eps + smooth * smooth)
        s = 0.5 * (eps + r)
        ds = 0.5 * (1.0 + eps / r)
        dds = 0.5 * smooth * smooth / (r * r * r)
    elif eps < 0.0:
        return 0.0, 0.0, 0.0
    else:
        return density(law, params, eps)
    w, dw, ddw = density(law, params, s)
    return w, dw * ds, ddw * ds * ds + dw * dds
