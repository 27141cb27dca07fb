"""The continuous collision detection of edge pairs (``catenet.kernels.ccd.accd``) advances
by the longer of additive CCD's bound (the largest relative speed of the ends) and the
separating plane's (``plane_time``: the ends' differences move linearly towards the plane
through the closest point). A pair sliding along itself at a gap far below its motion (a
rope round a paddle's corner at 0.36 nm, moving 1.5 um in a Newton step) took 1 000 of
additive CCD's advances to cover a quarter of the step, where the iterations ran out: the
step was capped at 0.2-0.6 every iteration and the run failed. Both bounds keep the pair
apart; checked here against the distance sampled along random motions."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.kernels.ccd import accd, plane_time
from catenet.kernels.strands import sqdist

G, H = np.empty(12), np.empty((12, 12))


def _distance(P, kind):
    return float(np.sqrt(sqdist(P, kind, G, H, False)))


def _first_contact(P, dP, kind, r, t_max, samples=801):
    """The first sampled time in [0, t_max] where the pair is within r (inf: none), the
    sampled times and the distances minus r there."""
    ts = np.linspace(0.0, t_max, samples)
    d = np.array([_distance(P + t * dP, kind) for t in ts]) - r
    hit = np.flatnonzero(d <= 0.0)
    return (ts[hit[0]] if hit.size else np.inf), ts, d


@pytest.mark.parametrize("kind", [0, 3])
def test_the_step_never_carries_a_pair_into_contact_and_stops_short_of_it(kind):
    """300 random pairs of segments (kind 0) or a segment and a point (kind 3, the point
    given twice as the edges' barrier gives a solid's lone corner), moving linearly, with
    a radius: the time CCD returns is never past the first contact, the pair is apart
    there, and where it reports none the pair stays apart over the whole span."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        P = rng.normal(size=12)
        dP = rng.normal(size=12) * rng.choice([0.1, 1.0, 5.0])
        if kind == 3:
            P[9:12], dP[9:12] = P[6:9], dP[6:9]
        r = rng.uniform(0.0, 0.3)
        if _distance(P, kind) <= r:
            continue
        t = accd(P, dP, 2.0, r, kind, True)
        toi, ts, d = _first_contact(P, dP, kind, r, 2.0)
        assert t <= toi + 1e-12, (t, toi)
        assert d[ts <= t].min() > 0.0  # apart all the way to it
        if np.isfinite(t):
            assert _distance(P + t * dP, kind) > r
        else:
            assert d.min() > 0.0


def test_a_pair_sliding_along_itself_at_a_tiny_gap_covers_the_step_at_once():
    """A rope's edge sliding 1.5 um along itself past a solid's edge 0.36 nm beyond its
    3 mm radius (the paddle's corner, in its frame): the separating plane gives the whole
    step (the pair does not approach), where additive CCD alone covered a quarter of it in
    its 1 000 advances; a pair closing on the same gap still stops before it closes."""
    r = 0.003
    gap = 3.6e-10
    P = np.array([-0.02, 0.0, 0.0, 0.0, 0.0, 0.0,  # the rope's edge along x
                  -0.01, -0.005, r + gap, -0.01, 0.005, r + gap])  # fmt: skip
    slide = np.zeros(12)
    slide[0:6:3] = 1.5e-6  # along itself (x)
    assert plane_time(P, slide, gap, r, 0, 0.9) == np.inf
    assert accd(P, slide, 4.0, r, 0, True) == np.inf
    assert accd(P, slide, np.inf, r, 0, True) == np.inf  # no span given: still none
    assert accd(P, slide, 4.0, r, 0) < 0.5  # l_p's bound alone: a quarter in 1 000 advances
    close = slide.copy()
    close[2::3][:2] = 2.0 * gap  # and towards the solid's edge: meets it at t = 0.5
    t = accd(P, close, 4.0, r, 0, True)
    assert 0.0 < t < 0.5
    assert _distance(P + t * close, 0) > r
