"""``catenet modes``: the result file's /modes, the summary's table, the sidecar's
animations and every kind of bad input."""

from __future__ import annotations

import subprocess

import h5py
import numpy as np
import pytest

from tests.conftest import catenet_command, check_xdmf, subprocess_env

NET = """\
title = "prestressed net"

[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 10.0
edge_length = 0.5

[material]
E = 10e6
radius = 0.01
density = 1000.0
prestress = 200.0

[load]
pressure = 2.0

[output]
file = "out/net.h5"
every = 0
"""

CABLES = """\
title = "two named cables"

[geometry]
kind = "graph"
nodes = [[0, 0, 0], [10, 0, 0], [0, 2, 0], [10, 2, 0]]
edges = []
fixed = [0, 1, 2, 3]

[[geometry.cable]]
name = "low"
nodes = [0, 1]
edge_length = 0.5
prestress = 1000.0

[[geometry.cable]]
name = "high"
nodes = [2, 3]
edge_length = 0.5
prestress = 4000.0

[material]
EA = 1e6
area = 1e-4
density = 5000.0
"""


def run(*args, cwd):
    return subprocess.run(
        catenet_command(*args), cwd=cwd, env=subprocess_env(), capture_output=True, text=True,
        timeout=300,
    )  # fmt: skip


def test_modes_writes_the_result_file_and_prints_the_table(tmp_path):
    (tmp_path / "net.toml").write_text(NET)
    done = run("modes", "net.toml", "--count", "5", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    out = tmp_path / "out" / "net.h5"
    with h5py.File(out, "r") as h5:
        n = h5["mesh/nodes"].shape[0]
        f = h5["modes/frequency"][()]
        assert f.shape == (5,) and np.all(np.diff(f) >= 0) and f[0] > 0
        np.testing.assert_allclose(h5["modes/period"][()], 1 / f)
        shape = h5["modes/shape"][()]
        assert shape.shape == (5, n, 3)
        mass = h5["mesh/mass"][()]
        free = ~h5["mesh/fixed"][()]
        gram = np.einsum("n,knd,jnd->kj", mass * free, shape, shape)
        np.testing.assert_allclose(gram, np.eye(5), atol=1e-10)
        gamma = h5["modes/participation"][()]
        np.testing.assert_allclose(h5["modes/effective_mass"][()], gamma**2)
        assert h5["modes/effective_mass"].shape == (5, 3)
        assert np.all(np.abs(shape[:, h5["mesh/fixed"][()]]) == 0)
        assert h5["result"].attrs["converged"]
        assert h5["modes"].attrs["zero_modes"] == 0
        assert h5["modes"].attrs["animated"] == 5
    for k in range(1, 6):
        assert f"{f[k - 1]:.6g}" in done.stdout
    assert "m_eff x/y/z" in done.stdout and "moves most" in done.stdout
    checked = check_xdmf(out.with_suffix(".xdmf"))
    assert checked["modes"] == 5


def test_modes_names_the_cables_that_move(tmp_path):
    """Two parallel cables: the lower-tension one's modes come first (f = n / (2 L)
    sqrt(T / mu)), and the table names it as the cable that moves."""
    (tmp_path / "c.toml").write_text(CABLES)
    done = run("modes", "c.toml", "--count", "4", "-o", "c.h5", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    rows = [line for line in done.stdout.splitlines() if line.strip().endswith(("low", "high"))]
    assert len(rows) == 4
    assert all(r.strip().endswith("low") for r in rows[:2])


@pytest.mark.parametrize(
    "args, message",
    [
        (("--count", "0"), "--count = '0': must be a positive integer"),
        (("--count", "two"), "--count = 'two': must be a positive integer"),
        (("--count", "1.5"), "--count = '1.5': must be a positive integer"),
        (("--count", "100000"), "more than the net's 615 free DOFs"),
        (("--set", "material.density=0"), "the net has none where it moves"),
        (  # no gravity is no load: the cause is the modes' need of mass, not gravity's
            ("--set", "material.density=0", "--set", "load.gravity=[0, 0, 0]"),
            "error: material.density = 0 and no [[mass]]: modes need mass",
        ),
    ],
)
def test_bad_input_exits_2_with_one_message(tmp_path, args, message):
    (tmp_path / "net.toml").write_text(NET)
    done = run("modes", "net.toml", *args, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert message in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out" / "net.h5").exists()  # found before anything was solved


def test_the_modes_summary_names_the_cases_units(tmp_path):
    """A kN-m case's tension is in kN: the summary says kN (as catenet run does), the
    numbers as the case wrote them."""
    from click.testing import CliRunner

    from catenet.cli import main

    (tmp_path / "c.toml").write_text('units = "kN-m"\n' + CABLES)
    res = CliRunner().invoke(main, ["modes", str(tmp_path / "c.toml"), "-k", "2",
                                    "-o", str(tmp_path / "c.h5")])  # fmt: skip
    assert res.exit_code == 0, res.output
    line = next(t for t in res.output.splitlines() if t.startswith("equilibrium"))
    assert line.endswith(" kN") and "max tension 4" in line


def test_failed_equilibrium_exits_1_with_the_static_message(tmp_path):
    (tmp_path / "net.toml").write_text(NET)
    done = run("modes", "net.toml", "--set", "solver.max_iter=1", cwd=tmp_path)
    assert done.returncode == 1
    assert "static equilibrium: no convergence" in done.stderr
    assert "Traceback" not in done.stderr


def test_dynamic_case_must_come_to_rest(tmp_path):
    """A dynamic case (solver.method = "dynamic") is relaxed by the paper's implicit Euler
    as `catenet run` does; stopped at t_end before rest it has no equilibrium: exit 1."""
    (tmp_path / "net.toml").write_text(NET)
    done = run("modes", "net.toml", "--set", "solver.method=dynamic", "--set",
               "solver.t_end=0.05", cwd=tmp_path)  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "before the net came to rest" in done.stderr
    assert (tmp_path / "out" / "net.h5").exists()  # the run's own file, as catenet run's


def test_an_equilibrium_without_stiffness_exits_1_and_keeps_it(tmp_path):
    """A sound case whose equilibrium carries no tension to speak of (gravity 1e-300, a
    fuzzed case): the equilibrium is solved and written, its modes do not exist: exit 1
    (a result, not bad input), the file kept."""
    from tests.conftest import CONFIGS

    (tmp_path / "c.toml").write_text((CONFIGS / "catenary.toml").read_text())
    done = run("modes", "c.toml", "-o", "c.h5", "--set", "load.gravity=[0, 0, 1e-300]",
               cwd=tmp_path)  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "modes about the equilibrium found: " in done.stderr
    assert "no free node has both mass and stiffness" in done.stderr
    assert "Traceback" not in done.stderr
    assert (tmp_path / "c.h5").exists()
