"""Barrier contact of nodes with a closed triangle mesh (see ``catenet.kernels.shapes``).

A node's gap is its signed distance to the nearest triangle: the nearest point p and its
feature (the face, one of its edges or vertices) come from the Voronoi regions of the
triangle (Ericson, Real-Time Collision Detection, 5.1.5); the sign is that of
(x - p).m with m the feature's angle-weighted pseudo-normal (Baerentzen and Aanaes 2005),
which is exact for the nearest feature of a closed, consistently oriented mesh.

Acceleration: a uniform grid whose cells list every triangle whose bounding box, grown
by dhat, overlaps the cell. A node's candidates are the triangles of its own cell, which
include every triangle within dhat of it; a node outside the grid touches nothing. The
first contact along a step (``mesh_max_step``) walks the cells the node's ray crosses
(Amanatides and Woo) and stops at the first cell that holds a hit before the ray leaves
it, so the cost per node is the cells crossed, not the triangles.

Offset (a rigid ball's centre against the mesh, ``catenet.terms.collide``): with r > 0
the gap is d - r, the distance to the mesh grown by r, with the curvature over d (see
``catenet.kernels.shapes``); the grid must then list the triangles within dhat + r, and
the first contact is the exact entry of the ray into the union, over the triangles, of
each triangle grown by r: its prism of half-thickness r (clipped by the five planes) and
the capsules of radius r on its three edges (their end balls are the vertex balls).

Feature codes: 0 face, 1..3 vertex k-1, 4..6 edge k-4 (from vertex k-4 to the next).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.contact import barrier
from catenet.kernels.shapes import _block, _zero_block, capsule_entry

EPS_BARY = 1e-9  # barycentric tolerance of the ray test: a grazing ray counts as a hit


@njit(cache=True, error_model="numpy", inline="always")
def _dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


@njit(cache=True, error_model="numpy")
def closest_point(x, A, B, C, p):
    """The point p of triangle ABC nearest to x; returns its feature code. Scalar
    arithmetic only (no temporary arrays: it runs for every candidate of every node)."""
    abx, aby, abz = B[0] - A[0], B[1] - A[1], B[2] - A[2]
    acx, acy, acz = C[0] - A[0], C[1] - A[1], C[2] - A[2]
    apx, apy, apz = x[0] - A[0], x[1] - A[1], x[2] - A[2]
    d1 = _dot(abx, aby, abz, apx, apy, apz)
    d2 = _dot(acx, acy, acz, apx, apy, apz)
    if d1 <= 0.0 and d2 <= 0.0:
        p[0], p[1], p[2] = A[0], A[1], A[2]
        return 1
    bpx, bpy, bpz = x[0] - B[0], x[1] - B[1], x[2] - B[2]
    d3 = _dot(abx, aby, abz, bpx, bpy, bpz)
    d4 = _dot(acx, acy, acz, bpx, bpy, bpz)
    if d3 >= 0.0 and d4 <= d3:
        p[0], p[1], p[2] = B[0], B[1], B[2]
        return 2
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        p[0], p[1], p[2] = A[0] + v * abx, A[1] + v * aby, A[2] + v * abz
        return 4
    cpx, cpy, cpz = x[0] - C[0], x[1] - C[1], x[2] - C[2]
    d5 = _dot(abx, aby, abz, cpx, cpy, cpz)
    d6 = _dot(acx, acy, acz, cpx, cpy, cpz)
    if d6 >= 0.0 and d5 <= d6:
        p[0], p[1], p[2] = C[0], C[1], C[2]
        return 3
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        p[0], p[1], p[2] = A[0] + w * acx, A[1] + w * acy, A[2] + w * acz
        return 6
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        p[0] = B[0] + w * (C[0] - B[0])
        p[1] = B[1] + w * (C[1] - B[1])
        p[2] = B[2] + w * (C[2] - B[2])
        return 5
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    p[0] = A[0] + abx * v + acx * w
    p[1] = A[1] + aby * v + acy * w
    p[2] = A[2] + abz * v + acz * w
    return 0


@njit(cache=True, error_model="numpy")
def _signed(x, V, T, fn, en, vn, t, code, p):
    """Signed distance of x to its nearest point p (feature ``code`` of triangle t)."""
    dist = np.sqrt((x[0] - p[0]) ** 2 + (x[1] - p[1]) ** 2 + (x[2] - p[2]) ** 2)
    if code == 0:
        m = fn[t]
    elif code <= 3:
        m = vn[T[t, code - 1]]
    else:
        m = en[t, code - 4]
    s = (x[0] - p[0]) * m[0] + (x[1] - p[1]) * m[1] + (x[2] - p[2]) * m[2]
    return dist if s > 0.0 else -dist


@njit(cache=True, error_model="numpy")
def _cell(x, lo, h, dims):
    """The grid cell holding x (-1 outside the grid)."""
    c = 0
    for a in range(3):
        i = int(np.floor((x[a] - lo[a]) / h))
        if i < 0 or i >= dims[a]:
            return -1
        c = c * dims[a] + i
    return c


@njit(cache=True, error_model="numpy")
def _nearest(x, V, T, fn, en, vn, lo, h, dims, start, items, p):
    """Signed gap of x to the nearest candidate triangle of its cell, with that triangle
    and feature (inf, -1, -1 when the cell holds none); p holds the nearest point."""
    c = _cell(x, lo, h, dims)
    if c < 0:
        return np.inf, -1, -1
    q = np.empty(3)
    best = np.inf
    best_t = -1
    best_code = -1
    for j in range(start[c], start[c + 1]):
        t = items[j]
        code = closest_point(x, V[T[t, 0]], V[T[t, 1]], V[T[t, 2]], q)
        d2 = (x[0] - q[0]) ** 2 + (x[1] - q[1]) ** 2 + (x[2] - q[2]) ** 2
        if d2 < best:
            best, best_t, best_code = d2, t, code
            p[0], p[1], p[2] = q[0], q[1], q[2]
    if best_t < 0:
        return np.inf, -1, -1
    return _signed(x, V, T, fn, en, vn, best_t, best_code, p), best_t, best_code


@njit(cache=True, error_model="numpy")
def _projection(V, T, t, code, n, P):
    """P of the feature (n n^T on a face, I - e e^T across an edge, I at a vertex)."""
    for a in range(3):
        for c in range(3):
            P[a, c] = 1.0 if a == c else 0.0
    if code == 0:
        for a in range(3):
            for c in range(3):
                P[a, c] = n[a] * n[c]
    elif code >= 4:
        k = code - 4
        e = V[T[t, (k + 1) % 3]] - V[T[t, k]]
        e = e / np.sqrt(e @ e)
        for a in range(3):
            for c in range(3):
                P[a, c] -= e[a] * e[c]


@njit(cache=True, error_model="numpy")
def mesh_gradient(x, nodes, V, T, fn, en, vn, lo, h, dims, start, items, kappa, dhat, off, grad):
    """Adds the mesh barrier's gradient at ``nodes`` (gap: distance - ``off``); returns
    the energy."""
    total = 0.0
    p = np.empty(3)
    for k in range(nodes.shape[0]):
        i = nodes[k]
        d, _, _ = _nearest(x[i], V, T, fn, en, vn, lo, h, dims, start, items, p)
        g = d - off
        if g >= dhat:
            continue
        b, db, _ = barrier(g, dhat)
        total += kappa * b
        if g > 0.0:
            for a in range(3):
                grad[i, a] += kappa * db * (x[i, a] - p[a]) / d
    return total


@njit(cache=True, error_model="numpy")
def mesh_hessian(x, nodes, V, T, fn, en, vn, lo, h, dims, start, items, kappa, dhat, off, values):
    """Writes the 3x3 blocks of the mesh barrier at ``nodes``; returns how many act."""
    active = 0
    p = np.empty(3)
    n = np.empty(3)
    P = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        i = nodes[k]
        d, t, code = _nearest(x[i], V, T, fn, en, vn, lo, h, dims, start, items, p)
        g = d - off
        if g >= dhat or g <= 0.0:
            _zero_block(values, k)
            continue
        active += 1
        _, db, ddb = barrier(g, dhat)
        for a in range(3):
            n[a] = (x[i, a] - p[a]) / d
        _projection(V, T, t, code, n, P)
        _block(values, k, kappa, db, ddb, d, n, P)  # curvature over d: the offset's too
    return active


@njit(cache=True, error_model="numpy")
def mesh_gap(x, nodes, V, T, fn, en, vn, box_lo, box_hi, off, out):
    """Signed distance of every node to the whole mesh (every triangle, those whose
    bounding box is farther than the best so far skipped), minus ``off``."""
    p = np.empty(3)
    q = np.empty(3)
    for k in range(nodes.shape[0]):
        xi = x[nodes[k]]
        best = np.inf
        best_t = -1
        best_code = -1
        for t in range(T.shape[0]):
            lb = 0.0
            for a in range(3):
                g = max(box_lo[t, a] - xi[a], 0.0, xi[a] - box_hi[t, a])
                lb += g * g
            if lb >= best:
                continue
            code = closest_point(xi, V[T[t, 0]], V[T[t, 1]], V[T[t, 2]], q)
            d2 = (xi[0] - q[0]) ** 2 + (xi[1] - q[1]) ** 2 + (xi[2] - q[2]) ** 2
            if d2 < best:
                best, best_t, best_code = d2, t, code
                p[0], p[1], p[2] = q[0], q[1], q[2]
        out[k] = _signed(xi, V, T, fn, en, vn, best_t, best_code, p) - off


@njit(cache=True, error_model="numpy")
def _ray_triangle(x, v, A, B, C):
    """t >= 0 at which x + t v meets triangle ABC (inf: never; both sides count)."""
    e1x, e1y, e1z = B[0] - A[0], B[1] - A[1], B[2] - A[2]
    e2x, e2y, e2z = C[0] - A[0], C[1] - A[1], C[2] - A[2]
    px = v[1] * e2z - v[2] * e2y  # v x e2
    py = v[2] * e2x - v[0] * e2z
    pz = v[0] * e2y - v[1] * e2x
    det = _dot(e1x, e1y, e1z, px, py, pz)
    if det == 0.0:
        return np.inf
    inv = 1.0 / det
    tx, ty, tz = x[0] - A[0], x[1] - A[1], x[2] - A[2]
    u = _dot(tx, ty, tz, px, py, pz) * inv
    if u < -EPS_BARY or u > 1.0 + EPS_BARY:
        return np.inf
    qx = ty * e1z - tz * e1y  # (x - A) x e1
    qy = tz * e1x - tx * e1z
    qz = tx * e1y - ty * e1x
    w = _dot(v[0], v[1], v[2], qx, qy, qz) * inv
    if w < -EPS_BARY or u + w > 1.0 + EPS_BARY:
        return np.inf
    t = _dot(e2x, e2y, e2z, qx, qy, qz) * inv
    return t if t >= 0.0 else np.inf


@njit(cache=True, error_model="numpy")
def _prism_entry(x, v, A, B, C, n, r):
    """The first t >= 0 at which x + t v is in the prism {p + s n: p in ABC, |s| <= r}
    (n the unit normal of ABC by its vertex order; inf: never): Cyrus-Beck clipping by
    its two caps and three sides (outward side normals e x n)."""
    enter = -np.inf
    leave = np.inf
    m = np.empty(3)
    for face in range(5):
        if face < 2:
            sign = 1.0 if face == 0 else -1.0
            for a in range(3):
                m[a] = sign * n[a]
            lim = sign * _dot(n[0], n[1], n[2], A[0], A[1], A[2]) + r
        else:
            P0 = A if face == 2 else (B if face == 3 else C)
            P1 = B if face == 2 else (C if face == 3 else A)
            ex, ey, ez = P1[0] - P0[0], P1[1] - P0[1], P1[2] - P0[2]
            m[0] = ey * n[2] - ez * n[1]
            m[1] = ez * n[0] - ex * n[2]
            m[2] = ex * n[1] - ey * n[0]
            lim = _dot(m[0], m[1], m[2], P0[0], P0[1], P0[2])
        num = lim - _dot(m[0], m[1], m[2], x[0], x[1], x[2])  # >= 0: inside at t = 0
        den = _dot(m[0], m[1], m[2], v[0], v[1], v[2])
        if den == 0.0:
            if num < 0.0:
                return np.inf
            continue
        t = num / den
        if den > 0.0:
            leave = min(leave, t)
        else:
            enter = max(enter, t)
    if enter > leave or leave < 0.0:
        return np.inf
    return max(enter, 0.0)


@njit(cache=True, error_model="numpy")
def _grown_triangle_entry(x, v, A, B, C, n, r):
    """The first t >= 0 at which x + t v is within r of triangle ABC (inf: never)."""
    t = _prism_entry(x, v, A, B, C, n, r)
    t = min(t, capsule_entry(x, v, A, B, r))
    t = min(t, capsule_entry(x, v, B, C, r))
    return min(t, capsule_entry(x, v, C, A, r))


@njit(cache=True, error_model="numpy")
def _first_hit(x, v, V, T, fn, off, lo, h, dims, start, items):
    """The first t >= 0 at which the ray x + t v meets the mesh, grown by ``off`` > 0
    (inf: never)."""
    t0 = 0.0
    t1 = np.inf
    for a in range(3):
        hi = lo[a] + dims[a] * h
        if v[a] == 0.0:
            if x[a] < lo[a] or x[a] > hi:
                return np.inf
            continue
        ta = (lo[a] - x[a]) / v[a]
        tb = (hi - x[a]) / v[a]
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    if t0 > t1:
        return np.inf
    idx = np.empty(3, dtype=np.int64)
    step = np.empty(3, dtype=np.int64)
    t_next = np.empty(3)
    t_delta = np.empty(3)
    for a in range(3):
        i = int(np.floor((x[a] + t0 * v[a] - lo[a]) / h))
        idx[a] = min(max(i, 0), dims[a] - 1)
        if v[a] > 0.0:
            step[a] = 1
            t_next[a] = (lo[a] + (idx[a] + 1) * h - x[a]) / v[a]
            t_delta[a] = h / v[a]
        elif v[a] < 0.0:
            step[a] = -1
            t_next[a] = (lo[a] + idx[a] * h - x[a]) / v[a]
            t_delta[a] = -h / v[a]
        else:
            step[a] = 0
            t_next[a] = np.inf
            t_delta[a] = np.inf
    best = np.inf
    for _ in range(dims[0] + dims[1] + dims[2] + 3):
        c = (idx[0] * dims[1] + idx[1]) * dims[2] + idx[2]
        for j in range(start[c], start[c + 1]):
            t = items[j]
            A, B, C = V[T[t, 0]], V[T[t, 1]], V[T[t, 2]]
            if off > 0.0:
                best = min(best, _grown_triangle_entry(x, v, A, B, C, fn[t], off))
            else:
                best = min(best, _ray_triangle(x, v, A, B, C))
        a = 0
        if t_next[1] < t_next[a]:
            a = 1
        if t_next[2] < t_next[a]:
            a = 2
        if best <= t_next[a] or t_next[a] > t1:
            break
        idx[a] += step[a]
        if idx[a] < 0 or idx[a] >= dims[a]:
            break
        t_next[a] += t_delta[a]
    return best


@njit(cache=True, error_model="numpy")
def mesh_max_step(x, dx, nodes, V, T, fn, off, lo, h, dims, start, items):
    """The largest t with every node outside the mesh (grown by ``off``) along x + t dx:
    the first time a node's ray meets a (grown) triangle (inf if none)."""
    t_max = np.inf
    for k in range(nodes.shape[0]):
        i = nodes[k]
        if dx[i, 0] == 0.0 and dx[i, 1] == 0.0 and dx[i, 2] == 0.0:
            continue
        hit = _first_hit(x[i], dx[i], V, T, fn, off, lo, h, dims, start, items)
        t_max = min(t_max, hit)
    return t_max


