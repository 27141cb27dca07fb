"""The Hessian of a free body's contact with the net's nodes, riding on the body's frame
(``catenet.terms.rigid_contact``, whose docstring derives it).

For each contact node k with the shape's Hessian H_k and gradient g_k at its body-frame
point, and u_k = x_k - c:

    L = [A^T, -A^T, e_1 u^T, e_2 u^T, e_3 u^T]          (3 x 15, q = (x, c, a1, a2, a3))
    K_q = L^T H_k L + S,   S = g_m 1 between a_m and x, -g_m 1 between a_m and c,

and on the body's four nodes p (``chain`` = kron(T, 1_3), (c, a) = chain p) the node's
blocks are K_q[x, x] (9 values), K_q[x, b] chain (36) and its transpose (36), row-major;
the body's (p, p) block is chain^T (sum_k K_q[b, b]) chain (144). K_q is symmetric, so
the (p, x) block is the (x, p) block transposed, exactly.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def frame_contact_hessian(A, U, H, g, chain, active, blocks, body):
    """Writes the blocks of the ``active`` contact nodes (indices into U, H, g: (K, 3),
    (K, 3, 3), (K, 3)) into ``blocks`` (K, 81) and the body's (p, p) block into ``body``
    (144,); the other nodes' blocks are left as they are (the caller zeroes them)."""
    L = np.zeros((3, 15))
    HL = np.empty((3, 15))
    Kq = np.empty((15, 15))
    bb = np.zeros((12, 12))
    for r in range(3):
        for m in range(3):
            L[r, m] = A[m, r]  # A^T
            L[r, 3 + m] = -A[m, r]
    for j in range(active.shape[0]):
        k = active[j]
        for m in range(3):
            for i in range(3):
                L[m, 6 + 3 * m + i] = U[k, i]
        for r in range(3):
            for col in range(15):
                s = 0.0
                for q in range(3):
                    s += H[k, r, q] * L[q, col]
                HL[r, col] = s
        for a in range(15):
            for b in range(a, 15):
                s = 0.0
                for q in range(3):
                    s += L[q, a] * HL[q, b]
                Kq[a, b] = s
                Kq[b, a] = s
        for m in range(3):  # S: g_m between a_m and x (+), a_m and c (-)
            for i in range(3):
                a = 6 + 3 * m + i
                Kq[a, i] += g[k, m]
                Kq[i, a] += g[k, m]
                Kq[a, 3 + i] -= g[k, m]
                Kq[3 + i, a] -= g[k, m]
        for r in range(3):
            for i in range(3):
                blocks[k, 3 * r + i] = Kq[r, i]
            for col in range(12):
                s = 0.0
                for q in range(12):
                    s += Kq[r, 3 + q] * chain[q, col]
                blocks[k, 9 + 12 * r + col] = s  # (x, p), row-major
                blocks[k, 45 + 3 * col + r] = s  # (p, x): its transpose
        for a in range(12):
            for b in range(12):
                bb[a, b] += Kq[3 + a, 3 + b]
        for m in range(3):
            for i in range(3):
                L[m, 6 + 3 * m + i] = 0.0
    for a in range(12):
        for b in range(12):
            s = 0.0
            for p in range(12):
                for q in range(12):
                    s += chain[p, a] * bb[p, q] * chain[q, b]
            body[12 * a + b] = s
