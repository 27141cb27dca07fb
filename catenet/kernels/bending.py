"""Bending of rods: discrete elastic rods (Bergou et al. 2008) without twist.

A hinge is an interior node j of a rod between its edges e1 = x_j - x_i and
e2 = x_k - x_j, with unit tangents t1, t2, turning angle phi and

    s = |t2 - t1| = 2 sin(phi / 2),    E = k (s - s0)^2,    k = EI / (l1 + l2),

l1, l2 the rest lengths (the Voronoi length of the hinge is (l1 + l2) / 2) and s0 the
natural value (0: straight). For a polygon inscribed in a circle of radius R with equal
chords l, s / l = 1 / R exactly, so E = EI / 2 kappa^2 (l1 + l2) / 2 is the rod's
bending energy of its Voronoi length. Bergou's curvature binormal has |kb| =
2 tan(phi / 2), which is the same to second order in phi but infinite at a 180-degree
fold; s is bounded (2 at a fold), smooth in x everywhere (for s0 = 0 a polynomial of
the tangents) and has a smooth maximum at the fold, so no state gives inf or NaN.

Everything is written through c = t1 . t2 (s^2 = 2 (1 - c)), whose derivatives are
exact and free of cancellation when 1 - c = |t2 - t1|^2 / 2 is taken from d = t2 - t1:

    dc/de1 = g1 = (t2 - c t1) / L1 = (d + q t1) / L1,   q = 1 - c = |d|^2 / 2,
    dc/de2 = g2 = (t1 - c t2) / L2 = (q t2 - d) / L2,
    d2c/de1 de1 = -(t1 g1^T + g1 t1^T) / L1 - c (I - t1 t1^T) / L1^2 (and 2 alike),
    d2c/de1 de2 = (I - t1 t1^T - t2 t2^T + c t1 t2^T) / (L1 L2),

L1, L2 the current lengths. With E = f(c): grad = f'(c) g, Hessian = f'(c) d2c +
f''(c) g g^T, where for s0 = 0 f = 2 k (1 - c) (f'' = 0), and for s0 > 0
f' = -2 k (1 - s0 / s), f'' = 2 k s0 / s^3. Below s = DELTA s0 (a naturally curved
hinge pressed straight: the energy's cone tip, where f'' is unbounded) the energy is
the quadratic a + b s^2 (linear in c) that meets k (s - s0)^2 with its slope at DELTA
s0: C1 everywhere, exact elsewhere.

The nodes' derivatives follow from e1 = x_j - x_i, e2 = x_k - x_j: (dE/dx_i, dE/dx_j,
dE/dx_k) = (-G1, G1 - G2, G2) and the 9 x 9 Hessian J^T H J.

A clamp holds the tangent of a rod's end edge e = x_o - x_c at t0 (the given one):
E = kc |t - t0|^2, kc = EI / l, the same energy with t1 = t0 fixed: the end of the rod
mirrored at the clamp (a hinge of angle 2 theta over the Voronoi length l, half of
whose energy is the rod's), exact to O(theta^2) at the one end node.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Below s = DELTA s0, a naturally curved hinge's energy is quadratic in s (see above).
DELTA = 1e-3


@njit(cache=True)
def _f(s, q, k, s0):
    """Energy and f'(c), f''(c) of a hinge whose |t2 - t1| is s (q = s^2 / 2)."""
    if s0 == 0.0:
        return 2.0 * k * q, -2.0 * k, 0.0
    delta = DELTA * s0
    if s < delta:
        b = k * (delta - s0) / delta
        a = k * (delta - s0) ** 2 - b * delta * delta
        return a + 2.0 * b * q, -2.0 * b, 0.0
    return k * (s - s0) ** 2, -2.0 * k * (1.0 - s0 / s), 2.0 * k * s0 / (s * s * s)


@njit(cache=True)
def _tangents(t1, t2):
    """d = t2 - t1, q = 1 - c, c, s."""
    d = t2 - t1
    q = 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    return d, q, 1.0 - q, np.sqrt(2.0 * q)


@njit(cache=True)
def _unit(x, i, j):
    e = x[j] - x[i]
    length = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    return e / length, length


@njit(cache=True)
def _hinge(t1, l1, t2, l2, k, s0, want_hessian):
    """Energy, dE/de1, dE/de2 and (want_hessian) the blocks H11, H12, H22."""
    d, q, c, s = _tangents(t1, t2)
    energy, f1, f2 = _f(s, q, k, s0)
    g1 = (d + q * t1) / l1
    g2 = (q * t2 - d) / l2
    h11 = np.zeros((3, 3))
    h12 = np.zeros((3, 3))
    h22 = np.zeros((3, 3))
    if want_hessian:
        for a in range(3):
            for b in range(3):
                eye = 1.0 if a == b else 0.0
                c11 = -(t1[a] * g1[b] + g1[a] * t1[b]) / l1 - c * (eye - t1[a] * t1[b]) / (l1 * l1)
                c22 = -(t2[a] * g2[b] + g2[a] * t2[b]) / l2 - c * (eye - t2[a] * t2[b]) / (l2 * l2)
                c12 = (eye - t1[a] * t1[b] - t2[a] * t2[b] + c * t1[a] * t2[b]) / (l1 * l2)
                h11[a, b] = f1 * c11 + f2 * g1[a] * g1[b]
                h22[a, b] = f1 * c22 + f2 * g2[a] * g2[b]
                h12[a, b] = f1 * c12 + f2 * g1[a] * g2[b]
    return energy, f1 * g1, f1 * g2, h11, h12, h22


