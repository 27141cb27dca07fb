"""The twist of a rod held at a rigid joint (``catenet.kernels.twist``): the joint's
director and the derivatives of its turn about the rod's end tangent, and the small
vector helpers the twist kernels share."""

from __future__ import annotations

import numpy as np
from numba import njit

#: Below this share of the partner edge's length, its part normal to the rod vanishes.
FOLD = 1e-12


@njit(cache=True)
def cross(a, b):
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


@njit(cache=True)
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def skew(v):
    out = np.zeros((3, 3))
    out[0, 1], out[0, 2] = -v[2], v[1]
    out[1, 0], out[1, 2] = v[2], -v[0]
    out[2, 0], out[2, 1] = -v[1], v[0]
    return out


@njit(cache=True)
def joint_director(x, j, other, t, phase):
    """A rigid joint's director for a rod ending at node j with unit end tangent t:
    cos(phase) n + sin(phase) t x n, n the unit part normal to t of the partner member's
    edge from j to ``other`` (``catenet.model.twist``); NaN where that part vanishes."""
    b = x[other] - x[j]
    v = b - dot(b, t) * t
    size = np.sqrt(dot(v, v))
    if not size > FOLD * np.sqrt(dot(b, b)):
        return np.full(3, np.nan)
    nv = v / size
    return np.cos(phase) * nv + np.sin(phase) * cross(t, nv)


@njit(cache=True)
def psi_gradient(a, b):
    """d psi / da, d psi / db: the turn psi of the unit normal part of b about the unit
    t = a / |a| (t . (n x dn)): with w = t x b and q = |b|^2 - (b . t)^2,
    d psi / db = w / q and d psi / da = -(b . t) w / (|a| q)."""
    A = np.sqrt(dot(a, a))
    t = a / A
    beta = dot(b, t)
    q = dot(b, b) - beta * beta
    w = cross(t, b)
    return -beta * w / (A * q), w / q


@njit(cache=True)
def psi_jacobian(a, b):
    """(2, 2, 3, 3): d(d psi / d e_p) / d e_q for e_1 = a, e_2 = b (``psi_gradient``),
    with P = I - t t^T and v = P b:
    d(w / q)/db = [t] / q - 2 w v^T / q^2,
    d(w / q)/da = -[b] P / (A q) + 2 beta w v^T / (A q^2),
    d(-beta w / (A q))/db = -(w t^T + beta [t]) / (A q) + 2 beta w v^T / (A q^2),
    d(-beta w / (A q))/da = (-w v^T + beta [b] P + beta w t^T) / (A^2 q)
        - 2 beta^2 w v^T / (A^2 q^2)."""
    A = np.sqrt(dot(a, a))
    t = a / A
    beta = dot(b, t)
    q = dot(b, b) - beta * beta
    w = cross(t, b)
    v = b - beta * t
    kt, kb_ = skew(t), skew(b)
    P = np.eye(3)
    for i in range(3):
        for k in range(3):
            P[i, k] -= t[i] * t[k]
    bP = kb_ @ P
    out = np.zeros((2, 2, 3, 3))
    for i in range(3):
        for k in range(3):
            wv = w[i] * v[k]
            out[1, 1, i, k] = kt[i, k] / q - 2.0 * wv / (q * q)
            out[1, 0, i, k] = -bP[i, k] / (A * q) + 2.0 * beta * wv / (A * q * q)
            out[0, 1, i, k] = -(w[i] * t[k] + beta * kt[i, k]) / (A * q) + 2.0 * beta * wv / (
                A * q * q
            )
            out[0, 0, i, k] = (-wv + beta * bP[i, k] + beta * w[i] * t[k]) / (A * A * q) - (
                2.0 * beta * beta * wv / (A * A * q * q)
            )
    return out
