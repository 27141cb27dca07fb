"""Water on a cable: Morison drag on each half edge, and buoyancy of the wetted part of
each edge (``catenet.terms.water``).

Drag, per half edge h at node i (tangent t, coefficients c_n, c_t fixed in the step):
E_h = (c_n |P u|^3 + c_t |t.u|^3) / (3 k) with u = k (x_i - c_i) - U_i the velocity
relative to the water (the scheme's velocity k (x - c)), P = I - t t^T: its gradient is
the drag c_n |P u| P u + c_t |t.u| (t.u) t and its Hessian
k (c_n (|w| P + w w^T / |w|) + 2 c_t |s| t t^T), w = P u, s = t.u: convex, continuous,
zero at u = 0.

Buoyancy of an edge between heights z_i, z_j below the still level z_s: with
zeta(s) = z_s - z(s) along the edge (s in [0, 1]), E = K int_0^1 Psi(zeta(s)) ds,
K = rho_w g A l0, and Psi the depth below the level smoothed over the cable's thickness
2 hw: 0 above zeta = -hw, (zeta + hw)^2 / (4 hw) across, zeta below +hw. Psi is convex and
C1 with Psi'' = 1 / (2 hw) across, so E is convex and its Hessian bounded by K / (6 hw)
whatever the edge's slope. The integrals are exact: the edge is cut where zeta crosses
+-hw and each piece (a polynomial of degree <= 3 in s) is integrated by 2-point Gauss.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_G = 1.0 / math.sqrt(3.0)


@njit(cache=True, error_model="numpy")
def drag_gradient(x, nodes, tang, cn, ct, flow, centre, kv, grad):
    """Adds the drag's gradient (minus the drag force) at each half edge's node to grad
    (N, 3); returns the energy."""
    total = 0.0
    for h in range(nodes.shape[0]):
        i = nodes[h]
        u0 = kv * (x[i, 0] - centre[i, 0]) - flow[i, 0]
        u1 = kv * (x[i, 1] - centre[i, 1]) - flow[i, 1]
        u2 = kv * (x[i, 2] - centre[i, 2]) - flow[i, 2]
        t0, t1, t2 = tang[h, 0], tang[h, 1], tang[h, 2]
        s = t0 * u0 + t1 * u1 + t2 * u2
        w0, w1, w2 = u0 - s * t0, u1 - s * t1, u2 - s * t2
        wn = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        a = cn[h] * wn
        b = ct[h] * abs(s) * s
        grad[i, 0] += a * w0 + b * t0
        grad[i, 1] += a * w1 + b * t1
        grad[i, 2] += a * w2 + b * t2
        total += (cn[h] * wn**3 + ct[h] * abs(s) ** 3) / (3.0 * kv)
    return total


@njit(cache=True, error_model="numpy")
def drag_hessian(x, nodes, tang, cn, ct, flow, centre, kv, slot, values):
    """Adds each half edge's 3 x 3 Hessian block into its node's block of values (9 per
    free node, row-major, at 9 slot[node])."""
    for h in range(nodes.shape[0]):
        i = nodes[h]
        k0 = 9 * slot[i]
        u = (
            kv * (x[i, 0] - centre[i, 0]) - flow[i, 0],
            kv * (x[i, 1] - centre[i, 1]) - flow[i, 1],
            kv * (x[i, 2] - centre[i, 2]) - flow[i, 2],
        )
        t = (tang[h, 0], tang[h, 1], tang[h, 2])
        s = t[0] * u[0] + t[1] * u[1] + t[2] * u[2]
        w = (u[0] - s * t[0], u[1] - s * t[1], u[2] - s * t[2])
        wn = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        lat = kv * cn[h] * wn
        out = kv * cn[h] / wn if wn > 0.0 else 0.0
        ax = 2.0 * kv * ct[h] * abs(s)
        for p in range(3):
            for q in range(3):
                eye = 1.0 if p == q else 0.0
                values[k0 + 3 * p + q] += (
                    lat * (eye - t[p] * t[q]) + out * w[p] * w[q] + ax * t[p] * t[q]
                )


@njit(cache=True)
def _ramp(zeta, hw):
    """Psi, Psi' and Psi'' at zeta (see the module docstring)."""
    if zeta <= -hw:
        return 0.0, 0.0, 0.0
    if zeta >= hw:
        return zeta, 1.0, 0.0
    q = zeta + hw
    return q * q / (4.0 * hw), q / (2.0 * hw), 1.0 / (2.0 * hw)


