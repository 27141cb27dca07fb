"""Twist of isotropic rods: discrete elastic rods (Bergou et al. 2008, 2010) with the
twist eliminated quasistatically.

A twisted rod segment is a chain of edges between two constraints on its twist (two
clamps, or a closed ring). Its tangents, in order, are t_1 .. t_n (the edges, current
lengths L_k) and, for an open segment, the clamps' held tangents T_0 before the first
edge and T_n+1 after the last, both along the chain ("phantom" edges that do not move).
Carry a unit vector D_A (normal to T_0) along the chain by discrete parallel transport
(the rotation about t_k-1 x t_k taking t_k-1 to t_k): the total twist of the segment's
material frame is the angle, about T_n+1, from the transported vector to the far
clamp's director D_B. With any unit frame a_k normal to each t_k (a_0 = D_A,
a_n+1 = D_B), that angle is the sum of the reference twists

    m_k = angle from P(t_k-1 -> t_k) a_k-1 to a_k, about t_k,

over the segment's vertices (a ring: over its n vertices, the last between t_n and t_1;
its sum is the holonomy of parallel transport around the ring). Whatever the frames,
the sum is the same function Theta(x) (mod 2 pi): the frames are kept from the last
accepted state (``twist_frames``: each m_k there Theta / V of the V vertices), so the
sum is continuous and never wraps. Its gradient does not depend on the frames: with
kb = 2 t1 x t2 / chi, chi = 1 + t1 . t2 (Bergou's curvature binormal),

    dm/de1 = kb / (2 L1),    dm/de2 = kb / (2 L2)

at each vertex (e1 = x_j - x_i, e2 = x_k - x_j; a phantom edge has no node), checked
against the parallel transport chain by finite differences. The Hessian of Theta is
the sum of the derivatives of those vectors, with c = t1 x t2, P_a = I - t_a t_a^T,
[v] the cross-product matrix:

    d(c / (chi L1))/de1 = -[t2] P1 / (chi L1^2) - c (P1 t2)^T / (chi^2 L1^2) - c t1^T / (chi L1^2)
    d(c / (chi L1))/de2 = [t1] P2 / (chi L1 L2) - c (P2 t1)^T / (chi^2 L1 L2)
    d(c / (chi L2))/de1 = -[t2] P1 / (chi L1 L2) - c (P1 t2)^T / (chi^2 L1 L2)
    d(c / (chi L2))/de2 = [t1] P2 / (chi L2^2) - c (P2 t1)^T / (chi^2 L2^2) - c t2^T / (chi L2^2)

(each vertex's share is not symmetric; the sum is, and is symmetrised).

With the twist uniform between the constraints (an isotropic rod: the per-edge twist
angles eliminated, Bergou 2008 sec. 4-5), the energy of a segment is

    E = (Theta(x) - Theta_0 + Phi)^2 / (2 C),    C = sum over its edges of l0 / GJ,

Theta_0 the value in the given geometry (the rod is untwisted as given), Phi the twist
the clamps impose; the twisting moment is M = (Theta - Theta_0 + Phi) / C along the whole
segment, grad E = M grad Theta and Hess E = grad Theta grad Theta^T / C + M Hess Theta: a
dense block over the segment's nodes. chi -> 0 (a 180-degree fold between two edges, or
an end edge turned against its clamp) makes kb infinite: the twist is undefined there,
and the energy is inf.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Below chi = 1 + t1 . t2 of this, two tangents are taken as folded: the twist is
#: undefined (energy inf).
FOLD = 1e-12


@njit(cache=True)
def _cross(a, b):
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def transport(u, v, w):
    """Parallel transport of w from the unit tangent u to v: the rotation about u x v
    that takes u to v (w + [b] w + [b]^2 w / (1 + u . v), b = u x v)."""
    b = _cross(u, v)
    bw = _cross(b, w)
    return w + bw + _cross(b, bw) / (1.0 + _dot(u, v))


@njit(cache=True)
def _turn(t, w, angle):
    """w (normal to the unit t) turned by ``angle`` about t, right-handed."""
    return np.cos(angle) * w + np.sin(angle) * _cross(t, w)


@njit(cache=True)
def _angle(a, b, t):
    """The signed angle from a to b about t."""
    return np.arctan2(_dot(_cross(a, b), t), _dot(a, b))


@njit(cache=True)
def _set_row(A, i, v):
    """A[i] = v for a 3-vector v (an array assigned to a row compiles slowly)."""
    for a in range(3):
        A[i, a] = v[a]


@njit(cache=True)
def _tangents(x, nodes, lo, hi, closed, head, tail, s):
    """The segment's tangent slots (V + 1, 3) and current lengths (0: a phantom edge)
    and each slot's edge nodes (V + 1, 2), -1 for a phantom: an open segment's slots are
    T_0, t_1 .. t_n, T_n+1 (V = n + 1 vertices), a ring's t_n, t_1 .. t_n (V = n)."""
    p = hi - lo
    n = p if closed[s] else p - 1
    slots = n + 1 if closed[s] else n + 2
    t = np.zeros((slots, 3))
    length = np.zeros(slots)
    ends = np.full((slots, 2), -1, dtype=np.int64)
    for k in range(n):
        a, b = nodes[lo + k], nodes[lo + (k + 1) % p]
        e = x[b] - x[a]
        ln = np.sqrt(_dot(e, e))
        r = k + 1
        _set_row(t, r, e / ln)
        length[r] = ln
        ends[r, 0], ends[r, 1] = lo + k, lo + (k + 1) % p
    if closed[s]:
        _set_row(t, 0, t[n])
        length[0] = length[n]
        ends[0, 0], ends[0, 1] = ends[n, 0], ends[n, 1]
    else:
        _set_row(t, 0, head[s])
        _set_row(t, n + 1, tail[s])
    return t, length, ends


