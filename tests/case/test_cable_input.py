"""Graph cases with cables: the per-cable results (Result stats, the HDF5 file, the run
summary), nets read from files (JSON, OBJ, line meshes through meshio), and bad input,
each refused with its key path, value and what is accepted (exit status 2)."""

from __future__ import annotations

import copy
import sys
import tomllib

import h5py
import numpy as np
import pytest
from cable_cases import one, problems, straight, two_cables
from click.testing import CliRunner
from conftest import CONFIGS

from catenet.case import build, dumps_toml, load_case, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.run.report import CableSummary
from catenet.run.runner import run_case

# --------------------------------------------------------------------------- results


def test_results_per_cable_in_stats_file_and_summary(tmp_path):
    """Cable "a" is pulled taut by a point load; the supports of cable "b" move towards
    each other, so that every edge of it is slack."""
    data = two_cables()
    data["geometry"]["sets"]["b_top"] = [3]
    data["supports"]["move"] = [{"node": "b_top", "displacement": [0, -0.5, 0]}]
    data["load"] = {"point": [{"cable": "a", "at": 0.5, "force": [0, 0, -10]}]}
    data["output"] = {"file": str(tmp_path / "r.h5")}
    case_file = tmp_path / "c.toml"
    case_file.write_text(dumps_toml(data))
    result = run_case(load_case(case_file))
    a, b = result.report.cables["a"], result.report.cables["b"]
    assert a.max_tension == pytest.approx(float(result.tension.max())) and a.max_tension > 100
    assert a.slack_fraction == 0.0
    assert b == CableSummary(max_tension=0.0, slack_fraction=1.0)
    b_full = result.report.summary["cables"]["b"]
    assert b_full["slack_edges"] > 0 and not b_full["strut"]  # every edge of b is slack
    with h5py.File(tmp_path / "r.h5") as h5:
        assert h5["mesh"].attrs["cable_names"].astype(str).tolist() == ["a", "b"]
        assert np.array_equal(h5["mesh/cable"][:], build(load_case(case_file)).cables.edge)
        assert h5["result/cable_max_tension"][:].tolist() == [a.max_tension, 0.0]
        assert h5["result/cable_slack_fraction"][:].tolist() == [0.0, 1.0]
        assert "tension" in h5["result"] and "reaction" in h5["result"]
    r = CliRunner().invoke(main, ["run", str(case_file), "-o", str(tmp_path / "s.h5")])
    assert r.exit_code == 0, r.output
    assert (
        "a: max tension" in r.output and "b: max tension 0 N, slack 100 % of its length" in r.output
    )


def test_graphs_without_cables_write_no_cable_data(tmp_path):
    data = straight()
    data["geometry"]["edges"] = [[0, 1], [1, 2]]
    del data["geometry"]["cable"]
    result = run_case(parse_case(data), tmp_path / "g.h5")
    assert result.report.cables is None
    with h5py.File(tmp_path / "g.h5") as h5:
        assert "cable" not in h5["mesh"] and "cable_max_tension" not in h5["result"]


# --------------------------------------------------------------------------- files


def test_a_line_mesh_from_meshio(tmp_path):
    meshio = pytest.importorskip("meshio")
    pts = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.1], [3, 0, 0]], dtype=float)
    meshio.Mesh(pts, [("line", np.array([[0, 1], [1, 2], [2, 3]]))]).write(tmp_path / "n.vtu")
    data = {
        "geometry": {"kind": "graph", "file": "n.vtu", "fixed": [0, 3], "prestress": [5.0] * 3},
        "material": {"EA": 1e4},
    }
    case = parse_case(data, base_dir=tmp_path)
    assert case.geometry.edges == ((0, 1), (1, 2), (2, 3))
    assert parse_case(tomllib.loads(case.to_toml())) == case  # the data is inlined
    data["geometry"]["nodes"] = pts.tolist()
    one(data, "geometry.nodes: give the graph in geometry.file or inline, not both")


def test_obj_polylines(tmp_path):
    (tmp_path / "n.obj").write_text(
        "# a net\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 1 1 0\nl 1 2 3\nl -1 2\n"
    )
    data = {
        "geometry": {"kind": "graph", "file": "n.obj", "fixed": [0, 2, 3]},
        "material": {"EA": 1.0},
    }
    case = parse_case(data, base_dir=tmp_path)
    # a polyline of more than two points is a cable (named by its place), a segment an edge
    assert case.geometry.edges == ((3, 1),)
    assert [(c.name, c.nodes) for c in case.geometry.cables] == [("line0", (0, 1, 2))]
    (tmp_path / "n.obj").write_text("v 0 0 0\nl 1 2\n")
    found = problems(data, base_dir=tmp_path)
    assert "line 2: 'l 1 2': a polyline needs at least 2 vertices defined before it" in found[0]


