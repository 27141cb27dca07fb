"""The floor's arithmetic (``floor_step.py``): plain Numba kernels of one implicit step's
incremental potential for a net and one free box, written from the formulas, not from
catenet's kernels, so that the two implementations check each other.

Phi(y) = sum_edges EA / (2 r) (l - r)^2 [l > r]            tension-only linear edges
       - f . x                                             loads (gravity)
       + k / 2 |A^T A - 1|_F^2                             the box's rigidity
       + sum_nodes kappa b(d(X))                           the barrier, X in the body frame
       + sum_dofs w / 2 (y - a)^2                          the step's inertia

with the box an affine body on four nodes p (c = mean p, A = P^T B), a node seen in the
body frame at X = c0 + A^T (x - c), d the distance of X to the box (body frame at t = 0)
and b(d) = -(d - dhat)^2 ln(d / dhat) for d < dhat. The Hessian is projected Newton's
(each contact's 15 x 15 block and the rigidity's 9 x 9 block with their negative
eigenvalues clamped to zero, as IPC and affine body dynamics do), so every matrix is
positive definite; it goes into a bordered band: the net's free DOFs in a band of half
width p (LAPACK's ``dpbtrf`` lower storage, ``band[i - j, j]`` = H[i, j] for
j <= i <= j + p), the body's 12 DOFs as a dense border ``C`` (n1, 12) and ``D`` (12, 12,
lower triangle).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def barrier(d, dhat):
    if d >= dhat:
        return 0.0, 0.0, 0.0
    if d <= 0.0:
        return np.inf, -np.inf, np.inf
    lg = np.log(d / dhat)
    r = d - dhat
    return -r * r * lg, -2.0 * r * lg - r * r / d, -2.0 * lg - 4.0 * r / d + r * r / (d * d)


@njit(cache=True)
def box_distance(X, center, axes, half, n, P):
    """Distance of X to the box (outside; <= 0 inside), its unit gradient n and the
    projection P on the directions the nearest point follows (hess d = (P - n n^T) / d)."""
    u = np.zeros(3)
    out = np.zeros(3)
    inside = -np.inf
    for a in range(3):
        s = 0.0
        for j in range(3):
            s += axes[j, a] * (X[j] - center[j])
        e = abs(s) - half[a]
        inside = max(inside, e)
        if e > 0.0:
            u[a] = e if s > 0.0 else -e
            out[a] = 1.0
    if inside <= 0.0:
        return inside
    d = np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    for j in range(3):
        n[j] = (axes[j, 0] * u[0] + axes[j, 1] * u[1] + axes[j, 2] * u[2]) / d
        for c in range(3):
            P[j, c] = 0.0
            for a in range(3):
                P[j, c] += axes[j, a] * out[a] * axes[c, a]
    return d


@njit(cache=True)
def pose(x, body, B):
    """(c, A) of the body's four nodes."""
    c = np.zeros(3)
    A = np.zeros((3, 3))
    for k in range(4):
        for i in range(3):
            c[i] += 0.25 * x[body[k], i]
            for m in range(3):
                A[i, m] += x[body[k], i] * B[k, m]
    return c, A


