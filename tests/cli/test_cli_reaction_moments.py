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
