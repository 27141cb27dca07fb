"""Coulomb friction of nodes on rigid obstacles: a lagged dissipative potential per step.

At the start of every load or time step each contact node k stores its weight
w_k = mu_f lambda_k (the friction coefficient times the barrier's normal force at the last
accepted state), the unit normal n_k there and an anchor point a_k (where it sticks).
During the step its tangential displacement from the anchor is

    u_k = P_k (x_k - a_k),   P_k = I - n_k n_k^T,   y = |u_k|,

and the step's potential is D = sum_k w_k f(y) with the smoothed |u| of incremental-
potential contact, shifted to vanish at u = 0,

    f(y) = -y^3 / (3 eps^2) + y^2 / eps   (y < eps),    y - eps / 3   (y >= eps),

whose slope f'(y) = 2 y / eps - y^2 / eps^2 (then 1) rises from 0 to 1 at the slip
distance eps; f is C2 at eps (f'' = 2/eps - 2y/eps^2 vanishes there). The friction force
-w_k f'(y) u/y opposes the tangential displacement and never exceeds w_k = mu_f lambda_k.

Gradient w f'(y)/y u; Hessian w [ (f'/y) P + (f'' - f'/y) u u^T / y^2 ], which is
w [ (2/eps - y/eps^2) P - u u^T / (eps^2 y) ] below eps and w / y (P - u u^T / y^2) beyond:
both positive semidefinite (D is convex in x: w, n and a are fixed within a step), so
incremental-potential contact's projection to a PSD matrix changes nothing here. Values
are written per node as a 3x3 block (row-major).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.contact import barrier


@njit(cache=True, error_model="numpy")
def normal_forces(gaps, kappa, dhat, out):
    """The barrier's normal force -kappa b'(d) >= 0 at each gap d (0 beyond dhat)."""
    for k in range(gaps.shape[0]):
        d = gaps[k]
        if d >= dhat:
            out[k] = 0.0
        else:
            _, db, _ = barrier(d, dhat)
            out[k] = -kappa * db
    return out


@njit(cache=True, error_model="numpy")
def update_anchors(x, nodes, normal, weight, was, anchor, eps):
    """The anchors of a new step at the accepted state x: a node that was not in contact
    (``was`` False) or is not now (weight 0) anchors where it is; one that slid farther
    than eps from its anchor drags it along to eps behind it (in the tangent plane); one
    within eps sticks (its anchor stays). Returns how many anchors were dragged."""
    dragged = 0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        if weight[k] == 0.0 or not was[k]:
            for a in range(3):
                anchor[k, a] = x[i, a]
            continue
        rn = 0.0
        for a in range(3):
            rn += (x[i, a] - anchor[k, a]) * normal[k, a]
        y2 = 0.0
        for a in range(3):
            u = x[i, a] - anchor[k, a] - rn * normal[k, a]
            y2 += u * u
        y = np.sqrt(y2)
        if y > eps:
            dragged += 1
            s = eps / y
            for a in range(3):
                u = x[i, a] - anchor[k, a] - rn * normal[k, a]
                anchor[k, a] = x[i, a] - s * u
    return dragged


@njit(cache=True, error_model="numpy")
def friction_gradient(x, nodes, anchor, normal, weight, eps, grad):
    """Adds the friction potential's gradient at ``nodes``; returns its value."""
    total = 0.0
    u = np.empty(3)
    for k in range(nodes.shape[0]):
        w = weight[k]
        if w == 0.0:
            continue
        i = nodes[k]
        rn = 0.0
        for a in range(3):
            rn += (x[i, a] - anchor[k, a]) * normal[k, a]
        y2 = 0.0
        for a in range(3):
            u[a] = x[i, a] - anchor[k, a] - rn * normal[k, a]
            y2 += u[a] * u[a]
        y = np.sqrt(y2)
        if y < eps:
            total += w * (y2 / eps - y2 * y / (3.0 * eps * eps))
            c = w * (2.0 / eps - y / (eps * eps))
        else:
            total += w * (y - eps / 3.0)
            c = w / y
        for a in range(3):
            grad[i, a] += c * u[a]
    return total


@njit(cache=True, error_model="numpy")
def friction_hessian(x, nodes, anchor, normal, weight, eps, values):
    """Writes the 3x3 blocks of the friction potential at ``nodes``; returns how many
    act (weight > 0)."""
    active = 0
    u = np.empty(3)
    n = np.empty(3)
    for k in range(nodes.shape[0]):
        w = weight[k]
        if w == 0.0:
            for a in range(9):
                values[9 * k + a] = 0.0
            continue
        active += 1
        i = nodes[k]
        rn = 0.0
        for a in range(3):
            n[a] = normal[k, a]
            rn += (x[i, a] - anchor[k, a]) * n[a]
        y2 = 0.0
        for a in range(3):
            u[a] = x[i, a] - anchor[k, a] - rn * n[a]
            y2 += u[a] * u[a]
        y = np.sqrt(y2)
        if y < eps:
            cp = w * (2.0 / eps - y / (eps * eps))
            cu = -w / (eps * eps * y) if y > 0.0 else 0.0
        else:
            cp = w / y
            cu = -w / (y * y2)
        for a in range(3):
            for c in range(3):
                p = -n[a] * n[c]
                if a == c:
                    p += 1.0
                values[9 * k + 3 * a + c] = cp * p + cu * u[a] * u[c]
    return active