@njit(cache=True)
def twist_frames(x, nodes, start, closed, head, tail, director, theta, ref, tau, first):
    """Writes each real edge's reference director ``ref`` and tangent ``tau`` at x: the
    director D_A (``director[s]``) carried along the chain and turned by theta / V per
    vertex, so that every reference twist there is theta[s] / V (``first[s]``: the
    segment's first edge row in ref and tau)."""
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        t, _, _ = _tangents(x, nodes, lo, hi, closed, head, tail, s)
        n = (hi - lo) if closed[s] else (hi - lo - 1)
        vertices = n if closed[s] else n + 1
        share = theta[s] / vertices
        if closed[s]:
            u = director[s] - _dot(director[s], t[1]) * t[1]
            u = u / np.sqrt(_dot(u, u))
        else:
            u = transport(t[0], t[1], director[s])
        for k in range(n):
            if k > 0:
                u = transport(t[k], t[k + 1], u)
            turns = k if closed[s] else k + 1
            _set_row(ref, first[s] + k, _turn(t[k + 1], u, turns * share))
            _set_row(tau, first[s] + k, t[k + 1])


@njit(cache=True)
def _frame(t, slot, n, closed, s, first, ref, tau, head_dir, tail_dir):
    """The frame of tangent slot ``slot`` at the current tangent t: a real edge's lagged
    director carried from its lagged tangent, a clamp's fixed director."""
    if not closed[s] and slot == 0:
        return head_dir[s]
    if not closed[s] and slot == n + 1:
        return tail_dir[s]
    k = (slot - 1) % n if slot > 0 else n - 1
    return transport(tau[first[s] + k], t, ref[first[s] + k])


@njit(cache=True)
def twist_angles(x, nodes, start, closed, head, tail, head_dir, tail_dir, ref, tau, first, out):
    """Theta of every segment at x (out, (S,)), from the frames ``ref``, ``tau``; inf where
    two tangents fold."""
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        t, _, _ = _tangents(x, nodes, lo, hi, closed, head, tail, s)
        n = (hi - lo) if closed[s] else (hi - lo - 1)
        vertices = n if closed[s] else n + 1
        total = 0.0
        for v in range(1, vertices + 1):
            t1, t2 = t[v - 1], t[v]
            if 1.0 + _dot(t1, t2) < FOLD:
                total = np.inf
                break
            a1 = _frame(t1, v - 1, n, closed, s, first, ref, tau, head_dir, tail_dir)
            a2 = _frame(t2, v, n, closed, s, first, ref, tau, head_dir, tail_dir)
            total += _angle(transport(t1, t2, a1), a2, t2)
        out[s] = total


