"""Self-contact of a net's strands: a log-barrier on the squared distance of edge pairs.

Two edges a = (a0, a1) and b = (b0, b1) that share no node are at the squared distance

    D(x) = min over (s, t) in [0, 1]^2 of f(x, s, t),  f = |a0 + s u - b0 - t v|^2,

u = a1 - a0, v = b1 - b0. Every distance here is the one generic form
r(s, t) = sum_k (alpha_k + beta_k s + gamma_k t) P_k over the four points P = (a0, a1,
b0, b1) with the coefficient rows of ``ALPHA``, ``BETA``, ``GAMMA``: row 0 the edge-edge
distance, rows 1-4 the distances of one end point to the other edge (a0|b, a1|b, b0|a,
b1|a). ``closest`` finds the optimum (s*, t*) (the clamped minimisation of Ericson,
Real-Time Collision Detection, 5.1.9, which also settles parallel edges). By the
envelope theorem grad D = grad_x f at (s*, t*); the Hessian follows from the implicit
function theorem on the free parameters F (those strictly inside (0, 1)):

    hess D = f_xx - f_xF (f_FF)^-1 f_Fx,

with f_xx = 2 c c^T (x) I: exact inside each regime (both free, one clamped, both
clamped: point-point), and D is C1 across regimes (the envelope of a convex quadratic).

Nearly parallel edges make f_FF singular. As in incremental potential contact (Li et
al. 2020), the edge-edge barrier is multiplied by the mollifier m(e) of
e = |u x v|^2 = |u|^2 |v|^2 - (u.v)^2, m = (2 - e/eps) e/eps below eps, 1 above
(C1 at eps), eps = EPS_PARALLEL |u0|^2 |v0|^2 from the rest lengths (about 1.8 degrees).
Where IPC lets point-edge terms of the same contact take over, here the complement
(1 - m) goes to the four end point-edge barriers of the same pair:

    E = kappa (m b(D) + (1 - m) sum_j b(D_j)).

E is C1 (m' = 0 at eps; at e = 0 grad m = m' grad e = 0), and still infinite when the
edges touch: exactly parallel edges are closest at an end point, where D = min_j D_j.
b is the obstacles' barrier (``catenet.kernels.contact.barrier``) on squared
distances, activation D_hat = dhat^2.

``candidates`` lists the pairs within a distance by a uniform grid (edges' boxes, each
pair tested once, in the cell of its boxes' overlap corner): its cost grows with the
number of close pairs. ``catenet.kernels.ccd`` caps a step by continuous collision
detection of the pairs (``strand_max_step``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.contact import barrier

#: eps = EPS_PARALLEL |u0|^2 |v0|^2: the mollifier acts below sin(angle) ~ 0.03.
EPS_PARALLEL = 1e-3

ALPHA = np.array(
    [[1, 0, -1, 0], [1, 0, -1, 0], [0, 1, -1, 0], [1, 0, -1, 0], [1, 0, 0, -1]], dtype=np.float64
)
BETA = np.array(
    [[-1, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0], [-1, 1, 0, 0], [-1, 1, 0, 0]], dtype=np.float64
)
GAMMA = np.array(
    [[0, 0, 1, -1], [0, 0, 1, -1], [0, 0, 1, -1], [0, 0, 0, 0], [0, 0, 0, 0]], dtype=np.float64
)


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _combine(P, coef):
    """sum_k coef[k] P[3k:3k+3]."""
    out = np.zeros(3)
    for k in range(4):
        c = coef[k]
        if c != 0.0:
            for i in range(3):
                out[i] += c * P[3 * k + i]
    return out


@njit(cache=True)
def _clamp(v):
    return 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)


@njit(cache=True)
def closest(P, kind):
    """(s*, t*, s free, t free) of the distance ``kind`` (0 edge-edge, 1-4 point-edge)
    of the points P (12,); a parameter the kind has not is 0 and not free."""
    r0 = _combine(P, ALPHA[kind])
    rs = _combine(P, BETA[kind])
    rt = _combine(P, GAMMA[kind])
    if kind == 1 or kind == 2:
        e = _dot(rt, rt)
        t = _clamp(-_dot(r0, rt) / e) if e > 0.0 else 0.0
        return 0.0, t, False, 0.0 < t < 1.0
    if kind == 3 or kind == 4:
        a = _dot(rs, rs)
        s = _clamp(-_dot(r0, rs) / a) if a > 0.0 else 0.0
        return s, 0.0, 0.0 < s < 1.0, False
    a, e = _dot(rs, rs), _dot(rt, rt)
    b, c, f = -_dot(rs, rt), _dot(rs, r0), -_dot(rt, r0)
    denom = a * e - b * b
    s = _clamp((b * f - c * e) / denom) if denom > 1e-14 * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t, s = 0.0, _clamp(-c / a)
    elif t > 1.0:
        t, s = 1.0, _clamp((b - c) / a)
    return s, t, 0.0 < s < 1.0, 0.0 < t < 1.0


@njit(cache=True)
def sqdist(P, kind, g, H, want):
    """The squared distance ``kind`` of P (12,), its gradient into g, with ``want`` its
    Hessian into H (kind and want passed as values: Numba compiles each literal anew)."""
    s, t, fs, ft = closest(P, kind)
    al, be, ga = ALPHA[kind], BETA[kind], GAMMA[kind]
    c = al + be * s + ga * t
    r = _combine(P, c)
    for k in range(4):
        for i in range(3):
            g[3 * k + i] = 2.0 * c[k] * r[i]
    if want:
        H[:, :] = 0.0
        for k in range(4):
            for m in range(4):
                for i in range(3):
                    H[3 * k + i, 3 * m + i] = 2.0 * c[k] * c[m]
        if fs or ft:
            _eliminate(P, c, r, be, ga, fs, ft, H)
    return _dot(r, r)


@njit(cache=True)
def _eliminate(P, c, r, be, ga, fs, ft, H):
    """H -= f_xF (f_FF)^-1 f_Fx over the free parameters F."""
    rs = _combine(P, be)
    rt = _combine(P, ga)
    fxs = np.empty(12)
    fxt = np.empty(12)
    for k in range(4):
        for i in range(3):
            fxs[3 * k + i] = 2.0 * (be[k] * r[i] + c[k] * rs[i])
            fxt[3 * k + i] = 2.0 * (ga[k] * r[i] + c[k] * rt[i])
    A, B, C = 2.0 * _dot(rs, rs), 2.0 * _dot(rs, rt), 2.0 * _dot(rt, rt)
    if fs and ft:
        det = A * C - B * B
        i00, i01, i11 = C / det, -B / det, A / det
        for p in range(12):
            for q in range(12):
                H[p, q] -= fxs[p] * (i00 * fxs[q] + i01 * fxt[q]) + fxt[p] * (
                    i01 * fxs[q] + i11 * fxt[q]
                )
    elif fs:
        for p in range(12):
            for q in range(12):
                H[p, q] -= fxs[p] * fxs[q] / A
    else:
        for p in range(12):
            for q in range(12):
                H[p, q] -= fxt[p] * fxt[q] / C


@njit(cache=True)
def parallelism(P, ge, He, want):
    """e = |u x v|^2 of the edges of P, its gradient into ge (12,) and, with ``want``,
    its Hessian into He (12, 12)."""
    be, ga = BETA[0], GAMMA[0]
    U, V = _combine(P, be), _combine(P, ga)
    uu, vv, uv = _dot(U, U), _dot(V, V), _dot(U, V)
    for k in range(4):
        for i in range(3):
            eu = 2.0 * vv * U[i] - 2.0 * uv * V[i]
            ev = 2.0 * uu * V[i] - 2.0 * uv * U[i]
            ge[3 * k + i] = be[k] * eu + ga[k] * ev
    if want:
        for i in range(3):
            for j in range(3):
                d = 1.0 if i == j else 0.0
                euu = 2.0 * vv * d - 2.0 * V[i] * V[j]
                evv = 2.0 * uu * d - 2.0 * U[i] * U[j]
                euv = 4.0 * U[i] * V[j] - 2.0 * V[i] * U[j] - 2.0 * uv * d
                evu = 4.0 * U[j] * V[i] - 2.0 * V[j] * U[i] - 2.0 * uv * d
                for k in range(4):
                    for m in range(4):
                        He[3 * k + i, 3 * m + j] = (
                            be[k] * be[m] * euu
                            + be[k] * ga[m] * euv
                            + ga[k] * be[m] * evu
                            + ga[k] * ga[m] * evv
                        )
    return uu * vv - uv * uv


@njit(cache=True)
def mollifier(e, eps):
    """m, m', m'' of the edge-edge mollifier at e = |u x v|^2."""
    if e >= eps:
        return 1.0, 0.0, 0.0
    q = e / eps
    return (2.0 - q) * q, (2.0 - 2.0 * q) / eps, -2.0 / (eps * eps)


