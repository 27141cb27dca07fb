"""A case in kN-m or N-mm is reported and drawn in its own units: the numbers are the
file's (the case's), and every label names the case's units (kN, kPa; mm, MPa), never
SI names for numbers that are not in SI."""

from __future__ import annotations

import re

import matplotlib
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main
from catenet.model.units import relabel, unit_in

matplotlib.use("Agg")

#: A cross of two prestressed cables, anticlastic, in kN and m: a ridge sagging under
#: snow, a valley holding the uplift.
CROSS = {
    "title": "cross of cables, kN-m",
    "units": "kN-m",
    "geometry": {
        "kind": "graph",
        "nodes": [[5, 5, 0.0], [5, 0, 1.0], [5, 10, 1.0], [0, 5, -1.0], [10, 5, -1.0]],
        "edges": [],
        "fixed": [1, 2, 3, 4],
        "cable": [
            {"name": "ridge", "nodes": [1, 0, 2], "prestress": 50.0},
            {"name": "valley", "nodes": [3, 0, 4], "prestress": 50.0},
        ],
    },
    "material": {"EA": 2.0e4, "breaking_load": 400.0},
    "load_case": [{"name": "snow", "point": [{"node": 0, "force": [0.0, 0.0, -20.0]}]}],
}


@pytest.fixture(scope="module")
def cross(tmp_path_factory):
    d = tmp_path_factory.mktemp("units")
    (d / "cross.toml").write_text(dumps_toml(CROSS))
    res = CliRunner().invoke(main, ["run", str(d / "cross.toml"), "-o", str(d / "cross.h5")])
    assert res.exit_code == 0, res.output
    return d / "cross.h5"


def test_unit_names_follow_the_system_part_by_part():
    assert unit_in("N/m", "kN-m") == "kN/m" and unit_in("N m", "N-mm") == "N mm"
    assert unit_in("m/s^2", "N-mm") == "mm/s^2" and unit_in("kg", "kN-m") == "t"
    assert unit_in("J", "N-mm") == "mJ" and unit_in("Pa", "kN-m") == "kPa"
    line = "tension 12.5 N at [1, 2, 3] m; Rx [N], slack length [m], [design] factors"
    assert relabel([line], "kN-m") == [
        "tension 12.5 kN at [1, 2, 3] m; Rx [kN], slack length [m], [design] factors"
    ]
    assert relabel([line], "SI") == [line]
    rods = "rods         largest moment 2.5 N m at node 4 (curvature 0.00332 1/m there)"
    assert relabel([rods], "N-mm") == [
        "rods         largest moment 2.5 N mm at node 4 (curvature 0.00332 1/mm there)"
    ]


def test_a_kn_m_case_is_reported_in_kn(cross, tmp_path):
    out = tmp_path / "cross.md"
    res = CliRunner().invoke(main, ["report", str(cross), "-o", str(out)])
    assert res.exit_code == 0, res.output
    md = out.read_text()
    assert "max tension [kN]" in md and "Rx [kN]" in md and "Fz [kN]" in md, md
    assert "max displacement [m]" in md
    assert not re.search(r"\[N\]", md), [x for x in md.splitlines() if "[N]" in x]


def test_a_kn_m_case_is_drawn_in_kn(cross):
    from matplotlib.text import Text

    from catenet.output import read_result
    from catenet.plot.figure import figure, in_units

    res = read_result(cross)
    fig = figure(res)
    in_units(fig, res.case.get("units"))
    texts = [t.get_text() for t in fig.findobj(Text) if t.get_text()]
    assert any("[kN]" in t for t in texts), texts
    assert not any(re.search(r"\[N\]|\d N\b", t) for t in texts), texts
