"""Contact of the net's nodes with a moving rigid sphere whose centre is a node of its own.

A rigid ball of radius R is one extra node c of the net (three DOFs, no edges, its mass
lumped there). Every free node i of the net and the centre share the barrier of
``catenet.kernels.contact`` on the gap d = |x_i - x_c| - R:

    E = kappa sum_i b(d_i),    grad_i E = kappa b'(d_i) n_i,    grad_c E = -sum_i grad_i E,

with n_i = (x_i - x_c) / rho_i, rho_i = |x_i - x_c|, so the net pushes the ball exactly
as much as the ball pushes the net (momentum is exchanged, never created). With
H_i = kappa ((b'' - b'/rho) n n^T + b'/rho I), the Hessian blocks are H_i at (i, i),
-H_i at (i, c) and (c, i), and sum_i H_i at (c, c). Values are written per node as its
(i, i), (i, c), (c, i) blocks (27 values, row-major), then the one (c, c) block (9).

The first contact along a step (x + t dx) is the first root of |u + t du| = R in the
relative motion u = x_i - x_c, du = dx_i - dx_c (a quadratic in t), exact for any motion
of both.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.contact import ball_root, sphere_block, sphere_force


@njit(cache=True, error_model="numpy")
def pair_gradient(x, nodes, c, radius, kappa, dhat, grad):
    """Adds the barrier's gradient between ``nodes`` and the centre node c; returns the
    energy."""
    total = 0.0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        u0 = x[i, 0] - x[c, 0]
        u1 = x[i, 1] - x[c, 1]
        u2 = x[i, 2] - x[c, 2]
        energy, f = sphere_force(u0, u1, u2, radius, kappa, dhat)
        total += energy
        grad[i, 0] += f * u0
        grad[i, 1] += f * u1
        grad[i, 2] += f * u2
        grad[c, 0] -= f * u0
        grad[c, 1] -= f * u1
        grad[c, 2] -= f * u2
    return total


@njit(cache=True, error_model="numpy")
def pair_hessian(x, nodes, c, radius, kappa, dhat, values):
    """Writes the blocks described in the module docstring; returns how many nodes act."""
    active = 0
    u = np.empty(3)
    cc = np.zeros(9)
    base = 27 * nodes.shape[0]
    for k in range(nodes.shape[0]):
        i = nodes[k]
        for a in range(3):
            u[a] = x[i, a] - x[c, a]
        active += sphere_block(u, radius, kappa, dhat, values, 27 * k)
        for a in range(9):
            h = values[27 * k + a]
            values[27 * k + 9 + a] = -h
            values[27 * k + 18 + a] = -h
            cc[a] += h
    for a in range(9):
        values[base + a] = cc[a]
    return active


@njit(cache=True, error_model="numpy")
def pair_max_step(x, dx, nodes, c, radius):
    """The largest t with every node outside the moving sphere along x + t dx: the first
    root of |u + t du|^2 = R^2 over the nodes (inf where none is hit)."""
    t_max = np.inf
    for k in range(nodes.shape[0]):
        i = nodes[k]
        u = (x[i, 0] - x[c, 0], x[i, 1] - x[c, 1], x[i, 2] - x[c, 2])
        du = (dx[i, 0] - dx[c, 0], dx[i, 1] - dx[c, 1], dx[i, 2] - dx[c, 2])
        t = ball_root(u, du, radius)
        if t < t_max:
            t_max = t
    return t_max


@njit(cache=True, error_model="numpy")
def pair_gap(x, nodes, c, radius, out):
    """Writes each node's gap |x_i - x_c| - R into ``out``."""
    for k in range(nodes.shape[0]):
        i = nodes[k]
        s = 0.0
        for j in range(3):
            u = x[i, j] - x[c, j]
            s += u * u
        out[k] = np.sqrt(s) - radius
