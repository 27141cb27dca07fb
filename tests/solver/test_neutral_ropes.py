"""The end states of tension-only nets (docs/guide/stability.md). Their stiffness is
never negative but for the terms that are not convex, so they were not judged at all:
- a neutral one is warned, as a bilateral net's is: a prestressed cable whose two ends
  stand on rollers (normals vertical: nothing holds it along its chord) slid both ends
  together and hung doubled, its prestress gone, "converged" in silence (a load tilted
  by 1e-9 sent it 4e4 m away); the same warning from starts moved by round-off, none on
  a cable its pins hold;
- an unstable one is refused (exit 1): a rope draped over a frictionless sphere, and a
  ball resting on a wire, would slide off (a curved barrier pushes the nodes pressed on
  it aside), and were called stable; with friction the rope rests."""

from __future__ import annotations

import math

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
    assert "neutral" not in done.output and "warning:" not in done.output, done.output


def drape(friction: float = 0.0, seed: int = 0) -> dict:
    """A rope (EA = 1e5 N, prestrained 1 %) draped over a sphere of radius 0.1 m from
    ends 0.2 m below its centre, 0.5 m to either side: two tangents and the arc between
    them; ``seed``: its free nodes moved by up to 1e-9 m."""
    a, end = 0.105, np.array([0.5, -0.2])
    turn = math.atan2(end[1], end[0]) + math.acos(a / float(np.linalg.norm(end)))
    touch = a * np.array([math.cos(turn), math.sin(turn)])
    right = [end + (touch - end) * s for s in np.linspace(0.0, 1.0, 12, endpoint=False)]
    arc = [a * np.array([math.cos(t), math.sin(t)]) for t in np.linspace(turn, math.pi - turn, 16)]
    points = np.array(right + arc + [p * [-1.0, 1.0] for p in right[::-1]])
    nodes = np.column_stack([points[:, 0], np.zeros(len(points)), points[:, 1]])
    if seed:
        nodes[1:-1] += np.random.default_rng(seed).uniform(-1e-9, 1e-9, nodes[1:-1].shape)
    return {
        "title": "a rope over a sphere",
        "geometry": {
            "kind": "graph",
            "nodes": nodes.tolist(),
            "edges": [[i, i + 1] for i in range(len(nodes) - 1)],
            "fixed": [0, len(nodes) - 1],
            "prestrain": 0.01,
        },
        "material": {"EA": 1e5, "radius": 0.002},
        "obstacle": [{"kind": "sphere", "center": [0.0] * 3, "radius": 0.1, "friction": friction}],
    }


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_rope_draped_over_a_frictionless_sphere_is_unstable(tmp_path, seed):
    done = run(tmp_path, drape(seed=seed))
    assert done.exit_code == 1, done.output
    assert "converged    no (an unstable equilibrium" in done.output
    assert "presses on obstacle[0] (kind 'sphere')" in done.output
    assert "would slide off it" in done.output and "compressed" not in done.output


def test_a_rope_draped_over_a_rough_sphere_rests(tmp_path):
    done = run(tmp_path, drape(friction=0.3))
    assert done.exit_code == 0, done.output
    assert "converged    yes" in done.output and "unstable" not in done.output


def test_a_ball_resting_on_a_wire_is_unstable(tmp_path):
    case = {
        "title": "a 2 kg ball resting on a steel wire",
        "geometry": {"kind": "cable", "start": [-1.0, 0, 0], "end": [1.0, 0, 0], "nodes": 21},
        "material": {"E": 2e11, "radius": 0.003, "density": 7850.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "sphere", "center": [0.0, 0.0, 0.3], "radius": 0.2, "mass": 2.0}],
    }
    done = run(tmp_path, case)
    assert done.exit_code == 1, done.output
    assert "unstable" in done.output and "would slide off it" in done.output
