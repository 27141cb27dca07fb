"""The MoorDyn comparison (benchmarks/peers/moordyn_lines.py): its motion is catenet's
sine with its exact velocity, its catenet cases parse and start where MoorDyn's lines
lie, and, where MoorDyn is installed (``pip install moordyn``), the taut polyester line
under a heave sine gives the same static and dynamic fairlead tension in both."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.peers import moordyn_lines as ml
from catenet.case import parse_case
from catenet.case.scene import build
from catenet.model.histories import Sine


def test_the_fairlead_motion_is_catenets_sine_with_its_velocity():
    line = ml.CHAIN
    s = Sine(line.period, 0.0, line.period)
    h = 1e-6
    for t in (0.0, 0.3, 5.9, 11.99, 12.5, 30.0):
        d, v = ml.sine(line, t)
        assert d == pytest.approx(np.array(line.amplitude) * s(t), abs=1e-12)
        slope = (s(t + h) - s(max(t - h, 0.0))) / (t + h - max(t - h, 0.0))
        assert v == pytest.approx(np.array(line.amplitude) * slope, abs=1e-5)


@pytest.mark.parametrize("line", ml.LINES, ids=lambda line: line.name.split(",")[0])
def test_catenets_lines_are_moordyns(line):
    """The same ends, unstretched length, mass and displaced volume per length, drag
    and added-mass coefficients and number of segments."""
    case = parse_case(ml.catenet_case(line, 1.0, 0.05))
    net = build(case).net
    assert net.n_edges == line.segments
    assert net.rest_length.sum() == pytest.approx(line.length, rel=1e-6)
    ends = net.nodes[net.fixed]
    assert {tuple(p) for p in ends.round(6)} == {line.anchor, line.fairlead} or line.guess
    m = case.material
    assert m.density * m.area == pytest.approx(line.mass, rel=1e-12)
    assert m.area == pytest.approx(math.pi / 4 * line.diameter**2, rel=1e-12)
    assert (m.cd_n, m.cd_t, m.ca_n, m.ca_t) == (line.cd_n, line.cd_t, line.ca_n, line.ca_t)


@pytest.mark.slow
def test_the_taut_line_agrees_with_moordyn():
    """Static fairlead tension to 0.1 %; under the heave sine, the tension histories to
    2 % of the peak (rms 1 %): the models are the same but for MoorDyn's internal axial
    damping and its explicit steps."""
    pytest.importorskip("moordyn")
    r = ml.compare(ml.TAUT, 12.0)
    cat, md = r["static"]
    assert cat == pytest.approx(md, rel=1e-3)
    cp, mp = r["peak"]
    assert cp == pytest.approx(mp, rel=0.02)
    assert r["largest difference"] < 0.02
    assert r["rms difference"] < 0.01
