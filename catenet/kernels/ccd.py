"""Continuous collision detection of edge pairs (``catenet.kernels.strands``' distances):
additive CCD (Li, Kaufman and Jiang 2021, ``accd``), optionally with the separating
plane's bound (``plane_time``), and the strands' step cap ``strand_max_step``: every
candidate pair kept apart and each node's motion relative to the mean motion within its
radius (see ``catenet.terms.strands``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from catenet.kernels.strands import ALPHA, BETA, GAMMA, _combine, _dot, closest, gather, sqdist

#: Additive CCD: a pair's step stops where its distance falls below this share of its
#: distance at the step's start; at most so many advances per pair (then the step so far).
CCD_SHARE = 0.1
CCD_ITERATIONS = 1000


@njit(cache=True, error_model="numpy")
def relative_speed(dP):
    """Additive CCD's l_p for four points moving with dP (12,): the largest speed of the
    first two plus that of the last two, relative to their mean motion."""
    q = dP.reshape(4, 3) - 0.25 * (dP[0:3] + dP[3:6] + dP[6:9] + dP[9:12])
    speed = np.sqrt(q[:, 0] ** 2 + q[:, 1] ** 2 + q[:, 2] ** 2)
    return max(speed[0], speed[1]) + max(speed[2], speed[3])


EPS_ROUND = np.finfo(np.float64).eps
PLANE_TRUST = 1e4  # the plane's round-off at most 1e-4 of the gap it advances through


@njit(cache=True, error_model="numpy")
def plane_time(X, dP, d, r, kind, share):
    """How long the pair X (12,) moving with dP (12,) keeps its distance ``kind`` above
    r + (1 - share) d, d its gap now, by the plane through the closest point of A - B
    normal to their offset n (conservative advancement along the separating direction):
    the two features are segments or points, so A - B is the hull of the differences
    of their ends, which lie on the far side of that plane and move linearly, each at
    the rate n . (its motion) towards it; inf where none approaches. For a pair that
    slides along itself at a gap far below its motion (a rope round a blade's corner at
    a fraction of a nanometre, moving microns) this is the whole step where l_p's bound
    takes thousands of advances."""
    s, t, fs, ft = closest(X, kind)
    c = ALPHA[kind] + BETA[kind] * s + GAMMA[kind] * t
    v = _combine(X, c)
    D = np.sqrt(_dot(v, v))
    size = 0.0  # the coordinates' size and the pair's extent, for n's round-off
    for p in range(12):
        size = max(size, abs(X[p]))
    extent = 0.0
    for k in range(2):
        for m in range(2, 4):
            e = 0.0
            for i in range(3):
                e += (X[3 * k + i] - X[3 * m + i]) ** 2
            extent = max(extent, np.sqrt(e))
    # n's error (eps |X| / D) turns each end's offset by extent eps |X| / D: well below
    # the gap, or the plane is not trusted (strands touching within 1e-12 m)
    if not PLANE_TRUST * EPS_ROUND * size * extent < d * D:
        return 0.0
    best = np.inf
    for k in range(2):
        if ALPHA[kind, k] == 0.0 and BETA[kind, k] == 0.0:
            continue  # not a point of this kind's first feature
        for m in range(2, 4):
            if ALPHA[kind, m] == 0.0 and GAMMA[kind, m] == 0.0:
                continue
            rate = 0.0
            room = -r - (1.0 - share) * d
            for i in range(3):
                rate += v[i] * (dP[3 * k + i] - dP[3 * m + i]) / D
                room += v[i] * (X[3 * k + i] - X[3 * m + i]) / D
            if rate < 0.0:
                best = min(best, max(room, 0.0) / -rate)
    return best


@njit(cache=True, error_model="numpy")
def accd(P, dP, t_max, r=0.0, kind=0, plane=False):
    """The first time t in (0, t_max] of additive CCD for the edge pair P (12,) moving
    with dP (12,): the distance ``kind`` (``sqdist``'s) stays above r on [0, t] (it falls
    by at most l_p per unit of t, l_p the largest relative speeds of the two edges'
    ends); inf when none comes before t_max. With ``plane``, each advance is the longer
    of l_p's and the separating plane's (``plane_time``), both of which keep the pair
    apart (the edges against a solid's outline; the strands' self-contact keeps l_p's
    alone: a strand balanced across another tipped off it earlier, its steps longer)."""
    lp = relative_speed(dP)
    if lp == 0.0:
        return np.inf
    g, H, X = np.empty(12), np.empty((1, 1)), np.empty(12)  # (no Hessian asked for)
    d = np.sqrt(sqdist(P, kind, g, H, np.bool_(False))) - r
    if not d > 0.0:
        return 0.0
    gap = CCD_SHARE * d
    t = 0.0
    tl = (1.0 - CCD_SHARE) * d / lp
    if plane:
        tl = max(tl, plane_time(P, dP, d, r, kind, 1.0 - CCD_SHARE))
    for _ in range(CCD_ITERATIONS):
        if tl == np.inf:  # the plane: no end of the pair ever approaches the other
            return np.inf
        for p in range(12):
            X[p] = P[p] + (t + tl) * dP[p]
        d = np.sqrt(sqdist(X, kind, g, H, np.bool_(False))) - r
        if t > 0.0 and d < gap:
            return t
        t += tl
        if t > t_max:
            return np.inf
        tl = 0.9 * d / lp
        if plane:
            tl = max(tl, plane_time(X, dP, d, r, kind, 0.9))
    return t


@njit(cache=True, error_model="numpy")
def strand_max_step(x, dx, base, nodes, radius, edges, pairs, t_max, r=0.0):
    """(t, t1): the largest multiple t (at most t_max: longer steps are never checked)
    of the step dx from x that keeps (1) every node's motion from ``base`` relative to
    the mean motion of ``nodes`` within its ``radius`` and (2) every candidate pair apart
    (``accd``); t1 the limit of (1) alone."""
    k = nodes.shape[0]
    m0, m1 = np.zeros(3), np.zeros(3)
    for j in range(k):
        n = nodes[j]
        for i in range(3):
            m0[i] += (x[n, i] - base[n, i]) / k
            m1[i] += dx[n, i] / k
    t = t_max
    for j in range(k):
        n = nodes[j]
        ww = wz = zz = 0.0
        for i in range(3):
            w = x[n, i] - base[n, i] - m0[i]
            z = dx[n, i] - m1[i]
            ww += w * w
            wz += w * z
            zz += z * z
        c = ww - radius[n] * radius[n]
        if c >= 0.0:
            return 0.0, 0.0
        if zz > 0.0:
            t = min(t, (-wz + np.sqrt(wz * wz - zz * c)) / zz)
    moved = t
    P, dP = np.empty(12), np.empty(12)
    for p in range(pairs.shape[0]):
        gather(x, edges, pairs[p, 0], pairs[p, 1], P)
        gather(dx, edges, pairs[p, 0], pairs[p, 1], dP)
        t = min(t, accd(P, dP, t, r, np.int64(0)))
    return t, moved