NET_CSV = """# a net saved from a spreadsheet
x,y,z
0,0,0
2,0,0
4,0,0.5
2,2,0
i,j,
0,1,
1,2
3,1
"""


def test_csv_nodes_and_edges_tables(tmp_path):
    """One sheet, two tables: nodes under x,y,z and edges under i,j; comma, semicolon
    (European spreadsheets) or tab, a byte-order mark and empty trailing cells; the
    graph runs like the same net given inline."""
    data = {
        "geometry": {"kind": "graph", "file": "n.csv", "fixed": [0, 2, 3]},
        "material": {"EA": 1e4},
        "load": {"point": [{"node": 1, "force": [0, 0, -10]}]},
    }
    for sep, bom in ((",", ""), (";", "\ufeff"), ("\t", "")):
        (tmp_path / "n.csv").write_text(bom + NET_CSV.replace(",", sep), encoding="utf-8")
        case = parse_case(data, base_dir=tmp_path)
        assert case.geometry.nodes == ((0, 0, 0), (2, 0, 0), (4, 0, 0.5), (2, 2, 0))
        assert case.geometry.edges == ((0, 1), (1, 2), (3, 1))
    assert parse_case(tomllib.loads(case.to_toml())) == case  # the data is inlined
    inline = copy.deepcopy(data)
    inline["geometry"] = {
        "kind": "graph",
        "nodes": [list(p) for p in case.geometry.nodes],
        "edges": [list(e) for e in case.geometry.edges],
        "fixed": [0, 2, 3],
    }
    a, b = run_case(parse_case(data, base_dir=tmp_path)), run_case(parse_case(inline))
    assert np.array_equal(a.x, b.x) and a.converged
    (tmp_path / "xy.csv").write_text("i,j\n0,1\nX,Y\n0,0\n1,0\n".replace("X,Y", "x,y"))
    data["geometry"].update(file="xy.csv", fixed=[0, 1])  # edges first, 2D nodes (z = 0)
    data["load"]["point"][0]["node"] = 0
    assert parse_case(data, base_dir=tmp_path).geometry.nodes == ((0, 0, 0), (1, 0, 0))


@pytest.mark.parametrize(
    "text, message",
    [
        ("0,0,0\n", "line 1: '0,0,0': must start with a header row 'x,y,z' or 'x,y' or 'i,j'"),
        ("x,y,z\n0,0,0\n1,0\n", "line 3: '1,0': has 2 cells: the nodes table has 3 columns"),
        ("x,y,z\n0,0,a\n", "line 2: '0,0,a': the nodes table holds finite numbers"),
        ("x,y,z\n0,0,0\n1,0,0\ni,j\n0,1.5\n", "line 5: '0,1.5': the edges table holds node"),
        ("x,y,z\n0,0,0\n1,0,0\ni,j\n0,2\n", "line 5: '0,2': node 2 is not a row of the nodes"),
        ("x,y,z\n0,0,0\n1,0,0\n", "has no edges: give a header row 'i,j' and a row per one"),
        ("x,y,z\n0,0,0\nx,y,z\n", "line 3: 'x,y,z': a second nodes table"),
    ],
)
def test_bad_csv_nets_name_the_line(tmp_path, text, message):
    (tmp_path / "n.csv").write_text(text)
    data = {"geometry": {"kind": "graph", "file": "n.csv", "fixed": [0]}, "material": {"EA": 1.0}}
    found = problems(data, base_dir=tmp_path)
    assert len(found) == 1 and found[0].startswith("geometry.file = 'n.csv': ")
    assert message in found[0], found
    case = tmp_path / "c.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 2 and message in done.output


def test_meshio_missing_is_named(tmp_path, monkeypatch):
    (tmp_path / "n.msh").write_text("")  # (.vtu, .vtp and .vtk: catenet reads them itself)
    monkeypatch.setitem(sys.modules, "meshio", None)
    data = {"geometry": {"kind": "graph", "file": "n.msh", "fixed": [0]}, "material": {"EA": 1.0}}
    found = problems(data, base_dir=tmp_path)
    assert "needs the Python package meshio, which is not installed" in found[0]