@njit(cache=True)
def _add_edge(g, ends, slot, w):
    """Adds w as d/de of edge slot ``slot`` into g (3 p,): -w at its first node, +w at
    its second (local rows); nothing for a phantom edge."""
    a, b = ends[slot, 0], ends[slot, 1]
    if a < 0:
        return
    for c in range(3):
        g[3 * a + c] -= w[c]
        g[3 * b + c] += w[c]


@njit(cache=True)
def segment_gradient(x, nodes, lo, hi, closed, head, tail, s):
    """d Theta / dx of segment s over its local nodes (3 (hi - lo),), indices local."""
    t, length, ends = _tangents(x, nodes, lo, hi, closed, head, tail, s)
    ends = ends - lo
    n = (hi - lo) if closed[s] else (hi - lo - 1)
    vertices = n if closed[s] else n + 1
    g = np.zeros(3 * (hi - lo))
    for v in range(1, vertices + 1):
        t1, t2 = t[v - 1], t[v]
        kb = _cross(t1, t2) / (1.0 + _dot(t1, t2))  # kb / 2
        if length[v - 1] > 0.0 and ends[v - 1, 0] >= 0:
            _add_edge(g, ends, v - 1, kb / length[v - 1])
        if length[v] > 0.0 and ends[v, 0] >= 0:
            _add_edge(g, ends, v, kb / length[v])
    return g


@njit(cache=True)
def _skew(v):
    out = np.zeros((3, 3))
    out[0, 1], out[0, 2] = -v[2], v[1]
    out[1, 0], out[1, 2] = v[2], -v[0]
    out[2, 0], out[2, 1] = -v[1], v[0]
    return out


@njit(cache=True)
def _vertex_blocks(t1, t2, l1, l2):
    """d(c / (chi L_p)) / de_q for p, q in 1, 2 (module docstring), as (2, 2, 3, 3).
    Written out entry by entry (no small NumPy products: they compile slowly and call
    BLAS for 3 x 3): with c = t1 x t2, skew(t2) (I - t1 t1^T) = skew(t2) + c t1^T and
    skew(t1) (I - t2 t2^T) = skew(t1) - c t2^T."""
    d = _dot(t1, t2)
    chi = 1.0 + d
    c = _cross(t1, t2)
    k1, k2 = _skew(t1), _skew(t2)
    out = np.zeros((2, 2, 3, 3))
    for a in range(3):
        for b in range(3):
            s1 = k2[a, b] + c[a] * t1[b]  # skew(t2) p1
            s2 = k1[a, b] - c[a] * t2[b]  # skew(t1) p2
            q1 = c[a] * (t2[b] - t1[b] * d) / (chi * chi)  # c (p1 t2)^T / chi^2
            q2 = c[a] * (t1[b] - t2[b] * d) / (chi * chi)  # c (p2 t1)^T / chi^2
            if l1 > 0.0:
                out[0, 0, a, b] = (-s1 / chi - q1 - c[a] * t1[b] / chi) / (l1 * l1)
            if l2 > 0.0:
                out[1, 1, a, b] = (s2 / chi - q2 - c[a] * t2[b] / chi) / (l2 * l2)
            if l1 > 0.0 and l2 > 0.0:
                out[0, 1, a, b] = (s2 / chi - q2) / (l1 * l2)
                out[1, 0, a, b] = (-s1 / chi - q1) / (l1 * l2)
    return out


@njit(cache=True)
def segment_hessian(x, nodes, lo, hi, closed, head, tail, s, scale, out, base):
    """Adds scale Hess Theta of segment s, symmetrised, into out[base:] (its dense
    (3 p)^2 block, row-major over local DOFs): each vertex's blocks (not symmetric by
    themselves) and their transposes, halved."""
    t, length, ends = _tangents(x, nodes, lo, hi, closed, head, tail, s)
    ends = ends - lo
    size = 3 * (hi - lo)
    n = (hi - lo) if closed[s] else (hi - lo - 1)
    vertices = n if closed[s] else n + 1
    half = 0.5 * scale
    for v in range(1, vertices + 1):
        blocks = _vertex_blocks(t[v - 1], t[v], length[v - 1], length[v])
        for p in range(2):
            sp = v - 1 + p
            if ends[sp, 0] < 0 or length[sp] == 0.0:
                continue
            for q in range(2):
                sq = v - 1 + q
                if ends[sq, 0] < 0 or length[sq] == 0.0:
                    continue
                for i_end in range(2):
                    ri = 3 * ends[sp, i_end]
                    si = -1.0 if i_end == 0 else 1.0
                    for j_end in range(2):
                        cj = 3 * ends[sq, j_end]
                        sj = -1.0 if j_end == 0 else 1.0
                        for a in range(3):
                            for b in range(3):
                                value = half * si * sj * blocks[p, q, a, b]
                                out[base + (ri + a) * size + cj + b] += value
                                out[base + (cj + b) * size + ri + a] += value


