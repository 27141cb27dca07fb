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

from catenet.kernels.contact import barrier
from catenet.kernels.friction import friction_gradient, friction_hessian
from catenet.kernels.shapes import _block, shape_feature


@njit(cache=True, error_model="numpy")
def _jacobi(M):
    """The eigenvalues and eigenvectors (columns) of a small symmetric matrix M (r x r,
    overwritten) by cyclic Jacobi rotations, to round-off (LAPACK's call costs more than
    the work at this size)."""
    r = M.shape[0]
    Z = np.eye(r)
    total = 0.0
    for p in range(r):
        for q in range(r):
            total += M[p, q] * M[p, q]
    for _ in range(50):
        off = 0.0
        for p in range(r):
            for q in range(p + 1, r):
                off += M[p, q] * M[p, q]
        if off <= 1e-32 * total:
            break
        for p in range(r - 1):
            for q in range(p + 1, r):
                apq = M[p, q]
                if apq == 0.0:
                    continue
                theta = (M[q, q] - M[p, p]) / (2.0 * apq)
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(r):  # columns p, q
                    mkp, mkq = M[k, p], M[k, q]
                    M[k, p] = c * mkp - s * mkq
                    M[k, q] = s * mkp + c * mkq
                for k in range(r):  # rows p, q
                    mpk, mqk = M[p, k], M[q, k]
                    M[p, k] = c * mpk - s * mqk
                    M[q, k] = s * mpk + c * mqk
                for k in range(r):
                    zkp, zkq = Z[k, p], Z[k, q]
                    Z[k, p] = c * zkp - s * zkq
                    Z[k, q] = s * zkp + c * zkq
    w = np.empty(r)
    for p in range(r):
        w[p] = M[p, p]
    return w, Z


@njit(cache=True, error_model="numpy")
def _project_contact(K, u, g, Q, M, W):
    """One contact's K_q (15 x 15, symmetric, in place) with its negative eigenvalues
    set to 0, computed on the at most nine directions its range lies in (the module
    docstring's L and S): (e_i, -e_i, 0) of x - c, and in a, e_m u^T and g e_j^T. On an
    orthonormal basis Q of them (Gram-Schmidt, twice) K_q = Q^T (Q K_q Q^T) Q exactly,
    and the middle (9 x 9 at most) is projected by Jacobi rotations: the same matrix
    as the 15 x 15 eigendecomposition's, several times cheaper. ``Q`` (9, 15), ``M``
    (9, 9) and ``W`` (15, 9): scratch."""
    r = 0
    for j in range(9):
        for b in range(15):
            Q[r, b] = 0.0
        if j < 3:  # (e_j, -e_j, 0)
            Q[r, j], Q[r, 3 + j] = 1.0, -1.0
        elif j < 6:  # e_m u^T in a_m
            for i in range(3):
                Q[r, 6 + 3 * (j - 3) + i] = u[i]
        else:  # g e_i^T: g_m in a_m's component i
            for m in range(3):
                Q[r, 6 + 3 * m + (j - 6)] = g[m]
        scale = 0.0
        for b in range(15):
            scale += Q[r, b] * Q[r, b]
        if scale == 0.0:
            continue
        for _ in range(2):
            for q in range(r):
                d = 0.0
                for b in range(15):
                    d += Q[q, b] * Q[r, b]
                for b in range(15):
                    Q[r, b] -= d * Q[q, b]
        norm = 0.0
        for b in range(15):
            norm += Q[r, b] * Q[r, b]
        if norm > 1e-20 * scale:
            norm = np.sqrt(norm)
            for b in range(15):
                Q[r, b] /= norm
            r += 1
    if r == 0:
        return
    for a in range(15):  # W = K Q^T, then M = Q W
        for q in range(r):
            t = 0.0
            for b in range(15):
                t += K[a, b] * Q[q, b]
            W[a, q] = t
    for p in range(r):
        for q in range(p, r):
            t = 0.0
            for a in range(15):
                t += Q[p, a] * W[a, q]
            M[p, q] = t
            M[q, p] = t
    w, Z = _jacobi(M[:r, :r])
    if w.min() >= 0.0:
        return
    for q in range(r):  # the eigenvectors in (x, c, a), scaled: W^T[q] = sqrt(w_q) Z^T Q
        root = np.sqrt(w[q]) if w[q] > 0.0 else 0.0
        for a in range(15):
            t = 0.0
            for p in range(r):
                t += Z[p, q] * Q[p, a]
            W[a, q] = root * t
    for a in range(15):
        for b in range(a, 15):
            t = 0.0
            for q in range(r):
                t += W[a, q] * W[b, q]
            K[a, b] = t
            K[b, a] = t