@njit(cache=True, error_model="numpy")
def _phi(D, reach2, r, dhat):
    """b, b', b'' with respect to D: the barrier on the squared distance D itself
    (r < 0, activation reach2) or on the gap sqrt(D) - r (activation dhat)."""
    if r < 0.0:
        return barrier(D, reach2)
    s = np.sqrt(D)
    b, db, ddb = barrier(s - r, dhat)
    return b, 0.5 * db / s, 0.25 * (ddb - db / s) / D


@njit(cache=True, error_model="numpy")
def pair_energy(P, eps, dhat2, kappa, g, H, want):
    """The barrier energy of one edge pair (points P (12,)); its gradient into g (12,)
    and, with ``want``, its Hessian into H (12, 12) (both zero out of reach)."""
    return edge_energy(P, eps, dhat2, -1.0, 0.0, kappa, g, H, want)


@njit(cache=True, error_model="numpy")
def edge_energy(P, eps, reach2, r, dhat, kappa, g, H, want):
    """``pair_energy`` on the squared distance (r < 0, activation reach2) or on the gap
    sqrt(D) - r of edges grown by r >= 0 (activation dhat, reach2 = (r + dhat)^2)."""
    g[:] = 0.0
    if want:
        H[:, :] = 0.0
    gd = np.empty(12)
    Hd = np.empty((12, 12))
    D = sqdist(P, np.int64(0), gd, Hd, np.bool_(False))
    if D >= reach2:
        return 0.0  # out of reach: no Hessian to compute
    if want:
        sqdist(P, np.int64(0), gd, Hd, np.bool_(True))
    if D <= 0.0 or D <= r * abs(r):
        return np.inf  # touching (m b would be 0 inf for parallel edges)
    ge = np.empty(12)
    He = np.empty((12, 12))
    m, dm, ddm = mollifier(parallelism(P, ge, He, want), eps)
    b, db, ddb = _phi(D, reach2, r, dhat)
    energy = m * b
    gB = db * gd  # the gradient of B = b(D) - sum_j b(D_j)
    for p in range(12):
        g[p] += m * db * gd[p]
    if want:
        for p in range(12):
            for q in range(12):
                H[p, q] += m * (ddb * gd[p] * gd[q] + db * Hd[p, q])
    B = b
    if m < 1.0:
        for kind in range(1, 5):
            Dj = sqdist(P, kind, gd, Hd, want)
            if Dj >= reach2:
                continue
            bj, dbj, ddbj = _phi(Dj, reach2, r, dhat)
            energy += (1.0 - m) * bj
            B -= bj
            for p in range(12):
                g[p] += (1.0 - m) * dbj * gd[p]
                gB[p] -= dbj * gd[p]
            if want:
                for p in range(12):
                    for q in range(12):
                        H[p, q] += (1.0 - m) * (ddbj * gd[p] * gd[q] + dbj * Hd[p, q])
        for p in range(12):
            g[p] += B * dm * ge[p]
        if want:
            for p in range(12):
                for q in range(12):
                    H[p, q] += dm * (ge[p] * gB[q] + gB[p] * ge[q])
                    H[p, q] += B * (ddm * ge[p] * ge[q] + dm * He[p, q])
    for p in range(12):
        g[p] *= kappa
    if want:
        for p in range(12):
            for q in range(12):
                H[p, q] *= kappa
    return kappa * energy


