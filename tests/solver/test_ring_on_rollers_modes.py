"""A ring that no fixed node or spring holds, lying on rollers (a ring on a smooth table):
its three in-plane rigid-body motions are zero-frequency modes, named as such (they were
called "a mechanism of the taut edges ... give them tension"), and its in-plane bending
modes follow the closed form of a free ring, f_n = n (n^2 - 1) / sqrt(n^2 + 1) sqrt(EI /
(m R^4)) / (2 pi)."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main

N = 120  # nodes around the ring
R = 0.5  # [m]


def _ring() -> str:
    pts = [
        [R * math.sin(2 * math.pi * k / N), -R * math.cos(2 * math.pi * k / N), 0.0]
        for k in range(N)
    ]
    return f"""
[geometry]
kind = "graph"
nodes = {pts}

[geometry.sets]
all = {list(range(N))}

[[geometry.cable]]
name = "ring"
nodes = {list(range(N)) + [0]}

[material]
E = 200e9
radius = 0.01
density = 7850.0
EI = "section"
natural_curvature = "given"
tension_only = false

[supports]
fixed = []

[[supports.roller]]
nodes = "all"
normal = [0.0, 0.0, 1.0]
"""


def test_a_ring_on_rollers_has_three_rigid_body_modes_and_the_free_rings_frequencies(
    tmp_path,
):
    case = tmp_path / "ring.toml"
    case.write_text(_ring())
    out = tmp_path / "m.h5"
    done = CliRunner().invoke(main, ["modes", str(case), "-o", str(out), "-k", "4"])
    assert done.exit_code == 0, done.output
    line = next(x for x in done.output.splitlines() if x.startswith("zero modes"))
    assert "3 zero-frequency modes" in line and "a rigid-body motion" in line, line
    assert "mechanism" not in line and "give them tension" not in line
    ei = 200e9 * math.pi * 0.01**4 / 4
    m = 7850.0 * math.pi * 0.01**2
    with h5py.File(out) as f:
        found = np.asarray(f["modes/frequency"][:4])
    for k, n in enumerate((2, 2, 3, 3)):
        exact = n * (n * n - 1) / math.sqrt(n * n + 1) * math.sqrt(ei / (m * R**4)) / (2 * math.pi)
        assert found[k] == pytest.approx(exact, rel=3e-3)