@njit(cache=True)
def build_grid(V, T, lo, h, dims, pad):
    """(start, items): per cell (row-major over dims), the triangles whose bounding box
    grown by ``pad`` overlaps it."""
    n_cells = dims[0] * dims[1] * dims[2]
    count = np.zeros(n_cells + 1, dtype=np.int64)
    ranges = np.empty((T.shape[0], 6), dtype=np.int64)
    for t in range(T.shape[0]):
        for a in range(3):
            mn = min(V[T[t, 0], a], V[T[t, 1], a], V[T[t, 2], a]) - pad
            mx = max(V[T[t, 0], a], V[T[t, 1], a], V[T[t, 2], a]) + pad
            ranges[t, a] = min(max(int(np.floor((mn - lo[a]) / h)), 0), dims[a] - 1)
            ranges[t, 3 + a] = min(max(int(np.floor((mx - lo[a]) / h)), 0), dims[a] - 1)
        for i in range(ranges[t, 0], ranges[t, 3] + 1):
            for j in range(ranges[t, 1], ranges[t, 4] + 1):
                for m in range(ranges[t, 2], ranges[t, 5] + 1):
                    count[(i * dims[1] + j) * dims[2] + m + 1] += 1
    start = np.cumsum(count)
    items = np.empty(start[-1], dtype=np.int64)
    fill = start[:-1].copy()
    for t in range(T.shape[0]):
        for i in range(ranges[t, 0], ranges[t, 3] + 1):
            for j in range(ranges[t, 1], ranges[t, 4] + 1):
                for m in range(ranges[t, 2], ranges[t, 5] + 1):
                    c = (i * dims[1] + j) * dims[2] + m
                    items[fill[c]] = t
                    fill[c] += 1
    return start, items
