"""Stretching of an edge: U = EA l0 w(eps) with eps = |e|/l0 - 1, e = x_j - x_i.

The material law of an edge is the dimensionless strain energy density w(eps) (per unit
rest length and per unit EA, EA the small-strain axial stiffness); ``catenet.kernels.laws``
gives w, w' and w'' for every law id. With the force N = EA w'(eps):

    dU/dx_j = N t (t = e/|e|),  dU/dx_i = -N t,
    d2U/dx_j2 = (EA/l0) w''(eps) t(x)t + (N/|e|)(I - t(x)t);

the blocks at (i,i) and (j,j) take this sign, (i,j) and (j,i) the opposite. (The paper's
Eq. 8 lacks the 1/|e| of the second term's strain derivative: d2eps/de2 =
(I - t(x)t)/(l0 |e|).) The paper's linear law is w = eps^2/2: U = 1/2 EA eps^2 l0.

Every law is data handed to these kernels per edge, never state: ``law`` (M,) holds the
law ids (or is None when every edge is linear: the kernels are then compiled without the
other laws, see ``Law.kernel_kind``), ``params`` (M, 2) their parameters, ``table`` (K, 3)
the rows of tabulated laws, ``tension_only`` (M,) the switch that makes an edge slack (no
energy, force or stiffness) while eps < 0, and ``smooth`` > 0 replaces that switch by a
smooth one (the static solver's continuation; see ``laws.tension_only``).
A slack edge writes its 36 Hessian values as zeros so that the sparsity pattern never
changes.

Zero-length edges are refused at input; one that arises during an iteration (a support
stepping onto its neighbour) is slack when tension-only and contributes nothing, else
its direction is undefined and the kernels give inf/NaN (error_model="numpy": no
exception), which the solvers' finite checks turn into a rejected step.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.laws import edge_density, strain_energy


@njit(cache=True, error_model="numpy")
def stretch_energy(x, edges, l0, ea, law, params, table, tension_only, smooth):
    """Total stretching energy [J] of positions x (N, 3)."""
    total = 0.0
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        eps = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) / l0[k] - 1.0
        w, _, _ = strain_energy(law, params, table, k, eps, tension_only[k], smooth)
        total += ea[k] * l0[k] * w
    return total


@njit(cache=True, error_model="numpy")
def stretch_gradient(x, edges, l0, ea, law, params, table, tension_only, smooth, grad):
    """Adds dU/dx into grad (N, 3) (the internal force, opposite to the force on the
    nodes) and returns the stretching energy."""
    return stretch_gradient_work(x, edges, l0, ea, law, params, table, tension_only, smooth, grad)[
        0
    ]


@njit(cache=True, error_model="numpy")
def stretch_gradient_work(x, edges, l0, ea, law, params, table, tension_only, smooth, grad):
    """``stretch_gradient``, returning (energy, sum |N| |e|): the energy's round-off level
    in units of eps (a strain error eps changes an edge's U by N |e| eps, however small U
    itself is), in the same pass."""
    total = 0.0
    work = 0.0
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        length = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        eps = length / l0[k] - 1.0
        w, force, _ = strain_energy(law, params, table, k, eps, tension_only[k], smooth)
        if force == 0.0 and w == 0.0:
            continue
        total += ea[k] * l0[k] * w
        work += abs(ea[k] * force) * length
        f = ea[k] * force / length
        grad[j, 0] += f * e0
        grad[j, 1] += f * e1
        grad[j, 2] += f * e2
        grad[i, 0] -= f * e0
        grad[i, 1] -= f * e1
        grad[i, 2] -= f * e2
    return total, work


@njit(cache=True, error_model="numpy")
def stretch_hessian(x, edges, l0, ea, law, params, table, tension_only, smooth, values):
    """Writes the 6x6 Hessian of every edge into values (M*36,), row-major over the
    local DOFs (x_i, y_i, z_i, x_j, y_j, z_j)."""
    e = np.empty(3)  # one buffer for every edge (no allocation in the loop)
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e[0] = x[j, 0] - x[i, 0]
        e[1] = x[j, 1] - x[i, 1]
        e[2] = x[j, 2] - x[i, 2]
        length = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        eps = length / l0[k] - 1.0
        _, force, stiffness = strain_energy(law, params, table, k, eps, tension_only[k], smooth)
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
def stretch_tension(x, edges, l0, ea, law, params, table, tension_only, out):
    """Axial force EA w'(eps) of every edge [N] (0 when slack and tension-only)."""
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        eps = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) / l0[k] - 1.0
        _, force, _ = strain_energy(law, params, table, k, eps, tension_only[k], 0.0)
        out[k] = ea[k] * force


