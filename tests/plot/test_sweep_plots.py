"""catenet plot DIR --x KEY --y COLUMN: a sweep over pretension with --modes and one over
drop height, plotted from the command line. Each figure's lines are the table's columns
(results.csv, read here with the csv module) against the swept key, one line per value of
the other keys, its axes named with units; a name the table lacks exits 2 and lists what
can be plotted. The utilisation column is there where a material gives a breaking load.
The paper's report is written only for a sweep of the square net over n and alpha."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.model import design
from catenet.plot.sweep import Table, is_square_net_sweep

STAY = """
title = "prestressed stay"
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [20, 0, 0]
nodes = 21
[material]
EA = 2e7
area = 1e-4
density = 7850.0
prestress = 2000.0
breaking_load = 1.2e5
[load]
gravity = [0, 0, -9.81]
"""

DROP = """
title = "a 2 kg ball dropped on a prestressed cable"
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [2, 0, 0]
nodes = 11
[material]
EA = 1e5
radius = 0.005
density = 7850.0
prestress = 500.0
[load]
gravity = [0, 0, -9.81]
[[obstacle]]
kind = "sphere"
center = [1.0, 0.0, 0.3]
radius = 0.1
mass = 2.0
[solver]
method = "dynamic"
dt = 0.005
t_end = 0.4
"""

PRESTRESS = [1000.0, 2000.0, 4000.0, 8000.0]
HEIGHTS = [0.15, 0.3, 0.6]


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def rows(directory):
    with open(directory / "results.csv", newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture
def saved(monkeypatch):
    """The figures the command draws, kept instead of (and as well as) written."""
    from matplotlib.figure import Figure

    figures = []
    save = Figure.savefig

    def keep(self, path, **kw):
        figures.append(self)
        save(self, path, **kw)

    monkeypatch.setattr(Figure, "savefig", keep)
    return figures


@pytest.fixture(scope="module")
def stays(tmp_path_factory):
    """The stay swept over pretension and EA, with its two lowest frequencies."""
    d = tmp_path_factory.mktemp("stay")
    (d / "stay.toml").write_text(STAY)
    values = ",".join(map(str, PRESTRESS))
    res = invoke(
        "sweep", d / "stay.toml", "-p", f"material.prestress={values}", "-p",
        "material.EA=2e7,4e7", "--modes", 2, "-o", d / "s", "-j", 1, "-q",
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    return d / "s"


@pytest.fixture(scope="module")
def drops(tmp_path_factory):
    """The ball dropped from three heights: an array-valued key, plotted by element."""
    d = tmp_path_factory.mktemp("drop")
    (d / "drop.toml").write_text(DROP)
    centres = ",".join(f"[1,0,{h}]" for h in HEIGHTS)
    res = invoke(
        "sweep", d / "drop.toml", "-p", f"obstacle.0.center={centres}", "-o", d / "s", "-j", 1, "-q"
    )
    assert res.exit_code == 0, res.output
    return d / "s"


def axis(fig, ylabel):
    return next(a for a in fig.axes if a.get_ylabel() == ylabel)


def test_pretension_sweep_frequencies_and_utilisation_against_pretension(stays, saved):
    res = invoke(
        "plot",
        stays,
        "--x",
        "material.prestress",
        "--y",
        "f1",
        "--y",
        "f2",
        "--y",
        "max_utilisation",
    )
    assert res.exit_code == 0, res.output
    path = stays / "sweep_f1_f2_max_utilisation_vs_material.prestress.png"
    assert res.output.split() == [str(path)] and path.stat().st_size > 20_000
    (fig,) = saved
    table = rows(stays)
    for column, label in (
        ("f1", "natural frequency f1 [Hz]"),
        ("f2", "natural frequency f2 [Hz]"),
        ("max_utilisation", "largest utilisation F_Ed / F_Rd [-]"),
    ):
        ax = axis(fig, label)
        assert ax.get_xlabel() == "material.prestress [N]"
        assert [line.get_label() for line in ax.get_lines()] == [
            "material.EA = 20000000.0",
            "material.EA = 40000000.0",
        ]
        for line, EA in zip(ax.get_lines(), ("20000000.0", "40000000.0"), strict=True):
            mine = [r for r in table if r["material.EA"] == EA]
            assert list(line.get_xdata()) == PRESTRESS
            assert list(line.get_ydata()) == [float(r[column]) for r in mine]
    # the string's frequency grows with its tension: f1 ~ sqrt(T / mu) / (2 L)
    f1 = np.array([float(r["f1"]) for r in table if r["material.EA"] == "20000000.0"])
    T = np.array([float(r["max_tension"]) for r in table if r["material.EA"] == "20000000.0"])
    assert np.all(np.diff(f1) > 0)
    mu = 7850.0 * 1e-4
    np.testing.assert_allclose(f1, np.sqrt(T / mu) / 40.0, rtol=0.05)
    # the utilisation column: EN 1993-1-11's rule on the largest tension, defaults of [design]
    u = np.array([float(r["max_utilisation"]) for r in table])
    t_max = np.array([float(r["max_tension"]) for r in table])
    rd = design.K_E * 1.2e5 / (design.BREAKING_FACTOR * design.GAMMA_R)
    np.testing.assert_allclose(u, t_max / rd, rtol=1e-12)
    assert {r["max_utilisation_cable"] for r in table} == {""}  # a single cable: no names


def test_default_figures_include_frequencies_and_utilisation(stays, monkeypatch):
    from matplotlib.figure import Figure

    saved = []
    monkeypatch.setattr(Figure, "savefig", lambda self, path, **kw: saved.append(self))
    res = invoke("plot", stays, "-o", stays / "all")
    assert res.exit_code == 0, res.output
    assert res.output.split() == [
        str(stays / "all" / "sweep_material.prestress.png"),
        str(stays / "all" / "sweep_material.EA.png"),
    ]
    ylabels = {a.get_ylabel() for a in saved[0].axes}
    assert {"natural frequency f1 [Hz]", "largest utilisation F_Ed / F_Rd [-]"} <= ylabels
    assert not (stays / "all" / "report.md").exists()


def test_drop_height_sweep_by_element_of_the_balls_centre(drops, saved):
    res = invoke(
        "plot", drops, "--x", "obstacle.0.center[2]", "--y", "peak_tension", "--y",
        "peak_displacement", "-o", drops / "drop.svg",
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert res.output.split() == [str(drops / "drop.svg")]
    (fig,) = saved
    table = rows(drops)
    assert [json.loads(r["obstacle.0.center"])[2] for r in table] == HEIGHTS
    for column, label in (
        ("peak_tension", "peak tension over the run [N]"),
        ("peak_displacement", "peak displacement over the run [m]"),
    ):
        ax = axis(fig, label)
        assert ax.get_xlabel() == "obstacle.0.center[2] [m]"
        (line,) = ax.get_lines()
        assert list(line.get_xdata()) == HEIGHTS
        assert list(line.get_ydata()) == [float(r[column]) for r in table]
        # a higher drop pulls the cable harder and further
        assert np.all(np.diff(line.get_ydata()) > 0)
    # no breaking load anywhere: no utilisation columns
    assert "max_utilisation" not in table[0]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (
            ["--x", "material.prestres"],
            "not a column of the sweep's table (did you mean 'material.prestress'?)",
        ),
        (["--y", "f9"], "--y 'f9': not a column"),
        (["--x", "max_tension"], "not a swept key with numbers (--x takes the swept keys)"),
        (["--y", "error"], "its values are not numbers"),
    ],
)
def test_a_name_the_table_lacks_lists_what_can_be_plotted(stays, args, says):
    res = invoke("plot", stays, *args)
    assert res.exit_code == 2, res.output
    (line,) = res.output.strip().splitlines()
    assert line.startswith("catenet: error: ") and says in line
    assert "swept keys (--x): material.prestress, material.EA;" in line
    assert "columns (--y): delta, " in line and ", f1, f2" in line and "max_utilisation" in line


def test_an_array_key_is_plotted_by_element(drops):
    res = invoke("plot", drops, "--x", "obstacle.0.center", "--y", "peak_tension")
    assert res.exit_code == 2
    assert (
        "its values are arrays: give an element, obstacle.0.center[0] .. obstacle.0.center[2]"
        in res.output
    )
    res = invoke("plot", drops, "--x", "obstacle.0.center[3]")
    assert res.exit_code == 2 and "obstacle.0.center has 3 elements" in res.output


def test_labels_follow_the_cases_units(stays):
    table = Table.read(stays)
    table.units = "kN-m"
    assert table.label("max_tension") == "largest tension [kN]"
    assert table.label("material.prestress") == "material.prestress [kN]"
    table.units = "N-mm"
    assert table.label("max_displacement") == "largest displacement [mm]"
    assert table.label("material.prestress") == "material.prestress [N]"


def test_the_papers_report_only_for_a_square_net_over_n_and_alpha(tmp_path):
    def journal(kind, keys):
        d = tmp_path / "-".join([kind, *keys])
        d.mkdir()
        header = {
            "catenet_sweep": 1,
            "base": {"geometry": {"kind": kind}},
            "params": [[k, [1, 2]] for k in keys],
        }
        (d / "results.jsonl").write_text(json.dumps(header) + "\n")
        return d

    assert is_square_net_sweep(journal("square_net", ["geometry.n", "geometry.alpha"]))
    assert not is_square_net_sweep(journal("square_net", ["load.pressure"]))
    assert not is_square_net_sweep(journal("square_net", ["geometry.n"]))
    assert not is_square_net_sweep(journal("graph", ["geometry.n", "geometry.alpha"]))