@njit(cache=True, error_model="numpy")
def frame_contact_hessian(A, U, H, g, chain, active, blocks, body, project=False):
    """Writes the blocks of the ``active`` contact nodes (indices into U, H, g: (K, 3),
    (K, 3, 3), (K, 3)) into ``blocks`` (K, 81) and the body's (p, p) block into ``body``
    (144,); the other nodes' blocks are left as they are (the caller zeroes them).
    ``project``: each contact's 15 x 15 block in (x, c, A) with its negative eigenvalues
    set to 0 (``_project_contact``: a positive semidefinite matrix, Newton's direction a descent
    one whatever the barrier's curvature and the frame's second derivative S)."""
    L = np.zeros((3, 15))
    HL = np.empty((3, 15))
    Kq = np.empty((15, 15))
    bb = np.zeros((12, 12))
    Q = np.empty((9, 15))  # the projection's scratch
    M = np.empty((9, 9))
    W = np.empty((15, 9))
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
        if project:
            _project_contact(Kq, U[k], g[k], Q, M, W)
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


@njit(cache=True, error_model="numpy")
def frame_state(x, body, B):
    """(c, A) of a body's four nodes ``body`` in x (N, 3): c their mean, A = P^T B
    (``catenet.terms.rigid.BodyFrame.state``)."""
    c = np.zeros(3)
    A = np.zeros((3, 3))
    for k in range(4):
        p = body[k]
        for i in range(3):
            c[i] += x[p, i]
            for m in range(3):
                A[i, m] += x[p, i] * B[k, m]
    for i in range(3):
        c[i] *= 0.25
    return c, A


@njit(cache=True, error_model="numpy")
def frame_local(x, nodes, body, B, c0):
    """(c, A, U, X): the body's pose, the nodes' offsets U = x - c from its centre and
    their body-frame points X = c0 + A^T U, (K, 3) each."""
    c, A = frame_state(x, body, B)
    K = nodes.shape[0]
    U = np.empty((K, 3))
    X = np.empty((K, 3))
    for k in range(K):
        for j in range(3):
            U[k, j] = x[nodes[k], j] - c[j]
        for m in range(3):
            s = 0.0
            for j in range(3):
                s += U[k, j] * A[j, m]
            X[k, m] = c0[m] + s
    return c, A, U, X


@njit(cache=True, error_model="numpy")
def rigidity_levels(x, body, B):
    """(max |x| over the body's nodes, max |A|, max |A^T A - 1|): what the round-off
    levels of ``catenet.terms.rigid.Rigidity`` are made of."""
    _, A = frame_state(x, body, B)
    spread = 0.0
    for k in range(4):
        for i in range(3):
            spread = max(spread, abs(x[body[k], i]))
    a_max = 0.0
    c_max = 0.0
    for i in range(3):
        for j in range(3):
            a_max = max(a_max, abs(A[i, j]))
            s = 0.0
            for m in range(3):
                s += A[m, i] * A[m, j]
            if i == j:
                s -= 1.0
            c_max = max(c_max, abs(s))
    return spread, a_max, c_max