def test_a_mesh_without_lines_is_refused(tmp_path):
    meshio = pytest.importorskip("meshio")
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]).write(tmp_path / "t.vtu")
    data = {"geometry": {"kind": "graph", "file": "t.vtu", "fixed": [0]}, "material": {"EA": 1.0}}
    assert "holds no line cells (it has triangle)" in problems(data, base_dir=tmp_path)[0]


# --------------------------------------------------------------------------- bad input


def _set(data: dict, path: str, value) -> dict:
    out = copy.deepcopy(data)
    *head, last = path.split(".")
    cur = out
    for p in head:
        cur = cur[int(p)] if isinstance(cur, list) else cur.setdefault(p, {})
    if isinstance(cur, list):
        cur[int(last)] = value
    else:
        cur[last] = value
    return out


BAD = [
    (
        "geometry.cable.0.nodes",
        [0, 9],
        "geometry.cable[0].nodes[1] = 9: is no node: must be a node index in 0..3",
    ),
    (
        "geometry.cable.0.nodes",
        [0, 0],
        "geometry.cable[0].nodes[0:2] = [0, 0]: zero-length segment",
    ),
    ("geometry.nodes.1", [0, 0, 0], "geometry.cable[0].nodes[0:2] = [0, 1]: zero-length segment"),
    (
        "geometry.cable.0.nodes",
        [0],
        "geometry.cable[0].nodes = [0]: must be an array of at least 2 nodes",
    ),
    (
        "geometry.cable.0.nodes",
        ["anchors", 1],
        "geometry.cable[0].nodes[0] = 'anchors': names 4 nodes",
    ),
    (
        "geometry.cable.0.nodes",
        ["wset", 1],
        "geometry.cable[0].nodes[0] = 'wset': no such node set",
    ),
    (
        "geometry.cable.1.nodes",
        [1, 0],
        "repeats the segment of geometry.cable[0]: cables share nodes, not segments",
    ),
    (
        "geometry.cable.1.name",
        "a",
        "geometry.cable[1].name = 'a': also the name of geometry.cable[0]",
    ),
    ("geometry.sets.west", [], "geometry.sets.west = []: names no node: must be a non-empty array"),
    (
        "geometry.sets.west",
        [0, 99],
        "geometry.sets.west[1] = 99: names no node: must be a node index in 0..3",
    ),
    ("geometry.sets.west", [0, 0], "geometry.sets.west = [0, 0]: node 0 appears more than once"),
    ("geometry.sets.center", [0], "geometry.sets.center = [0]: 'center' names a node already"),
    (
        "supports.fixed",
        ["anchrs"],
        "supports.fixed[0] = 'anchrs': must be a node index or one of 'center', 'anchors', "
        "'west' (named nodes and the node sets of [geometry.sets]); did you mean 'anchors'?",
    ),
    (
        "geometry.cable.1.material",
        {"EAA": 1.0},
        "geometry.cable[1].material.EAA: unknown key of [material] (accepted: E, radius",
    ),
    (
        "geometry.cable.1.material",
        {"EA": -1.0},
        "geometry.cable[1].material.EA = -1.0: must be finite and > 0",
    ),
    (
        "geometry.cable.1.material",
        {"E": 1e9},
        "geometry.cable[1].material.E = 1000000000.0: needs a cross-section",
    ),
    (
        "geometry.cable.0.prestress",
        -5.0,
        "geometry.cable[0].prestress = -5.0: tension-only cables carry no compression",
    ),
    (
        "geometry.cable.0.material",
        {"prestress": 5.0},
        "geometry.cable[0].prestress = 100.0: give geometry.cable[0].prestress or "
        "geometry.cable[0].material.prestress, not both",
    ),
    (
        "geometry.cable.0.colour",
        "red",
        "geometry.cable[0].colour: unknown key (accepted: name, nodes, edge_length, "
        "prestress, rest_length, material, twist)",
    ),
    (
        "geometry.prestrain",
        0.01,
        "geometry.prestrain = 0.01: a cable's prestress gives its rest lengths",
    ),
    (
        "load.point",
        [{"cable": "c", "at": 0.5, "force": [0, 0, 1]}],
        "load.point[0].cable = 'c': no such cable (accepted: 'a', 'b')",
    ),
    (
        "load.point",
        [{"cable": "a", "at": 1.5, "force": [0, 0, 1]}],
        "load.point[0].at = 1.5: must be finite, in 0..1",
    ),
    ("load.point", [{"cable": "a", "force": [0, 0, 1]}], "load.point[0].at: missing"),
    (
        "load.point",
        [{"node": 0, "at": 0.5, "force": [0, 0, 1]}],
        "load.point[0].at = 0.5: only with cable",
    ),
    ("load.point", [{"force": [0, 0, 1]}], "load.point[0]: gives neither of node and cable"),
    ("load.point", [{"node": "ancors", "force": [0, 0, 1]}], "did you mean 'anchors'?"),
    (
        "load.line",
        [{"cable": "bb", "force": [0, 0, 1]}],
        "load.line[0].cable = 'bb': no such cable (accepted: 'a', 'b'); did you mean 'b'?",
    ),
    ("load.line", [{"force": [0, 0]}], "load.line[0].force = [0, 0]: must be [x, y, z]"),
]


