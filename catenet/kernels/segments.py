"""Contact along the whole edge: the net's edges as capsules against a solid's outline.

A net edge (x_i, x_j) of contact radius r meets a solid whose surface is its outline
(``catenet.scene.shapes``: points Y, edges between them and a radius R per feature: a
box's corners and edges, a capsule's axis, a sphere's centre, a mesh's vertices and
edges, a cylinder's core capsule and its end bands' prisms). Each point is linear in a
few nodes, Y = W x_b (a free body's four nodes, a ball's centre; none for a fixed
obstacle). Two features of the pair are barriers on their gap d - rf with rf = R + r
the feature's (``rf``, per feature: the outline edges, then the lone points):

- every outline edge against the net edge: the strands' mollified edge-edge barrier
  (``catenet.kernels.strands.edge_energy``: exact gradient and Hessian in every regime
  of the segment distance, the mollifier where they are nearly parallel, the end
  point-edge barriers taking over there);
- every outline point on no outline edge (a sphere's centre) against the net edge: the
  point-segment distance (the strands' ``sqdist`` kind 3), whose Hessian never
  degenerates (the segment's own length is its curvature's scale).

The net edge's end points against the solid's shape are the shape's own node barrier,
grown by r (``catenet.terms.segments``). For a polyhedral outline (box, mesh) the three
together decide the distance of the segment to the solid: the closest points of a
segment and a polyhedron are an end of the segment on the surface, a point of the
segment on an edge of the polyhedron, or (a segment parallel to a face) both at once;
for a sphere and a capsule the distance to the centre or the axis is exact by itself.

Values, per net edge k of the term (its nodes i, j and the solid's nb nodes b):
the (i j, i j) block (36), the (i j, b) block (18 nb) and the (b, i j) block (18 nb),
row-major, at S k with S = 36 + 36 nb; after them the (b, b) block (9 nb^2) summed
over the edges.

Candidates (``near_pairs``, every evaluation): the pairs whose bounding boxes, grown by
the reach, overlap, the features binned in a uniform grid (a mesh of thousands of edges
costs its cells, not its edges, per net edge).

``segment_ccd`` caps a step by the strands' additive CCD of every pair within reach of
the step's motion (points of a body move linearly with its nodes: W is constant).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.ccd import accd
from catenet.kernels.strands import EPS_PARALLEL, _phi, edge_energy, sqdist

POINT = 3  # the strands' distance kind of point b0 against edge a
GRID_CELLS = 1 << 18  # the features' grid never has more cells


@njit(cache=True, error_model="numpy")
def _points(x, edges, e, Y, F, lone, f, P):
    """P (12,): the net edge e's ends, then the outline edge f's (a lone point twice,
    f >= len(F)); returns the distance kind (0 edge-edge, POINT point-edge)."""
    i, j = edges[e, 0], edges[e, 1]
    nf = F.shape[0]
    if f < nf:
        p, q = F[f, 0], F[f, 1]
    else:
        p = lone[f - nf]
        q = p
    for a in range(3):
        P[a] = x[i, a]
        P[3 + a] = x[j, a]
        P[6 + a] = Y[p, a]
        P[9 + a] = Y[q, a]
    return 0 if f < nf else POINT


@njit(cache=True, error_model="numpy")
def _ends(F, lone, f):
    nf = F.shape[0]
    if f < nf:
        return F[f, 0], F[f, 1]
    return lone[f - nf], -1


@njit(cache=True, error_model="numpy")
def point_energy(P, reach2, r, dhat, kappa, g, H, want):
    """The barrier on the gap sqrt(D) - r of the point P[6:9] and the segment P[0:6]
    (D their squared distance); gradient into g (12,), with ``want`` the Hessian into H
    (12, 12); both zero out of reach, inf at contact."""
    g[:] = 0.0
    if want:
        H[:, :] = 0.0
    gd = np.empty(12)
    Hd = np.empty((12, 12))
    D = sqdist(P, np.int64(POINT), gd, Hd, np.bool_(False))
    if D >= reach2:
        return 0.0
    if D <= r * r:
        return np.inf
    if want:
        sqdist(P, np.int64(POINT), gd, Hd, np.bool_(True))
    b, db, ddb = _phi(D, reach2, r, dhat)
    for p in range(12):
        g[p] = kappa * db * gd[p]
    if want:
        for p in range(12):
            for q in range(12):
                H[p, q] = kappa * (ddb * gd[p] * gd[q] + db * Hd[p, q])
    return kappa * b


@njit(cache=True, error_model="numpy")
def _pair(x, edges, rest, Y, F, flen, lone, e, f, rf, dhat, kappa, g, H, want):
    """The barrier of net edge e and outline feature f (``_points``) on their gap
    d - rf[f] (the feature's radius and the net's contact radius)."""
    P = np.empty(12)
    kind = _points(x, edges, e, Y, F, lone, f, P)
    r = rf[f]
    reach = r + dhat
    if kind == POINT:
        return point_energy(P, reach * reach, r, dhat, kappa, g, H, want)
    eps = EPS_PARALLEL * (rest[e] * flen[f]) ** 2
    return edge_energy(P, eps, reach * reach, r, dhat, kappa, g, H, want)


@njit(cache=True, error_model="numpy")
def _feature_boxes(Y, dY, F, lone, reach, upto):
    """Each feature's box (lo, hi) (T, 3), swept along Y + t dY for t in [0, upto] and
    grown by its ``reach`` (T,)."""
    total = F.shape[0] + lone.shape[0]
    lo = np.empty((total, 3))
    hi = np.empty((total, 3))
    for f in range(total):
        p, q = _ends(F, lone, f)
        if q < 0:
            q = p
        for a in range(3):
            v = (Y[p, a], Y[q, a], Y[p, a] + upto * dY[p, a], Y[q, a] + upto * dY[q, a])
            lo[f, a] = min(min(v[0], v[1]), min(v[2], v[3])) - reach[f]
            hi[f, a] = max(max(v[0], v[1]), max(v[2], v[3])) + reach[f]
    return lo, hi


@njit(cache=True, error_model="numpy")
def _median(values):
    """np.median of a 1D array, exactly (the middle order statistic, or the mean of the
    two): a quickselect on a copy, which compiles in a fraction of np.median's time."""
    a = values.copy()
    n = a.shape[0]
    half = n >> 1
    left, right = 0, n - 1
    while left < right:  # Hoare's partition until a[half] is the half-th smallest
        pivot = a[(left + right) >> 1]
        i, j = left, right
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if half <= j:
            right = j
        elif half >= i:
            left = i
        else:
            break
    upper = a[half]
    if n & 1:
        return upper
    lower = a[0]  # the largest of a[:half], all at most a[half]
    for k in range(1, half):
        lower = max(lower, a[k])
    return (lower + upper) / 2


