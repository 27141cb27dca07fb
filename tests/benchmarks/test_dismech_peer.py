"""The dismech-newton comparisons (benchmarks/peers/dismech_cantilever.py, dismech_column.py
and dismech_drop.py), short: where dismech-newton is installed (``pip install
dismech-newton==0.1.0.post2``; its 0.1.0.post4 does not import on Python 3.11), its tip
converges to the elastica at first order in the edge length (its clamp holds the first
edge, half an edge out), catenet's many times closer at the same edges; its falling rod
meets the plane when free fall does and stops on it."""

from __future__ import annotations

import math

import pytest

from benchmarks.peers import dismech_cantilever as dc
from catenet.validate.rods import elastica_tip

try:  # 0.1.0.post4 fails at import on Python < 3.14 with a TypeError, not an ImportError
    import dismech_newton  # noqa: F401
except (ImportError, TypeError) as exc:  # pragma: no cover - the peer is optional
    pytest.skip(f"dismech-newton: {exc}", allow_module_level=True)


def test_dismech_newtons_cantilever_converges_to_the_elastica_at_first_order():
    """P L^2 / EI = 1 at 20 and 40 edges: dismech-newton's tip error 0.4 L / n (halving
    with the edge), catenet's below a tenth of it at 20 edges."""
    _, x, y = elastica_tip(1.0)
    errors = []
    for edges in (20, 40):
        tip, _, steps = dc.dismech_tip(1.0, edges, 0.2 * 50 / edges)
        assert steps < 500
        errors.append(max(abs(tip[0] - x), abs(tip[1] - y)))
    assert 0.2 / 20 < errors[0] < 0.6 / 20, errors
    assert 0.4 < errors[1] / errors[0] < 0.6, errors
    tip, _ = dc.catenet_tip(1.0, 20)
    assert max(abs(tip[0] - x), abs(tip[1] - y)) < 0.1 * errors[0]


def test_dismech_newtons_buckled_column_converges_to_the_elastica_at_first_order():
    """The column of benchmarks/peers/dismech_column.py at 1.5 P_cr, 50 and 100 edges
    (on 20, at its 0.5 s steps, it comes to rest before it has buckled): dismech-newton's
    tip error halves with the edge, catenet's at 50 edges is below a tenth of its."""
    from benchmarks.peers import dismech_column as dcol

    exact = dcol.elastica_column(1.5)
    errors = []
    for edges in (50, 100):
        tip, _, _ = dcol.dismech_column_tip(1.5, edges, 0.2 * 50 / edges)
        errors.append(max(abs(tip[0] - exact[0]), abs(tip[1] - exact[1])))
    assert 0.4 < errors[1] / errors[0] < 0.6, errors
    tip, _ = dcol.column_tip(1.5, 50)
    assert max(abs(tip[0] - exact[0]), abs(tip[1] - exact[1])) < 0.1 * errors[0]


def test_dismech_newtons_falling_rod_meets_the_plane_with_free_fall_and_stops_on_it():
    """The rod of benchmarks/peers/dismech_drop.py at dismech-newton's 1 ms steps to 0.15 s:
    its first step in contact is the one free fall meets the plane in (0.10096 s), its
    underside never more than 1e-5 m into the plane, and its contact (a projection within
    implicit Euler) keeps no energy: the rod lies on the plane, straight, by 0.15 s."""
    from benchmarks.peers import dismech_drop as dd

    free = math.sqrt(2.0 * dd.HEIGHT / dd.GRAVITY)
    r = dd.dismech_drop(1e-3, final_time=0.15, t_after=0.14)
    assert r["before"] < free <= r["contact"] + 1e-12 and r["contact"] - r["before"] < 1.5e-3
    assert r["gap"] > -1e-5
    assert r["kept"] < 0.01
    assert abs(r["height"]) < 1e-5 and r["sag"] < 1e-5
