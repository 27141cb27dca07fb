"""What `catenet formfind` writes beside the shape, besides the net: the case's point
masses, obstacles, load cases, combinations and time histories, so that `catenet run` on
OUT.toml gives the same summary as the original case would in the form-found geometry;
and targets per cable (``formfind.force = { "hang*" = ..., edges = ... }``)."""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from meshes import hypar_roof

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.formfind import write_formfind
from catenet.formfind.case import formfind_scene
from catenet.run.runner import run_case


def original() -> dict:
    """A graph roof to form find, with every table a loaded analysis of it may carry:
    point masses (on a named node and a node set), a plane below it, load cases (a point
    along a cable, an area over a region, a line along a cable, gravity) and combinations."""
    data = hypar_roof(edge_length=0.5)
    data["material"] = {"E": 160e9, "radius": 0.006, "density": 7850.0}
    data["geometry"]["sets"]["mid"] = {"near": [0, 0, 0]}
    data["geometry"]["sets"]["east"] = {"box": [[0, -6, -3], [6, 6, 3]]}
    data["formfind"] = {"method": "linear", "force_density": 1e4}
    data["load"] = {"gravity": [0, 0, -9.81], "point": [{"node": "mid", "force": [0, 0, -500.0]}]}
    data["mass"] = [{"node": "center", "mass": 40.0}, {"node": "mid", "mass": 25.0}]
    data["obstacle"] = [{"kind": "plane", "point": [0, 0, -5.0], "normal": [0, 0, 1]}]
    data["load_case"] = [
        {"name": "snow", "area": [{"pressure": 800.0}]},
        {
            "name": "wind_east",
            "area": [{"pressure": -500.0, "direction": "normal", "nodes": "east"}],
        },
        {
            "name": "hoist",
            "point": [{"cable": "y0", "at": 0.3, "force": [0, 0, -2000.0]}],
            "line": [{"cable": "x1", "force": [0, 0, -100.0]}],
        },
    ]
    data["combination"] = [
        {"name": "ULS", "factors": {"snow": 1.5, "wind_east": 0.9, "hoist": 1.35}},
    ]
    data["output"] = {"probe": "center"}
    return data


def in_found_geometry(written, data: dict) -> dict:
    """The original case in the form-found geometry: the written net (nodes, cables with
    their rest lengths, node sets) with the original's own tables, a load along a cable
    put on the node that form finding split there (its position along the new cable is
    not the same fraction of its length)."""
    out = tomllib.loads(written.case_file.read_text())
    scene = build(parse_case(data))
    for key in ("mass", "obstacle", "combination"):
        out[key] = data[key]
    cases = [dict(c) for c in data["load_case"]]
    offset = len(data["load"]["point"])
    for c in cases:
        c["point"] = [
            {"node": int(scene.at_nodes[offset + j]), "force": p["force"]}
            for j, p in enumerate(c.get("point", ()))
        ]
        offset += len(c["point"])
        if not c["point"]:
            del c["point"]
    out["load_case"] = cases
    out["mass"] = [
        dict(m, node=int(scene.names["center"])) if m["node"] == "center" else m
        for m in data["mass"]
    ]
    out["output"]["probe"] = int(scene.names["center"])
    return out


def numbers(result) -> dict:
    """The summary's numbers of a run and of each of its load cases."""
    return {"base": result.report.summary, **result.report.cases}


def same(a, b, path="") -> None:
    """Equal summaries: numbers to 1e-9 (relative; the same solves from the same
    state), the rest exactly."""
    if isinstance(a, dict):
        assert set(a) == set(b), path
        for k in a:
            same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, float) and not isinstance(b, bool):
        assert b == pytest.approx(a, rel=1e-9, abs=1e-9), path
    elif isinstance(a, (list, tuple, np.ndarray)):
        np.testing.assert_allclose(
            np.asarray(a, float), np.asarray(b, float), rtol=1e-9, atol=1e-9, err_msg=path
        )
    else:
        assert a == b, path


def test_the_written_case_runs_as_the_original_would_in_the_found_geometry(tmp_path):
    data = original()
    case = parse_case(data, source=str(tmp_path / "roof.toml"))
    written = write_formfind(case, tmp_path / "found.h5")
    back = tomllib.loads(written.case_file.read_text())
    assert [c["name"] for c in back["load_case"]] == ["snow", "wind_east", "hoist"]
    assert back["combination"] == data["combination"]
    assert back["obstacle"][0]["kind"] == "plane" and len(back["mass"]) == 2
    assert back["mass"][1]["node"] == "mid"  # a node set stays a node set
    assert isinstance(back["mass"][0]["node"], int)  # "center" moves with the shape
    assert back["load_case"][1]["area"][0]["nodes"] == "east"
    hoist = back["load_case"][2]
    assert "cable" not in hoist["point"][0] and hoist["line"] == data["load_case"][2]["line"]
    got = run_case(written.case, tmp_path / "run.h5")
    want = run_case(parse_case(in_found_geometry(written, data)), tmp_path / "want.h5")
    assert got.converged and all(r.converged for r in got.cases)
    assert [r.name for r in got.cases] == ["snow", "wind_east", "hoist", "ULS"]
    same(numbers(want), numbers(got))
    assert (
        got.report.cases["ULS"]["max_displacement"] > got.report.cases["snow"]["max_displacement"]
    )
    # The point masses are in the net written, on the same nodes.
    assert np.array_equal(build(written.case).net.point_mass, build(case).net.point_mass)
    assert build(case).net.point_mass.sum() == 65.0