@njit(cache=True, error_model="numpy")
def _grid(lo, hi):
    """A uniform grid of the feature boxes: (origin, cell, dims, start, items), each
    cell listing the boxes that overlap it (cells about the median box's size, at most
    GRID_CELLS of them)."""
    total = lo.shape[0]
    origin = np.empty(3)
    top = np.empty(3)
    sizes = np.empty(total)
    for a in range(3):
        origin[a] = lo[:, a].min()
        top[a] = hi[:, a].max()
    for f in range(total):
        sizes[f] = max(hi[f, 0] - lo[f, 0], max(hi[f, 1] - lo[f, 1], hi[f, 2] - lo[f, 2]))
    cell = max(_median(sizes), 1e-300)
    dims = np.empty(3, dtype=np.int64)
    while True:
        for a in range(3):
            dims[a] = int((top[a] - origin[a]) / cell) + 1
        if dims[0] * dims[1] * dims[2] <= GRID_CELLS:
            break
        cell *= 1.5
    count = np.zeros(dims[0] * dims[1] * dims[2] + 1, dtype=np.int64)
    span = np.empty((total, 6), dtype=np.int64)
    for f in range(total):
        for a in range(3):
            span[f, a] = min(int((lo[f, a] - origin[a]) / cell), dims[a] - 1)
            span[f, 3 + a] = min(int((hi[f, a] - origin[a]) / cell), dims[a] - 1)
        for cx in range(span[f, 0], span[f, 3] + 1):
            for cy in range(span[f, 1], span[f, 4] + 1):
                for cz in range(span[f, 2], span[f, 5] + 1):
                    count[(cx * dims[1] + cy) * dims[2] + cz + 1] += 1
    for c in range(count.shape[0] - 1):
        count[c + 1] += count[c]
    items = np.empty(count[-1], dtype=np.int64)
    fill = count[:-1].copy()
    for f in range(total):
        for cx in range(span[f, 0], span[f, 3] + 1):
            for cy in range(span[f, 1], span[f, 4] + 1):
                for cz in range(span[f, 2], span[f, 5] + 1):
                    c = (cx * dims[1] + cy) * dims[2] + cz
                    items[fill[c]] = f
                    fill[c] += 1
    return origin, cell, dims, count, items


