"""Support reactions as targets of the force density method: R_i = grad_i - P_i at a
fixed node i, with grad_i = sum over its edges of +-q_e u_e (+ at the edge's second end)
and P_i its load (the constant one and, where the net weighs, g rho l0 / 2 of each edge
at it, l0 = L / (1 + eps(q L))). Their partial derivatives, with the edge's other end j
free: dR_i/dx_j = -q_e I - g (dl0/dL)/2 rho (+-n_e) (n_e = u_e / L_e, + where j is the
second end) and dR_i/dq_e = +-u_e - g rho (dl0/dq)/2, the weight's coefficients those of
``catenet.formfind.newton.weight_jacobian``. (The elastic method's reactions are in
``catenet.formfind.elastic``.)
"""

from __future__ import annotations

import numpy as np


def reaction(net, x: np.ndarray, q: np.ndarray, load: np.ndarray) -> np.ndarray:
    """The force each support exerts on the net (N, 3) at the shape x."""
    u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    pull = q[:, None] * u
    out = np.zeros_like(x)
    for c in range(3):
        out[:, c] = np.bincount(net.edges[:, 1], pull[:, c], net.n_nodes)
        out[:, c] -= np.bincount(net.edges[:, 0], pull[:, c], net.n_nodes)
    out -= load
    out[~np.asarray(net.fixed)] = 0.0
    return out


def partials(goals, a, shape, x, q, index, own: bool = False):
    """(dr/dx_f, dr/dq) of the reaction rows of ``goals`` (the others 0), sparse; with
    ``own`` the columns of each support's own node too (where ``index`` gives it one: a
    support that moves), dR_i/dx_i = q_e I + g (dl0/dL)/2 rho (-+n_e) per edge at it."""
    import scipy.sparse as sp

    from catenet.formfind.newton import weight_coefficients

    net = shape.net
    u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    length = np.linalg.norm(u, axis=1)
    n = u / length[:, None]
    wa, wc = np.zeros(net.n_edges), np.zeros(net.n_edges)
    g = np.zeros(3)
    if shape.weighs:
        wa, wc = weight_coefficients(shape, q, length)
        g = np.asarray(shape.gravity, dtype=np.float64)
    slope = goals.slope(a)
    rx, cx, vx, rq, cq, vq = [], [], [], [], [], []
    for j in np.flatnonzero(goals.reacts):
        i, c = int(goals.node[j]), int(goals.axis[j])
        for end, sign in ((0, -1.0), (1, 1.0)):
            e = np.flatnonzero(net.edges[:, end] == i)
            rq.append(np.full(len(e), j))
            cq.append(e)
            vq.append(slope[j] * (sign * u[e, c] - g[c] * wc[e]))
            for other in (True, False) if own else (True,):
                f = index[net.edges[e, 1 - end] if other else np.full(len(e), i)]
                k = f >= 0
                ek, f = e[k], f[k]
                turn = 1.0 if other else -1.0  # (its own node moves u the other way)
                for d in range(3):  # the other end is the first (sign +) or the second (-)
                    weight = g[c] * wa[ek] * (-sign) * n[ek, d]
                    rx.append(np.full(len(ek), j))
                    cx.append(3 * f + d)
                    vx.append(slope[j] * turn * (-q[ek] * (c == d) - weight))
    cat = np.concatenate
    n3 = 3 * int(np.count_nonzero(index >= 0))
    d_x = sp.csr_matrix((cat(vx), (cat(rx), cat(cx))), shape=(goals.rows, n3))
    d_q = sp.csr_matrix((cat(vq), (cat(rq), cat(cq))), shape=(goals.rows, net.n_edges))
    return d_x, d_q


__all__ = ["partials", "reaction"]
