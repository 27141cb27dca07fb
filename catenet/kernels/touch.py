"""Edge-edge contact between the surfaces of two rigid solids (free bodies, balls, fixed
obstacles), each surface point linear in a few nodes: y_p = sum_a W[p, a] x_a (a fixed
obstacle's points have no weights).

Every candidate pair of edges (one of each solid) stores the strands' mollified
edge-edge barrier (``catenet.kernels.strands.edge_energy``) on the gap d - r (d the
segments' distance, r the summed radii of the edges: a capsule's axis, 0 for a box's or
a mesh's edges), its gradient g (12) and Hessian H (12, 12) on the four end points. The
chain to the solids' nodes is the constant W: per node a and axis i,

    grad_a = sum_k W[p_k, a] g_k,   H_(a i)(b j) = sum_(k, m) W[p_k, a] W[p_m, b] H_(k i)(m j).

``touch_ccd`` caps a step by the strands' additive CCD of each candidate pair, its
points moving linearly (the nodes do, and W is constant).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.ccd import accd
from catenet.kernels.strands import EPS_PARALLEL, edge_energy, gather


@njit(cache=True, error_model="numpy")
def touch_edges(Y, W, edges, rest, pairs, r, dhat, kappa, gn, Hn, want):
    """Adds the barrier of the edge ``pairs`` (K, 2) of the points Y (V, 3) to the
    nodes' gradient gn (n, 3) and, with ``want``, their Hessian Hn (3n, 3n); returns the
    energy. ``rest``: each edge's length (the mollifier's scale)."""
    P = np.empty(12)
    g = np.empty(12)
    H = np.empty((12, 12))
    reach = r + dhat
    total = 0.0
    nn = W.shape[1]
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        pts = gather(Y, edges, a, b, P)
        eps = EPS_PARALLEL * (rest[a] * rest[b]) ** 2
        energy = edge_energy(P, eps, reach * reach, r, dhat, kappa, g, H, want)
        if energy == 0.0:
            continue
        total += energy
        for k in range(4):
            for u in range(nn):
                w = W[pts[k], u]
                if w != 0.0:
                    for i in range(3):
                        gn[u, i] += w * g[3 * k + i]
        if not want:
            continue
        for k in range(4):
            for m in range(4):
                for u in range(nn):
                    wu = W[pts[k], u]
                    if wu == 0.0:
                        continue
                    for v in range(nn):
                        w = wu * W[pts[m], v]
                        if w == 0.0:
                            continue
                        for i in range(3):
                            for j in range(3):
                                Hn[3 * u + i, 3 * v + j] += w * H[3 * k + i, 3 * m + j]
    return total


@njit(cache=True, error_model="numpy")
def touch_ccd(Y, dY, edges, pairs, r, t_max):
    """The first time in (0, t_max] at which an edge pair of the points Y moving with dY
    comes within r (the additive CCD's conservative time); inf when none does."""
    P, dP = np.empty(12), np.empty(12)
    t = np.inf
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        gather(Y, edges, a, b, P)
        gather(dY, edges, a, b, dP)
        t = min(t, accd(P, dP, min(t, t_max), r, np.int64(0)))
    return t
