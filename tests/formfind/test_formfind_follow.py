"""Form finding's area and line loads act on the shape found (``catenet.formfind.case.
formfind_scene``): the force density method lumps them again on each shape found and
finds the shape again under them until they agree; the given geometry is only the
start."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main

DIAMOND = """
units = "kN-m"
[geometry]
kind = "graph"
nodes = [[0, 0, 0], [5, 0, 0], [0, 5, 0], [-5, 0, 0], [0, -5, 0],
         [10, 0, 0], [0, 10, 0], [-10, 0, 0], [0, -10, 0]]
edges = [[0, 1], [0, 2], [0, 3], [0, 4], [1, 5], [2, 6], [3, 7], [4, 8],
         [1, 2], [2, 3], [3, 4], [4, 1]]
fixed = [5, 6, 7, 8]
[material]
EA = 1e5
[load]
area = [{ pressure = 1.0, direction = "plan" }]
[formfind]
force_density = 10.0
"""


def _formfind(tmp_path, text: str) -> dict:
    (tmp_path / "in.toml").write_text(text)
    r = CliRunner().invoke(
        main, ["formfind", str(tmp_path / "in.toml"), "-o", str(tmp_path / "f.h5")]
    )
    assert r.exit_code == 0, r.output
    return tomllib.loads((tmp_path / "f.toml").read_text())


def test_an_area_load_is_lumped_on_the_shape_found_not_the_given_one(tmp_path):
    """Four radials and a ring at radius 5 m, held at 10 m, q = 10 kN/m: the ring's
    nodes settle at radius 2.5 m (4 q r = q (10 - r) + ...: in plan each ring node is
    pulled equally in and out), so the centre carries a third of the 12.5 m^2 inner
    square's 1 kPa: 4.1667 kN (it carried a third of the given 50 m^2: 16.667 kN). The
    written shape with the area load in place of its point loads is in equilibrium."""
    data = _formfind(tmp_path, DIAMOND)
    force = {p["node"]: p["force"] for p in data["load"]["point"]}
    assert force[0][2] == pytest.approx(-12.5 / 3.0, rel=1e-9)
    ring = np.array(data["geometry"]["nodes"])[1:5, :2]
    assert np.linalg.norm(ring, axis=1) == pytest.approx(2.5, rel=1e-12)
    del data["load"]["point"]
    data["load"]["area"] = [{"pressure": 1.0, "direction": "plan"}]
    import tomli_w

    (tmp_path / "again.toml").write_text(tomli_w.dumps(data))
    r = CliRunner().invoke(
        main, ["run", str(tmp_path / "again.toml"), "-o", str(tmp_path / "r.h5")]
    )
    assert r.exit_code == 0 and "(equilibrium; 0 Newton iterations" in r.output, r.output


def test_a_line_load_per_unstressed_length_is_the_self_weight(tmp_path):
    """A steel strand's weight (96.77 N/m of unstressed length) given as a line load
    gives the shape gravity gives: 6.07733 m of sag over 100 m at q = 4000 N/m (it was
    lumped along the given 100 m, not the 100.97 m of rest length found: 6.048 m)."""
    cable = """
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [100, 0, 0]
nodes = 21
[material]
E = 160e9
radius = 0.02
{extra}
[load]
{load}
[formfind]
force_density = 4000.0
"""
    weight = 7850.0 * 9.81 * np.pi * 0.02**2
    line = _formfind(
        tmp_path, cable.format(extra="", load=f"line = [{{ force = [0, 0, {-weight!r}] }}]")
    )
    sag_line = -min(z for _, _, z in line["geometry"]["nodes"])
    gravity = _formfind(
        tmp_path, cable.format(extra="density = 7850.0", load="gravity = [0, 0, -9.81]")
    )
    sag_gravity = -min(z for _, _, z in gravity["geometry"]["nodes"])
    assert sag_line == pytest.approx(sag_gravity, rel=1e-9)
    assert sag_gravity == pytest.approx(6.07733, rel=1e-6)
