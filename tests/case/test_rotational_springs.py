"""Rotational springs at rod ends (``[[supports.rotational]]``): a rod end whose tangent
a spring k [N m/rad] holds toward its given direction. Against closed forms: a cantilever
on a rotational spring under a small end load deflects P L^3 / (3 EI) + P L^2 / k, with the
moment P L at its foot; a stiff spring is the clamp; a twisting rod untwists at a spring;
bad input exits 2 with one message."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main

EI, L, P = 2.0, 1.5, 1e-3  # N m^2, m, N: P L^2 / EI ~ 1e-3, linear

MAST = {
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [0.0, 0.0, L], "nodes": 61},
    "material": {"EA": 1e7, "EI": EI},
    "supports": {"fixed": ["start"], "rotational": [{"nodes": ["start"], "stiffness": 5.0}]},
    "load": {"point": [{"node": "end", "force": [P, 0.0, 0.0]}]},
    "solver": {"rtol": 1e-10},
}


def run(tmp_path, data) -> tuple[np.ndarray, np.ndarray, str]:
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "r.h5") as f:
        return f["result/x"][:], f["result/bending_moment"][:], done.output


@pytest.mark.parametrize("k", [0.5, 5.0, 50.0])
def test_a_cantilever_on_a_rotational_spring(tmp_path, k):
    """The mast leans on its foot's spring and bends above it: tip P L^3 / (3 EI) +
    P L^2 / k (to the discretisation's O(h^2)), the moment at the foot P L."""
    data = {
        **MAST,
        "supports": {**MAST["supports"], "rotational": [{"nodes": [0], "stiffness": k}]},
    }
    x, moment, _ = run(tmp_path, data)
    tip = x[-1, 0]
    assert tip == pytest.approx(P * L**3 / (3 * EI) + P * L**2 / k, rel=1e-3)
    assert moment[0] == pytest.approx(P * L, rel=1e-3)


@pytest.mark.parametrize("nodes", [31, 61, 121])
def test_the_curvature_at_a_spring_foot_is_its_moment_over_ei(tmp_path, nodes):
    """At a spring foot the rod's curvature is M / EI whatever the edges: the end
    edge's turn there is mostly the spring's own, not the rod's bending (it read
    2 |t - t0| / l, which doubled with every halving of the edges)."""
    data = {**MAST, "geometry": {**MAST["geometry"], "nodes": nodes}}
    run(tmp_path, data)
    with h5py.File(tmp_path / "r.h5") as f:
        kappa = f["result/curvature"][:]
    assert kappa[0] == pytest.approx(P * L / EI, rel=1e-3)
    assert kappa[1] == pytest.approx(P * (L - L / (nodes - 1)) / EI, rel=2e-2)


def test_a_stiff_spring_is_the_clamp(tmp_path):
    stiff = {
        **MAST,
        "supports": {**MAST["supports"], "rotational": [{"nodes": [0], "stiffness": 1e8}]},
    }
    clamped = {**MAST, "supports": {"fixed": ["start"], "clamped": ["start"]}}
    a, _, _ = run(tmp_path, stiff)
    b, _, _ = run(tmp_path, clamped)
    assert np.max(np.abs(a - b)) < 1e-6 * np.max(np.abs(b[:, 0]))


def test_a_spring_holds_no_twist():
    """A rod with GJ clamped at one end and on a spring at the other does not twist (it
    untwists at the spring); clamped at both ends it does."""
    twisted = {
        **MAST,
        "material": {**MAST["material"], "GJ": 1.0},
        "supports": {"fixed": ["start", "end"], "clamped": ["start", "end"]},
    }
    names = [t.name for t in build(parse_case(twisted)).terms]
    assert "twist" in names
    sprung = {
        **twisted,
        "supports": {
            "fixed": ["start", "end"],
            "clamped": ["start"],
            "rotational": [{"nodes": ["end"], "stiffness": 5.0}],
        },
    }
    assert "twist" not in [t.name for t in build(parse_case(sprung)).terms]


@pytest.mark.parametrize(
    "supports, says",
    [
        ({"rotational": [{"nodes": [0], "stiffness": -1.0}]}, "supports.rotational[0].stiffness"),
        ({"rotational": [{"nodes": [0]}]}, "supports.rotational[0].stiffness"),
        (
            {"rotational": [{"nodes": [30], "stiffness": 1.0}]},
            "node 30 is an interior node of a rod: a rotational spring's node must be the end",
        ),
        (
            {"clamped": [0], "rotational": [{"nodes": [0], "stiffness": 1.0}]},
            "node 0 is in supports.clamped too",
        ),
        (
            {"rotational": [{"nodes": [0], "stiffness": 1.0}, {"nodes": [0], "stiffness": 2.0}]},
            "node 0 is on a rotational spring already",
        ),
    ],
)
def test_bad_rotational_springs_exit_2(tmp_path, supports, says):
    data = {**MAST, "supports": {"fixed": ["start"], **supports}}
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 2 and says in done.output, done.output
    assert "Traceback" not in done.output


def test_no_rod_no_spring(tmp_path):
    data = {**MAST, "material": {"EA": 1e7}}
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 2 and "a rotational spring holds a rod's end" in done.output
