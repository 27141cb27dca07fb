"""/mesh/mass (contract section 7): each node's lumped mass [kg] in every result file
(catenet run, sweep --save-runs, formfind, modes), the net's total mass rho A l0 + point
masses, and the very masses ``catenet modes`` takes its modes with."""

from __future__ import annotations

import math
import subprocess

import h5py
import numpy as np

import catenet
from tests.conftest import catenet_command, subprocess_env

# Two cables of different materials, a loose edge between their midpoints of the
# default material, point masses on a node set and on a support.
CASE = """\
title = "two cables with clamps"

[geometry]
kind = "graph"
nodes = [[0, 0, 0], [12, 0, 0], [0, 3, 0], [12, 3, 0], [6, 0, 0], [6, 3, 0]]
edges = [[4, 5]]
sets = { mids = [4, 5] }
fixed = [0, 1, 2, 3]

[[geometry.cable]]
name = "low"
nodes = [0, 4, 1]
edge_length = 1.0
prestress = 800.0

[[geometry.cable]]
name = "high"
nodes = [2, 5, 3]
edge_length = 1.5
prestress = 1500.0
material = { density = 2700.0, radius = 0.008 }

[material]
EA = 2.0e6
density = 7850.0
radius = 0.005

[[mass]]
node = "mids"
mass = 3.5

[[mass]]
node = 0
mass = 1.25

[load]
gravity = [0.0, 0.0, -9.81]

[solver]
steps = 2

[output]
file = "out/net.h5"
every = 0
"""

STEEL = 7850.0 * math.pi * 0.005**2  # rho A of the default material [kg/m]
ALLOY = 2700.0 * math.pi * 0.008**2  # ... of cable "high"
POINTS = 2 * 3.5 + 1.25  # [[mass]] [kg]


def expected_mass(f, points: bool = True) -> float:
    """The net's total mass from the file's own rest lengths and cables, by hand:
    rho A l0 of every edge plus the point masses."""
    l0 = f["mesh/rest_length"][()]
    names = [str(n) for n in f["mesh"].attrs["cable_names"]]
    cable = f["mesh/cable"][()]
    high = cable == names.index("high")
    return float(STEEL * l0[~high].sum() + ALLOY * l0[high].sum() + POINTS * points)


def check_mass(path, points: bool = True) -> np.ndarray:
    with h5py.File(path, "r") as f:
        mass = f["mesh/mass"][()]
        assert mass.shape == (f["mesh/nodes"].shape[0],) and mass.dtype == np.float64
        assert np.all(mass > 0)
        assert math.isclose(mass.sum(), expected_mass(f, points), rel_tol=1e-12)
        # each end of an edge gets half its mass: a clamp's node its point mass on top
        l0, edges = f["mesh/rest_length"][()], f["mesh/edges"][()]
        at_mid = [STEEL if c != 1 else ALLOY for c in f["mesh/cable"][()]]
        half = np.zeros_like(mass)
        np.add.at(half, edges[:, 0], 0.5 * np.asarray(at_mid) * l0)
        np.add.at(half, edges[:, 1], 0.5 * np.asarray(at_mid) * l0)
        extra = mass - half
        clamps = [0, 4, 5] if points else []
        np.testing.assert_allclose(extra[clamps], [1.25, 3.5, 3.5][: len(clamps)], rtol=1e-12)
        others = np.setdiff1d(np.arange(mass.size), clamps)
        np.testing.assert_allclose(extra[others], 0.0, atol=1e-12)
    return mass


def run(*args, cwd):
    done = subprocess.run(
        catenet_command(*args), cwd=cwd, capture_output=True, text=True, env=subprocess_env()
    )
    assert done.returncode == 0, done.stderr
    return done


def test_a_run_writes_the_mass_its_gravity_acts_on(tmp_path):
    (tmp_path / "net.toml").write_text(CASE)
    result = catenet.run_case(catenet.load_case(tmp_path / "net.toml"), tmp_path / "run.h5")
    mass = check_mass(tmp_path / "run.h5")
    # the supports carry the whole weight (to the equilibrium's residual): the same
    # masses the solve used
    reaction = np.asarray(result.reaction).sum(axis=0)
    tol = 10 * float(result.residual) + 1e-9
    np.testing.assert_allclose(reaction, [0.0, 0.0, 9.81 * mass.sum()], rtol=0, atol=tol)


def test_modes_take_the_files_mass(tmp_path):
    from catenet.run.modes import modes_case

    (tmp_path / "net.toml").write_text(CASE)
    done = modes_case(catenet.load_case(tmp_path / "net.toml"), tmp_path / "m.h5", count=3)
    mass = check_mass(tmp_path / "m.h5")
    with h5py.File(tmp_path / "m.h5", "r") as f:
        free = ~f["mesh/fixed"][()]
        shape = f["modes/shape"][()]
        total = f["modes"].attrs["total_mass"]
    np.testing.assert_array_equal(done.modes.mass[free], mass[free])
    np.testing.assert_allclose(total, mass[free].sum(), rtol=1e-12)
    gram = np.einsum("n,knd,jnd->kj", mass * free, shape, shape)
    np.testing.assert_allclose(gram, np.eye(3), atol=1e-10)


def test_sweep_runs_and_formfind_write_it(tmp_path):
    (tmp_path / "net.toml").write_text(CASE)
    run("sweep", "net.toml", "-p", "material.EA=1e6,4e6", "-o", "sw", "--save-runs", "-j", "1",
        cwd=tmp_path)  # fmt: skip
    files = sorted((tmp_path / "sw" / "runs").rglob("*.h5"))
    assert len(files) == 2
    for path in files:
        check_mass(path)
    # form finding gives the cables their tensions (no prestress of their own): the net
    # without its point masses, and with them (OUT.toml keeps its [[mass]] tables)
    found = CASE.replace("prestress = 800.0\n", "").replace("prestress = 1500.0\n", "")
    bare = found.split("[[mass]]")[0] + "[load]" + found.split("[load]")[1]
    ff = '\n[formfind]\nmethod = "linear"\nforce_density = 1000.0\n'
    (tmp_path / "ff.toml").write_text(bare + ff)
    run("formfind", "ff.toml", "-o", "out/ff.h5", cwd=tmp_path)
    check_mass(tmp_path / "out" / "ff.h5", points=False)
    (tmp_path / "ffm.toml").write_text(found + ff)
    run("formfind", "ffm.toml", "-o", "out/ffm.h5", cwd=tmp_path)
    check_mass(tmp_path / "out" / "ffm.h5")
    run("run", "out/ffm.toml", "-o", "out/ffm_run.h5", cwd=tmp_path)
    check_mass(tmp_path / "out" / "ffm_run.h5")
