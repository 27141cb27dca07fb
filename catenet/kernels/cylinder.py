"""Barrier contact of nodes with a solid cylinder with flat ends (a pipe, a drum, a pile).

The cylinder has centre c, unit axis e, half length h and radius r. A point x has the
axial coordinate z = (x - c).e and the radial vector w = x - c - z e of length rho; with
dr = rho - r and dz = |z| - h it lies

- inside where dr <= 0 and dz <= 0 (the gap is max(dr, dz) <= 0: infinite energy);
- beside the curved side where dr > 0 >= dz: d = dr, n = w / rho and
  hess d = (I - e e^T - n n^T) / rho;
- above a flat end where dz > 0 >= dr: d = dz, n = sign(z) e, hess d = 0;
- off a rim (dr > 0 and dz > 0): the distance to the rim circle,
  d = |v|, v = dr w/rho + dz sign(z) e, n = v / d and
  hess d = (w w^T / rho^2 + e e^T - n n^T) / d + (1 - r / rho) / d t t^T, t = e x w / rho
  (the nearest point turns round the circle by r / rho of a sideways move).

The energy kappa b(g) of the barrier b (``catenet.kernels.contact``) on the gap
g = d - offset (a ball of radius ``offset`` against the cylinder: its centre against the
cylinder grown by the ball, exact) has the gradient kappa b'(g) n and the Hessian
kappa (b''(g) n n^T + b'(g) hess d). The distance is C1 outside the cylinder; its Hessian
jumps where the nearest feature changes (side, end, rim), only inside the active layer,
as for the box (``catenet.kernels.shapes``).

First contact along x + t dx (``cylinder_max_step``): for the cylinder itself the exact
entry of the line into the intersection of the infinite cylinder rho <= r and the slab
|z| <= h (the roots of a quadratic, in the form that does not cancel, and two planes).
Grown by g > 0 the cylinder is the union of the cylinder of radius r + g and half length
h, that of radius r and half length h + g, and the two tori of tube radius g round the
rims: the exact entries into the two cylinders, and for the tori sphere tracing on the
distance to the rim circles (a point moves by at most that distance minus g before it can
touch a torus, so no trace passes one; at most TRACE steps, after which the contact is
taken where the trace got: earlier than the true one, never later).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.contact import barrier

TRACE = 200  # sphere-tracing steps towards a grown cylinder's rim tori
CONVERGED = 1e-12  # the trace stops this share of the tube radius from a torus


@njit(cache=True, error_model="numpy")
def cylinder_feature(x, c, e, h, r, n, H):
    """Signed distance of point x to the cylinder (centre c, unit axis e, half length h,
    radius r); fills n (outward unit gradient) and H (hess d) when outside (module
    docstring). Returns max(dr, dz) <= 0 inside."""
    y0, y1, y2 = x[0] - c[0], x[1] - c[1], x[2] - c[2]  # scalars: no array per node
    e0, e1, e2 = e[0], e[1], e[2]
    z = y0 * e0 + y1 * e1 + y2 * e2
    w0, w1, w2 = y0 - z * e0, y1 - z * e1, y2 - z * e2
    rho = np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    dr = rho - r
    dz = abs(z) - h
    if dr <= 0.0 and dz <= 0.0:
        return max(dr, dz)
    s = 1.0 if z >= 0.0 else -1.0
    if dr <= 0.0:  # above a flat end
        for j in range(3):
            n[j] = s * e[j]
            for k in range(3):
                H[j, k] = 0.0
        return dz
    w = (w0 / rho, w1 / rho, w2 / rho)  # the radial unit vector
    if dz <= 0.0:  # beside the curved side
        for j in range(3):
            n[j] = w[j]
        for j in range(3):
            for k in range(3):
                eye = 1.0 if j == k else 0.0
                H[j, k] = (eye - e[j] * e[k] - w[j] * w[k]) / rho
        return dr
    d = np.sqrt(dr * dr + dz * dz)  # off a rim: the distance to the rim circle
    for j in range(3):
        n[j] = (dr * w[j] + dz * s * e[j]) / d
    t = (e1 * w[2] - e2 * w[1], e2 * w[0] - e0 * w[2], e0 * w[1] - e1 * w[0])
    turn = 1.0 - r / rho
    for j in range(3):
        for k in range(3):
            plane = w[j] * w[k] + e[j] * e[k] - n[j] * n[k]
            H[j, k] = (plane + turn * t[j] * t[k]) / d
    return d


@njit(cache=True, error_model="numpy")
def cylinder_gap(x, nodes, c, e, h, r, offset, out):
    n = np.empty(3)
    H = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        out[k] = cylinder_feature(x[nodes[k]], c, e, h, r, n, H) - offset


@njit(cache=True, error_model="numpy")
def cylinder_gradient(x, nodes, c, e, h, r, offset, kappa, dhat, grad):
    """Adds the barrier's gradient at ``nodes``; returns the energy."""
    total = 0.0
    n = np.empty(3)
    H = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        i = nodes[k]
        g = cylinder_feature(x[i], c, e, h, r, n, H) - offset
        if g >= dhat:
            continue
        b, db, _ = barrier(g, dhat)
        total += kappa * b
        if g > 0.0:
            for a in range(3):
                grad[i, a] += kappa * db * n[a]
    return total


