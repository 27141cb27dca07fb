"""The summary's sag of a cable that lies above its chord (lifted by a bar, pushed up by a
load): how far above, not "0 m vertical" beside a normal sag of 0.5 m, which read as a
contradiction to a newcomer (``catenet.model.measures.sag``'s ``rise``)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.model.measures import sag

CABLE = """
[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 21

[material]
EA = 1.0e5
prestress = 100.0

[load]
point = [{ node = 10, force = [0.0, 0.0, FZ] }]
"""


def _chain(z):
    x = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, z], [1.0, 0.0, 0.0]])
    net = SimpleNamespace(edges=np.array([[0, 1], [1, 2]]))  # only the edges are read
    return sag(net, x)


def test_a_cable_above_its_chord_has_a_rise_and_no_drop():
    """The middle node 0.5 above the chord: normal 0.5, vertical 0, rise 0.5; below it:
    the other way round; straight: neither (the ends' round-off is not a rise)."""
    up, down, flat = _chain(0.5), _chain(-0.5), _chain(0.0)
    assert (up["normal"], up["vertical"], up["rise"]) == (0.5, 0.0, 0.5)
    assert (down["normal"], down["vertical"], down["rise"]) == (0.5, 0.5, 0.0)
    assert (flat["vertical"], flat["rise"]) == (0.0, 0.0)
    assert not math.isnan(up["rise"])


def test_the_summary_says_how_far_above_its_chord_a_cable_is_pushed(tmp_path):
    """A 2 m cable (EA 100 kN, 100 N prestress) pushed up by 20 N at its middle: it
    rises f where 20 N = 2 T f / sqrt(1 + f^2), T = EA (sqrt(1 + f^2) / l0 - 1), l0 the
    1 m half's rest length (f = 0.0473 m: its tension grows to about 211 N); the summary's
    sag line gives it as above the chord, and one pushed down as vertical sag."""
    for fz, word in ((20.0, "above it"), (-20.0, "m vertical")):
        case = tmp_path / "c.toml"
        case.write_text(CABLE.replace("FZ", repr(fz)))
        done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
        assert done.exit_code == 0, done.output
        line = next(row for row in done.output.splitlines() if row.startswith("sag"))
        assert word in line, line
        value = float(line.split(", ")[1].split(" m")[0])
        assert abs(value / _rise(20.0) - 1.0) < 2e-3, (line, _rise(20.0))


def _rise(force: float) -> float:
    """The middle's rise of the pinned 2 m cable under ``force`` there (bisection)."""
    l0 = 1.0 / (1.0 + 100.0 / 1.0e5)
    lo, hi = 0.0, 1.0
    for _ in range(100):
        f = 0.5 * (lo + hi)
        length = math.hypot(1.0, f)
        if 2.0 * 1.0e5 * (length / l0 - 1.0) * f / length < force:
            lo = f
        else:
            hi = f
    return 0.5 * (lo + hi)


def _steep(off: float, sway: float):
    """A chain of three nodes from the origin to (off, 0, 10) (a rope ``off`` from the
    vertical), its middle node ``sway`` to the side of the chord, along x."""
    x = np.array([[0.0, 0.0, 0.0], [0.5 * off + sway, 0.0, 5.0], [off, 0.0, 10.0]])
    net = SimpleNamespace(edges=np.array([[0, 1], [1, 2]]))
    return sag(net, x)


def test_a_steep_chord_has_no_vertical_sag_where_the_vertical_misses_it():
    """A rope hung 0.1 mm off the vertical, its middle 5.6 mm to the side: the vertical
    through the middle meets the chord's plane nowhere between its ends (the plan of the
    chord is 0.1 mm long), so there is no vertical sag (the summary read 557 m); the normal
    sag is the sway. A stay at 45 degrees sagging 0.1 m normal to its chord has a vertical
    sag of 0.1 sqrt(2): its middle's vertical meets the chord between the ends."""
    steep = _steep(1e-4, -5.6e-3)
    assert steep["normal"] == pytest.approx(5.6e-3, rel=1e-6)
    assert math.isnan(steep["vertical"]) and math.isnan(steep["rise"])
    x = np.array([[0.0, 0.0, 0.0], [5.0 + 0.1 / math.sqrt(2), 0.0, 5.0 - 0.1 / math.sqrt(2)],
                  [10.0, 0.0, 10.0]])  # fmt: skip
    stay = sag(SimpleNamespace(edges=np.array([[0, 1], [1, 2]])), x)
    assert stay["normal"] == pytest.approx(0.1, rel=1e-12)
    assert stay["vertical"] == pytest.approx(0.1 * math.sqrt(2.0), rel=1e-12)
    assert stay["rise"] == 0.0


def test_a_post_bent_sideways_has_no_vertical_sag_or_rise():
    """A post 2.5 m high whose top moved 16.7 mm sideways and whose middle bowed 2.5 mm
    off its chord: the chord stands 89.6 degrees from the horizontal, and the vertical
    distance of the middle from it, 370 mm "above it" in the summary, was the normal
    2.5 mm over cos(89.6 degrees), whatever the load. Beyond 80 degrees no vertical sag is
    measured; a chord at 79 degrees still has one."""
    x = np.array([[0.0, 0.0, 0.0], [0.00835 + 0.0025, 0.0, 1.25], [0.0167, 0.0, 2.5]])
    post = sag(SimpleNamespace(edges=np.array([[0, 1], [1, 2]])), x)
    assert post["normal"] == pytest.approx(0.0025, rel=1e-3)
    assert math.isnan(post["vertical"]) and math.isnan(post["rise"])
    run = 2.5 / math.tan(math.radians(79.0))
    x = np.array([[0.0, 0.0, 0.0], [0.5 * run, 0.0, 1.25 - 0.01], [run, 0.0, 2.5]])
    stay = sag(SimpleNamespace(edges=np.array([[0, 1], [1, 2]])), x)
    assert stay["vertical"] == pytest.approx(0.01, rel=1e-12)