@njit(cache=True, error_model="numpy")
def near_pairs(x, dx, edges, Y, dY, F, lone, reach, upto):
    """The pairs (net edge, feature) (K, 2) whose boxes, swept along x + t dx and
    Y + t dY for t in [0, upto] and the feature's grown by its ``reach`` (T,), overlap:
    every pair that can come within reach in that motion (features: the outline edges,
    then the lone points). The features' boxes are binned in a uniform grid, so each net
    edge tests only the features of the cells its box covers."""
    lo, hi = _feature_boxes(Y, dY, F, lone, reach, upto)
    total = lo.shape[0]
    out = np.empty((16, 2), dtype=np.int64)
    if total == 0:
        return out[:0]
    origin, cell, dims, start, items = _grid(lo, hi)
    seen = np.full(total, -1, dtype=np.int64)
    count = 0
    elo = np.empty(3)
    ehi = np.empty(3)
    c0 = np.empty(3, dtype=np.int64)
    c1 = np.empty(3, dtype=np.int64)
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        clear = False
        for a in range(3):
            v = (x[i, a], x[j, a], x[i, a] + upto * dx[i, a], x[j, a] + upto * dx[j, a])
            elo[a] = min(min(v[0], v[1]), min(v[2], v[3]))
            ehi[a] = max(max(v[0], v[1]), max(v[2], v[3]))
            top = origin[a] + dims[a] * cell
            clear = clear or elo[a] > top or ehi[a] < origin[a] or not ehi[a] >= elo[a]
            c0[a] = max(int((elo[a] - origin[a]) / cell), 0) if not clear else 0
            c1[a] = min(int((ehi[a] - origin[a]) / cell), dims[a] - 1) if not clear else -1
        if clear:
            continue
        for cx in range(c0[0], c1[0] + 1):
            for cy in range(c0[1], c1[1] + 1):
                for cz in range(c0[2], c1[2] + 1):
                    c = (cx * dims[1] + cy) * dims[2] + cz
                    for k in range(start[c], start[c + 1]):
                        f = items[k]
                        if seen[f] == e:
                            continue
                        seen[f] = e
                        hit = True
                        for a in range(3):
                            if elo[a] > hi[f, a] or ehi[a] < lo[f, a]:
                                hit = False
                                break
                        if not hit:
                            continue
                        if count == out.shape[0]:
                            more = np.empty((2 * count, 2), dtype=np.int64)
                            for r in range(count):  # by hand: a slice assignment compiles slowly
                                more[r, 0], more[r, 1] = out[r, 0], out[r, 1]
                            out = more
                        out[count, 0] = e
                        out[count, 1] = f
                        count += 1
    return out[:count]


@njit(cache=True, error_model="numpy")
def segment_gradient(x, edges, rest, Y, W, bnodes, F, flen, lone, pairs, rf, dhat, kappa, grad):
    """Adds the barrier's gradient of the ``pairs`` to grad (N, 3) (the solid's share
    through W to its nodes ``bnodes``); returns the energy."""
    g = np.empty(12)
    H = np.empty((1, 1))
    total = 0.0
    nb = bnodes.shape[0]
    for k in range(pairs.shape[0]):
        e, f = pairs[k, 0], pairs[k, 1]
        energy = _pair(
            x, edges, rest, Y, F, flen, lone, e, f, rf, dhat, kappa, g, H, np.bool_(False)
        )
        if energy == 0.0:
            continue
        total += energy
        if not np.isfinite(energy):
            continue
        i, j = edges[e, 0], edges[e, 1]
        for a in range(3):
            grad[i, a] += g[a]
            grad[j, a] += g[3 + a]
        p, q = _ends(F, lone, f)
        for u in range(nb):
            w0 = W[p, u]
            w1 = W[q, u] if q >= 0 else 0.0
            for a in range(3):
                grad[bnodes[u], a] += w0 * g[6 + a] + w1 * g[9 + a]
    return total


