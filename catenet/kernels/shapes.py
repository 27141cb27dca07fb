"""Barrier contact of nodes with a box, a capsule and a closed triangle mesh.

Every kind uses the log-barrier b(d) of ``catenet.kernels.contact`` on the node's gap d,
its distance to the obstacle's surface (d <= 0 inside: infinite energy). The gap of each
kind is the distance to the nearest point p of the surface, with n = (x - p) / d its unit
gradient, so the energy kappa b(d) has the gradient kappa b'(d) n and the Hessian

    kappa (b''(d) n n^T + b'(d) hess d),   hess d = (P - n n^T) / d,

where P projects on the directions in which the nearest point moves with x: none on a
flat face (P = n n^T: hess d = 0), the plane across an edge or a cylinder axis
(P = I - e e^T), every direction at a vertex or a ball (P = I).

Smoothness: outside a convex body (box, capsule) the distance is C1 and its Hessian
jumps where the nearest feature changes (face to edge to vertex): the energy is C1 with
a piecewise-continuous Hessian. Newton copes: the jump is bounded (b'(d)/d times a
projection), it only occurs inside the thin active layer d < dhat, and the line search
works on the continuous energy and gradient. For a mesh the distance is that to the
nearest triangle; outside a non-convex mesh it has kinks (the medial axis) where two
parts of the surface are equally near, which the line search also handles.

Each kind's ``max_step`` is the exact first contact along x + t dx (t in (0, inf)): a
slab test for the box, the first root over the lateral cylinder and the two end balls
for the capsule, and a ray-triangle test over the cells of a uniform grid that the ray
crosses for the mesh (barycentric tolerance 1e-9: a ray grazing an edge counts as a hit,
which is conservative). The line search never tries a step at or beyond it.

Offset surfaces (a rigid ball's centre against a shape, ``catenet.terms.collide``): the
gap is g = d - r, the centre's distance to the shape minus the ball's radius r, i.e. the
distance to the Minkowski sum of the shape and the ball. The Hessian is then
kappa (b''(g) n n^T + b'(g) (P - n n^T) / d), the curvature still over the true distance d
(``_fold`` writes P so that the shared ``_block`` divides by d, not g). A capsule grows its
radius. The box's first contact is the exact entry of the ray into the rounded box: the
union of the box with its faces moved out by r along each axis (three slabs), and of the
12 capsules of radius r on its edges (their end balls are the 8 corner balls).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.contact import ball_root, barrier

# --------------------------------------------------------------------------- shared


@njit(cache=True, error_model="numpy")
def _block(values, k, kappa, db, ddb, d, n, P):
    """values[9k:9k+9] = kappa (b'' n n^T + b' (P - n n^T) / d) for the feature's P."""
    for a in range(3):
        for c in range(3):
            values[9 * k + 3 * a + c] = kappa * (
                ddb * n[a] * n[c] + db * (P[a, c] - n[a] * n[c]) / d
            )


@njit(cache=True, error_model="numpy")
def _zero_block(values, k):
    for a in range(9):
        values[9 * k + a] = 0.0


@njit(cache=True, error_model="numpy")
def _ball_root(x, dx, center, radius):
    """The first t >= 0 with |x + t dx - c| = R (inf: never, or moving away)."""
    u = (x[0] - center[0], x[1] - center[1], x[2] - center[2])
    return ball_root(u, (dx[0], dx[1], dx[2]), radius)


@njit(cache=True, error_model="numpy")
def _fold(P, n, f):
    """P := f (P - n n^T) + n n^T: the shared ``_block`` divides the curvature by the gap
    g; with f = g / d it is divided by the distance d whose Hessian it is."""
    for j in range(3):
        for c in range(3):
            P[j, c] = f * (P[j, c] - n[j] * n[c]) + n[j] * n[c]


# --------------------------------------------------------------------------- box


@njit(cache=True, error_model="numpy")
def box_feature(x, geom, n, P):
    """Signed distance of point x to the box ``geom`` (packed as BOX says: centre, axes
    as columns of the row-major 3x3, half sizes); fills n (outward unit gradient, world)
    and P (the projection of the nearest feature, world) when outside. Returns
    max(|q| - h) <= 0 inside. Scalars only: called per node, the arrays and views it
    made per call cost more than the distance itself."""
    c0, c1, c2 = geom[0], geom[1], geom[2]
    rows = ((geom[3], geom[4], geom[5]), (geom[6], geom[7], geom[8]), (geom[9], geom[10], geom[11]))
    x0, x1, x2 = x[0], x[1], x[2]
    inside = -np.inf
    y0, y1, y2 = x0 - c0, x1 - c1, x2 - c2
    u0, o0, inside = _box_axis(y0, y1, y2, geom[3], geom[6], geom[9], geom[12], inside)
    u1, o1, inside = _box_axis(y0, y1, y2, geom[4], geom[7], geom[10], geom[13], inside)
    u2, o2, inside = _box_axis(y0, y1, y2, geom[5], geom[8], geom[11], geom[14], inside)
    if inside <= 0.0:
        return inside
    d = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    for j in range(3):
        a0, a1, a2 = rows[j]
        n[j] = (a0 * u0 + a1 * u1 + a2 * u2) / d
        for c in range(3):
            b0, b1, b2 = rows[c]
            P[j, c] = a0 * o0 * b0 + a1 * o1 * b1 + a2 * o2 * b2
    return d


@njit(cache=True, error_model="numpy", inline="always")
def _box_axis(y0, y1, y2, a0, a1, a2, half, inside):
    """Along the box's axis (a0, a1, a2), of the point y from the centre: its signed
    excess beyond the face (0 within the slab), 1.0 where it is beyond, and the largest
    |q_a| - h_a so far (``inside``)."""
    s = a0 * y0 + a1 * y1 + a2 * y2
    e = abs(s) - half
    inside = max(inside, e)
    if e > 0.0:
        return (e if s > 0.0 else -e), 1.0, inside
    return 0.0, 0.0, inside


@njit(cache=True, error_model="numpy")
def _slab_entry(q, v, half):
    """The first t >= 0 at which q + t v is in the box |q_a| <= half_a (box frame; inf:
    never): the slab test."""
    enter = -np.inf
    leave = np.inf
    for a in range(3):
        if v[a] == 0.0:
            if abs(q[a]) > half[a]:
                return np.inf
            continue
        t1 = (-half[a] - q[a]) / v[a]
        t2 = (half[a] - q[a]) / v[a]
        enter = max(enter, min(t1, t2))
        leave = min(leave, max(t1, t2))
    if enter > leave or leave < 0.0:
        return np.inf
    return max(enter, 0.0)


@njit(cache=True, error_model="numpy")
def _rounded_entry(q, v, half, r):
    """The first t >= 0 at which q + t v is within r of the box (box frame): the first
    entry into the three slabs grown by r along one axis and the 12 edge capsules."""
    t = np.inf
    grown = np.empty(3)
    p0 = np.empty(3)
    p1 = np.empty(3)
    for a in range(3):
        for j in range(3):
            grown[j] = half[j] + (r if j == a else 0.0)
        t = min(t, _slab_entry(q, v, grown))
        b, c = (a + 1) % 3, (a + 2) % 3
        for sb in (-1.0, 1.0):
            for sc in (-1.0, 1.0):
                p0[a] = -half[a]
                p1[a] = half[a]
                p0[b] = sb * half[b]
                p1[b] = sb * half[b]
                p0[c] = sc * half[c]
                p1[c] = sc * half[c]
                t = min(t, capsule_entry(q, v, p0, p1, r))
    return t


@njit(cache=True, error_model="numpy")
def box_max_step(x, dx, nodes, center, axes, half, offset, upto=np.inf):
    """The largest t with every node outside the box (grown by ``offset``: the rounded
    box) along x + t dx: the first entry of each node's line (inf if none); a node whose
    path up to t = ``upto`` clears the box's bounds is not tested (its entry, if any,
    comes later: the result is exact up to ``upto``)."""
    t_max = np.inf
    q = np.empty(3)
    v = np.empty(3)
    for k in range(nodes.shape[0]):
        i = nodes[k]
        for a in range(3):
            q[a] = 0.0
            v[a] = 0.0
            for j in range(3):
                q[a] += axes[j, a] * (x[i, j] - center[j])
                v[a] += axes[j, a] * dx[i, j]
        if _misses(q, v, half, offset, upto):
            continue  # the segment's bounds clear the box grown by offset on every side
        if offset > 0.0:
            t = _rounded_entry(q, v, half, offset)
        else:
            t = _slab_entry(q, v, half)
        t_max = min(t_max, t)
    return t_max


@njit(cache=True, error_model="numpy")
def _misses(q, v, half, r, upto):
    """Whether the path q + t v, t in [0, upto], stays on one axis outside the box grown
    by r along every axis (which holds the box rounded by r): it cannot touch it."""
    for a in range(3):
        end = q[a] + upto * v[a] if v[a] != 0.0 else q[a]  # (inf * 0 is NaN)
        lo = min(q[a], end)
        hi = max(q[a], end)
        if lo > half[a] + r or hi < -half[a] - r:
            return True
    return False


# --------------------------------------------------------------------------- capsule


@njit(cache=True, error_model="numpy")
def capsule_feature(x, geom, n, P):
    """Signed distance of x to the capsule ``geom`` (packed as CAPSULE says: ends a and
    b, radius); fills n and P (scalars and indices only, as ``box_feature``)."""
    w0, w1, w2 = geom[3] - geom[0], geom[4] - geom[1], geom[5] - geom[2]
    ww = w0 * w0 + w1 * w1 + w2 * w2
    s = ((x[0] - geom[0]) * w0 + (x[1] - geom[1]) * w1 + (x[2] - geom[2]) * w2) / ww
    middle = 0.0 < s < 1.0
    s = min(max(s, 0.0), 1.0)
    n[0] = x[0] - geom[0] - s * w0
    n[1] = x[1] - geom[1] - s * w1
    n[2] = x[2] - geom[2] - s * w2
    rho = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    d = rho - geom[6]
    if d <= 0.0 or rho == 0.0:
        return d
    for j in range(3):
        n[j] /= rho
    w = (w0, w1, w2)
    for j in range(3):
        for c in range(3):
            P[j, c] = (1.0 if j == c else 0.0) - (w[j] * w[c] / ww if middle else 0.0)
    _fold(P, n, d / rho)  # hess d = (P - n n^T) / rho, not / d
    return d


@njit(cache=True, error_model="numpy")
def capsule_entry(x, v, a, b, radius):
    """The first t >= 0 at which x + t v is in the capsule (segment a-b, radius): the
    first of the entries into the two end balls and through the lateral surface of the
    cylinder between them (the capsule is their union; inf if none)."""
    t = min(_ball_root(x, v, a, radius), _ball_root(x, v, b, radius))
    ww = 0.0
    ys = 0.0
    vs = 0.0
    for j in range(3):
        w = b[j] - a[j]
        ww += w * w
        ys += (x[j] - a[j]) * w
        vs += v[j] * w
    A = 0.0
    B = 0.0
    C = -radius * radius
    for j in range(3):
        w = b[j] - a[j]
        y = x[j] - a[j] - ys / ww * w
        u = v[j] - vs / ww * w
        A += u * u
        B += 2.0 * y * u
        C += y * y
    if A > 0.0 and B < 0.0 and C > 0.0:
        disc = B * B - 4.0 * A * C
        if disc >= 0.0:
            tc = (-B - np.sqrt(disc)) / (2.0 * A)
            s = (ys + tc * vs) / ww
            if 0.0 <= s <= 1.0:
                t = min(t, tc)
    return t


@njit(cache=True, error_model="numpy")
def capsule_max_step(x, dx, nodes, a, b, radius):
    """The largest t with every node outside the capsule along x + t dx (inf if none)."""
    t_max = np.inf
    for k in range(nodes.shape[0]):
        i = nodes[k]
        t_max = min(t_max, capsule_entry(x[i], dx[i], a, b, radius))
    return t_max


# ------------------------------------------------ box and capsule: one gap, gradient, Hessian

BOX = 0  # geom: centre (3), axes (3x3, row-major), half sizes (3), offset (rounding)
CAPSULE = 1  # geom: end a (3), end b (3), radius


@njit(cache=True, error_model="numpy")
def shape_feature(kind, x, geom, n, P):
    """The gap of point x to the box or capsule ``geom`` (packed as BOX or CAPSULE says),
    with its unit gradient n and projection P (module docstring)."""
    if kind == BOX:
        d = box_feature(x, geom, n, P)
        g = d - geom[15]
        if geom[15] > 0.0 and g > 0.0:
            _fold(P, n, g / d)  # the rounded box: curvature over d, not g
        return g
    return capsule_feature(x, geom, n, P)


@njit(cache=True, error_model="numpy")
def shape_gap(kind, x, nodes, geom, out):
    n = np.empty(3)
    P = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        out[k] = shape_feature(kind, x[nodes[k]], geom, n, P)


@njit(cache=True, error_model="numpy")
def shape_gradient(kind, x, nodes, geom, kappa, dhat, grad):
    """Adds the barrier's gradient at ``nodes``; returns the energy."""
    total = 0.0
    n = np.empty(3)
    P = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        i = nodes[k]
        d = shape_feature(kind, x[i], geom, n, P)
        if d >= dhat:
            continue
        b, db, _ = barrier(d, dhat)
        total += kappa * b
        if d > 0.0:
            for a in range(3):
                grad[i, a] += kappa * db * n[a]
    return total


@njit(cache=True, error_model="numpy")
def shape_hessian(kind, x, nodes, geom, kappa, dhat, values):
    """Writes the 3x3 blocks of the barrier at ``nodes``; returns how many act."""
    active = 0
    n = np.empty(3)
    P = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        d = shape_feature(kind, x[nodes[k]], geom, n, P)
        if d >= dhat or d <= 0.0:
            _zero_block(values, k)
            continue
        active += 1
        _, db, ddb = barrier(d, dhat)
        _block(values, k, kappa, db, ddb, d, n, P)
    return active