@njit(cache=True)
def gather(x, edges, a, b, P):
    """The coordinates of the two edges a and b (12 numbers into P); their node indices."""
    n = (edges[a, 0], edges[a, 1], edges[b, 0], edges[b, 1])
    for k in range(4):
        for i in range(3):
            P[3 * k + i] = x[n[k], i]
    return n


@njit(cache=True, error_model="numpy")
def strand_gradient(x, edges, rest, pairs, dhat, kappa, grad, r=-1.0):
    """Adds the barrier's gradient of the edge ``pairs`` (K, 2) to grad (N, 3) (r >= 0:
    on the gap d - r, ``edge_energy``); returns the energy."""
    P, g, H = np.empty(12), np.empty(12), np.empty((12, 12))
    total, skip = 0.0, np.bool_(False)  # (no Hessian: a value, not a literal)
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        n = gather(x, edges, a, b, P)
        eps = EPS_PARALLEL * (rest[a] * rest[b]) ** 2
        total += edge_energy(P, eps, (max(r, 0.0) + dhat) ** 2, r, dhat, kappa, g, H, skip)
        for k in range(4):
            for i in range(3):
                grad[n[k], i] += g[3 * k + i]
    return total


@njit(cache=True, error_model="numpy")
def strand_hessian(x, edges, rest, pairs, slots, dhat, kappa, values, r=-1.0):
    """Writes the 12x12 blocks (row-major, points a0 a1 b0 b1) of the ``pairs`` at
    values[144 slot:]; the other blocks are zero. Returns how many pairs act."""
    values[:] = 0.0
    P = np.empty(12)
    g = np.empty(12)
    H = np.empty((12, 12))
    active = 0
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        gather(x, edges, a, b, P)
        eps = EPS_PARALLEL * (rest[a] * rest[b]) ** 2
        edge_energy(P, eps, (max(r, 0.0) + dhat) ** 2, r, dhat, kappa, g, H, np.bool_(True))
        at = 144 * slots[p]
        nonzero = False
        for i in range(12):
            for j in range(12):
                h = H[i, j]
                values[at + 12 * i + j] = h
                nonzero = nonzero or h != 0.0
        active += 1 if nonzero else 0
    return active


