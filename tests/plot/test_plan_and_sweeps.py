"""What catenet plot shows an engineer: slack edges in their own colour, a static run's
load-deflection curve from zero load, a plan view of a graph coloured by displacement
with the reactions as arrows, and for any sweep each output column against each swept
parameter (the paper's report only for the square net)."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import CONFIGS

from catenet.case import dumps_toml, parse_case
from catenet.cli import main
from catenet.output import read_result
from catenet.plot.figure import figure
from catenet.plot.plan import SLACK_COLOUR, slack_edges
from catenet.run.runner import run_case

MAST = CONFIGS / "structures" / "guyed_mast.toml"


def panel(fig, title):
    return next(ax for ax in fig.axes if ax.get_title() == title)


def test_graph_plan_view_reactions_and_load_curve_from_zero(tmp_path):
    run_case(parse_case(tomllib.loads(MAST.read_text())), tmp_path / "m.h5")
    res = read_result(tmp_path / "m.h5")
    fig = figure(res)
    plan = panel(fig, "plan view")
    labels = [t.get_text() for t in plan.get_legend().get_texts()]
    assert any(s.startswith("reactions (horizontal part; largest |R|") for s in labels)
    u = np.linalg.norm(res.x - res.mesh.nodes, axis=1)
    assert f"node 1 moves most: {u[1]:.4g} m" in labels
    quiver = [c for c in plan.collections if type(c).__name__ == "Quiver"]
    assert len(quiver) == 1 and len(quiver[0].U) == int(res.mesh.fixed.sum())
    # the arrows are the reactions' horizontal parts: the windward anchor pulls hardest
    r = res.reaction[res.mesh.fixed]
    assert np.allclose(
        quiver[0].U / quiver[0].U[np.argmax(np.abs(quiver[0].U))],
        r[:, 0] / r[np.argmax(np.abs(r[:, 0])), 0],
    )
    # a graph's load curve: how far its probe (the top) moves, from zero load
    ax = panel(fig, "probe displacement against load")
    curve = ax.lines[0]
    assert ax.get_ylabel() == "displacement |x - X| of node 1 [m]"
    assert curve.get_xdata()[0] == 0.0 and curve.get_ydata()[0] == 0.0
    assert list(curve.get_xdata()[1:]) == [0.5, 1.0]
    assert curve.get_ydata()[-1] == pytest.approx(u[1], rel=1e-12)


def test_slack_edges_have_their_own_colour(tmp_path):
    """A cable whose support moves 0.8 m inwards hangs slack: its edges are drawn dotted
    in the slack colour and counted in the legend."""
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [4, 0, 0], [0, 1, 0], [4, 1, 0]],
            "edge_length": 1.0,
            "sets": {"moved": [3]},
            "cable": [
                {"name": "taut", "nodes": [0, 1], "prestress": 100.0},
                {"name": "loose", "nodes": [2, 3]},
            ],
            "fixed": [0, 1, 2, 3],
        },
        "supports": {"move": [{"node": "moved", "displacement": [-0.8, 0, 0]}]},
        "material": {"EA": 1e5},
        "load": {"point": [{"cable": "taut", "at": 0.5, "force": [0, 0, -10.0]}]},
    }
    run_case(parse_case(data), tmp_path / "s.h5")
    res = read_result(tmp_path / "s.h5")
    slack = slack_edges(res)
    assert slack.sum() == 4
    side = panel(figure(res), "side view")
    labels = [t.get_text() for t in side.get_legend().get_texts()]
    assert "slack edges (4)" in labels
    dotted = [c for c in side.collections if c.get_label() == "slack edges (4)"]
    assert len(dotted) == 1 and len(dotted[0].get_segments()) == 4
    from matplotlib.colors import to_rgba

    assert tuple(dotted[0].get_colors()[0]) == to_rgba(SLACK_COLOUR)


def test_any_sweep_gets_its_columns_plotted_and_no_paper_report(tmp_path):
    out = tmp_path / "s"
    r = CliRunner().invoke(
        main,
        [
            "sweep",
            str(MAST),
            "-p",
            "material.EA=1e7,2e7,4e7",
            "-p",
            "geometry.edge_length=5,10",
            "-o",
            str(out),
            "-j",
            "1",
        ],
    )
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["plot", str(out)])
    assert r.exit_code == 0, r.output
    files = r.output.split()
    assert files == [
        str(out / "sweep_material.EA.png"),
        str(out / "sweep_geometry.edge_length.png"),
    ]
    assert not (out / "report.md").exists()
    from catenet.plot.sweep import OUTPUTS, plot_columns

    assert "max_displacement" in OUTPUTS and "max_tension" in OUTPUTS
    assert plot_columns(out, tmp_path / "again") == [
        tmp_path / "again" / "sweep_material.EA.png",
        tmp_path / "again" / "sweep_geometry.edge_length.png",
    ]


def test_sweep_panels_hold_the_table(tmp_path, monkeypatch):
    """The panels are the table's columns against the parameter, one line per value of
    the other parameter."""
    out = tmp_path / "s"
    data = tomllib.loads(MAST.read_text())
    case = tmp_path / "mast.toml"
    case.write_text(dumps_toml(data))
    r = CliRunner().invoke(
        main, ["sweep", str(case), "-p", "material.EA=1e7,2e7,4e7", "-o", str(out), "-j", "1"]
    )
    assert r.exit_code == 0, r.output
    import csv

    from matplotlib.figure import Figure

    saved = []
    monkeypatch.setattr(Figure, "savefig", lambda self, path, **kw: saved.append(self))
    from catenet.plot.sweep import plot_columns

    plot_columns(out)
    (fig,) = saved
    ax = next(a for a in fig.axes if a.get_ylabel() == "largest displacement [m]")
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    line = ax.lines[0]
    assert list(line.get_xdata()) == [1e7, 2e7, 4e7]
    assert list(line.get_ydata()) == [float(r["max_displacement"]) for r in rows]
