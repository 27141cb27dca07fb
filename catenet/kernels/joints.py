"""Rigid joints of rods (``catenet.model.joints``): E = sum_i k_i |t_i - R t_i0|^2 over
a joint's members, R the rotation that minimises it, and E's exact derivatives.

Member i is the edge e_i = x_o - x_j from the joint node j, L_i = |e_i|, t_i = e_i / L_i,
P_i = I - t_i t_i^T. R is the polar factor of B = sum_i k_i t_i t_i0^T, a proper rotation:
B = U S V^T, U' = U D and s' = D S with D = diag(1, 1, det(U V^T)), R = U' V^T.

- Gradient: R minimises E, so dE/dt_i = -2 k_i w_i, w_i = R t_i0 (envelope theorem), and
  dE/de_i = -2 k_i P_i w_i / L_i.
- Hessian: d/de_l of that is -2 k_i (P_i dw_i / L_i + delta_il d2(w . t_i)/de_i^2 with w
  fixed), where d2(w . t)/de^2 = -((t . w) P + t w_p^T + w_p t^T) / L^2, w_p = P w, and
  dw_i = dR t_i0, dR = U' Omega V^T with Omega skew, Omega_ab = (C_ab - C_ba) / (s'_a +
  s'_b), C = U'^T dB V, dB = sum_l k_l (P_l de_l / L_l) t_l0^T (from B = R Y, Y = V S'
  V^T symmetric: C - C^T = Omega S' + S' Omega).
- Nodes: dE/dx_o = dE/de_i, dE/dx_j = -sum_i dE/de_i, and the Hessian's blocks likewise.

The denominators s'_a + s'_b vanish only where the members all lie on one line (then the
turn about it is free: R is not unique) or the joint is turned half a turn against its
members; ``catenet.model.joints`` refuses joints drawn on one line, and such a Omega
entry is left 0 (its rotation's share of the Hessian dropped, E and its gradient exact).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: A denominator s'_a + s'_b below this share of the largest singular value: left out.
TINY = 1e-12


@njit(cache=True)
def _polar(B):
    """R, U', s', V of B (module docstring)."""
    U, S, Vt = np.linalg.svd(B)
    V = np.ascontiguousarray(Vt.T)
    Up = U.copy()
    s = S.copy()
    if np.linalg.det(U @ Vt) < 0.0:
        Up[:, 2] = -Up[:, 2]
        s[2] = -s[2]
    return np.ascontiguousarray(Up @ Vt), Up, s, V


@njit(cache=True)
def _members(x, j, lo, hi, other):
    """The members' unit tangents (m, 3) and lengths (m,)."""
    m = hi - lo
    t = np.empty((m, 3))
    length = np.empty(m)
    for p in range(m):
        e = x[other[lo + p]] - x[j]
        n = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        length[p] = n
        t[p] = e / n
    return t, length


@njit(cache=True)
def _joint(x, j, lo, hi, other, rest, k):
    """R, U', s', V, the tangents, lengths and the energy of one joint."""
    t, length = _members(x, j, lo, hi, other)
    B = np.zeros((3, 3))
    for p in range(hi - lo):
        B += k[lo + p] * np.outer(t[p], rest[lo + p])
    R, Up, s, V = _polar(B)
    energy = 0.0
    for p in range(hi - lo):
        d = t[p] - R @ rest[lo + p]
        energy += k[lo + p] * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    return R, Up, s, V, t, length, energy


@njit(cache=True)
def joint_rotations(x, node, start, other, rest, k, out):
    """Each joint's rotation R at x into out (J, 3, 3)."""
    for jj in range(len(node)):
        R, _, _, _, _, _, _ = _joint(x, node[jj], start[jj], start[jj + 1], other, rest, k)
        out[jj] = R


@njit(cache=True)
def joint_energy(x, node, start, other, rest, k):
    total = 0.0
    for jj in range(len(node)):
        total += _joint(x, node[jj], start[jj], start[jj + 1], other, rest, k)[6]
    return total


@njit(cache=True)
def joint_gradient(x, node, start, other, rest, k, grad):
    """Adds dE/dx into grad (N, 3); returns E."""
    total = 0.0
    for jj in range(len(node)):
        j, lo, hi = node[jj], start[jj], start[jj + 1]
        R, _, _, _, t, length, energy = _joint(x, j, lo, hi, other, rest, k)
        total += energy
        for p in range(hi - lo):
            w = R @ rest[lo + p]
            wp = w - t[p] * (t[p] @ w)
            g = -2.0 * k[lo + p] * wp / length[p]
            grad[other[lo + p]] += g
            grad[j] -= g
    return total


@njit(cache=True)
def _edge_hessian(R, Up, s, V, t, length, rest, k):
    """(3m, 3m) d2E/de de of one joint (module docstring)."""
    m = len(length)
    H = np.zeros((3 * m, 3 * m))
    P = np.empty((m, 3, 3))
    w = np.empty((m, 3))
    for p in range(m):
        P[p] = np.eye(3) - np.outer(t[p], t[p])
        w[p] = R @ rest[p]
        wp = P[p] @ w[p]
        block = (t[p] @ w[p]) * P[p] + np.outer(t[p], wp) + np.outer(wp, t[p])
        H[3 * p : 3 * p + 3, 3 * p : 3 * p + 3] += 2.0 * k[p] * block / length[p] ** 2
    scale = abs(s[0])
    for q in range(m):
        for c in range(3):
            dt = P[q][:, c] / length[q]
            dB = k[q] * np.outer(dt, rest[q])
            C = Up.T @ dB @ V
            omega = np.zeros((3, 3))
            for a in range(3):
                for b in range(3):
                    den = s[a] + s[b]
                    if a != b and abs(den) > TINY * scale:
                        omega[a, b] = (C[a, b] - C[b, a]) / den
            dR = Up @ omega @ V.T
            for p in range(m):
                dw = dR @ rest[p]
                col = -2.0 * k[p] * (P[p] @ dw) / length[p]
                H[3 * p : 3 * p + 3, 3 * q + c] += col
    return 0.5 * (H + H.T)


@njit(cache=True)
def joint_hessian(x, node, start, other, rest, k, values):
    """Each joint's dense 3 (m + 1) square block over its nodes (the joint node, then its
    members' others), row-major, one after another into values."""
    at = 0
    for jj in range(len(node)):
        j, lo, hi = node[jj], start[jj], start[jj + 1]
        m = hi - lo
        R, Up, s, V, t, length, _ = _joint(x, j, lo, hi, other, rest, k)
        He = _edge_hessian(R, Up, s, V, t, length, rest[lo:hi], k[lo:hi])
        n = 3 * (m + 1)
        H = np.zeros((n, n))
        for p in range(m):
            for q in range(m):
                blk = He[3 * p : 3 * p + 3, 3 * q : 3 * q + 3]
                H[3 + 3 * p : 6 + 3 * p, 3 + 3 * q : 6 + 3 * q] += blk
                H[3 + 3 * p : 6 + 3 * p, 0:3] -= blk
                H[0:3, 3 + 3 * q : 6 + 3 * q] -= blk
                H[0:3, 0:3] += blk
        for a in range(n):
            for b in range(n):
                values[at + a * n + b] = H[a, b]
        at += n * n
