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

An open segment's end on a rigid joint (``partner`` >= 0, ``catenet.model.twist``) has
no vertex of its own: its phantom slot takes the end edge's tangent t and the joint's
director D(x) (``catenet.kernels.joint_twist``: the unit part n of the partner's edge b
normal to t, turned by phi0), so its reference twist there turns with n about t, at the
rate
d psi = t . (n x dn): with a the end edge (along the chain), w = t x b and
q = |b|^2 - (b . t)^2,

    d psi / db = w / q,    d psi / da = -(b . t) w / (|a| q)

(``psi_gradient``; the partner's node joins the segment's local nodes, after its chain's),
which adds to d Theta with sign -1 at the head (the turns start from its director) and +1
at the tail; ``psi_jacobian`` differentiates it once more for the Hessian. q -> 0 (the
partner turned onto the rod's axis) leaves the director undefined: the energy is inf.

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

from catenet.kernels.joint_twist import cross, dot, joint_director, psi_gradient, psi_jacobian, skew

#: Below chi = 1 + t1 . t2 of this, two tangents are taken as folded: the twist is
#: undefined (energy inf).
FOLD = 1e-12


@njit(cache=True)
def transport(u, v, w):
    """Parallel transport of w from the unit tangent u to v: the rotation about u x v
    that takes u to v (w + [b] w + [b]^2 w / (1 + u . v), b = u x v)."""
    b = cross(u, v)
    bw = cross(b, w)
    return w + bw + cross(b, bw) / (1.0 + dot(u, v))


@njit(cache=True)
def _turn(t, w, angle):
    """w (normal to the unit t) turned by ``angle`` about t, right-handed."""
    return np.cos(angle) * w + np.sin(angle) * cross(t, w)


@njit(cache=True)
def _angle(a, b, t):
    """The signed angle from a to b about t."""
    return np.arctan2(dot(cross(a, b), t), dot(a, b))


@njit(cache=True)
def _set_row(A, i, v):
    """A[i] = v for a 3-vector v (an array assigned to a row compiles slowly)."""
    for a in range(3):
        A[i, a] = v[a]


@njit(cache=True)
def _tangents(x, nodes, lo, hi, closed, head, tail, s, partner):
    """The segment's tangent slots (V + 1, 3) and current lengths (0: a phantom edge)
    and each slot's edge nodes (V + 1, 2), -1 for a phantom: an open segment's slots are
    T_0, t_1 .. t_n, T_n+1 (V = n + 1 vertices), a ring's t_n, t_1 .. t_n (V = n). At an
    end on a rigid joint (``partner`` >= 0) the phantom's tangent is its end edge's own."""
    p = hi - lo
    n = p if closed[s] else p - 1
    slots = n + 1 if closed[s] else n + 2
    t = np.zeros((slots, 3))
    length = np.zeros(slots)
    ends = np.full((slots, 2), -1, dtype=np.int64)
    for k in range(n):
        a, b = nodes[lo + k], nodes[lo + (k + 1) % p]
        e = x[b] - x[a]
        ln = np.sqrt(dot(e, e))
        r = k + 1
        _set_row(t, r, e / ln)
        length[r] = ln
        ends[r, 0], ends[r, 1] = lo + k, lo + (k + 1) % p
    if closed[s]:
        _set_row(t, 0, t[n])
        length[0] = length[n]
        ends[0, 0], ends[0, 1] = ends[n, 0], ends[n, 1]
    else:
        _set_row(t, 0, head[s] if partner[s, 0] < 0 else t[1])
        _set_row(t, n + 1, tail[s] if partner[s, 1] < 0 else t[n])
    return t, length, ends


@njit(cache=True)
def _end_directors(x, nodes, lo, hi, s, t, n, head_dir, tail_dir, partner, phase):
    """An open segment's directors at its head and tail: a clamp's fixed one, a rigid
    joint's at x (``catenet.kernels.joint_twist.joint_director``)."""
    hd = head_dir[s]
    td = tail_dir[s]
    if partner[s, 0] >= 0:
        hd = joint_director(x, nodes[lo], partner[s, 0], t[1], phase[s, 0])
    if partner[s, 1] >= 0:
        td = joint_director(x, nodes[hi - 1], partner[s, 1], t[n], phase[s, 1])
    return hd, td


@njit(cache=True)
def _extras(partner, s, p):
    """A segment's local nodes beyond its chain's p: (how many, the head partner's local
    index, the tail partner's; -1: none)."""
    count = 0
    head = -1
    tail = -1
    if partner[s, 0] >= 0:
        head = p
        count += 1
    if partner[s, 1] >= 0:
        tail = p + count
        count += 1
    return count, head, tail


@njit(cache=True)
def twist_frames(
    x, nodes, start, closed, head, tail, director, theta, ref, tau, first, partner, phase
):
    """Writes each real edge's reference director ``ref`` and tangent ``tau`` at x: the
    director D_A (``director[s]``, a rigid joint's at x) carried along the chain and
    turned by theta / V per vertex, so that every reference twist there is theta[s] / V
    (``first[s]``: the segment's first edge row in ref and tau)."""
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        t, _, _ = _tangents(x, nodes, lo, hi, closed, head, tail, s, partner)
        n = (hi - lo) if closed[s] else (hi - lo - 1)
        vertices = n if closed[s] else n + 1
        share = theta[s] / vertices
        if closed[s]:
            u = director[s] - dot(director[s], t[1]) * t[1]
            u = u / np.sqrt(dot(u, u))
        else:
            d = director[s]
            if partner[s, 0] >= 0:
                d = joint_director(x, nodes[lo], partner[s, 0], t[1], phase[s, 0])
            u = transport(t[0], t[1], d)
        for k in range(n):
            if k > 0:
                u = transport(t[k], t[k + 1], u)
            turns = k if closed[s] else k + 1
            _set_row(ref, first[s] + k, _turn(t[k + 1], u, turns * share))
            _set_row(tau, first[s] + k, t[k + 1])


@njit(cache=True)
def _frame(t, slot, n, closed, s, first, ref, tau, hd, td):
    """The frame of tangent slot ``slot`` at the current tangent t: a real edge's lagged
    director carried from its lagged tangent, the head's or tail's director hd, td."""
    if not closed[s] and slot == 0:
        return hd
    if not closed[s] and slot == n + 1:
        return td
    k = (slot - 1) % n if slot > 0 else n - 1
    return transport(tau[first[s] + k], t, ref[first[s] + k])


@njit(cache=True)
def twist_angles(
    x, nodes, start, closed, head, tail, head_dir, tail_dir, ref, tau, first, partner, phase, out
):
    """Theta of every segment at x (out, (S,)), from the frames ``ref``, ``tau``; inf where
    two tangents fold (or a rigid joint's partner lies along the rod)."""
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        t, _, _ = _tangents(x, nodes, lo, hi, closed, head, tail, s, partner)
        n = (hi - lo) if closed[s] else (hi - lo - 1)
        vertices = n if closed[s] else n + 1
        hd, td = head_dir[s], tail_dir[s]
        if not closed[s]:
            hd, td = _end_directors(x, nodes, lo, hi, s, t, n, head_dir, tail_dir, partner, phase)
        total = 0.0
        for v in range(1, vertices + 1):
            t1, t2 = t[v - 1], t[v]
            if 1.0 + dot(t1, t2) < FOLD:
                total = np.inf
                break
            a1 = _frame(t1, v - 1, n, closed, s, first, ref, tau, hd, td)
            a2 = _frame(t2, v, n, closed, s, first, ref, tau, hd, td)
            total += _angle(transport(t1, t2, a1), a2, t2)
        out[s] = total if np.isfinite(total) else np.inf


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
def _joint_end(x, nodes, lo, hi, partner, s, end, extra):
    """A segment end on a rigid joint (``end`` 0: head, 1: tail): its sign in Theta (the
    head's director is where the turns start: -1, the tail's +1), the local nodes of its
    end edge a (along the chain) and of the partner's edge b (from the joint node), and
    a, b at x."""
    p = hi - lo
    if end == 0:
        a0, a1, j = 0, 1, 0
        sign = -1.0
    else:
        a0, a1, j = p - 2, p - 1, p - 1
        sign = 1.0
    a = x[nodes[lo + a1]] - x[nodes[lo + a0]]
    b = x[partner[s, end]] - x[nodes[lo + j]]
    return sign, a0, a1, j, extra, a, b


@njit(cache=True)
def segment_gradient(x, nodes, lo, hi, closed, head, tail, s, partner):
    """d Theta / dx of segment s over its local nodes (3 (hi - lo + its joints'
    partners),), indices local: its chain's nodes, then a head's partner, a tail's."""
    t, length, ends = _tangents(x, nodes, lo, hi, closed, head, tail, s, partner)
    ends = ends - lo
    n = (hi - lo) if closed[s] else (hi - lo - 1)
    vertices = n if closed[s] else n + 1
    count, head_at, tail_at = _extras(partner, s, hi - lo)
    g = np.zeros(3 * (hi - lo + count))
    for v in range(1, vertices + 1):
        t1, t2 = t[v - 1], t[v]
        kb = cross(t1, t2) / (1.0 + dot(t1, t2))  # kb / 2
        if length[v - 1] > 0.0 and ends[v - 1, 0] >= 0:
            _add_edge(g, ends, v - 1, kb / length[v - 1])
        if length[v] > 0.0 and ends[v, 0] >= 0:
            _add_edge(g, ends, v, kb / length[v])
    for end in range(2):
        extra = head_at if end == 0 else tail_at
        if extra < 0 or closed[s]:
            continue
        sign, a0, a1, j, o, a, b = _joint_end(x, nodes, lo, hi, partner, s, end, extra)
        ga, gb = psi_gradient(a, b)
        for c in range(3):
            g[3 * a1 + c] += sign * ga[c]
            g[3 * a0 + c] -= sign * ga[c]
            g[3 * o + c] += sign * gb[c]
            g[3 * j + c] -= sign * gb[c]
    return g


@njit(cache=True)
def _vertex_blocks(t1, t2, l1, l2):
    """d(c / (chi L_p)) / de_q for p, q in 1, 2 (module docstring), as (2, 2, 3, 3).
    Written out entry by entry (no small NumPy products: they compile slowly and call
    BLAS for 3 x 3): with c = t1 x t2, skew(t2) (I - t1 t1^T) = skew(t2) + c t1^T and
    skew(t1) (I - t2 t2^T) = skew(t1) - c t2^T."""
    d = dot(t1, t2)
    chi = 1.0 + d
    c = cross(t1, t2)
    k1, k2 = skew(t1), skew(t2)
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
def segment_hessian(x, nodes, lo, hi, closed, head, tail, s, partner, scale, out, base):
    """Adds scale Hess Theta of segment s, symmetrised, into out[base:] (its dense
    (3 p)^2 block, row-major over local DOFs, ``segment_gradient``'s): each vertex's
    blocks and a rigid joint end's (``psi_jacobian``; not symmetric by themselves) and
    their transposes, halved."""
    t, length, ends = _tangents(x, nodes, lo, hi, closed, head, tail, s, partner)
    ends = ends - lo
    count, head_at, tail_at = _extras(partner, s, hi - lo)
    size = 3 * (hi - lo + count)
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
                _add_block(out, base, size, ends[sp], ends[sq], blocks[p, q], half)
    pair = np.empty((2, 2), dtype=np.int64)
    for end in range(2):
        extra = head_at if end == 0 else tail_at
        if extra < 0 or closed[s]:
            continue
        sign, a0, a1, j, o, a, b = _joint_end(x, nodes, lo, hi, partner, s, end, extra)
        blocks = psi_jacobian(a, b)
        pair[0, 0], pair[0, 1], pair[1, 0], pair[1, 1] = a0, a1, j, o
        for p in range(2):
            for q in range(2):
                _add_block(out, base, size, pair[p], pair[q], blocks[p, q], half * sign)


@njit(cache=True)
def _add_block(out, base, size, ep, eq, block, half):
    """Adds half (block + its transpose) of d(d/de_p)/de_q, the edges' local nodes ep, eq
    (first, second: -, +), into the dense block at out[base:]."""
    for i_end in range(2):
        ri = 3 * ep[i_end]
        si = -1.0 if i_end == 0 else 1.0
        for j_end in range(2):
            cj = 3 * eq[j_end]
            sj = -1.0 if j_end == 0 else 1.0
            for a in range(3):
                for b in range(3):
                    value = half * si * sj * block[a, b]
                    out[base + (ri + a) * size + cj + b] += value
                    out[base + (cj + b) * size + ri + a] += value


@njit(cache=True)
def _local_node(nodes, lo, hi, partner, s, k):
    """The net's node of local node k of segment s (``segment_gradient``)."""
    p = hi - lo
    if k < p:
        return nodes[lo + k]
    if k == p and partner[s, 0] >= 0:
        return partner[s, 0]
    return partner[s, 1]


@njit(cache=True)
def twist_gradient(x, nodes, start, closed, head, tail, partner, moment, grad):
    """Adds M_s d Theta_s / dx of every segment into grad (N, 3)."""
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        g = segment_gradient(x, nodes, lo, hi, closed, head, tail, s, partner)
        for k in range(len(g) // 3):
            node = _local_node(nodes, lo, hi, partner, s, k)
            for c in range(3):
                grad[node, c] += moment[s] * g[3 * k + c]


@njit(cache=True)
def twist_hessian(x, nodes, start, closed, head, tail, partner, moment, compliance, values):
    """Writes every segment's dense block (3 p)^2, row-major over its local DOFs:
    g g^T / C + M Hess Theta (symmetrised)."""
    base = np.int64(0)
    for s in range(len(start) - 1):
        lo, hi = start[s], start[s + 1]
        g = segment_gradient(x, nodes, lo, hi, closed, head, tail, s, partner)
        size = len(g)
        for r in range(size):
            gr = g[r] / compliance[s]
            row = base + r * size
            for c in range(size):
                values[row + c] = gr * g[c]
        segment_hessian(x, nodes, lo, hi, closed, head, tail, s, partner, moment[s], values, base)
        base += size * size


@njit(cache=True)
def vertex_gradients(x, nodes, start, closed, head, tail, held, slot_c, partner, end_c):
    """Per vertex of every chain, the gradient of its reference twist m_v (the
    un-eliminated twist, ``catenet.model.torsion``): (V,) the vertex's compliance c_v =
    (c_a + c_b) / 2 of its two edge slots a, b (``slot_c``: each chain edge row's l0 / GJ,
    a clamp's phantom slot 0); (V, 3) the nodes of its gradient (the first edge's first
    node, the shared node, the second edge's last node; -1: a phantom edge's);
    (V, 3, 3) dm_v / dx at those nodes (kb / (2 L) per edge, module docstring); (V, 2)
    the chain edge rows of its slots a, b (-1: a clamp). An open chain has the vertex at
    a clamped end (``held[s, 0]``, ``held[s, 1]``: head, tail) and none at a free end.
    At an end on a rigid joint (``partner`` >= 0) the phantom edge's node is the
    partner's and the joint's director turns the vertex (``psi_gradient``); ``end_c``
    (S, 2) adds to an end vertex's compliance (a joint partner's half edge, a 6x6
    spring's twist, in series)."""
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
        t, length, ends = _tangents(x, nodes, lo, hi, closed, head, tail, s, partner)
        n = (hi - lo) if closed[s] else (hi - lo - 1)
        first_v = 1 if closed[s] or held[s, 0] else 2
        last_v = n if closed[s] else (n + 1 if held[s, 1] else n)
        for v in range(first_v, last_v + 1):
            kb = cross(t[v - 1], t[v]) / (1.0 + dot(t[v - 1], t[v]))  # kb / 2
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
            end = 0 if v == 1 else 1
            if not closed[s] and (v == 1 or v == n + 1):
                c += end_c[s, end]  # a joint's partner's half edge, a spring's twist
            if not closed[s] and (v == 1 or v == n + 1) and partner[s, end] >= 0:
                if end == 0:  # the triple: partner, joint node, the end edge's other
                    a = x[nodes[lo + 1]] - x[nodes[lo]]
                    b = x[partner[s, 0]] - x[nodes[lo]]
                    ga, gb = psi_gradient(a, b)
                    who[out, 0] = partner[s, 0]
                    for d in range(3):
                        grad[out, 0, d] -= gb[d]
                        grad[out, 1, d] += ga[d] + gb[d]
                        grad[out, 2, d] -= ga[d]
                else:  # the end edge's other, joint node, partner
                    a = x[nodes[hi - 1]] - x[nodes[hi - 2]]
                    b = x[partner[s, 1]] - x[nodes[hi - 1]]
                    ga, gb = psi_gradient(a, b)
                    who[out, 2] = partner[s, 1]
                    for d in range(3):
                        grad[out, 0, d] -= ga[d]
                        grad[out, 1, d] += ga[d] - gb[d]
                        grad[out, 2, d] += gb[d]
            comp[out] = c
            out += 1
        row0 += n
    return comp, who, grad, rows