def test_time_histories_are_kept_for_dynamic_runs(tmp_path):
    """A graph's line and area loads with a history are no part of the form finding
    (its loads are the constant ones): they are written as given; load.history too."""
    data = original()
    for key in ("load_case", "combination", "obstacle"):
        del data[key]
    data["solver"] = {"method": "dynamic", "t_end": 0.02, "dt": 0.01}
    data["load"]["area"] = [{"pressure": 200.0, "history": [[0, 0], [0.02, 1]]}]
    data["load"]["line"] = [{"cable": "x1", "force": [0, 0, -10.0], "history": [[0, 1], [1, 0]]}]
    written = write_formfind(parse_case(data), tmp_path / "dyn.h5")
    back = tomllib.loads(written.case_file.read_text())
    assert back["load"]["area"] == [dict(data["load"]["area"][0], direction="plan")]
    assert back["load"]["line"] == data["load"]["line"]
    assert run_case(written.case, tmp_path / "dyn_run.h5").converged
    # A square net: its timed loads as nodal point loads with their history.
    sq = {
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.0, "size": 1.0, "edge_length": 0.25},
        "material": {"EA": 1e3, "density": 1e3, "radius": 0.01},
        "load": {"point": [{"node": "center", "force": [0, 0, -1.0], "history": [[0, 0], [1, 1]]}]},
        "solver": {"method": "dynamic", "t_end": 0.1, "dt": 0.05},
        "formfind": {"method": "linear", "force_density": 10.0},
    }
    w2 = write_formfind(parse_case(sq), tmp_path / "sq.h5")
    points = tomllib.loads(w2.case_file.read_text())["load"]["point"]
    center = build(parse_case(sq)).names["center"]
    assert points == [
        {"node": center, "force": [0.0, 0.0, -1.0], "history": [[0.0, 0.0], [1.0, 1.0]]}
    ]


def test_targets_by_cable(tmp_path):
    """force = { pattern = N, edges = N }: each cable's edges meet their value, the
    graph's own edges theirs."""
    data = hypar_roof(cells=3)
    data["material"] = {"EA": 1e7}
    ring = data["geometry"]["cable"][-1]["nodes"]
    data["geometry"]["edges"] = [ring[:2]]  # its first piece an own edge (between supports)
    data["geometry"]["cable"][-1]["nodes"] = ring[1:]
    data["formfind"] = {
        "method": "forces",
        "force": {"x*": 2e3, "y*": 3e3, "edge": 5e3, "edges": 1e3},
    }
    scene = build(parse_case(data))
    found = formfind_scene(scene)
    names = np.array(scene.cables.names)
    edge = np.asarray(scene.cables.edge)
    want = np.select(
        [edge < 0, np.char.startswith(names[edge], "x"), np.char.startswith(names[edge], "y")],
        [1e3, 2e3, 3e3],
        5e3,
    )
    np.testing.assert_allclose(found.force, want, rtol=1e-9)


@pytest.mark.parametrize(
    ("force", "message"),
    [
        (
            {"x*": 2e3, "z*": 1.0},
            "formfind.force.z* = 1.0: matches no cable (the cables: x-2, x-1, x0, x1, x2, "
            "y-2, y-1, y0, y1, y2, edge)",
        ),
        (
            {"x*": 2e3, "x1": 3e3, "y*": 1e3, "edge": 1e3},
            "formfind.force.x1 = 3000.0: cable 'x1' has a value already (from formfind.force.x*): "
            "give each cable one",
        ),
        (
            {"x*": 2e3, "edge": 1e3},
            "formfind.force = { \"x*\" = 2000.0, edge = 1000.0 }: gives no value for cable 'y-2': "
            "give every edge one",
        ),
        ({"x*": -1.0}, "formfind.force.x* = -1.0: must be a number, finite and > 0"),
        ({}, 'formfind.force = {}: must name at least one cable: { NAME or "PATTERN*" = value'),
    ],
)
def test_bad_tables_by_cable_exit_2_naming_the_key(tmp_path, force, message):
    data = hypar_roof(cells=3)
    data["material"] = {"EA": 1e7}
    data["formfind"] = {"method": "forces", "force": force}
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["formfind", str(path), "-o", str(tmp_path / "o.h5")])
    assert r.exit_code == 2, r.output
    assert message in r.output, r.output
    assert not (tmp_path / "o.h5").exists()


