"""Each cable's peak tension over the run (issue 23: the capture's peak tether load):
``/result/cable_peak_tension`` and ``cable_peak_tension_time`` beside
``cable_max_tension``, the summary numbers' ``cables[name]["peak_tension"]`` and the
cable's printed line when the peak is above its final max tension."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import load_case
from catenet.cli import main
from catenet.run.runner import run_case

CONFIGS = Path(__file__).parents[2] / "configs"

# A 2 kg payload flies away from its anchor at 3 m/s on a tether 10 % longer than its
# chord: the tether snaps taut and throws it back into a prestressed stay on the other
# side. Frames every 7th step only: they miss the snap.
TETHER = """\
title = "a payload snaps its tether taut"

[geometry]
kind = "graph"
nodes = [[0, 0, 0], [2, 0, 0], [6, 0, 0]]
edges = []
fixed = [0, 2]

[[geometry.cable]]
name = "tether"
nodes = [0, 1]
edge_length = 0.5
rest_length = [0.55, 0.55, 0.55, 0.55]

[[geometry.cable]]
name = "stay"
nodes = [1, 2]
edge_length = 1.0
prestress = 20.0

[material]
EA = 1.0e4
density = 1000.0
radius = 0.002

[[mass]]
node = 1
mass = 2.0
velocity = [3.0, 0.0, 0.0]

[solver]
method = "dynamic"
dt = 0.005
t_end = 0.8
damping = 0.0

[output]
file = "out/tether.h5"
every = 7
"""


def cable_lines(output: str) -> dict[str, str]:
    return {s.split()[1].rstrip(":"): s for s in output.splitlines() if s.startswith("cable ")}


def test_each_cables_peak_is_its_edges_peak_over_every_step(tmp_path):
    (tmp_path / "tether.toml").write_text(TETHER)
    out = tmp_path / "tether.h5"
    result = run_case(load_case(tmp_path / "tether.toml"), out)
    with h5py.File(out, "r") as f:
        names = [str(n) for n in f["mesh"].attrs["cable_names"]]
        cable = f["mesh/cable"][()]
        peak = f["result/peak_tension"][()]
        peak_time = f["result/peak_tension_time"][()]
        per = f["result/cable_peak_tension"][()]
        per_time = f["result/cable_peak_tension_time"][()]
        final = f["result/cable_max_tension"][()]
        frames = f["trajectory/tension"][()]
    assert names == ["tether", "stay"] and per.shape == per_time.shape == (2,)
    numbers = result.report.summary["cables"]
    for k, name in enumerate(names):
        edges = np.flatnonzero(cable == k)
        e = edges[np.argmax(peak[edges])]
        assert per[k] == peak[edges].max() and per_time[k] == peak_time[e]
        assert np.all(per[k] >= frames[:, edges])  # never below a stored frame
        assert per[k] > frames[:, edges].max()  # ... which miss the snap (every = 7)
        assert per[k] > 5 * final[k]  # the final state hides it
        c = numbers[name]
        assert c["peak_tension"] == per[k] and c["peak_tension_edge"] == e
        assert c["peak_tension_time"] == per_time[k]
    # the tether snaps first, the stay takes the payload thrown back
    assert 0.0 < per_time[0] < per_time[1] < 0.8
    # the largest of the cables' peaks is the run's
    assert per.max() == result.report.summary["peak_tension"]


def test_the_cable_line_prints_the_peak_where_it_is_above_the_final(tmp_path):
    (tmp_path / "tether.toml").write_text(TETHER)
    res = CliRunner().invoke(main, ["run", str(tmp_path / "tether.toml"), "-o",
                                    str(tmp_path / "t.h5")])  # fmt: skip
    assert res.exit_code == 0, res.output
    with h5py.File(tmp_path / "t.h5", "r") as f:
        per = f["result/cable_peak_tension"][()]
        when = f["result/cable_peak_tension_time"][()]
    lines = cable_lines(res.output)
    for k, name in enumerate(["tether", "stay"]):
        assert lines[name].startswith(
            f"cable        {name}: max tension 0 N, peak {per[k]:.6g} N at t = {when[k]:.4g} s,"
            " slack 100 % of its length"
        )
    # a static run: load factors, and no peak where the final state is the largest
    mast = CONFIGS / "structures" / "guyed_mast.toml"
    res = CliRunner().invoke(main, ["run", str(mast), "-o", str(tmp_path / "mast.h5")])
    assert res.exit_code == 0, res.output
    lines = cable_lines(res.output)
    assert "peak" not in lines["guy_windward"]  # loaded: the final state is its peak
    assert "peak" in lines["guy_leeward"] and "at load factor" in lines["guy_leeward"]
    with h5py.File(tmp_path / "mast.h5", "r") as f:
        names = [str(n) for n in f["mesh"].attrs["cable_names"]]
        per = dict(zip(names, f["result/cable_peak_tension"][()], strict=True))
        final = dict(zip(names, f["result/cable_max_tension"][()], strict=True))
    assert per["guy_windward"] == pytest.approx(final["guy_windward"], rel=1e-12)
    assert per["guy_leeward"] > final["guy_leeward"]
    assert f"peak {per['guy_leeward']:.6g} N" in lines["guy_leeward"]
