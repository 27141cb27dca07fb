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