@njit(cache=True)
def wetted(a, b, hw, out):
    """out[:] = G, dG/da, dG/db, d2G/da2, d2G/dadb, d2G/db2 of
    G(a, b) = int_0^1 Psi(a + s (b - a)) ds (exact, piecewise 2-point Gauss)."""
    for k in range(6):
        out[k] = 0.0
    cuts = np.empty(4)  # 0, 1 and where a + s d crosses -hw and hw, sorted
    cuts[0], cuts[1] = 0.0, 1.0
    m = 2
    d = b - a
    if d != 0.0:
        for level in (-hw, hw):
            s = (level - a) / d
            if 0.0 < s < 1.0:
                j = m  # insertion (a list's sort compiles slowly)
                while cuts[j - 1] > s:
                    cuts[j] = cuts[j - 1]
                    j -= 1
                cuts[j] = s
                m += 1
    for c in range(m - 1):
        mid = 0.5 * (cuts[c] + cuts[c + 1])
        half = 0.5 * (cuts[c + 1] - cuts[c])
        if half <= 0.0:
            continue
        for sign in (-1.0, 1.0):
            s = mid + sign * _G * half
            psi, dpsi, ddpsi = _ramp(a + s * d, hw)
            r = 1.0 - s
            out[0] += half * psi
            out[1] += half * r * dpsi
            out[2] += half * s * dpsi
            out[3] += half * r * r * ddpsi
            out[4] += half * r * s * ddpsi
            out[5] += half * s * s * ddpsi


@njit(cache=True)
def buoyancy_gradient(x, edges, weight, half, surface, grad):
    """Adds the buoyancy's gradient (z only) to grad (N, 3); returns the energy."""
    total = 0.0
    g = np.zeros(6)
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        wetted(surface - x[i, 2], surface - x[j, 2], half[e], g)
        total += weight[e] * g[0]
        grad[i, 2] -= weight[e] * g[1]
        grad[j, 2] -= weight[e] * g[2]
    return total


@njit(cache=True)
def buoyancy_hessian(x, edges, weight, half, surface, values):
    """The z-z Hessian values of each edge, 4 per edge: (i, i), (i, j), (j, i), (j, j)."""
    g = np.zeros(6)
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        wetted(surface - x[i, 2], surface - x[j, 2], half[e], g)
        k = 4 * e
        values[k] = weight[e] * g[3]
        values[k + 1] = weight[e] * g[4]
        values[k + 2] = weight[e] * g[4]
        values[k + 3] = weight[e] * g[5]


@njit(cache=True)
def added_gradient(x, nodes, added, centre, ka, inflow, grad):
    """Adds ka M_i (x_i - c_i) - F_i at the given nodes (M_i: the (3, 3) added mass,
    F_i the flow's inertia force) to grad; returns 1/2 ka r.M r - F.x summed."""
    total = 0.0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        r0, r1, r2 = x[i, 0] - centre[i, 0], x[i, 1] - centre[i, 1], x[i, 2] - centre[i, 2]
        for p in range(3):
            m = added[i, p, 0] * r0 + added[i, p, 1] * r1 + added[i, p, 2] * r2
            grad[i, p] += ka * m - inflow[i, p]
            total -= inflow[i, p] * x[i, p]
            total += 0.5 * ka * m * (r0 if p == 0 else r1 if p == 1 else r2)
    return total
