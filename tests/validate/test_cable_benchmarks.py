"""Classical cable benchmarks against Irvine's exact elastic catenary (Cable Structures,
1981): supports at different heights, a buoyant line, a nearly inextensible cable, and a
very slack one.

catenet's chain lumps the weight of each edge at its ends and replaces arcs by chords:
both are second-order approximations of the continuum, so node i (the material point at
unstretched arc length s_i = i L0 / (N - 1)) must lie within C (h/L0)^2 L0 of the
closed-form position, with the observed order about 2 under refinement. C = 2 leaves a
margin over the constants seen in the level-support validation (0.5 to 0.93).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import catenet as cn
from catenet.validate.analytic import elastic_catenary, inclined_catenary

PAPER_EA = 10e6 * math.pi * 0.01**2  # 3141.6 N
PAPER_RHOA = 1000.0 * math.pi * 0.01**2  # 0.314 kg/m: w = 3.08 N/m
G = 9.81

CASES = {
    # name: (L0, span, rise, EA, rho*A, g_z)
    "inclined": (1.3, 1.0, 0.4, PAPER_EA, PAPER_RHOA, -G),
    "buoyant": (1.3, 1.0, 0.4, PAPER_EA, PAPER_RHOA, +G),
    "nearly inextensible": (1.3, 1.0, -0.3, 1e9, PAPER_RHOA, -G),
    "very slack": (2.5, 1.0, 0.0, PAPER_EA, PAPER_RHOA, -G),
    "soft, stretched by its weight": (1.05, 1.0, 0.2, 5.0, PAPER_RHOA, -G),
}


def solve(name: str, nodes: int):
    L0, span, rise, EA, rho_a, gz = CASES[name]
    mat = cn.Material(EA=EA, line_density=rho_a)
    net = cn.cable([0.0, 0.0, 0.0], [span, 0.0, rise], nodes, mat, length=L0)
    result = cn.solve_static(net, cn.Loads(gravity=np.array([0.0, 0.0, gz])), rtol=1e-12)
    exact = inclined_catenary(L0, EA, -rho_a * gz, span, rise)
    s = np.linspace(0.0, L0, nodes)
    error = max(
        np.max(np.abs(result.x[:, 0] - exact.x(s))), np.max(np.abs(result.x[:, 2] - exact.z(s)))
    )
    return result, exact, error / L0


@pytest.mark.parametrize("name", list(CASES))
def test_shape_converges_at_second_order(name):
    L0 = CASES[name][0]
    sizes = [41, 81, 161]
    errors = []
    for nodes in sizes:
        result, exact, error = solve(name, nodes)
        assert result.converged
        h = L0 / (nodes - 1)
        assert error <= 2.0 * (h / L0) ** 2, (nodes, error)
        errors.append(error)
    h = [L0 / (n - 1) for n in sizes]
    order = np.polyfit(np.log(h), np.log(errors), 1)[0]
    assert 1.8 <= order <= 2.2, (errors, order)


@pytest.mark.parametrize("name", list(CASES))
def test_support_reactions_match_the_end_tensions(name):
    """The left support holds the cable with (-H, V) (x outward, z up)."""
    result, exact, _ = solve(name, 161)
    h = CASES[name][0] / 160
    scale = float(exact.tension(0.0))
    assert abs(result.reaction[0, 0] + exact.H) <= 2 * (h / CASES[name][0]) ** 2 * scale
    assert abs(result.reaction[0, 2] - exact.V) <= 2 * (h / CASES[name][0]) ** 2 * scale


def test_buoyant_line_floats_up_and_hangs_down_mirrored():
    """With the weight reversed a level line is the mirror image of the hanging one."""
    L0, span = 1.3, 1.0
    up = inclined_catenary(L0, PAPER_EA, -PAPER_RHOA * G, span, 0.0)
    down = inclined_catenary(L0, PAPER_EA, PAPER_RHOA * G, span, 0.0)
    s = np.linspace(0, L0, 9)
    np.testing.assert_allclose(up.z(s), -down.z(s), atol=1e-12)
    assert up.z(L0 / 2) > 0 > down.z(L0 / 2)


def test_level_supports_reduce_to_the_symmetric_solution():
    L0, span, w = 1.2, 1.0, PAPER_RHOA * G
    general = inclined_catenary(L0, PAPER_EA, w, span, 0.0)
    level = elastic_catenary(L0, PAPER_EA, w, span)
    assert general.H == pytest.approx(level.H, rel=1e-12)
    assert general.V == pytest.approx(w * L0 / 2, rel=1e-12)
