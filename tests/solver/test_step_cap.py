"""The step cap looks only as far as the line search goes (``Term.horizon``,
``Potential.max_step(..., upto)``): a free body's contact walks its nodes' paths in pieces
whose count grows with the distance, so it stops at ``upto``, and the line search asks
again only when it lengthens a step beyond what it knows. The same trajectory to the bit
as the search to 4^13 of every step, at about half its cost per step in the drop
(benchmarks/peers/mujoco_drop.toml: 2.8 s of CPU against 1.5 s at 0.4 s)."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np

import catenet.solver.linesearch as linesearch
from catenet.case import build, parse_case
from catenet.solver.path import solve
from catenet.solver.settings import Settings
from catenet.solver.workspace import Workspace

ROOT = Path(__file__).resolve().parents[2]


def drop(t_end: float = 0.15):
    case = tomllib.loads((ROOT / "benchmarks" / "peers" / "mujoco_drop.toml").read_text())
    case["solver"]["t_end"] = t_end
    return build(parse_case(case))


def test_a_body_contacts_cap_up_to_a_reach_is_the_full_one_below_it():
    """Up to a reach of a power of two the pieces are the full search's (the step, then
    doubling), so below it the cap is the same number; beyond it, none is claimed."""
    scene = drop()
    ws = Workspace(scene.net, terms=scene.terms)
    contact = next(t for t in ws.system.terms if t.horizon)
    x = scene.net.nodes.copy()
    rng = np.random.default_rng(3)
    for _ in range(20):
        dx = np.zeros_like(x)
        dx[~scene.net.fixed] = rng.normal(0.0, 0.05, (int((~scene.net.fixed).sum()), 3))
        full = contact.max_step(x, dx)
        for upto in (2.0, 4.0, 64.0):
            near = contact.max_step_within(x, dx, upto)
            if full < upto:
                assert near == full
            else:
                assert math.isinf(near) or near >= upto * (1 - 1e-12)


def test_the_drop_is_the_same_to_the_bit_whatever_the_first_reach(monkeypatch):
    scene = drop()
    runs = []
    for reach in (math.inf, linesearch.REACH):
        monkeypatch.setattr(linesearch, "REACH", reach)
        r = solve(scene, Settings.of(scene.case.solver))
        runs.append((r.x.copy(), r.v.copy(), r.iterations))
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])
    assert runs[0][2] == runs[1][2]