@njit(cache=True)
def _shares(edges, a, b):
    """Whether edges a and b share a node (adjacent strands: no contact between them)."""
    a0, a1, b0, b1 = edges[a, 0], edges[a, 1], edges[b, 0], edges[b, 1]
    return a0 == b0 or a0 == b1 or a1 == b0 or a1 == b1


@njit(cache=True)
def _boxes(x, edges, grow, reach):
    """Every edge's box grown by reach / 2 + grow[e]: (lo, hi) (M, 3) and the largest side."""
    m = edges.shape[0]
    lo, hi = np.empty((m, 3)), np.empty((m, 3))
    size = 0.0
    for e in range(m):
        pad = 0.5 * reach + grow[e]
        for i in range(3):
            p, q = x[edges[e, 0], i], x[edges[e, 1], i]
            lo[e, i] = min(p, q) - pad
            hi[e, i] = max(p, q) + pad
            size = max(size, hi[e, i] - lo[e, i])
    return lo, hi, size


@njit(cache=True)
def _cells(lo, hi, origin, cell, dims):
    """Each box's cell range (M, 6): first and last cell per axis."""
    m = lo.shape[0]
    out = np.empty((m, 6), dtype=np.int64)
    for e in range(m):
        for i in range(3):
            c0 = int(np.floor((lo[e, i] - origin[i]) / cell))
            c1 = int(np.floor((hi[e, i] - origin[i]) / cell))
            out[e, i] = min(max(c0, 0), dims[i] - 1)
            out[e, 3 + i] = min(max(c1, 0), dims[i] - 1)
    return out


