"""A static equilibrium far beyond the loads' linear response at the start is warned: a
buckling (limit) load was passed on the way (``catenet.solver.amplified``). A pinned
strut bowed by L/100000 at 1.006 times its Euler load ends on its post-buckled elastica,
bowed about 200 mm, stable: it converged with only "the equilibrium is neutral ...
which the loads do not drive" (wrong: they drive it); a portal out of plumb beyond its
sway buckling load swayed 1.6 m with no word at all. Below its buckling load, a
structure that stiffens (a cantilever bent far) and one in tension are not warned."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.solver.amplified import AMPLIFIED, amplification
from catenet.solver.path import Settings, solve

L, N = 3.0, 41  # m, nodes
SECTION = {"E": 210e9, "radius": 0.03, "inner_radius": 0.026, "EI": "section"}
EI = 210e9 * math.pi / 4.0 * (0.03**4 - 0.026**4)
EULER = math.pi**2 * EI / L**2  # 63.9 kN


def strut(share: float, bow: float = L / 1e5) -> dict:
    """The pinned strut, bowed by ``bow`` in z (a half sine), pushed along its axis on a
    slider by ``share`` of its Euler load."""
    s = np.linspace(0.0, L, N)
    nodes = np.column_stack([s, np.zeros(N), bow * np.sin(np.pi * s / L)])
    return {
        "geometry": {"kind": "graph", "nodes": nodes.tolist(),
                     "cable": [{"name": "strut", "nodes": list(range(N))}]},
        "material": {**SECTION, "density": 7850.0, "natural_curvature": "straight"},
        "supports": {"fixed": [0], "slider": [{"nodes": N - 1, "direction": [1.0, 0, 0]}]},
        "load": {"point": [{"node": N - 1, "force": [-share * EULER, 0.0, 0.0]}]},
    }  # fmt: skip


def run(case: dict, caplog) -> tuple:
    scene = build(parse_case(case))
    with caplog.at_level(logging.WARNING):
        result = solve(scene, Settings.of(scene.case.solver))
    return result, [r.getMessage() for r in caplog.records]


def test_a_strut_past_its_euler_load_is_said_to_have_passed_a_buckling_load(caplog):
    result, said = run(strut(1.006), caplog)
    assert result.converged and np.abs(result.x[:, 2]).max() > 0.1  # bowed ~0.2 m
    (far,) = [m for m in said if "as far as the loads' linear response" in m]
    assert "passed a buckling (limit) load" in far
    assert not [m for m in said if "the equilibrium is neutral" in m]  # (it said so)
    assert "moved 195 times as far" in far  # (docs/guide/stability.md quotes it)


@pytest.mark.parametrize("share", [0.5, 0.9])
def test_a_strut_below_its_euler_load_is_not_warned(share, caplog):
    """Its bow is amplified 1 / (1 - P / Pcr), tenfold at 0.9: a small share of its
    motion (the axial shortening), within twice the linear step."""
    result, said = run(strut(share), caplog)
    assert result.converged
    assert not [m for m in said if "linear response" in m]


def test_a_cantilever_bent_far_and_a_net_in_tension_are_not_warned(caplog):
    """A cantilever under an end load 10 EI / L^2 bends past 60 degrees, less far than
    the linear step says (it stiffens); a prestressed net is in tension: neither is a
    buckling, neither is warned (the net: no compression, no ratio at all)."""
    cantilever = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [L, 0, 0], "nodes": 31},
        "material": {**SECTION, "density": 0.0},
        "supports": {"fixed": ["start"], "clamped": ["start"]},
        "load": {"point": [{"node": "end", "force": [0.0, 0.0, -10.0 * EI / L**2]}]},
    }
    result, said = run(cantilever, caplog)
    assert result.converged and not [m for m in said if "linear response" in m]
    net = {
        "geometry": {"kind": "square_net", "n": 6, "alpha": 0.0, "size": 1.0,
                     "edge_length": 0.05},
        "material": {"E": 1e9, "radius": 0.002, "density": 1000.0, "prestress": 100.0},
        "load": {"pressure": 500.0},
    }  # fmt: skip
    scene = build(parse_case(net))
    result = solve(scene, Settings.of(scene.case.solver))
    from catenet.solver.workspace import Workspace

    ws = Workspace(scene.net, terms=scene.terms)
    assert amplification(ws, scene.net, scene.loads, scene.net.nodes, result) is None
    assert AMPLIFIED == 10.0