@pytest.mark.parametrize(
    "path, value, message", BAD, ids=[b[0] + "=" + repr(b[1])[:20] for b in BAD]
)
def test_bad_cable_input_names_key_value_and_what_is_accepted(path, value, message):
    one(_set(two_cables(), path, value), message)


def test_edges_or_cables_are_needed():
    data = two_cables()
    del data["geometry"]["cable"]
    one(data, "geometry.edges: missing: [[i, j], ...] (at least 1 edge), or cables")


PER_EDGE = [
    ({"prestress": [1.0]}, "geometry.prestress = [1.0]: has 1 values: must have one per edge (2)"),
    ({"prestress": [1.0, "x"]}, "geometry.prestress[1] = 'x': must be a finite number"),
    ({"tension_only": [True, 1]}, "geometry.tension_only[1] = 1: must be true or false"),
    (
        {"prestress": [1.0, 1.0], "rest_length": [1.0, 1.0]},
        "geometry.prestress: gives the rest lengths of the edges: give it or "
        "geometry.rest_length, not both",
    ),
    ({"prestress": [1.0, 1.0], "prestrain": 0.1}, "give it or geometry.prestrain, not both"),
]


@pytest.mark.parametrize("extra, message", PER_EDGE)
def test_bad_per_edge_arrays(extra, message):
    data = straight()
    del data["geometry"]["cable"]
    data["geometry"]["edges"] = [[0, 1], [1, 2]]
    data["geometry"].update(extra)
    one(data, message)


def test_a_prestress_that_leaves_no_positive_rest_length_is_refused(tmp_path):
    """A strut (tension_only = false) prestressed to -EA would need l0 = |e| / 0."""
    data = straight(prestress=-1000.0, material={"tension_only": False})
    with pytest.raises(ConfigError, match=r"geometry.cable\[0\].prestress = -1000.0: cannot be"):
        build(parse_case(data))
    data = straight()
    del data["geometry"]["cable"]
    data["geometry"]["edges"] = [[0, 1], [1, 2]]
    data["geometry"]["prestress"] = [5.0, -3.0]
    with pytest.raises(ConfigError, match=r"geometry.prestress\[1\] = -3.0: .*tension-only"):
        build(parse_case(data))
    case_file = tmp_path / "bad.toml"
    case_file.write_text(dumps_toml(straight(prestress=-2000.0, material={"tension_only": False})))
    r = CliRunner().invoke(main, ["run", str(case_file), "-o", str(tmp_path / "x.h5")])
    assert r.exit_code == 2 and "geometry.cable[0].prestress = -2000.0" in r.output
    assert not (tmp_path / "x.h5").exists()


def test_cable_loads_need_a_graph_with_cables():
    data = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 5},
        "material": {"EA": 1.0},
        "load": {"line": [{"cable": "a", "force": [0, 0, -1]}]},
    }
    one(data, "load.line[0].cable = 'a': this geometry has no cables (geometry.kind = 'cable'")
    data["load"]["line"][0].pop("cable")  # every edge: any kind
    scene = build(parse_case(data))
    assert scene.loads.force[:, 2].sum() == pytest.approx(-1.0)