def test_a_table_by_cable_needs_cables():
    data = {
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.0, "size": 1.0, "edge_length": 0.25},
        "material": {"EA": 1e3},
        "formfind": {"method": "forces", "force": {"a": 1.0}},
    }
    with pytest.raises(ConfigError) as info:
        formfind_scene(build(parse_case(data)))
    assert info.value.problems == [
        "formfind.force = { a = 1.0 }: a table by cable needs a graph with [[geometry.cable]]: "
        "give one number, or one per edge"
    ]


def test_a_free_body_is_kept_out_of_the_form_finding(tmp_path):
    """A free rigid body (an obstacle with mass) adds a node of its own to the net, with
    no edge: form finding leaves it where it is, and the written case, which holds the
    obstacle, adds it again."""
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0], [2, 2, 1.0]],
            "edges": [[0, 4], [1, 4], [2, 4], [3, 4]],
            "fixed": [0, 1, 2, 3],
        },
        "material": {"EA": 1e5, "density": 1000.0, "radius": 0.01},
        "formfind": {"method": "linear", "force_density": 100.0},
        "obstacle": [{"kind": "sphere", "center": [2, 2, 3], "radius": 0.5, "mass": 10.0}],
        "solver": {"method": "dynamic", "t_end": 0.05, "dt": 0.01},
    }
    written = write_formfind(parse_case(data), tmp_path / "fb.h5")
    back = tomllib.loads(written.case_file.read_text())
    assert len(back["geometry"]["nodes"]) == 5 and back["geometry"]["fixed"] == [0, 1, 2, 3]
    assert back["geometry"]["nodes"][4] == [2.0, 2.0, 0.0]  # the corners' mean
    assert back["obstacle"][0]["mass"] == 10.0
    assert build(written.case).net.bodies == build(parse_case(data)).net.bodies == 1


def test_tensions_given_to_cables_are_refused_with_one_message(tmp_path):
    data = hypar_roof(cells=3)
    data["material"] = {"EA": 1e7}
    for cable in data["geometry"]["cable"][:3]:
        cable["prestress"] = 3e3
    data["formfind"] = {"method": "linear", "force_density": 1e3}
    with pytest.raises(ConfigError) as info:
        parse_case(data)
    assert info.value.problems == [
        "geometry.cable[0].prestress = 3000.0: form finding gives every edge its tension: "
        "remove it (2 more cables give theirs) (target tensions by cable: formfind.method = "
        "'forces' with formfind.force = { NAME = N, ... })"
    ]


@pytest.mark.parametrize("units", ["kN-m", "N-mm"])
def test_the_written_case_keeps_the_units_it_was_found_in(tmp_path, units):
    """A star of four cables in kN-m or N-mm, its centre to hang 300 mm (0.3 m) below
    the supports under 10 kN: OUT.toml names the case's units (its numbers are the
    case's own), and `catenet run` on it warns of no unit slip and reproduces the shape
    and the tension (by hand: T = P / (4 sin a), sin a = 0.3 / sqrt(2^2 + 0.3^2))."""
    mm = units == "N-mm"
    length, force = (1000.0, 10e3) if mm else (1.0, 10.0)
    data = {
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], *[[2 * length * c, 2 * length * s, 0]
                                   for c, s in ((1, 0), (-1, 0), (0, 1), (0, -1))]],
            "edge_length": 0.25 * length,
            "sets": {"centre": [0], "supports": [1, 2, 3, 4]},
            "cable": [{"name": n, "nodes": [0, k + 1]} for k, n in enumerate("ENWS")],
        },
        "supports": {"fixed": ["supports"]},
        "material": {"E": 200e3 if mm else 200e6, "area": 78.5 if mm else 78.5e-6},
        "load": {"point": [{"node": "centre", "force": [0, 0, -force]}]},
        "formfind": {"force_density": 1.0, "vary": "cables"},
        "target": [{"node": "centre", "z": -0.3 * length}],
    }  # fmt: skip
    path = tmp_path / "star.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["formfind", str(path), "-o", str(tmp_path / "f.h5")])
    assert r.exit_code == 0, r.output
    written = tomllib.loads((tmp_path / "f.toml").read_text())
    assert written["units"] == units
    r = CliRunner().invoke(main, ["run", str(tmp_path / "f.toml"), "-o", str(tmp_path / "r.h5")])
    assert r.exit_code == 0, r.output
    assert "check units" not in r.output and "warning:" not in r.output
    with h5py.File(tmp_path / "r.h5") as h5:
        tension = h5["result/tension"][()]
        z = h5["result/x"][0, 2]
    sin_a = 0.3 / np.hypot(2.0, 0.3)
    np.testing.assert_allclose(tension, force / (4 * sin_a), rtol=1e-6)
    assert z == pytest.approx(-0.3 * length, rel=1e-6)
