"""A tension-only net's end state that is neutral is warned, as a bilateral one's is
(docs/guide/stability.md): tension-only stiffness is never negative, so such nets were
not judged at all, and a prestressed cable whose two ends stand on rollers (its normals
vertical: nothing holds the cable along its chord) slid both ends together and hung
doubled, its prestress gone, "converged" in silence (a load tilted by 1e-9 sent it 4e4 m
away). The same warning from the exact geometry and from starts moved by round-off, and
none on a cable its pins hold."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main


def cable(seed: int = 0, *, rollers: bool = True) -> dict:
    """A 10 m cable of 11 nodes, prestressed to 1 kN, 100 N down at midspan; its ends on
    rollers with vertical normals (or pinned). ``seed``: its ends moved by up to 1e-9 m."""
    start, end = np.array([0.0, 0.0, 0.0]), np.array([10.0, 0.0, 0.0])
    if seed:
        rng = np.random.default_rng(seed)
        start, end = start + rng.uniform(-1e-9, 1e-9, 3), end + rng.uniform(-1e-9, 1e-9, 3)
    supports: dict = {"fixed": []}
    if rollers:
        supports["roller"] = [{"nodes": ["start", "end"], "normal": [0.0, 0.0, 1.0]}]
    else:
        supports["fixed"] = ["start", "end"]
    return {
        "title": "a cable on rollers",
        "geometry": {"kind": "cable", "start": start.tolist(), "end": end.tolist(), "nodes": 11},
        "material": {"EA": 1e6, "prestress": 1000.0},
        "supports": supports,
        "load": {"point": [{"node": "midpoint", "force": [0.0, 0.0, -100.0]}]},
    }


def run(tmp_path, data: dict):
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    return CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "out.h5")])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_cable_on_rollers_that_leave_its_chord_free_is_warned_neutral(tmp_path, seed):
    done = run(tmp_path, cable(seed))
    assert done.exit_code == 0, done.output
    assert "the equilibrium is neutral" in done.output, done.output
    assert "rigid-body motion" in done.output


def test_a_pinned_cable_is_not_warned_neutral(tmp_path):
    done = run(tmp_path, cable(rollers=False))
    assert done.exit_code == 0, done.output
    assert "neutral" not in done.output and "WARNING" not in done.output, done.output
