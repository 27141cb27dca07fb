"""The step cap of a free body's contact with the net's nodes (``BodyContact.max_step``,
``catenet.terms.rigid_contact``, whose docstring derives it) for a box or a capsule, in
one kernel: the body's pose and its change along the step, every node's quadratic
body-frame path X0 + t V + t^2 W, the floor, and the pieces' chords tested exactly
against the shape grown by their deviation.

Only the candidates are walked: the nodes whose path could come within the grown shape
before ``far`` (gap(X0) <= |V| far + |W| far^2 plus the most the shape is grown, dhat / 2
plus twice the floor). A node that is no candidate cannot touch the shape before ``far``,
so leaving it out keeps the cap safe; the pieces' lengths then follow the smallest gap
of the candidates (the nodes the chords are tested for) instead of every node's.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.rigid import frame_state
from catenet.kernels.shapes import BOX, box_max_step, capsule_max_step, shape_feature

EPS = float(np.finfo(np.float64).eps)


@njit(cache=True, error_model="numpy")
def body_paths(x, dx, nodes, body, B, c0):
    """Each node's body-frame point X0 and its path's V and W along the step dx, and the
    coordinates' scale max(|X0|, |U|, |c0|) (U = x - c)."""
    c, A = frame_state(x, body, B)
    dc, dA = frame_state(dx, body, B)
    K = nodes.shape[0]
    X0 = np.empty((K, 3))
    V = np.empty((K, 3))
    W = np.empty((K, 3))
    scale = 0.0
    for m in range(3):
        scale = max(scale, abs(c0[m]))
    for k in range(K):
        i = nodes[k]
        u0, u1, u2 = x[i, 0] - c[0], x[i, 1] - c[1], x[i, 2] - c[2]  # (scalars: no
        d0, d1, d2 = dx[i, 0] - dc[0], dx[i, 1] - dc[1], dx[i, 2] - dc[2]  # allocation)
        scale = max(scale, abs(u0), abs(u1), abs(u2))
        for m in range(3):
            s = c0[m]
            s += u0 * A[0, m]
            s += u1 * A[1, m]
            s += u2 * A[2, m]
            v = 0.0
            v += d0 * A[0, m] + u0 * dA[0, m]
            v += d1 * A[1, m] + u1 * dA[1, m]
            v += d2 * A[2, m] + u2 * dA[2, m]
            w = 0.0
            w += d0 * dA[0, m]
            w += d1 * dA[1, m]
            w += d2 * dA[2, m]
            X0[k, m] = s
            V[k, m] = v
            W[k, m] = w
            scale = max(scale, abs(s))
    return X0, V, W, scale


@njit(cache=True, error_model="numpy")
def body_room(x, dx, nodes, body, B, c0, start, room):
    """The largest multiple t of the step dx that keeps every node within ``room`` of
    its body-frame point ``start``: the least t > 0 with |W| t^2 + |V| t = room -
    |X0 - start| over the nodes (inf: none); -1 where a node is already beyond its room
    (``BodyContact._roomy``)."""
    X0, V, W, _ = body_paths(x, dx, nodes, body, B, c0)
    best = np.inf
    for k in range(nodes.shape[0]):
        e0, e1, e2 = X0[k, 0] - start[k, 0], X0[k, 1] - start[k, 1], X0[k, 2] - start[k, 2]
        r = room[k] - np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        if r <= 0.0:
            return -1.0
        b = np.sqrt(V[k, 0] * V[k, 0] + V[k, 1] * V[k, 1] + V[k, 2] * V[k, 2])
        a = np.sqrt(W[k, 0] * W[k, 0] + W[k, 1] * W[k, 1] + W[k, 2] * W[k, 2])
        below = b + np.sqrt(b * b + 4.0 * a * r)  # (the stable root's form)
        if below > 0.0:
            best = min(best, 2.0 * r / below)
    return best


@njit(cache=True, error_model="numpy")
def _ray(kind, geom, P, D, grow):
    """The first contact of the segments P + s D (s in [0, 1]) with the shape grown by
    ``grow`` (inf, or beyond 1: none)."""
    nodes = np.arange(P.shape[0])
    if kind == BOX:
        axes = geom[3:12].reshape(3, 3)
        return box_max_step(P, D, nodes, geom[0:3], axes, geom[12:15], geom[15] + grow, 1.0)
    return capsule_max_step(P, D, nodes, geom[0:3], geom[3:6], geom[6] + grow)


