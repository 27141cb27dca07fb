"""The summary's reactions when the supports hold moments alone: a shaft turned at its
clamp and held at its far end by a coupling (a 6x6 spring) has no support that holds a
force in the summary's sense, and its moment line stood under the `loads` line without a
label of its own."""

from __future__ import annotations

import math

import pytest
from click.testing import CliRunner

from catenet.cli import main

SHAFT = """
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [1.5, 0.0, 0.0]
nodes = 31

[material]
E = 210e9
G = 80e9
radius = 0.025
EI = "section"
GJ = "section"

[supports]
fixed = ["start"]
clamped = ["start"]

[[supports.twist]]
nodes = ["start"]
angle = 0.05

[[supports.spring]]
nodes = "end"
stiffness = [1e9, 1e9, 1e9, 3.0e4, 1e6, 1e6]
"""


def test_a_shafts_torque_at_its_supports_is_labelled_reactions(tmp_path):
    """The torque phi / (L / GJ + 1 / k_t) on its own `reactions` line."""
    case = tmp_path / "shaft.toml"
    case.write_text(SHAFT)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "s.h5")])
    assert done.exit_code == 0, done.output
    gj = 80e9 * math.pi * 0.025**4 / 2.0
    torque = 0.05 / (1.5 / gj + 1.0 / 3.0e4)
    line = next(x for x in done.output.splitlines() if "moment largest" in x)
    assert line.startswith("reactions")
    assert float(line.split("moment largest")[1].split()[0]) == pytest.approx(torque, rel=1e-5)


BEAM = """
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [2.0, 0.0, 0.0]
nodes = 21

[material]
E = 210e9
radius = 0.02
EI = "section"
prestress = 1000.0

[[load.point]]
node = "midpoint"
force = [0.0, 0.0, -500.0]
"""


def test_a_rod_case_without_held_ends_writes_zero_moments(tmp_path):
    """/result/reaction_moment is (N, 3) in every case with rods (contract), zeros where no
    support holds a rod end's direction: a pinned beam's file had none, and a script
    reading it failed with a KeyError."""
    import h5py
    import numpy as np

    case = tmp_path / "beam.toml"
    case.write_text(BEAM)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "b.h5")])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "b.h5") as f:
        moment = f["result/reaction_moment"][()]
        assert moment.shape == f["result/x"].shape
        assert np.all(moment == 0.0)
        assert np.abs(f["result/bending_moment"][()]).max() > 0.0
