"""A mooring line's records over time (catenet.model.lines, /history, catenet report):
the anchor's uplift angle and the touchdown point at every step, each line's least and
largest tension, snap events and the spectrum of the fairlead tension."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.model.lines import Lines, line_paths, snaps, spectral_summary, spectrum
from catenet.output.history import read_history

ROOT = Path(__file__).resolve().parents[2]
MOORING = ROOT / "configs" / "water" / "mooring_surge.toml"


def test_a_lines_path_uplift_and_touchdown():
    """The path runs from the lower end whatever the edges' order; uplift is the first
    edge's angle above the horizontal; touchdown the arc length to the last grounded
    node of the stretch from the anchor."""
    nodes = np.array([[0, 0, 10.0], [3, 0, 6.0], [6, 0, 0.0], [9, 0, 0.0], [12, 0, 0.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4]])
    rest = np.array([5.0, 7.0, 3.0, 3.0])
    (path,) = line_paths(nodes, edges, rest, np.zeros(4, int))
    assert path.nodes.tolist() == [4, 3, 2, 1, 0]
    assert path.arc.tolist() == [0.0, 3.0, 6.0, 13.0, 18.0]
    assert path.uplift(nodes) == pytest.approx(0.0)
    lifted = nodes.copy()
    lifted[3, 2] = 3.0
    assert path.uplift(lifted) == pytest.approx(45.0)
    grounded = np.array([False, False, True, True, False])
    assert path.touchdown(grounded) == 6.0  # nodes 3 and 2 on the ground
    assert path.touchdown(np.zeros(5, bool)) == 0.0  # lifted at the anchor
    assert path.touchdown(np.ones(5, bool)) == 18.0
    lines = Lines([path, None, path])  # all at once, a line without edges among them
    t = np.array([1.0, 5.0, -2.0, 3.0])
    assert lines.tension_range(t).tolist() == [[-2.0, 5.0], [0.0, 0.0], [-2.0, 5.0]]
    assert lines.uplift(lifted) == pytest.approx([45.0, 0.0, 45.0])
    for g in (grounded, np.zeros(5, bool), np.ones(5, bool)):
        assert lines.touchdown(g).tolist() == [path.touchdown(g), 0.0, path.touchdown(g)]


def test_snaps_and_spectrum_of_records():
    """Snap events are the returns from slack to taut; the spectrum of a sine peaks at
    its period and its 4 sqrt(m0) is 4 A / sqrt(2) (Welch's area is the variance)."""
    t = np.linspace(0.0, 10.0, 11)
    least = np.array([5.0, 0.0, 0.0, 3.0, 1e-9, 4.0, 4.0, 0.0, 2.0, 2.0, 0.0])
    assert snaps(t, least, 1e4).tolist() == [3.0, 5.0, 8.0]  # 1e-9 <= 1e-6 x 1e4: slack
    assert snaps(t, least, 1e-4).tolist() == [3.0, 8.0]  # 1e-9 > 1e-6 x 1e-4: taut
    time = np.arange(0.0, 1200.0, 0.05)
    f, p = spectrum(time, 1e5 + 3e4 * np.sin(2 * math.pi * time / 12.0))
    period, sig = spectral_summary(f, p)
    assert period == pytest.approx(12.0, rel=0.05)
    assert sig == pytest.approx(4 * 3e4 / math.sqrt(2), rel=0.02)
    assert spectrum(time[:10], time[:10])[0].size == 0
    short = np.arange(0.0, 3.0, 0.05)  # a 3 s record of a 9 s motion: no peak to tell
    period, sig = spectral_summary(*spectrum(short, np.sin(2 * math.pi * short / 9.0)))
    assert math.isnan(period) and sig > 0.0


def test_the_mooring_chain_records_its_touchdown_uplift_and_tension_range(tmp_path):
    """configs/water/mooring_surge.toml (coarse, 10 s): every step's row has the chain's
    tension range (the /result tensions' at the end), its uplift angle at the anchor
    (on the seabed: about 0) and its touchdown point, which moves away from the anchor
    as the fairlead surges toward it; catenet report shows the lines' table."""
    out = tmp_path / "m.h5"
    args = ["run", str(MOORING), "-o", str(out), "-q", "--set", "solver.t_end=10"]
    args += ["--set", "geometry.edge_length=20"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    h = read_history(out)
    assert h is not None and h.touchdown is not None
    assert h.cable_tension_range.shape == (len(h.time), 1, 2)
    import h5py

    with h5py.File(out) as f:
        final = f["result/tension"][:]
        assert f["history/anchor_uplift"].attrs["unit"] == "deg"
        assert f["history/touchdown"].attrs["unit"] == "m"
    assert h.cable_tension_range[-1, 0].tolist() == pytest.approx([final.min(), final.max()])
    assert np.all(np.abs(h.anchor_uplift) < 0.1)
    down = h.touchdown[:, 0]
    assert 560.0 < down[0] < 700.0  # 800 m of chain, about 155 m suspended
    assert down.max() - down[0] > 19.0  # by an edge of 20 m
    rep = CliRunner().invoke(main, ["report", str(out), "-o", "-"])
    assert rep.exit_code == 0, rep.output
    assert "Lines over time" in rep.output and "| chain |" in rep.output


def test_a_slack_line_snaps(tmp_path):
    """A short taut tether whose top heaves down faster than it can follow goes slack
    and snaps taut again: the history's least tension shows it, and the summary and the
    report count the same events."""
    case = tmp_path / "snap.toml"
    case.write_text(
        """
[geometry]
kind = "cable"
start = [0.0, 0.0, -20.0]
end = [0.0, 0.0, -2.0]
nodes = 10
[material]
EA = 2e6
radius = 0.02
density = 1140.0
prestress = 200.0
tension_only = true
cd_n = 1.2
cd_t = 0.01
ca_n = 1.0
[water]
density = 1025.0
[load]
gravity = [0.0, 0.0, -9.81]
[[supports.vessel]]
nodes = ["end"]
sine = [{ amplitude = [0.0, 0.0, 0.3, 0.0, 0.0, 0.0], period = 1.0 }]
ramp = 0.5
[[obstacle]]
kind = "plane"
point = [0.0, 0.0, -21.0]   # the seabed, 1 m below the anchor: never reached
[solver]
method = "dynamic"
initial_state = "equilibrium"
dt = 0.005
t_end = 3.0
"""
    )
    out = tmp_path / "s.h5"
    res = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert res.exit_code == 0, res.output
    h = read_history(out)
    low, high = h.cable_tension_range[:, 0, 0], h.cable_tension_range[:, 0, 1]
    events = snaps(h.time, low, high.max())
    assert events.size >= 2
    said = next(x for x in res.output.splitlines() if x.startswith("line "))
    assert f"to {high.max():.6g} N" in said and f", {events.size} snap events" in said, said
    assert f"(first at t = {events[0]:.4g} s)" in said, said
    assert said.endswith("no touchdown (off the seabed from its anchor)"), said
    touch = next(x for x in res.output.splitlines() if x.startswith("contact "))
    assert touch.endswith("(obstacles, bodies and the water)"), touch  # buoyancy, drag
    assert (low == 0.0).any() and high.max() > 3 * 200.0  # the snap loads
    rep = CliRunner().invoke(main, ["report", str(out), "-o", "-"])
    lines = rep.output.split("Lines over time")[1].splitlines()
    row = next(r for r in lines if r.startswith("| cable |"))
    assert row.split("|")[6].strip() == str(events.size)


def test_a_roof_nets_cables_have_no_lines_table(tmp_path):
    """A dynamic run out of water with named cables (a rope swinging under its weight):
    its report has no "Lines over time" (an anchor's uplift, a touchdown, a fairlead's
    spectrum mean nothing there; a roof net's report showed them), as the run's summary
    shows lines in water only."""
    case = tmp_path / "rope.toml"
    case.write_text(
        """
[geometry]
kind = "graph"
nodes = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]]
edge_length = 0.5
fixed = [0]
[[geometry.cable]]
name = "rope"
nodes = [0, 1]
[material]
EA = 1e5
density = 1000.0
area = 1e-4
[load]
gravity = [0.0, 0.0, -9.81]
[solver]
method = "dynamic"
t_end = 0.2
"""
    )
    out = tmp_path / "r.h5"
    res = CliRunner().invoke(main, ["run", str(case), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    rep = CliRunner().invoke(main, ["report", str(out), "-o", "-"])
    assert rep.exit_code == 0, rep.output
    assert "Lines over time" not in rep.output