@njit(cache=True)
def _entries(span, dims):
    """(cell key, edge) of every cell every box covers, sorted by key (by counting where
    the grid is dense, as a net's is)."""
    m = span.shape[0]
    count = 0
    for e in range(m):
        count += (
            (span[e, 3] - span[e, 0] + 1)
            * (span[e, 4] - span[e, 1] + 1)
            * (span[e, 5] - span[e, 2] + 1)
        )
    keys = np.empty(count, dtype=np.int64)
    ids = np.empty(count, dtype=np.int64)
    k = 0
    for e in range(m):
        for cx in range(span[e, 0], span[e, 3] + 1):
            for cy in range(span[e, 1], span[e, 4] + 1):
                for cz in range(span[e, 2], span[e, 5] + 1):
                    keys[k] = (cx * dims[1] + cy) * dims[2] + cz
                    ids[k] = e
                    k += 1
    cells = dims[0] * dims[1] * dims[2]
    if cells > 4 * count + 1024:  # a sparse grid: sort the keys
        order = np.argsort(keys, kind="mergesort")
        return keys[order], ids[order]
    start = np.zeros(cells + 1, dtype=np.int64)  # else by counting, in linear time
    for k in range(count):
        start[keys[k] + 1] += 1
    for c in range(cells):
        start[c + 1] += start[c]
    out_keys, out_ids = np.empty(count, dtype=np.int64), np.empty(count, dtype=np.int64)
    for k in range(count):
        p = start[keys[k]]
        out_keys[p], out_ids[p] = keys[k], ids[k]
        start[keys[k]] = p + 1
    return out_keys, out_ids


@njit(cache=True, error_model="numpy")
def candidates(x, edges, grow, reach):
    """The pairs (a < b) of edges that share no node and are within
    reach + grow[a] + grow[b] of each other (K, 2), by a uniform grid of the edges'
    grown boxes: each pair is tested once, in the cell of its boxes' overlap corner."""
    m = edges.shape[0]
    out = np.empty((max(16, m), 2), dtype=np.int64)
    if m < 2:
        return out[:0]
    lo, hi, size = _boxes(x, edges, grow, reach)
    origin = np.empty(3)
    dims = np.empty(3, dtype=np.int64)
    extent = 0.0
    for i in range(3):
        origin[i] = lo[:, i].min()
        extent = max(extent, hi[:, i].max() - origin[i])
    cell = max(size, 1e-6 * extent, 1e-300)
    for i in range(3):
        dims[i] = int(np.floor((hi[:, i].max() - origin[i]) / cell)) + 1
    span = _cells(lo, hi, origin, cell, dims)
    keys, ids = _entries(span, dims)
    P, g, H = np.empty(12), np.empty(12), np.empty((12, 12))
    count, i, n = 0, 0, keys.size
    while i < n:
        j = i
        while j < n and keys[j] == keys[i]:
            j += 1
        cz = keys[i] % dims[2]
        cy = (keys[i] // dims[2]) % dims[1]
        cx = keys[i] // (dims[1] * dims[2])
        for p in range(i, j):
            for q in range(p + 1, j):
                a, b = min(ids[p], ids[q]), max(ids[p], ids[q])
                if not _owned(lo, hi, span, a, b, cx, cy, cz) or _shares(edges, a, b):
                    continue
                gather(x, edges, a, b, P)
                limit = reach + grow[a] + grow[b]
                if sqdist(P, np.int64(0), g, H, np.bool_(False)) > limit * limit:
                    continue
                if count == out.shape[0]:
                    more = np.empty((2 * count, 2), dtype=np.int64)
                    for r in range(count):  # by hand: a slice assignment compiles slowly
                        more[r, 0], more[r, 1] = out[r, 0], out[r, 1]
                    out = more
                out[count, 0], out[count, 1] = a, b
                count += 1
        i = j
    return out[:count]


@njit(cache=True)
def _owned(lo, hi, span, a, b, cx, cy, cz):
    """Whether the boxes a and b overlap and the cell (cx, cy, cz) holds the corner of
    their overlap (the one cell where the pair is tested)."""
    for i in range(3):
        if lo[a, i] > hi[b, i] or lo[b, i] > hi[a, i]:
            return False
    corner = (max(span[a, 0], span[b, 0]), max(span[a, 1], span[b, 1]), max(span[a, 2], span[b, 2]))
    return corner[0] == cx and corner[1] == cy and corner[2] == cz
