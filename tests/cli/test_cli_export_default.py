"""catenet export works in the default install (`make run`: pip install -e . with
constraints.txt): meshio is one of catenet's own dependencies, pinned with its own."""

from __future__ import annotations

import re
import tomllib

from click.testing import CliRunner

from catenet.cli import main
from tests.conftest import REPO


def _name(requirement: str) -> str:
    return re.split(r"[<>=!~;\[ ]", requirement, maxsplit=1)[0].lower()


def test_meshio_is_a_dependency_of_every_install_and_pinned():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert "meshio" in {_name(r) for r in project["dependencies"]}
    pinned = {
        line.split("==")[0].lower()
        for line in (REPO / "constraints.txt").read_text().splitlines()
        if "==" in line
    }
    assert {"meshio", "rich", "markdown-it-py", "mdurl", "pygments"} <= pinned


def test_export_after_a_run(tmp_path):
    import meshio

    case = tmp_path / "line.toml"
    case.write_text(
        '[geometry]\nkind = "cable"\nstart = [0, 0, 0]\nend = [2, 0, 0]\nlength = 2.2\n'
        "nodes = 5\n[material]\nEA = 1000.0\n[load]\n"
        'point = [{ node = "midpoint", force = [0, 0, -10.0] }]\n'
    )
    out = tmp_path / "line.h5"
    runner = CliRunner()
    assert runner.invoke(main, ["run", str(case), "-o", str(out), "-q"]).exit_code == 0
    res = runner.invoke(main, ["export", str(out), "--to", "vtu", "--frames", "last"])
    assert res.exit_code == 0, res.output
    files = sorted((tmp_path / "line-vtu").glob("*.vtu"))
    assert files and len(meshio.read(files[-1]).points) == 5


def test_export_carries_the_rods_moments_and_the_utilisation(tmp_path):
    """A cantilever rod (steel tube, clamped at its root, a tip load) with a breaking
    load: its final state's file carries /result/bending_moment and /result/curvature as
    point data and /result/utilisation as cell data, as the result file holds them."""
    import h5py
    import meshio
    import numpy as np

    case = tmp_path / "rod.toml"
    case.write_text(
        '[geometry]\nkind = "cable"\nstart = [0, 0, 0]\nend = [2, 0, 0]\nnodes = 11\n'
        '[material]\nE = 2.1e11\nradius = 0.02\ninner_radius = 0.015\nEI = "section"\n'
        "breaking_load = 2e5\n"
        "[supports]\nfixed = [0, 10]\nclamped = [0]\n"
        '[load]\npoint = [{ node = "midpoint", force = [0, 0, -500.0] }]\n'
    )
    out = tmp_path / "rod.h5"
    runner = CliRunner()
    run = runner.invoke(main, ["run", str(case), "-o", str(out), "-q"])
    assert run.exit_code == 0, run.output
    res = runner.invoke(main, ["export", str(out), "--to", "vtu", "--frames", "last"])
    assert res.exit_code == 0, res.output
    (file,) = sorted((tmp_path / "rod-vtu").glob("*.vtu"))
    mesh = meshio.read(file)
    with h5py.File(out, "r") as h5:
        stored = {k: h5["result"][k][()] for k in ("bending_moment", "curvature", "utilisation")}
    assert np.abs(stored["bending_moment"]).max() > 0 and np.nanmax(stored["utilisation"]) > 0
    for name in ("bending_moment", "curvature"):
        assert np.array_equal(mesh.point_data[name].reshape(stored[name].shape), stored[name])
    util = mesh.cell_data["utilisation"][0]
    assert np.array_equal(util, stored["utilisation"], equal_nan=True)