@njit(cache=True, error_model="numpy")
def rigidity_gradient(x, body, B, k, grad):
    """Adds the gradient of E = k |A^T A - 1|_F^2 / 2 (``catenet.terms.rigid.Rigidity``)
    at the body's nodes into grad (N, 3); returns E."""
    _, A = frame_state(x, body, B)
    C = A.T @ A
    energy = 0.0
    for i in range(3):
        C[i, i] -= 1.0
        for j in range(3):
            energy += C[i, j] * C[i, j]
    gA = 2.0 * k * (A @ C)
    for q in range(4):
        for i in range(3):
            s = 0.0
            for m in range(3):
                s += B[q, m] * gA[i, m]
            grad[body[q], i] += s
    return 0.5 * k * energy


@njit(cache=True, error_model="numpy")
def rigidity_hessian(x, body, B, k, D, values):
    """The (12, 12) Hessian of the rigidity at the body's nodes, row-major into values:
    D^T (k H) D with H = M^T M + 2 kron(1, C) in vec(A) (row-major), M the Jacobian of
    vec(C) (``catenet.terms.rigid.Rigidity.hessian``)."""
    _, A = frame_state(x, body, B)
    C = A.T @ A
    for i in range(3):
        C[i, i] -= 1.0
    M = np.zeros((9, 9))
    for i in range(3):  # column (l, m): dC_ij = delta_im A_lj + A_li delta_jm
        for j in range(3):
            for lv in range(3):
                for m in range(3):
                    v = 0.0
                    if i == m:
                        v += A[lv, j]
                    if j == m:
                        v += A[lv, i]
                    M[3 * i + j, 3 * lv + m] = v
    H = M.T @ M
    for lv in range(3):
        for m in range(3):
            for q in range(3):
                H[3 * lv + m, 3 * lv + q] += 2.0 * C[m, q]
    Hp = D.T @ (k * H) @ D
    for a in range(12):
        for b in range(12):
            values[12 * a + b] = Hp[a, b]


@njit(cache=True, error_model="numpy")
def rigidity_turn(dx, body, B):
    """|dA|_2: the largest singular value of the step's change of A."""
    _, dA = frame_state(dx, body, B)
    return np.linalg.svd(dA)[1][0]


@njit(cache=True, error_model="numpy")
def frame_contact_gradient(kind, geom, kappa, dhat, x, nodes, body, B, c0, grad):
    """Adds the gradient of the barrier of a box or capsule riding on the body (``kind``,
    ``geom``: ``catenet.kernels.shapes``) at the contact ``nodes`` and the body's four
    nodes into grad (N, 3): A g at a node, -A g at the centre, U g^T on A
    (``catenet.terms.rigid_contact``); returns the energy."""
    _, A, U, X = frame_local(x, nodes, body, B, c0)
    n = np.empty(3)
    P = np.empty((3, 3))
    total = 0.0
    fsum = np.zeros(3)
    gA = np.zeros((3, 3))
    for k in range(nodes.shape[0]):
        d = shape_feature(kind, X[k], geom, n, P)
        if d >= dhat:
            continue
        b, db, _ = barrier(d, dhat)
        total += kappa * b
        if not d > 0.0:
            continue
        g = (kappa * db * n[0], kappa * db * n[1], kappa * db * n[2])  # no array per node
        for i in range(3):
            f = A[i, 0] * g[0] + A[i, 1] * g[1] + A[i, 2] * g[2]
            grad[nodes[k], i] += f
            fsum[i] += f
            for m in range(3):
                gA[i, m] += U[k, i] * g[m]
    for q in range(4):
        for i in range(3):
            s = -0.25 * fsum[i]
            for m in range(3):
                s += B[q, m] * gA[i, m]
            grad[body[q], i] += s
    return total


