"""Node sets from an imported net's point data, in every format that carries it: flag
columns of a CSV nodes table, a gmsh mesh's node data and physical groups, a PLY file's
vertex properties, an XDMF file's point data (VTK files: tests/case/test_net_files.py).
Each gives the run the same net with the node sets listed inline gives. A format that
carries no point data (OBJ) says so where a set it lacks is named: exit status 2."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml, parse_case
from catenet.cli import main
from catenet.run.runner import run_case

POINTS = np.array(
    [[0, 0, 0], [1, 0, 0], [2, 0, 0.2], [3, 0, 0], [1.5, -1, 0.1], [1.5, 1, 0.1]], dtype=float
)
EDGES = np.array([[0, 1], [1, 2], [2, 3], [4, 2], [2, 5]])
FIXED = np.array([1, 0, 0, 1, 1, 1])  # the supports: the four ends
MIDDLE = np.array([0, 1, 0, 0, 0, 0])  # a loaded node

GMSH = """$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
3
0 1 "fixed"
0 2 "middle"
1 3 "net"
$EndPhysicalNames
$Nodes
6
1 0 0 0
2 1 0 0
3 2 0 0.2
4 3 0 0
5 1.5 -1 0.1
6 1.5 1 0.1
$EndNodes
$Elements
10
1 15 2 1 1 1
2 15 2 1 4 4
3 15 2 1 5 5
4 15 2 1 6 6
5 15 2 2 2 2
6 1 2 3 1 1 2
7 1 2 3 1 2 3
8 1 2 3 1 3 4
9 1 2 3 2 5 3
10 1 2 3 2 3 6
$EndElements
"""


def case(file: str | None = None, sets=("fixed", "middle")) -> dict:
    """The net from ``file`` (None: inline, its node sets listed), fixed at the set
    named sets[0], loaded at sets[1]."""
    geometry: dict = {"kind": "graph"}
    if file is None:
        geometry |= {"nodes": POINTS.tolist(), "edges": EDGES.tolist()}
        geometry["sets"] = {
            "fixed": np.flatnonzero(FIXED).tolist(),
            "middle": np.flatnonzero(MIDDLE).tolist(),
        }
    else:
        geometry["file"] = file
    return {
        "geometry": geometry,
        "supports": {"fixed": [sets[0]]},
        "material": {"EA": 1e4, "prestress": 10.0},
        "load": {"point": [{"node": sets[1], "force": [0, 0, -1.0]}]},
    }


def csv_file(tmp_path) -> str:
    rows = ["x,y,z,fixed,middle"]
    for p, f, m in zip(POINTS, FIXED, MIDDLE, strict=True):
        rows.append(",".join([*map(str, p), str(f), str(m)]))
    rows += ["i,j", *(f"{i},{j}" for i, j in EDGES)]
    (tmp_path / "net.csv").write_text("\n".join(rows) + "\n")
    return "net.csv"


def meshio_file(tmp_path, name: str, **kw) -> str:
    meshio = pytest.importorskip("meshio")
    data = {"fixed": FIXED.astype(float), "middle": MIDDLE.astype(float)}
    mesh = meshio.Mesh(POINTS, [("line", EDGES)], point_data=data)
    meshio.write(tmp_path / name, mesh, **kw)
    return name


def gmsh_groups(tmp_path) -> str:
    """A gmsh 2.2 file as gmsh writes it: Physical Points "fixed" and "middle", a
    Physical Curve "net"."""
    pytest.importorskip("meshio")
    (tmp_path / "groups.msh").write_text(GMSH)
    return "groups.msh"


MAKERS = {
    "csv": csv_file,
    "gmsh22": lambda t: meshio_file(t, "nodedata22.msh", file_format="gmsh22", binary=True),
    "gmsh41": lambda t: meshio_file(t, "nodedata41.msh", file_format="gmsh", binary=True),
    "gmsh groups": gmsh_groups,
    "ply": lambda t: meshio_file(t, "net.ply"),
    "xdmf": lambda t: meshio_file(t, "net.xdmf"),
}


@pytest.mark.parametrize("fmt", list(MAKERS))
def test_point_data_flags_are_node_sets_in_every_format_that_carries_them(tmp_path, fmt):
    want = run_case(parse_case(case()), tmp_path / "inline.h5")
    file = MAKERS[fmt](tmp_path)
    got_case = parse_case(case(file), base_dir=tmp_path)
    sets = got_case.geometry.sets.as_dict()
    assert sets["fixed"] == tuple(np.flatnonzero(FIXED)) and sets["middle"] == (1,)
    if fmt == "gmsh groups":  # a Physical Curve: the nodes of its lines
        assert sets["net"] == tuple(range(6))
    got = run_case(got_case, tmp_path / "file.h5")
    assert got.converged
    np.testing.assert_array_equal(got.x, want.x)
    np.testing.assert_array_equal(got.tension, want.tension)


def test_a_format_without_point_data_says_so_where_a_set_is_missing(tmp_path):
    obj = "v 0 0 0\nv 1 0 0\nv 2 0 0\no main\nl 1 2 3\n"
    (tmp_path / "net.obj").write_text(obj)
    data = case("net.obj", sets=("fixed", 1))
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path)])
    assert r.exit_code == 2
    assert (
        "supports.fixed[0] = 'fixed': must be a node index or one of 'center' (named nodes "
        "and the node sets of [geometry.sets]); geometry.file = 'net.obj' is an OBJ file, "
        "which carries no point data flags: name the nodes in [geometry.sets] (by region: "
        "{ box = ... }), or give the net as .vtu, .vtp, .vtk, .msh or CSV with flag columns"
    ) in r.output


@pytest.mark.parametrize(
    ("header", "row", "message"),
    [
        (
            "x,y,z,fixed",
            "1,0,0,2",
            "line 3: '1,0,0,2': the flag column 'fixed' holds 0 or 1 (a node set: its nodes "
            "are the rows with 1), not '2'",
        ),
        ("x,y,z,a,a", "1,0,0,0,1", "line 1: 'x,y,z,a,a': a flag column named twice"),
    ],
)
def test_bad_flag_columns_exit_2(tmp_path, header, row, message):
    first = "0,0,0" + ",1" * (header.count(",") - 2)
    text = f"{header}\n{first}\n{row}\ni,j\n0,1\n"
    (tmp_path / "net.csv").write_text(text)
    data = case("net.csv", sets=(0, 1))
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path)])
    assert r.exit_code == 2
    assert f"geometry.file = 'net.csv': {message}" in r.output, r.output
