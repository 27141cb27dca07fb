"""The rods' closed forms of ``catenet validate`` (``catenet.validate.rods``): the
elastica against Bisshopp and Drucker's table, the Euler load from the stability
verdict, and the hardest cantilever (P L^2 / EI = 10), which the table leaves out for
its time."""

from __future__ import annotations

import math

import pytest

from catenet.validate import rods


@pytest.mark.parametrize(
    ("alpha", "theta0_deg", "y", "x"),
    [  # Bisshopp and Drucker (1945), Table 1: tip angle, vertical and horizontal deflection
        (1.0, 26.43, 0.30172, 1 - 0.05643),
        (10.0, 81.95, 0.81061, 1 - 0.55500),
    ],
)
def test_elastica_reproduces_the_table(alpha, theta0_deg, y, x):
    theta0, x_found, y_found = rods.elastica_tip(alpha)
    assert math.degrees(theta0) == pytest.approx(theta0_deg, abs=6e-3)
    assert y_found == pytest.approx(y, abs=6e-6)
    assert x_found == pytest.approx(x, abs=6e-6)


@pytest.mark.roundoff  # the stability verdict at a bifurcation: perturbed, 2 threads
def test_euler_load_from_the_verdict_matches_the_discrete_strut():
    """At 50 edges the critical load is the discrete strut's exact one,
    pi^2 EI / L^2 (sin(h') / h')^2 with h' = pi / 100, to 1e-6, and within 1e-3 of Euler's."""
    found = rods.critical_load(50)
    euler = math.pi**2 * rods.EI / rods.LENGTH**2
    h = math.pi / 100
    assert found == pytest.approx(euler * (math.sin(h) / h) ** 2, rel=1e-6)
    assert abs(found / euler - 1) < 1e-3


@pytest.mark.slow
def test_cantilever_at_ten_meets_the_elastica():
    _, x, y = rods.elastica_tip(10.0)
    tip = rods.tip(100, 10.0)
    assert abs(tip[0] - x) < 1e-4 and abs(tip[1] - y) < 1e-4


def test_a_ring_under_diametral_load_meets_roarks_thin_ring():
    """Case (d): the ring as a case writes it (a closed cable, natural curvature as
    given, rollers in its plane, a slider under the load): both diameters' changes and
    the moment under the load within 1e-3 of the thin ring's at 400 edges, and the
    error falls about 4-fold per halving of the edge."""
    rows = rods.ring_rows()
    for row in rows:
        assert row["passed"] is not False, row
        if row["resolution"] == rods.RING_EDGES[-1]:
            assert row["error"] < rods.RING_TOL, row
        if "order" in row:
            assert 1.8 <= row["order"] <= 2.2, row
    moment = rows[-1]
    assert moment["quantity"] == "M under the load"
    assert moment["catenet"] == pytest.approx(rods.RING_LOAD / math.pi, rel=1e-4)