@njit(cache=True, error_model="numpy")
def segment_hessian(x, edges, rest, Y, W, nb, F, flen, lone, pairs, rf, dhat, kappa, values):
    """Writes the blocks of the module docstring into ``values`` (all of them: zeros
    where no pair acts); returns how many pairs act."""
    values[:] = 0.0
    g = np.empty(12)
    H = np.empty((12, 12))
    S = 36 + 36 * nb
    body = edges.shape[0] * S
    nn = 3 * nb
    C = np.zeros((12, 6 + nn))  # the points' coordinates by (i, j, b)
    for a in range(6):
        C[a, a] = 1.0
    HC = np.empty((12, 6 + nn))
    active = 0
    for k in range(pairs.shape[0]):
        e, f = pairs[k, 0], pairs[k, 1]
        want = np.bool_(True)
        energy = _pair(x, edges, rest, Y, F, flen, lone, e, f, rf, dhat, kappa, g, H, want)
        if energy == 0.0 or not np.isfinite(energy):
            continue
        active += 1
        p, q = _ends(F, lone, f)
        for u in range(nb):
            w0 = W[p, u]
            w1 = W[q, u] if q >= 0 else 0.0
            for a in range(3):
                C[6 + a, 6 + 3 * u + a] = w0
                C[9 + a, 6 + 3 * u + a] = w1
        for m in range(12):
            for c in range(6 + nn):
                s = 0.0
                for n in range(12):
                    if C[n, c] != 0.0:
                        s += H[m, n] * C[n, c]
                HC[m, c] = s
        at = e * S
        for a in range(6 + nn):
            for c in range(6 + nn):
                s = 0.0
                for m in range(12):
                    if C[m, a] != 0.0:
                        s += C[m, a] * HC[m, c]
                if a < 6 and c < 6:
                    values[at + 6 * a + c] += s
                elif a < 6:
                    values[at + 36 + nn * a + (c - 6)] += s
                elif c < 6:
                    values[at + 36 + 6 * nn + 6 * (a - 6) + c] += s
                else:
                    values[body + nn * (a - 6) + (c - 6)] += s
    return active


@njit(cache=True, error_model="numpy")
def segment_gaps(x, edges, Y, F, lone, rf, out):
    """out[k] (M,): the least gap d - rf[f] of net edge k to the outline's features f
    (its edges and lone points; inf without features)."""
    g = np.empty(12)
    H = np.empty((1, 1))
    P = np.empty(12)
    total = F.shape[0] + lone.shape[0]
    for e in range(edges.shape[0]):
        best = np.inf
        for f in range(total):
            kind = _points(x, edges, e, Y, F, lone, f, P)
            best = min(best, np.sqrt(sqdist(P, kind, g, H, np.bool_(False))) - rf[f])
        out[e] = best


@njit(cache=True, error_model="numpy")
def segment_ccd(x, dx, edges, Y, dY, F, lone, pairs, rf, t_max):
    """The first time in (0, t_max] at which a pair, moving with dx and dY, may come
    within its feature's rf[f] (the additive CCD's conservative time); inf when none
    does."""
    P, dP = np.empty(12), np.empty(12)
    t = np.inf
    for k in range(pairs.shape[0]):
        e, f = pairs[k, 0], pairs[k, 1]
        kind = _points(x, edges, e, Y, F, lone, f, P)
        _points(dx, edges, e, dY, F, lone, f, dP)
        t = min(t, accd(P, dP, min(t, t_max), rf[f], kind, True))
    return t


@njit(cache=True, error_model="numpy")
def pair_forces(x, edges, rest, Y, F, flen, lone, pairs, rf, dhat, kappa, force, share):
    """Per pair (K,): the force of the solid on the net edge (force (K, 3): minus the
    barrier's gradient on its two nodes) and the share of it on its second node
    (share (K,): where along the edge the force acts, in [0, 1]; 0 out of reach)."""
    g = np.empty(12)
    H = np.empty((1, 1))
    for k in range(pairs.shape[0]):
        e, f = pairs[k, 0], pairs[k, 1]
        energy = _pair(
            x, edges, rest, Y, F, flen, lone, e, f, rf, dhat, kappa, g, H, np.bool_(False)
        )
        total = 0.0
        for a in range(3):
            force[k, a] = -(g[a] + g[3 + a]) if np.isfinite(energy) else 0.0
            total += force[k, a] * force[k, a]
        share[k] = 0.0
        if total > 0.0:
            on_j = 0.0
            for a in range(3):
                on_j -= g[3 + a] * force[k, a]
            share[k] = min(max(on_j / total, 0.0), 1.0)