@njit(cache=True, error_model="numpy")
def _least_gap(kind, geom, Xc, Vc, Wc, t, Pc, low, n, P3):
    """The least gap of the candidates' paths at t (their points Pc moved there), the
    same number as the least of every gap: a gap is evaluated only where its bound in
    ``low`` does not exceed the least found so far. The bound is the gap last evaluated
    less how far the point has moved since (a distance to a shape, less a radius, grows
    no faster than its point moves) and 64 round-offs of its coordinates' and the
    shape's size; ``low`` keeps each gap evaluated and the others' bounds. (A node
    thrown at 9e18 m/s past a box: 60 pieces of 65 candidates in each of 11 500 caps,
    2 ms each; 0.2 ms now, the same caps.)"""
    m = Xc.shape[0]
    size = np.max(np.abs(geom))
    first = 0
    for j in range(m):
        moved = 0.0
        far = size
        for a in range(3):
            p = Xc[j, a] + t * Vc[j, a] + t * t * Wc[j, a]
            moved += (p - Pc[j, a]) ** 2
            far = max(far, abs(p), abs(Pc[j, a]))
            Pc[j, a] = p
        low[j] -= np.sqrt(moved) * (1.0 + 1e-9) + 64.0 * EPS * far
        if low[j] < low[first]:
            first = j
    low[first] = shape_feature(kind, Pc[first], geom, n, P3)  # the likeliest least
    best = min(np.inf, low[first])  # (a NaN gap is passed over, as min passed it over)
    for j in range(m):
        if j != first and not low[j] > best:
            low[j] = shape_feature(kind, Pc[j], geom, n, P3)
            best = min(best, low[j])
    return best


@njit(cache=True, error_model="numpy")
def body_step_cap(kind, geom, X0, V, W, scale, dhat, share, pieces, floor_share, roundoff,
                  slack, far):  # fmt: skip
    """The first contact of the paths X0 + t V + t^2 W (K, 3) with the shape (``kind``,
    ``geom``: ``catenet.kernels.shapes``) grown by the floor (FLOOR_SHARE dhat, at least
    ROUNDOFF round-offs of ``scale``, below the smallest gap by SLACK of it), over
    pieces whose chords stay within ``share`` of the smallest gap: a contact no later
    than the true one; inf where none comes before ``far``."""
    if not (np.any(V != 0.0) or np.any(W != 0.0)):
        return np.inf
    n = np.empty(3)
    P3 = np.empty((3, 3))
    K = X0.shape[0]
    gap = np.empty(K)
    g_min = np.inf
    for k in range(K):
        gap[k] = shape_feature(kind, X0[k], geom, n, P3)
        g_min = min(g_min, gap[k])
    floor = max(floor_share * dhat, roundoff * np.finfo(np.float64).eps * scale)
    floor = min(floor, (1.0 - slack) * g_min) if g_min > 0.0 else 0.0
    w = 0.0
    reach = np.empty(K)
    for k in range(K):
        wk = np.sqrt(W[k, 0] ** 2 + W[k, 1] ** 2 + W[k, 2] ** 2)
        vk = np.sqrt(V[k, 0] ** 2 + V[k, 1] ** 2 + V[k, 2] ** 2)
        w = max(w, wk)
        reach[k] = (vk * far + wk * far * far) if (vk > 0.0 or wk > 0.0) else 0.0
    take = np.empty(K, dtype=np.int64)
    m = 0
    for k in range(K):  # the candidates (module docstring)
        if not gap[k] > reach[k] + 0.5 * dhat + 2.0 * floor:
            take[m] = k
            m += 1
    if m == 0:
        return np.inf
    Xc = np.empty((m, 3))
    Vc = np.empty((m, 3))
    Wc = np.empty((m, 3))
    for j in range(m):
        for a in range(3):
            Xc[j, a] = X0[take[j], a]
            Vc[j, a] = V[take[j], a]
            Wc[j, a] = W[take[j], a]
    Pc = Xc.copy()
    D = np.empty((m, 3))
    low = np.empty(m)  # each candidate's gap at Pc, or a bound below it (_least_gap)
    for j in range(m):
        low[j] = gap[take[j]]
    t = 0.0
    for _ in range(pieces):
        g_c = _least_gap(kind, geom, Xc, Vc, Wc, t, Pc, low, n, P3)
        delta = min(share * (g_c - floor), 0.5 * dhat)
        if not delta > 0.0:  # a node at the floor already (or NaN): no safe advance
            return t
        h = min(max(1.0, t), far - t)  # pieces of the step, then doubling
        if w > 0.0:
            h = min(h, 2.0 * np.sqrt(delta / w))
        for j in range(m):
            for a in range(3):
                D[j, a] = h * Vc[j, a] + (2.0 * t * h + h * h) * Wc[j, a]
        s = _ray(kind, geom, Pc, D, 0.25 * w * h * h + floor)
        if s <= 1.0:
            return t + s * h
        t += h
        if t >= far:
            return np.inf
    return t