@njit(cache=True, error_model="numpy")
def frame_contact_hessian_shape(
    kind, geom, kappa, dhat, x, nodes, body, B, c0, chain, values, project=False
):
    """The Hessian of the barrier of a box or capsule riding on the body (``kind``,
    ``geom``) into ``values`` (the term's: K blocks of 81, then the body's 144): the
    nodes' body-frame points, each node's barrier block and gradient where it acts
    (0 < gap < dhat, as ``shape_hessian`` and ``shape_gradient`` give them), then
    ``frame_contact_hessian``; returns how many nodes act."""
    _, A, U, X = frame_local(x, nodes, body, B, c0)
    K = nodes.shape[0]
    values[:] = 0.0
    H = np.zeros((K, 3, 3))
    g = np.zeros((K, 3))
    hv = np.zeros(9)
    n = np.empty(3)
    P = np.empty((3, 3))
    active = np.empty(K, dtype=np.int64)
    count = 0
    for k in range(K):
        d = shape_feature(kind, X[k], geom, n, P)
        if d >= dhat or d <= 0.0:
            continue
        _, db, ddb = barrier(d, dhat)
        _block(hv, 0, kappa, db, ddb, d, n, P)
        for a in range(3):
            g[k, a] = kappa * db * n[a]
            for c in range(3):
                H[k, a, c] = hv[3 * a + c]
        active[count] = k
        count += 1
    if count:
        blocks = values[: 81 * K].reshape((K, 81))
        frame_contact_hessian(A, U, H, g, chain, active[:count], blocks, values[81 * K :], project)
    return count


@njit(cache=True, error_model="numpy")
def frame_friction_gradient(x, nodes, body, B, c0, anchor, normal, weight, eps, grad):
    """Adds the gradient of the lagged friction riding on the body (``anchor``,
    ``normal``, ``weight`` per contact node, slip ``eps``: ``catenet.kernels.friction``,
    at the nodes' body-frame points) at the contact ``nodes`` and the body's four nodes
    into grad (N, 3), as ``frame_contact_gradient`` does the barrier's. Returns the
    energy."""
    _, A, U, X = frame_local(x, nodes, body, B, c0)
    K = nodes.shape[0]
    g = np.zeros((K, 3))
    energy = friction_gradient(X, np.arange(K), anchor, normal, weight, eps, g)
    if not np.isfinite(energy):
        return energy
    fsum = np.zeros(3)
    gA = np.zeros((3, 3))
    for k in range(K):
        i = nodes[k]
        for a in range(3):
            f = A[a, 0] * g[k, 0] + A[a, 1] * g[k, 1] + A[a, 2] * g[k, 2]
            grad[i, a] += f
            fsum[a] += f
            for m in range(3):
                gA[a, m] += U[k, a] * g[k, m]
    for q in range(4):
        for a in range(3):
            s = -0.25 * fsum[a]
            for m in range(3):
                s += B[q, m] * gA[a, m]
            grad[body[q], a] += s
    return energy


@njit(cache=True, error_model="numpy")
def frame_friction_hessian(x, nodes, body, B, c0, anchor, normal, weight, eps, chain, values):
    """The Hessian of the lagged friction riding on the body into ``values`` (K blocks
    of 81, then the body's 144), as ``frame_contact_hessian_shape`` does the barrier's;
    returns how many nodes act."""
    _, A, U, X = frame_local(x, nodes, body, B, c0)
    K = nodes.shape[0]
    local = np.arange(K)
    hv = np.zeros(9 * K)
    friction_hessian(X, local, anchor, normal, weight, eps, hv)
    g = np.zeros((K, 3))
    friction_gradient(X, local, anchor, normal, weight, eps, g)
    values[:] = 0.0
    H = hv.reshape((K, 3, 3))
    active = np.empty(K, dtype=np.int64)
    count = 0
    for k in range(K):
        acts = False
        for a in range(9):
            acts = acts or hv[9 * k + a] != 0.0
        for m in range(3):
            acts = acts or g[k, m] != 0.0
        if acts:
            active[count] = k
            count += 1
    if count:
        blocks = values[: 81 * K].reshape((K, 81))
        frame_contact_hessian(A, U, H, g, chain, active[:count], blocks, values[81 * K :])
    return count
