"""A load step's start kept outside the obstacles (``static.solve_static``): moved
supports carry the free nodes with them (``start.start_state``), and a load path's
predictor extrapolates them; where that straight way from the last equilibrium meets
an obstacle, the nodes start short of it. Found on a newcomer's model: a prestressed
steel cord whose ends are moved 0.3 m down past a block under its middle. In one load
step it came to hang under the block ("converged"); in 10 or 40 load steps the start of
the step that brings it onto the block lay in the block's barrier, and every step
failed ("stagnated")."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main

CORD = """
title = "a cord's ends moved 0.3 m down past a block under its middle"

[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 9

[material]
E = 2e11
radius = 0.003
density = 7850.0
prestress = 1000.0

[load]
gravity = [0.0, 0.0, -9.81]

[[supports.move]]
node = "start"
displacement = [0.0, 0.0, -0.3]

[[supports.move]]
node = "end"
displacement = [0.0, 0.0, -0.3]

[[obstacle]]
kind = "box"
center = [0.0, 0.0, -0.13]
half_size = [0.37, 0.2, 0.1]
distance = 0.001
"""


@pytest.mark.parametrize("steps", [1, 10, 40])
def test_a_cord_pulled_down_over_a_block_lies_on_it(write_case, tmp_path, steps):
    """The three nodes over the block rest on its top (z = -0.03, within the barrier's
    distance), the others on the straight line from the last of them to the support,
    symmetric; no step ends on the block's far side. (Contact is at the nodes: the edge
    from the block's top to the support cuts its corner, and that is warned.)"""
    out = tmp_path / "o.h5"
    args = ["run", str(write_case(CORD)), "-o", str(out), "--set", f"solver.steps={steps}"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "far side" not in res.output and "edges cut" in res.output
    with h5py.File(out, "r") as f:
        x = f["result/x"][:]
        tension = f["result/tension"][:]
    top = x[3:6, 2]
    assert np.all(top > -0.03) and np.all(top < -0.03 + 0.001)
    assert np.allclose(x[:, 2], x[::-1, 2], atol=1e-9)  # symmetric
    slope = (x[8, 2] - x[5, 2]) / (x[8, 0] - x[5, 0])
    assert np.allclose(x[6:8, 2], x[5, 2] + slope * (x[6:8, 0] - x[5, 0]), atol=1e-5)
    assert np.ptp(tension[[5, 6, 7]]) < 1e-5 * tension.max()  # one tension to the support