@njit(cache=True)
def twist_gradient(x, nodes, start, closed, head, tail, moment, grad):
    """Adds M_s d Theta_s / dx of every segment into grad (N, 3)."""
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        g = segment_gradient(x, nodes, lo, hi, closed, head, tail, s)
        for p in range(hi - lo):
            node = nodes[lo + p]
            for c in range(3):
                grad[node, c] += moment[s] * g[3 * p + c]


@njit(cache=True)
def twist_hessian(x, nodes, start, closed, head, tail, moment, compliance, values):
    """Writes every segment's dense block (3 p)^2, row-major over its local DOFs:
    g g^T / C + M Hess Theta (symmetrised)."""
    base = np.int64(0)
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        size = 3 * (hi - lo)
        g = segment_gradient(x, nodes, lo, hi, closed, head, tail, s)
        for r in range(size):
            gr = g[r] / compliance[s]
            row = base + r * size
            for c in range(size):
                values[row + c] = gr * g[c]
        segment_hessian(x, nodes, lo, hi, closed, head, tail, s, moment[s], values, base)
        base += size * size


@njit(cache=True)
def vertex_gradients(x, nodes, start, closed, head, tail, held, slot_c):
    """Per vertex of every chain, the gradient of its reference twist m_v (the
    un-eliminated twist, ``catenet.model.torsion``): (V,) the vertex's compliance c_v =
    (c_a + c_b) / 2 of its two edge slots a, b (``slot_c``: each chain edge row's l0 / GJ,
    a clamp's phantom slot 0); (V, 3) the nodes of its gradient (the first edge's first
    node, the shared node, the second edge's last node; -1: a phantom edge's);
    (V, 3, 3) dm_v / dx at those nodes (kb / (2 L) per edge, module docstring); (V, 2)
    the chain edge rows of its slots a, b (-1: a clamp). An open chain has the vertex at
    a clamped end (``held[s, 0]``, ``held[s, 1]``: head, tail) and none at a free end."""
    count = 0
    for s in range(len(start) - 1):
        n = (start[s + 1] - start[s]) - (0 if closed[s] else 1)
        count += n if closed[s] else n - 1 + int(held[s, 0]) + int(held[s, 1])
    comp = np.zeros(count)
    who = np.full((count, 3), -1, dtype=np.int64)
    grad = np.zeros((count, 3, 3))
    rows = np.full((count, 2), -1, dtype=np.int64)
    out = 0
    row0 = 0
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        t, length, ends = _tangents(x, nodes, lo, hi, closed, head, tail, s)
        n = (hi - lo) if closed[s] else (hi - lo - 1)
        first_v = 1 if closed[s] or held[s, 0] else 2
        last_v = n if closed[s] else (n + 1 if held[s, 1] else n)
        for v in range(first_v, last_v + 1):
            kb = _cross(t[v - 1], t[v]) / (1.0 + _dot(t[v - 1], t[v]))  # kb / 2
            c = 0.0
            for side in range(2):
                slot = v - 1 + side
                if ends[slot, 0] < 0:
                    continue  # a clamp's phantom edge
                k = (slot - 1) % n if slot > 0 else n - 1
                rows[out, side] = row0 + k
                c += 0.5 * slot_c[row0 + k]
                w = kb / length[slot]
                a, b = nodes[ends[slot, 0]], nodes[ends[slot, 1]]
                # the first edge's nodes are slots 0, 1 of the triple; the second's 1, 2
                who[out, side] = a
                who[out, side + 1] = b
                for d in range(3):
                    grad[out, side, d] -= w[d]
                    grad[out, side + 1, d] += w[d]
            comp[out] = c
            out += 1
        row0 += n
    return comp, who, grad, rows