@njit(cache=True)
def _clamp(x, c, o, t0, kc, want_hessian):
    """Energy, dE/de and d2E/de2 of a clamp (e = x_o - x_c against the fixed t0)."""
    t, length = _unit(x, c, o)
    energy, _, g, _, _, h = _hinge(t0, 1.0, t, length, kc, 0.0, want_hessian)
    return energy, g, h


@njit(cache=True)
def bend_gradient(x, hinges, k, s0, clamps, t0, kc, grad):
    """Adds dE/dx into grad (N, 3); returns the bending energy."""
    total = 0.0
    for h in range(hinges.shape[0]):
        i, j, m = hinges[h, 0], hinges[h, 1], hinges[h, 2]
        t1, l1 = _unit(x, i, j)
        t2, l2 = _unit(x, j, m)
        energy, g1, g2, _, _, _ = _hinge(t1, l1, t2, l2, k[h], s0[h], np.bool_(False))
        total += energy
        for a in range(3):
            grad[i, a] -= g1[a]
            grad[j, a] += g1[a] - g2[a]
            grad[m, a] += g2[a]
    for h in range(clamps.shape[0]):
        c, o = clamps[h, 0], clamps[h, 1]
        energy, g, _ = _clamp(x, c, o, t0[h], kc[h], np.bool_(False))
        total += energy
        for a in range(3):
            grad[c, a] -= g[a]
            grad[o, a] += g[a]
    return total


@njit(cache=True)
def bend_energy(x, hinges, k, s0, clamps, t0, kc):
    """The bending energy [J] of positions x (N, 3)."""
    return bend_gradient(x, hinges, k, s0, clamps, t0, kc, np.zeros_like(x))


@njit(cache=True)
def bend_hessian(x, hinges, k, s0, clamps, t0, kc, values):
    """Writes the Hessian values: per hinge the 9 x 9 block of its nodes (i, j, k) row by
    row, then per clamp the 6 x 6 block of (c, o)."""
    jac = np.array([[-1.0, 0.0], [1.0, -1.0], [0.0, 1.0]])  # d(e1, e2)/d(x_i, x_j, x_k)
    for h in range(hinges.shape[0]):
        i, j, m = hinges[h, 0], hinges[h, 1], hinges[h, 2]
        t1, l1 = _unit(x, i, j)
        t2, l2 = _unit(x, j, m)
        _, _, _, h11, h12, h22 = _hinge(t1, l1, t2, l2, k[h], s0[h], np.bool_(True))
        base = 81 * h
        for p in range(3):
            for r in range(3):
                a11 = jac[p, 0] * jac[r, 0]
                a12 = jac[p, 0] * jac[r, 1]
                a21 = jac[p, 1] * jac[r, 0]
                a22 = jac[p, 1] * jac[r, 1]
                for a in range(3):
                    row = base + 27 * p + 9 * a + 3 * r
                    for b in range(3):
                        values[row + b] = (
                            a11 * h11[a, b] + a12 * h12[a, b] + a21 * h12[b, a] + a22 * h22[a, b]
                        )
    base = 81 * hinges.shape[0]
    for h in range(clamps.shape[0]):
        _, _, hc = _clamp(x, clamps[h, 0], clamps[h, 1], t0[h], kc[h], np.bool_(True))
        for p in range(2):
            for r in range(2):
                sign = 1.0 if p == r else -1.0
                for a in range(3):
                    row = base + 18 * p + 6 * a + 3 * r
                    for b in range(3):
                        values[row + b] = sign * hc[a, b]
        base += 36


@njit(cache=True)
def bend_measure(x, hinges, clamps, t0, out_hinge, out_clamp):
    """|t2 - t1| of every hinge and |t - t0| of every clamp at x."""
    for h in range(hinges.shape[0]):
        t1, _ = _unit(x, hinges[h, 0], hinges[h, 1])
        t2, _ = _unit(x, hinges[h, 1], hinges[h, 2])
        out_hinge[h] = _tangents(t1, t2)[3]
    for h in range(clamps.shape[0]):
        t, _ = _unit(x, clamps[h, 0], clamps[h, 1])
        out_clamp[h] = _tangents(t0[h], t)[3]