@njit(cache=True, error_model="numpy")
def cylinder_hessian(x, nodes, c, e, h, r, offset, kappa, dhat, values):
    """Writes the 3x3 blocks of the barrier at ``nodes``; returns how many act."""
    active = 0
    n = np.empty(3)
    H = np.empty((3, 3))
    for k in range(nodes.shape[0]):
        g = cylinder_feature(x[nodes[k]], c, e, h, r, n, H) - offset
        if g >= dhat or g <= 0.0:
            for a in range(9):
                values[9 * k + a] = 0.0
            continue
        active += 1
        _, db, ddb = barrier(g, dhat)
        for a in range(3):
            for b in range(3):
                values[9 * k + 3 * a + b] = kappa * (ddb * n[a] * n[b] + db * H[a, b])
    return active


@njit(cache=True, error_model="numpy")
def _interval(x, v, c, e, h, r):
    """(enter, leave): the times at which x + t v is in the cylinder (enter > leave:
    never)."""
    z0 = 0.0
    vz = 0.0
    for j in range(3):
        z0 += (x[j] - c[j]) * e[j]
        vz += v[j] * e[j]
    A = 0.0
    B = 0.0
    C = -r * r
    for j in range(3):
        w = x[j] - c[j] - z0 * e[j]
        u = v[j] - vz * e[j]
        A += u * u
        B += 2.0 * w * u
        C += w * w
    lo, hi = -np.inf, np.inf
    if A > 0.0:
        disc = B * B - 4.0 * A * C
        if disc < 0.0:
            return np.inf, -np.inf
        sq = np.sqrt(disc)
        q = -0.5 * (B + sq) if B >= 0.0 else -0.5 * (B - sq)
        r1 = q / A
        r2 = C / q if q != 0.0 else r1
        lo, hi = min(r1, r2), max(r1, r2)
    elif C > 0.0:  # moving along the axis, outside the radius
        return np.inf, -np.inf
    if vz != 0.0:
        t1 = (-h - z0) / vz
        t2 = (h - z0) / vz
        lo = max(lo, min(t1, t2))
        hi = min(hi, max(t1, t2))
    elif abs(z0) > h:
        return np.inf, -np.inf
    return lo, hi


@njit(cache=True, error_model="numpy")
def _entry(x, v, c, e, h, r):
    """The first t >= 0 at which x + t v is in the cylinder (inf: never)."""
    lo, hi = _interval(x, v, c, e, h, r)
    if lo > hi or hi < 0.0:
        return np.inf
    return max(lo, 0.0)


@njit(cache=True, error_model="numpy")
def _rims(p, c, e, h, r):
    """The distance of point p to the nearer rim circle."""
    z = 0.0
    for j in range(3):
        z += (p[j] - c[j]) * e[j]
    rho = 0.0
    for j in range(3):
        w = p[j] - c[j] - z * e[j]
        rho += w * w
    dr = np.sqrt(rho) - r
    dz = abs(z) - h
    return np.sqrt(dr * dr + dz * dz)


@njit(cache=True, error_model="numpy")
def cylinder_entry(x, v, c, e, h, r, grow):
    """The first t >= 0 at which x + t v is within ``grow`` of the cylinder (module
    docstring; inf: never)."""
    if grow <= 0.0:
        return _entry(x, v, c, e, h, r)
    t = min(_entry(x, v, c, e, h, r + grow), _entry(x, v, c, e, h + grow, r))
    lo, hi = _interval(x, v, c, e, h + grow, r + grow)  # holds the tori
    speed = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if lo > hi or hi < 0.0 or speed == 0.0:
        return t
    s = max(lo, 0.0)
    end = min(hi, t)
    p = np.empty(3)
    for _ in range(TRACE):
        if s >= end:
            return t
        for j in range(3):
            p[j] = x[j] + s * v[j]
        f = _rims(p, c, e, h, r) - grow
        if f <= CONVERGED * grow:
            return min(s, t)
        s += f / speed
    return min(s, t)  # not converged: where the trace got, before any contact


@njit(cache=True, error_model="numpy")
def cylinder_max_step(x, dx, nodes, c, e, h, r, grow):
    """The largest t with every node outside the cylinder grown by ``grow`` along
    x + t dx (inf if none)."""
    t_max = np.inf
    for k in range(nodes.shape[0]):
        i = nodes[k]
        t_max = min(t_max, cylinder_entry(x[i], dx[i], c, e, h, r, grow))
    return t_max
