"""The PyElastica comparisons of a buckling strut and a rod falling onto a plane
(benchmarks/peers/pyelastica_buckling.py, pyelastica_drop.py), short: catenet's
verdict finds the discrete extensible strut's critical load, and where PyElastica is
installed (``pip install pyelastica``) both tools agree where their models agree: the
imperfect strut's deflection under 0.5 P_e, the first contact of the falling rod
(free fall), an elastic impact keeping the energy (PyElastica's spring without its
damper; catenet's barrier never creates any), no point of catenet's rod in the plane."""

from __future__ import annotations

import math

import pytest

from benchmarks.peers import pyelastica_buckling as pb
from benchmarks.peers import pyelastica_drop as pd


def test_the_verdict_finds_the_extensible_discrete_struts_load():
    """Euler's load times the discrete rod's (sin h / h)^2, h = pi / (2 n), and the
    extensible strut's P (1 - P / EA) = P_e: within 1e-5 at 20 edges."""
    edges = 20
    found, _, _ = pb.catenet_verdict(edges)
    h = math.pi / (2 * edges)
    discrete = pb.EULER * (math.sin(h) / h) ** 2
    axial = pb.E * math.pi * pb.RADIUS**2
    expected = 0.5 * axial * (1.0 - math.sqrt(1.0 - 4.0 * discrete / axial))
    assert found == pytest.approx(expected, rel=1e-5)


def test_the_amplification_gives_back_its_load():
    for p in (0.2, 0.5, 0.8, 0.95):
        ratio = pb.amplification(p)
        assert pb.critical_from(ratio, p * pb.EULER) == pytest.approx(pb.EULER, rel=1e-10)
    assert pb.amplification(0.01) == pytest.approx(1.0 + 0.4067 * (0.05 * math.pi) ** 2, rel=1e-4)


@pytest.mark.slow
def test_the_imperfect_strut_deflects_alike():
    """10 edges: the mid-span deflection under the lateral load alone and with 0.5 P_e,
    catenet's static solves and PyElastica's damped runs (shortened: 0.5 and 1 s), to
    5e-3; the critical loads they give to 5e-3 (their discretisations differ by that
    much at 10 edges; 3e-5 at 50, the script's)."""
    pytest.importorskip("elastica")
    edges, dt = 10, 2.5e-5  # the step bounded by the shear mode, not the element
    w_cat, w_pe = [], []
    for load, final in ((0.0, 0.5), (0.5 * pb.EULER, 1.0)):
        result = pb.catenet_solve(pb.strut_case(edges, load, pb.LATERAL))
        w_cat.append(-result.x[edges // 2, 2])
        w_pe.append(pb.pyelastica_deflection(edges, load, dt, final)[0])
    for a, b in zip(w_cat, w_pe, strict=True):
        assert a == pytest.approx(b, rel=5e-3)
    p_cat = pb.critical_from(w_cat[1] / w_cat[0], 0.5 * pb.EULER)
    p_pe = pb.critical_from(w_pe[1] / w_pe[0], 0.5 * pb.EULER)
    assert p_cat == pytest.approx(p_pe, rel=5e-3)


def test_the_falling_rod_meets_the_plane_at_free_falls_time():
    """catenet's default steps: the first step in contact brackets the free fall's
    time and ends within 0.1 ms of it (the touch is looked for along the predictor
    bent by gravity: along the straight one it was 0.7 ms late, and 3 ms after steps of
    80 ms), the rod's underside never reaches the plane and the impact creates no energy;
    PyElastica's elastic contact (nu = 0, 0.15 s): its first contact within two steps of
    it and the energy kept to 1e-2."""
    t_free = math.sqrt(2.0 * pd.HEIGHT / pd.GRAVITY)
    cat = pd.catenet_drop({})  # its energy read in the rebound's flight (T_AFTER)
    assert cat["before"] < t_free <= cat["contact"] < t_free + 1e-4  # landed on it
    assert cat["gap"] > 0.0
    assert 0.0 < cat["kept"] <= 1.0 + 1e-3
    pytest.importorskip("elastica")
    pe = pd.pyelastica_drop(0.0, final_time=0.15, t_after=0.15)
    assert abs(pe["contact"] - t_free) <= 2 * pd.STEP
    assert pe["kept"] == pytest.approx(1.0, abs=1e-2)
    assert pe["gap"] < 0.0  # a penalty spring: the rod enters the plane


def test_the_rod_rests_on_its_underside_straight():
    """catenet's rod relaxed to rest: its underside within the barrier's distance (1e-4
    of the 2 cm edges) above the plane, straight to it."""
    rest = pd.catenet_rest()
    dhat = 1e-4 * pd.L / pd.EDGES
    assert 0.0 < rest["height"] <= dhat
    assert rest["sag"] <= dhat