@njit(cache=True)
def potential(x, free, f, edges, l0, ea, body, B, krig, c0, box, contact, kappa, dhat, w, a, g):
    """Phi at x (N, 3) and its gradient into g (N, 3) (zero on fixed nodes); inf where
    a node is inside the box. ``box`` = (center 3, axes 9 row-major, half 3)."""
    g[:] = 0.0
    phi = 0.0
    for k in range(edges.shape[0]):
        i, j = edges[k, 0], edges[k, 1]
        e = x[j] - x[i]
        length = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        if length <= l0[k]:
            continue
        s = ea[k] / l0[k] * (length - l0[k])
        phi += 0.5 * s * (length - l0[k])
        for q in range(3):
            t = s * e[q] / length
            g[j, q] += t
            g[i, q] -= t
    c, A = pose(x, body, B)
    C = A.T @ A - np.eye(3)
    phi += 0.5 * krig * np.sum(C * C)
    gA = 2.0 * krig * (A @ C)
    for k in range(4):
        for i in range(3):
            for m in range(3):
                g[body[k], i] += B[k, m] * gA[i, m]
    center, axes, half = box[:3], box[3:12].reshape(3, 3), box[12:15]
    n = np.zeros(3)
    P = np.zeros((3, 3))
    gc = np.zeros(3)
    gAc = np.zeros((3, 3))
    for kk in range(contact.shape[0]):
        node = contact[kk]
        u = x[node] - c
        X = c0 + A.T @ u
        d = box_distance(X, center, axes, half, n, P)
        if d >= dhat:
            continue
        if d <= 0.0:
            return np.inf
        b, db, _ = barrier(d, dhat)
        phi += kappa * b
        gX = kappa * db * n
        gx = A @ gX
        for i in range(3):
            g[node, i] += gx[i]
            gc[i] -= gx[i]
            for m in range(3):
                gAc[i, m] += u[i] * gX[m]
    for k in range(4):
        for i in range(3):
            g[body[k], i] += 0.25 * gc[i]
            for m in range(3):
                g[body[k], i] += B[k, m] * gAc[i, m]
    for node in range(x.shape[0]):
        for i in range(3):
            phi -= f[node, i] * x[node, i]
            g[node, i] -= f[node, i]
            if free[node]:
                r = x[node, i] - a[node, i]
                phi += 0.5 * w[node, i] * r * r
                g[node, i] += w[node, i] * r
            else:
                g[node, i] = 0.0
    return phi


@njit(cache=True)
def _add(pos, nb, band, C, D, ri, rj, blk):
    """Adds the 3x3 block blk at DOF rows 3 ri.., columns 3 rj.. (ri, rj: positions in the
    ordering; the net's first, the body's last nb) into the bordered band, lower part."""
    n1 = band.shape[1]
    for a in range(3):
        for b in range(3):
            r = 3 * ri + a
            s = 3 * rj + b
            if r < s:
                continue
            if r < n1:
                band[r - s, s] += blk[a, b]
            elif s < n1:
                C[s, r - n1] += blk[a, b]
            else:
                D[r - n1, s - n1] += blk[a, b]


@njit(cache=True)
def psd(H):
    """H with its negative eigenvalues set to zero (projected Newton, as IPC and affine
    body dynamics do: every iteration's matrix positive semidefinite, plus inertia)."""
    lam, Q = np.linalg.eigh(H)
    if lam[0] >= 0.0:
        return H
    out = np.zeros_like(H)
    for k in range(lam.shape[0]):
        if lam[k] > 0.0:
            out += lam[k] * np.outer(Q[:, k], Q[:, k])
    return out