@njit(cache=True, error_model="numpy")
def stretch_node_roundoff(x, edges, l0, ea, law, params, table, tension_only, smooth, level):
    """Adds to level (N,) the round-off of every edge's force at both of its nodes, in
    units of eps: |N| (its direction) + EA |x| / l0 (its strain, from coordinates of
    size |x| that carry an error eps |x|)."""
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        eps = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) / l0[k] - 1.0
        _, force, _ = strain_energy(law, params, table, k, eps, tension_only[k], smooth)
        size = 0.0
        for a in range(3):
            size = max(size, abs(x[i, a]), abs(x[j, a]))
        f = abs(ea[k] * force) + ea[k] * size / l0[k]
        level[i] += f
        level[j] += f


@njit(cache=True, error_model="numpy")
def stretch_held(x, edges, l0, ea, law, params, table, held, values, grad):
    """The held edges (``held`` (M,) true) that are slack at x enter Newton's model as if
    taut: their axial stiffness (EA/l0) w''(0) t(x)t added to the Hessian ``values``
    (where ``stretch_hessian`` wrote zeros for them) and their pull toward the rest
    length, EA w'(eps)-like (EA/l0) w''(0) (|e| - l0) t, added to ``grad`` (N, 3), the
    model's gradient (skipped when ``grad`` has no rows). Returns how many it held."""
    count = 0
    for k in range(edges.shape[0]):
        if not held[k]:
            continue
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        length = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        if length >= l0[k] or length == 0.0:
            continue
        count += 1
        _, _, stiffness = edge_density(law, params, table, k, 0.0)
        k_axial = ea[k] / l0[k] * stiffness
        if grad.shape[0] > 0:
            f = k_axial * (length - l0[k]) / length
            grad[j, 0] += f * e0
            grad[j, 1] += f * e1
            grad[j, 2] += f * e2
            grad[i, 0] -= f * e0
            grad[i, 1] -= f * e1
            grad[i, 2] -= f * e2
        if values.shape[0] > 0:
            axial = k_axial / (length * length)
            base = 36 * k
            for a in range(3):
                da = x[j, a] - x[i, a]
                for b in range(3):
                    h = axial * da * (x[j, b] - x[i, b])
                    values[base + 6 * a + b] = h
                    values[base + 6 * (a + 3) + b + 3] = h
                    values[base + 6 * a + b + 3] = -h
                    values[base + 6 * (a + 3) + b] = -h
    return count


@njit(cache=True, error_model="numpy")
def stretch_near_taut(x, edges, l0, tension_only, reach, out):
    """out[k]: whether edge k is tension-only and longer than (1 - reach) of its rest
    length."""
    for k in range(edges.shape[0]):
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        length = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        out[k] = tension_only[k] and length > (1.0 - reach) * l0[k]


@njit(cache=True, error_model="numpy")
def stretch_release(x, dx, edges, l0, held, times, recent):
    """Releases the held slack edges that Newton's model step dx (N, 3) leaves shorter
    than their rest length (to first order: the model's spring that held them pushes
    there, a tension-only edge cannot): ``held`` false, ``recent`` true (not held at the
    next factorisation), ``times`` counts it. Returns how many it released."""
    count = 0
    for k in range(edges.shape[0]):
        if not held[k]:
            continue
        i = edges[k, 0]
        j = edges[k, 1]
        e0 = x[j, 0] - x[i, 0]
        e1 = x[j, 1] - x[i, 1]
        e2 = x[j, 2] - x[i, 2]
        length = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        if length >= l0[k] or length == 0.0:
            continue
        d = e0 * (dx[j, 0] - dx[i, 0]) + e1 * (dx[j, 1] - dx[i, 1]) + e2 * (dx[j, 2] - dx[i, 2])
        if length + d / length < l0[k]:
            held[k] = False
            recent[k] = True
            times[k] += 1
            count += 1
    return count
