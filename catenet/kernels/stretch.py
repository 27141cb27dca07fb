"""Stretching of an edge: U = 1/2 EA eps^2 l0 with eps = |e|/l0 - 1, e = x_j - x_i.

dU/dx_j = EA eps t (t = e/|e|), dU/dx_i = -EA eps t.
d2U/dx_j2 = (EA/l0) t(x)t + (EA eps/|e|)(I - t(x)t); the blocks at (i,i) and (j,j) take
this sign, (i,j) and (j,i) the opposite. (The paper's Eq. 8 lacks the 1/|e| of the
second term's strain derivative: d2eps/de2 = (I - t(x)t)/(l0 |e|).)

Tension-only edges (``tension_only``) use s(eps) = max(eps, 0) in place of eps: a slack
edge (eps < 0) has no energy, force or stiffness; its 36 Hessian values are written as
zeros so that the sparsity pattern never changes. With ``smooth`` = mu > 0 they use
s(eps) = (eps + sqrt(eps^2 + mu^2)) / 2 instead, a smooth law that tends to max(eps, 0)
as mu -> 0 and keeps every edge slightly taut: the static solver's continuation path.

Zero-length edges are refused at input; one that arises during an iteration (a support
stepping onto its neighbour) is slack when tension-only and contributes nothing, else
its direction is undefined and the kernels give inf/NaN (error_model="numpy": no
exception), which the solvers' finite checks turn into a rejected step.
In general U = 1/2 EA l0 s^2, dU/deps = EA l0 s s', d2U/deps2 = EA l0 (s'^2 + s s''):

    force on x_j = EA s s' t,
    Hessian block = (EA/l0)(s'^2 + s s'') t(x)t + (EA s s'/|e|)(I - t(x)t).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def _law(eps, tension_only, smooth):
    """s, s s' (force / EA) and s'^2 + s s'' (stiffness / (EA/l0)) of the strain law."""
    if not tension_only:
        return eps, eps, 1.0
    if smooth > 0.0:
        r = np.sqrt(eps * eps + smooth * smooth)
        s = 0.5 * (eps + r)
        ds = 0.5 * (1.0 + eps / r)
        dds = 0.5 * smooth * smooth / (r * r * r)
        return s, s * ds, ds * ds + s * dds
    if eps < 0.0:
        return 0.0, 0.0, 0.0
    return eps, eps, 1.0


@njit(cache=True, error_model="numpy")
def stretch_energy(x, edges, l0, ea, tension_only, smooth):
    """Total stretching energy [J] of positions x (N, 3)."""
    total = 0.0
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        eps = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) / l0[k] - 1.0
        s, _, _ = _law(eps, tension_only, smooth)
        total += 0.5 * ea[k] * s * s * l0[k]
    return total


@njit(cache=True, error_model="numpy")
def stretch_gradient(x, edges, l0, ea, tension_only, smooth, grad):
    """Adds dU/dx into grad (N, 3) (the internal force, opposite to the force on the
    nodes) and returns the stretching energy."""
    total = 0.0
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        length = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        eps = length / l0[k] - 1.0
        s, force, _ = _law(eps, tension_only, smooth)
        if force == 0.0 and s == 0.0:
            continue
        total += 0.5 * ea[k] * s * s * l0[k]
        f = ea[k] * force / length
        grad[j, 0] += f * e0
        grad[j, 1] += f * e1
        grad[j, 2] += f * e2
        grad[i, 0] -= f * e0
        grad[i, 1] -= f * e1
        grad[i, 2] -= f * e2
    return total


@njit(cache=True, error_model="numpy")
def stretch_hessian(x, edges, l0, ea, tension_only, smooth, values):
    """Writes the 6x6 Hessian of every edge into values (M*36,), row-major over the
    local DOFs (x_i, y_i, z_i, x_j, y_j, z_j)."""
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e = np.empty(3)
        e[0] = x[j, 0] - x[i, 0]
        e[1] = x[j, 1] - x[i, 1]
        e[2] = x[j, 2] - x[i, 2]
        length = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        eps = length / l0[k] - 1.0
        _, force, stiffness = _law(eps, tension_only, smooth)
        base = 36 * k
        if stiffness == 0.0 and force == 0.0:  # slack: no division by a length
            for a in range(36):
                values[base + a] = 0.0
            continue
        axial = ea[k] / l0[k] * stiffness
        geometric = ea[k] * force / length
        for a in range(3):
            ta = e[a] / length
            for b in range(3):
                tb = e[b] / length
                h = (axial - geometric) * ta * tb
                if a == b:
                    h += geometric
                values[base + 6 * a + b] = h
                values[base + 6 * (a + 3) + b + 3] = h
                values[base + 6 * a + b + 3] = -h
                values[base + 6 * (a + 3) + b] = -h


@njit(cache=True, error_model="numpy")
def stretch_tension(x, edges, l0, ea, tension_only, out):
    """Axial force EA*eps of every edge [N] (0 when slack and tension-only)."""
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        eps = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) / l0[k] - 1.0
        _, force, _ = _law(eps, tension_only, 0.0)
        out[k] = ea[k] * force