@njit(cache=True)
def rigidity_block(A, B, krig, project):
    """The rigidity's (12, 12) Hessian at the body's nodes: the 9 x 9 Hessian in vec(A)
    (row-major, 3 i + m), clamped where ``project``, chained by d vec(A) / d p."""
    Cm = A.T @ A - np.eye(3)
    HA = np.zeros((9, 9))
    for p in range(9):
        dA = np.zeros((3, 3))
        dA[p // 3, p % 3] = 1.0
        dC = dA.T @ A + A.T @ dA
        for q in range(p, 9):
            eA = np.zeros((3, 3))
            eA[q // 3, q % 3] = 1.0
            eC = eA.T @ A + A.T @ eA
            curv = dA.T @ eA + eA.T @ dA
            v = krig * (np.sum(dC * eC) + np.sum(Cm * curv))
            HA[p, q] = v
            HA[q, p] = v
    J = np.zeros((9, 12))  # A[i, m] = sum_k p_k[i] B[k, m]
    for i in range(3):
        for m in range(3):
            for k in range(4):
                J[3 * i + m, 3 * k + i] = B[k, m]
    return J.T @ (psd(HA) if project else HA) @ J


@njit(cache=True)
def contact_blocks(x, c, A, pos, B, c0, box, contact, kappa, dhat, band, C, D, project):
    """The barrier's blocks: each contact node's (x, x) into the band, (x, p) into the
    border C; returns the body's (p, p) block (12, 12). L = d X / d q, q = (x, c, a1,
    a2, a3), chained to (x, p)."""
    nb = 4
    blk = np.zeros((3, 3))
    center, axes, half = box[:3], box[3:12].reshape(3, 3), box[12:15]
    T = np.zeros((12, 12))  # (c, a1, a2, a3) = T (p0..p3), per axis
    for k in range(4):
        for i in range(3):
            T[i, 3 * k + i] = 0.25
            for m in range(3):
                T[3 + 3 * m + i, 3 * k + i] = B[k, m]
    n = np.zeros(3)
    P = np.zeros((3, 3))
    L = np.zeros((3, 15))
    for r in range(3):
        for m in range(3):
            L[r, m] = A[m, r]
            L[r, 3 + m] = -A[m, r]
    Kbb = np.zeros((12, 12))
    for kk in range(contact.shape[0]):
        node = contact[kk]
        u = x[node] - c
        X = c0 + A.T @ u
        d = box_distance(X, center, axes, half, n, P)
        if d >= dhat or d <= 0.0:
            continue
        _, db, ddb = barrier(d, dhat)
        HX = np.empty((3, 3))
        for p in range(3):
            for q in range(3):
                HX[p, q] = kappa * (ddb * n[p] * n[q] + db * (P[p, q] - n[p] * n[q]) / d)
        gX = kappa * db * n
        for m in range(3):
            for i in range(3):
                L[m, 6 + 3 * m + i] = u[i]
        Kq = L.T @ HX @ L
        for m in range(3):
            for i in range(3):
                Kq[6 + 3 * m + i, i] += gX[m]
                Kq[i, 6 + 3 * m + i] += gX[m]
                Kq[6 + 3 * m + i, 3 + i] -= gX[m]
                Kq[3 + i, 6 + 3 * m + i] -= gX[m]
        for m in range(3):
            for i in range(3):
                L[m, 6 + 3 * m + i] = 0.0
        if project:
            Kq = psd(Kq)
        xb = np.ascontiguousarray(Kq[:3, 3:]) @ T  # (x, p)
        pn = pos[node]
        for a in range(3):
            for b in range(3):
                blk[a, b] = Kq[a, b]
        _add(pos, nb, band, C, D, pn, pn, blk)
        for a in range(3):
            for s in range(12):
                C[3 * pn + a, s] += xb[a, s]
        Kbb += Kq[3:, 3:]
    return T.T @ Kbb @ T


@njit(cache=True)
def hessian(
    x, pos, edges, l0, ea, body, B, krig, c0, box, contact, kappa, dhat, w, band, C, D, project
):
    """The Hessian of ``potential`` into the bordered band (band, C, D: zeroed here);
    ``pos[node]`` the node's place in the ordering (-1 fixed), the body's nodes last;
    ``project``: the blocks' negative eigenvalues clamped (else the exact Hessian)."""
    band[:] = 0.0
    C[:] = 0.0
    D[:] = 0.0
    n1 = band.shape[1]
    nb = 4
    blk = np.zeros((3, 3))
    for k in range(edges.shape[0]):
        i, j = edges[k, 0], edges[k, 1]
        e = x[j] - x[i]
        length = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        if length <= l0[k]:
            continue
        kk = ea[k] / l0[k]
        tension = kk * (length - l0[k])
        for p in range(3):
            for q in range(3):
                t = e[p] * e[q] / (length * length)
                blk[p, q] = kk * t + tension / length * ((1.0 if p == q else 0.0) - t)
        pi, pj = pos[i], pos[j]
        if pi >= 0:
            _add(pos, nb, band, C, D, pi, pi, blk)
        if pj >= 0:
            _add(pos, nb, band, C, D, pj, pj, blk)
        if pi >= 0 and pj >= 0:
            if pi > pj:
                _add(pos, nb, band, C, D, pi, pj, -blk)
            else:
                _add(pos, nb, band, C, D, pj, pi, -blk)
    c, A = pose(x, body, B)
    Hb = rigidity_block(A, B, krig, project)
    Hb += contact_blocks(x, c, A, pos, B, c0, box, contact, kappa, dhat, band, C, D, project)
    for r in range(12):
        for s in range(r + 1):
            D[r, s] += Hb[r, s]
    # the inertia
    for node in range(x.shape[0]):
        pn = pos[node]
        if pn < 0:
            continue
        for i in range(3):
            r = 3 * pn + i
            if r < n1:
                band[0, r] += w[node, i]
            else:
                D[r - n1, r - n1] += w[node, i]


@njit(cache=True)
def slab_entry(q, v, half):
    """The first s in [0, 1] at which q + s v (box frame) is inside the box of half
    sizes ``half``; inf where it stays out."""
    enter, leave = 0.0, 1.0
    for a in range(3):
        if v[a] == 0.0:
            if abs(q[a]) > half[a]:
                return np.inf
            continue
        t1 = (-half[a] - q[a]) / v[a]
        t2 = (half[a] - q[a]) / v[a]
        enter = max(enter, min(t1, t2))
        leave = min(leave, max(t1, t2))
    return enter if enter <= leave else np.inf


@njit(cache=True)
def step_cap(x, dx, body, B, c0, box, contact, share):
    """The largest multiple t <= 1 of the step dx that keeps every node outside the box.
    A node's body-frame point follows X(t) = X0 + t V + t^2 W; over pieces of the step
    whose chords stay within |W| h^2 / 4 <= delta of the path, each chord's exact entry
    (slab test) into the box grown by 2 delta along every axis bounds the first contact
    (delta = ``share`` / 4 of the node's gap: the grown box stays clear of X0)."""
    c, A = pose(x, body, B)
    dc, dA = pose(dx, body, B)
    center, axes, half = box[:3], box[3:12].reshape(3, 3), box[12:15]
    n = np.zeros(3)
    P = np.zeros((3, 3))
    t_cap = 1.0
    for kk in range(contact.shape[0]):
        node = contact[kk]
        u = x[node] - c
        du = dx[node] - dc
        X0 = c0 + A.T @ u
        V = A.T @ du + dA.T @ u
        W = dA.T @ du
        w = np.sqrt(np.sum(W * W))
        speed = np.sqrt(np.sum(V * V)) + 2.0 * w
        if speed == 0.0:
            continue
        d0 = box_distance(X0, center, axes, half, n, P)
        if d0 > speed * t_cap:
            continue  # cannot reach the box within the cap
        delta = 0.25 * share * d0
        grown = half + 2.0 * delta
        t = 0.0
        while t < t_cap:
            h = t_cap - t
            if w > 0.0:
                h = min(h, 2.0 * np.sqrt(delta / w))
            p0 = X0 + t * V + t * t * W
            chord = h * V + (2.0 * t * h + h * h) * W
            q = axes.T @ (p0 - center)
            s = slab_entry(q, axes.T @ chord, grown)
            if s <= 1.0:
                t_cap = t + s * h
                break
            t += h
    return t_cap


@njit(cache=True)
def closest(x, body, B, c0, box, contact):
    """The smallest distance of a contact node to the box [m]."""
    c, A = pose(x, body, B)
    center, axes, half = box[:3], box[3:12].reshape(3, 3), box[12:15]
    n = np.zeros(3)
    P = np.zeros((3, 3))
    out = np.inf
    for kk in range(contact.shape[0]):
        X = c0 + A.T @ (x[contact[kk]] - c)
        out = min(out, box_distance(X, center, axes, half, n, P))
    return out
