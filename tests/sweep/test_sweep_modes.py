"""``catenet sweep --modes K``: the lowest natural frequencies as columns f1..fK."""

from __future__ import annotations

import math
import subprocess

import h5py
import numpy as np

from tests.conftest import catenet_command, subprocess_env

CASE = """\
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [10, 0, 0]
nodes = 41

[material]
EA = 1e6
area = 1e-4
density = 5000.0
prestress = 1000.0

[output]
file = "out/c.h5"
"""


def test_sweep_columns_are_the_string_frequencies(tmp_path):
    """A taut string over its prestress T: f1 = f2 (y, z) = 1 / (2 L) sqrt(T / mu) with
    mu = rho A / (1 + T / EA) per stretched length, to the discretisation's error
    (n pi h / L)^2 / 24 (2.6e-4 for n = 1, 1e-3 for n = 2 at 40 edges); the columns come after
    the usual ones, in Hz, in the CSV and the HDF5 table."""
    (tmp_path / "c.toml").write_text(CASE)
    done = subprocess.run(
        catenet_command("sweep", "c.toml", "-p", "material.prestress=1000,4000", "--modes", "3",
                        "-o", "sw", "-j", "1", "-q"),
        cwd=tmp_path, env=subprocess_env(), capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    with h5py.File(tmp_path / "sw" / "results.h5", "r") as h5:
        t = h5["table"]
        tension = t["material.prestress"][()]
        f = np.column_stack([t["f1"][()], t["f2"][()], t["f3"][()]])
    rho_a = 5000.0 * 1e-4
    for T, row in zip(tension, f, strict=True):
        mu = rho_a / (1 + T / 1e6)
        string = 1 / 20 * math.sqrt(T / mu)
        np.testing.assert_allclose(row[:2], string, rtol=3e-4)
        np.testing.assert_allclose(row[2], 2 * string, rtol=1.1e-3)
    header = (tmp_path / "sw" / "results.csv").read_text().splitlines()[0].split(",")
    assert header[-3:] == ["f1", "f2", "f3"]