def test_a_json_graph_may_hold_cables_sets_and_per_edge_arrays(tmp_path):
    import json

    g = two_cables()["geometry"]
    g.pop("kind")
    g["edges"] = [[0, 2]]
    g["tension_only"] = [False]
    (tmp_path / "net.json").write_text(json.dumps(g))
    data = {**two_cables(), "geometry": {"kind": "graph", "file": "net.json"}}
    case = parse_case(data, base_dir=tmp_path)
    scene = build(case)
    assert scene.cables.names == ("a", "b") and scene.net.law.tension_only[0] == np.False_
    assert parse_case(tomllib.loads(case.to_toml())) == case
    g["cable"][0]["nodes"] = [0, 7]
    (tmp_path / "net.json").write_text(json.dumps(g))
    found = problems(data, base_dir=tmp_path)
    assert found == [
        "geometry.cable[0].nodes[1] = 7: is no node: must be a node index in 0..3 "
        "(in geometry.file = 'net.json')"
    ]


# --------------------------------------------------------------------------- named nodes


def test_center_of_a_cable_only_net_is_a_free_node_that_moves(tmp_path):
    """Every given node of two crossing cables is an anchor: 'center' (the probe, and a
    load's node) is the free node of the built net nearest the bounding box's centre (a
    cable subdivision), so the deflection reported is the net's, not a support's 0."""
    data = two_cables()
    data["load"] = {"point": [{"node": "center", "force": [0, 0, -50]}]}
    scene = build(parse_case(data))
    c = scene.probe
    assert c >= 4 and not scene.net.fixed[c]  # a subdivision node, free
    mid = 0.5 * (scene.net.nodes.min(axis=0) + scene.net.nodes.max(axis=0))
    free = np.flatnonzero(~scene.net.fixed)
    dist = np.linalg.norm(scene.net.nodes - mid, axis=1)
    assert dist[c] == pytest.approx(dist[free].min())
    result = run_case(parse_case(data), tmp_path / "c.h5")
    assert result.report.probe == c and result.report.delta > 1e-4
    # A net whose middle node is free keeps it; one whose middle node is a support
    # moves 'center' to the nearest free node.
    data = straight()
    assert build(parse_case(data)).probe == 1
    data["geometry"]["fixed"] = [0, 1, 2]
    scene = build(parse_case(data))
    assert scene.probe != 1 and not scene.net.fixed[scene.probe]


def test_output_probe_picks_the_reported_node(tmp_path):
    """output.probe names the node whose deflection is delta: an index, a node name or a
    set of one node, in a graph and in a square net; the run reports it."""
    data = straight(prestress=100.0)
    data["load"] = {"point": [{"node": 1, "force": [0, 0, -50]}]}
    data["geometry"]["sets"] = {"knee": [1]}
    for ref, node in ((1, 1), ("knee", 1), ("center", 1)):
        data["output"] = {"probe": ref}
        assert build(parse_case(data)).probe == node
    data["geometry"]["nodes"] += [[0, 0, 3], [-1.5, -0.5, 5]]  # a free node 3 on cable d
    data["geometry"]["fixed"] = [0, 2, 4]
    data["geometry"]["cable"].append({"name": "d", "nodes": [1, 3, 4], "prestress": 100.0})
    data["output"] = {"probe": 3}
    result = run_case(parse_case(data), tmp_path / "p.h5")
    x0 = build(parse_case(data)).net.nodes
    with h5py.File(tmp_path / "p.h5") as f:
        z = f["result/x"][3, 2]
    assert result.report.probe == 3
    assert abs(result.report.delta) > 1e-3
    assert result.report.delta == pytest.approx(x0[3, 2] - z, rel=1e-12)
    assert parse_case(data).output.probe == 3
    assert "probe = 3" in dumps_toml(parse_case(data).to_dict())
    with open(CONFIGS / "fig4a_n10_alpha_0.toml", "rb") as f:
        square = tomllib.load(f)
    square["output"] = {"probe": 7}
    assert build(parse_case(square)).probe == 7


@pytest.mark.parametrize(
    ("ref", "message"),
    [
        (99, "output.probe = 99: must be a node index in 0..3"),
        ("anchors", "output.probe = 'anchors': the node set has 4 nodes: the probe must be one"),
        ("nowhere", "output.probe = 'nowhere': must be a node index or one of"),
        (-1, "output.probe = -1: must be a node index (an integer >= 0)"),
    ],
)
def test_a_bad_probe_is_named(ref, message):
    data = two_cables()
    data["output"] = {"probe": ref}
    assert any(message in p for p in problems(data)), problems(data)
