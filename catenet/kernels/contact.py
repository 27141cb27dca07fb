"""Frictionless contact of nodes with rigid obstacles: a log-barrier of the gap d.

Every free node k at distance d_k from an obstacle (d > 0 outside) stores
E_k = kappa b(d_k) with the barrier of incremental-potential contact,

    b(d) = -(d - dhat)^2 ln(d / dhat)  for 0 < d < dhat,  0 for d >= dhat,

which is C2 at d = dhat (b = b' = b'' = 0 there) and grows without bound as d -> 0: a
state with a node on or inside an obstacle has infinite energy, and the solvers' line
search, capped by the first time a node would touch an obstacle along the step
(``*_max_step``), never accepts one. The contact force is -kappa b'(d) along the outward
normal; at equilibrium the gap is the d at which it balances the node's load, below dhat.

Gradient kappa b'(d) grad d; Hessian kappa (b''(d) grad d grad d^T + b'(d) hess d), with
grad d = n the outward normal and hess d = 0 (plane) or (I - n n^T)/rho (sphere of centre
c, rho = |x - c|). Values are written per free node as a 3x3 block (row-major).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def barrier(d, dhat):
    """b, b', b'' of the log-barrier at gap d with activation distance dhat."""
    if d >= dhat:
        return 0.0, 0.0, 0.0
    if d <= 0.0:
        return np.inf, -np.inf, np.inf
    lg = np.log(d / dhat)
    r = d - dhat
    return -r * r * lg, -2.0 * r * lg - r * r / d, -2.0 * lg - 4.0 * r / d + r * r / (d * d)


@njit(cache=True, error_model="numpy")
def plane_gradient(x, nodes, point, normal, kappa, dhat, grad):
    """Adds the barrier's gradient of the plane n.(x - p) >= 0 at ``nodes``; returns the
    energy."""
    total = 0.0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        d = 0.0
        for a in range(3):
            d += normal[a] * (x[i, a] - point[a])
        if d >= dhat:
            continue
        b, db, _ = barrier(d, dhat)
        total += kappa * b
        for a in range(3):
            grad[i, a] += kappa * db * normal[a]
    return total


@njit(cache=True, error_model="numpy")
def plane_hessian(x, nodes, point, normal, kappa, dhat, values):
    """Writes the 3x3 blocks of the plane barrier at ``nodes``; returns how many act."""
    active = 0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        d = 0.0
        for a in range(3):
            d += normal[a] * (x[i, a] - point[a])
        _, _, ddb = barrier(d, dhat)
        if ddb != 0.0:
            active += 1
        for a in range(3):
            for c in range(3):
                values[9 * k + 3 * a + c] = kappa * ddb * normal[a] * normal[c]
    return active


@njit(cache=True, error_model="numpy")
def plane_max_step(x, dx, nodes, point, normal):
    """The largest t in (0, inf] with every node's n.(x + t dx - p) > 0 (the step at which
    the first node would reach the plane)."""
    t_max = np.inf
    for k in range(nodes.shape[0]):
        i = nodes[k]
        d = 0.0
        v = 0.0
        for a in range(3):
            d += normal[a] * (x[i, a] - point[a])
            v += normal[a] * dx[i, a]
        if v < 0.0:
            t = -d / v
            if t < t_max:
                t_max = t
    return t_max


@njit(cache=True, error_model="numpy")
def sphere_gradient(x, nodes, center, radius, kappa, dhat, grad):
    """Adds the barrier's gradient of the sphere |x - c| >= R at ``nodes``; returns the
    energy."""
    total = 0.0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        u0 = x[i, 0] - center[0]
        u1 = x[i, 1] - center[1]
        u2 = x[i, 2] - center[2]
        energy, f = sphere_force(u0, u1, u2, radius, kappa, dhat)
        total += energy
        grad[i, 0] += f * u0
        grad[i, 1] += f * u1
        grad[i, 2] += f * u2
    return total


@njit(cache=True, error_model="numpy")
def sphere_hessian(x, nodes, center, radius, kappa, dhat, values):
    """Writes the 3x3 blocks of the sphere barrier at ``nodes``; returns how many act."""
    active = 0
    u = np.empty(3)
    for k in range(nodes.shape[0]):
        i = nodes[k]
        for a in range(3):
            u[a] = x[i, a] - center[a]
        active += sphere_block(u, radius, kappa, dhat, values, 9 * k)
    return active


@njit(cache=True, error_model="numpy")
def sphere_max_step(x, dx, nodes, center, radius):
    """The largest t with every node outside the sphere along x + t dx: the first root of
    |x + t dx - c|^2 = R^2 over the nodes (inf where none is hit)."""
    t_max = np.inf
    for k in range(nodes.shape[0]):
        i = nodes[k]
        u = (x[i, 0] - center[0], x[i, 1] - center[1], x[i, 2] - center[2])
        t = ball_root(u, (dx[i, 0], dx[i, 1], dx[i, 2]), radius)
        if t < t_max:
            t_max = t
    return t_max


@njit(cache=True, error_model="numpy")
def sphere_force(u0, u1, u2, radius, kappa, dhat):
    """(energy, f) of the barrier on the gap d = |u| - R of a point at u from a ball's
    centre: its gradient with respect to the point is f u (0, 0 out of reach)."""
    rho = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    d = rho - radius
    if d >= dhat:
        return 0.0, 0.0
    b, db, _ = barrier(d, dhat)
    return kappa * b, kappa * db / rho


@njit(cache=True, error_model="numpy")
def sphere_block(u, radius, kappa, dhat, out, at):
    """Writes the 3x3 Hessian block kappa ((b'' - b'/rho) n n^T + b'/rho I) of the barrier
    on the gap d = rho - R of a point at u (3,) from a ball's centre (rho = |u|,
    n = u / rho; u is overwritten by n) at out[at:at + 9], zeros out of reach; returns 1
    where the barrier acts, else 0."""
    rho = np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    d = rho - radius
    if d >= dhat:
        for a in range(9):
            out[at + a] = 0.0
        return 0
    _, db, ddb = barrier(d, dhat)
    for a in range(3):
        u[a] /= rho
    for a in range(3):
        for c in range(3):
            h = kappa * (ddb - db / rho) * u[a] * u[c]
            if a == c:
                h += kappa * db / rho
            out[at + 3 * a + c] = h
    return 1


@njit(cache=True, error_model="numpy")
def ball_root(u, du, radius):
    """The first t >= 0 with |u + t du| = R (u, du: 3-tuples, a point relative to a ball's
    centre and its relative motion); inf when it never gets there or moves away."""
    a = du[0] * du[0] + du[1] * du[1] + du[2] * du[2]
    b = 2.0 * (u[0] * du[0] + u[1] * du[1] + u[2] * du[2])
    c = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] - radius * radius
    if a == 0.0 or b >= 0.0:
        return np.inf  # not moving, or moving away from the centre
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return np.inf
    return max((-b - np.sqrt(disc)) / (2.0 * a), 0.0)
