"""The twisted rods' closed forms of ``catenet validate`` (``catenet.validate.twist``), at
coarser resolutions than the table's: each within its discretisation's error of the
closed form, which the table's resolutions then meet to 1e-3."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.validate import twist


def test_a_straight_rod_turned_at_both_ends_carries_c_phi_over_l():
    (row,) = twist.straight_rows()
    assert row["passed"] is True and row["error"] < 1e-12, row


def test_the_helix_is_the_kirchhoff_equilibrium_under_its_wrench():
    """At 100 edges F within 1e-3 and M within 1e-4 (errors 6.4e-4 and 1.5e-5; second
    order in the edge length), the reaction along the axis only."""
    force, moment = twist.helix_wrench()
    f, m, across = twist.helix(100)
    assert f == pytest.approx(force, rel=1e-3)
    assert m == pytest.approx(moment, rel=1e-4)
    assert across < 1e-3 * abs(force)


@pytest.mark.roundoff  # the stability verdict at a bifurcation
def test_greenhill_critical_twist_from_the_verdict():
    """Clamped at both ends: M L / B = 8.9868 at 50 edges to 3e-3 (2.4e-3: O(h^2))."""
    exact = twist.GREENHILL * twist.EI / twist.GJ
    assert twist.greenhill(50) == pytest.approx(exact, rel=3e-3)


def test_michells_ring_turns_unstable_at_2_pi_sqrt3_b_over_c():
    """Tw_cr = 2 pi sqrt(3) B / C: within 1e-3 at 100 edges (6.6e-4), 4 times closer at
    200 than at 100."""
    exact = 2.0 * math.pi * math.sqrt(3.0) * twist.EI / twist.GJ
    coarse, fine = twist.michell(100), twist.michell(200)
    assert coarse == pytest.approx(exact, rel=1e-3)
    assert abs(fine - exact) == pytest.approx(abs(coarse - exact) / 4, rel=0.05)


@pytest.mark.parametrize("ends", ["clamped-free", "clamped-clamped"])
def test_a_shafts_torsional_frequencies_are_the_discrete_waves(ends):
    """The three lowest torsional frequencies at 25 edges: below the closed form by the
    staggered grid's (k h)^2 / 24 (k = (2 n - 1) pi / 2L or n pi / L) to 2 % of it (its
    next term), so that the error falls with h^2: 6.6e-4 at 25 edges for the first
    clamped-clamped one, 1.6e-4 at 50."""
    found = twist.shaft(25, ends, 3)
    c = math.sqrt(twist.GJ / twist.SHAFT_POLAR)
    n = np.arange(1, 4)
    k = (2 * n - 1) * math.pi / 2 if ends == "clamped-free" else n * math.pi
    exact = k * c / (2 * math.pi)
    error = (exact - found) / exact
    assert error == pytest.approx((k / 25) ** 2 / 24, rel=0.02)
