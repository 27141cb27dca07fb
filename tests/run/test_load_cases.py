"""Load cases and combinations (contract §7): the base state solved once, each case
and combination solved from it on one workspace, results in /cases/<name>/ with the
layout of /result, envelopes in /envelope/."""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml, load_case, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.run.runner import run_case
from tests.conftest import CONFIGS

MAST = CONFIGS / "structures" / "guyed_mast.toml"
WIND_X = [10.0e3, 0.0, 0.0]
WIND_Y = [0.0, 10.0e3, 0.0]


def mast(cases=True) -> dict:
    """The bundled guyed mast (prestressed to equilibrium, no base load) with its top
    load as load case wind_x, a side wind wind_y and three combinations."""
    data = tomllib.loads(MAST.read_text())
    data["load"] = {}
    if cases:
        data["load_case"] = [
            {"name": "wind_x", "point": [{"node": "top", "force": WIND_X}]},
            {"name": "wind_y", "point": [{"node": "top", "force": WIND_Y}]},
        ]
        data["combination"] = [
            {"name": "ULS_x", "factors": {"wind_x": 1.5}},
            {"name": "both", "factors": {"wind_x": 1.0, "wind_y": 1.0}},
            {"name": "suction", "factors": {"wind_x": -0.5}},
        ]
    return data


def separate(tmp_path, name, forces) -> dict:
    """A plain run of the mast with the given top loads as its [load]."""
    data = mast(cases=False)
    data["load"] = {"point": [{"node": "top", "force": f} for f in forces]}
    path = tmp_path / f"{name}.h5"
    run_case(parse_case(data), path)
    return read_group(path, "result")


def read_group(path, group) -> dict:
    with h5py.File(path) as h5:
        g = h5[group]
        return {k: g[k][:] for k in ("x", "tension", "reaction")} | {"attrs": dict(g.attrs)}


def test_load_cases_match_separate_runs_bit_for_bit(tmp_path):
    """Each load case and combination equals a separate run of the mast under its loads
    (1.5 x wind_x: a run at 15 kN), bit for bit: the base state of the prestressed mast
    is its given geometry, and the solve path from there is the separate run's."""
    path = tmp_path / "cases.h5"
    result = run_case(parse_case(mast()), path)
    assert [r.name for r in result.cases] == ["wind_x", "wind_y", "ULS_x", "both", "suction"]
    assert all(r.converged for r in result.cases)
    want = {
        "wind_x": [WIND_X],
        "wind_y": [WIND_Y],
        "ULS_x": [[15.0e3, 0.0, 0.0]],
        "both": [WIND_X, WIND_Y],
        "suction": [[-5.0e3, 0.0, 0.0]],
    }
    for name, forces in want.items():
        got = read_group(path, f"cases/{name}")
        ref = separate(tmp_path, name, forces)
        for key in ("x", "tension", "reaction"):
            assert np.array_equal(got[key], ref[key]), (name, key)
        for key in ("max_displacement", "max_tension", "max_compression", "delta"):
            assert got["attrs"][key] == ref["attrs"][key], (name, key)
        assert got["attrs"]["kind"] == ("load_case" if name.startswith("wind") else "combination")
    # The base state is the unloaded, prestressed mast; /result holds it.
    base = read_group(path, "result")
    assert np.array_equal(base["x"], result.x)
    assert base["attrs"]["max_tension"] == pytest.approx(20e3, rel=1e-9)
    # Not superposed: the combination's displacement is not the sum of its cases'.
    x0 = result.x
    both = result.cases[3].result.x - x0
    summed = (result.cases[0].result.x - x0) + (result.cases[1].result.x - x0)
    assert not np.allclose(both, summed, rtol=1e-9, atol=0)
    assert np.allclose(both, summed, rtol=0.2, atol=1e-4)


def test_envelopes_and_stats(tmp_path):
    path = tmp_path / "cases.h5"
    result = run_case(parse_case(mast()), path)
    t = np.array([r.result.tension for r in result.cases])
    u = np.array([np.linalg.norm(r.result.x - result.x, axis=1) for r in result.cases])
    with h5py.File(path) as h5:
        env = h5["envelope"]
        assert env.attrs["cases"].astype(str).tolist() == [r.name for r in result.cases]
        assert np.array_equal(env["tension_max"][:], t.max(axis=0))
        assert np.array_equal(env["tension_min"][:], t.min(axis=0))
        assert np.array_equal(env["tension_max_case"][:], t.argmax(axis=0))
        assert np.array_equal(env["displacement_max"][:], u.max(axis=0))
        assert "peak_tension" in h5["cases/both"] and "reaction" in h5["cases/both"]
    s = result.report.cases
    assert s["ULS_x"]["max_displacement"] > s["wind_x"]["max_displacement"] > 0
    assert s["wind_x"]["max_tension"] == result.cases[0].result.tension.max()
    assert s["suction"]["converged"] and s["suction"]["max_displacement_vector"][0] < 0


def test_one_case_alone_equals_it_among_all(tmp_path):
    """--case NAME (run_case(load_case=...)) solves the base and that case only, with
    the same numbers as the run of all of them: the shared workspace leaves no trace."""
    all_ = run_case(parse_case(mast()), tmp_path / "all.h5")
    one = run_case(parse_case(mast()), tmp_path / "one.h5", load_case="both")
    assert [r.name for r in one.cases] == ["both"]
    assert np.array_equal(one.cases[0].result.x, all_.cases[3].result.x)
    with h5py.File(tmp_path / "one.h5") as h5:
        assert list(h5["cases"]) == ["both"]
    r = CliRunner().invoke(
        main,
        ["run", str(_write(tmp_path, mast())), "--case", "ULS_x", "-o", str(tmp_path / "c.h5")],
    )
    assert r.exit_code == 0, r.output
    assert "ULS_x" in r.output and "wind_y " not in r.output
    assert "load case         load z [N] horiz. [N] max displ. [m]" in r.output
    r = CliRunner().invoke(
        main, ["run", str(_write(tmp_path, mast())), "--case", "snow", "-o", str(tmp_path / "d.h5")]
    )
    assert r.exit_code == 2
    assert "--case 'snow': no [[load_case]] or [[combination]] is named so" in r.output
    assert not (tmp_path / "d.h5").exists()


def test_the_cases_table_tells_uplift_from_a_downward_load(tmp_path):
    """The table's load column is the resultant's signed z component (up +) and its
    horizontal size, not its length: snow (500 Pa down) and an uplift (800 Pa) on a
    12 m square's 144 m^2 read -72 kN and +115.2 kN; a sideways point load reads as
    horizontal."""
    case = {
        "geometry": {"kind": "square_net", "n": 6, "size": 12.0, "edge_length": 12.0, "alpha": 0.0},
        "material": {"EA": 1e6, "prestress": 2000.0},
        "load_case": [
            {"name": "snow", "area": [{"pressure": 500.0}]},
            {"name": "uplift", "area": [{"pressure": -800.0}]},
            {"name": "side", "point": [{"node": 14, "force": [300.0, -400.0, 0.0]}]},
        ],
    }
    r = CliRunner().invoke(main, ["run", str(_write(tmp_path, case)), "-o", str(tmp_path / "u.h5")])
    assert r.exit_code == 0, r.output
    rows = {line.split()[0]: line.split() for line in r.output.splitlines() if line}
    assert [float(v) for v in rows["snow"][1:3]] == [-72000.0, 0.0]
    assert [float(v) for v in rows["uplift"][1:3]] == [115200.0, 0.0]
    assert [float(v) for v in rows["side"][1:3]] == [0.0, 500.0]


def _write(tmp_path, data):
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(data))
    return path


def test_bad_load_cases_exit_2_with_the_key_path(tmp_path):
    data = mast()
    data["combination"][0]["factors"] = {"wind_z": 1.5}
    with pytest.raises(ConfigError) as info:
        parse_case(data)
    assert info.value.problems == [
        "combination[0].factors.wind_z = 1.5: no [[load_case]] is named 'wind_z' (the load "
        "cases: 'wind_x', 'wind_y')"
    ]
    r = CliRunner().invoke(main, ["run", str(_write(tmp_path, data))])
    assert r.exit_code == 2 and "combination[0].factors.wind_z = 1.5" in r.output
    bad = {
        ("load_case", 1, "name"): ("wind_x", "load_case[1].name = 'wind_x': already names"),
        ("load_case", 0, "name"): ("a/b", "load_case[0].name = 'a/b': must be a name"),
        ("combination", 1, "name"): ("wind_y", "combination[1].name = 'wind_y': already names"),
        ("combination", 0, "factors"): ({"wind_x": "x"}, "combination[0].factors.wind_x = 'x'"),
        ("load_case", 0, "point"): (
            [{"node": 99, "force": WIND_X}],
            "load_case[0].point[0].node = 99: must be a node index in 0..",
        ),
        ("load_case", 0, "pressure"): (100.0, "load_case[0].pressure = 100.0: only for"),
        ("load_case", 1, "point"): (
            [{"cable": "guy_x", "at": 0.5, "force": WIND_X}],
            "load_case[1].point[0].cable = 'guy_x'",
        ),
        ("load_case", 1, "line"): (
            [{"cable": "guy", "force": WIND_X}],
            "load_case[1].line[0].cable = 'guy'",
        ),
        ("load_case", 0, "snow"): (1.0, "load_case[0].snow: unknown key"),
        ("load_case", 0, "history"): ([[0, 0], [1, 1]], "load_case[0].history: a load case is"),
        ("load_case", 0, "area"): (  # (it was applied in full, in silence)
            [{"pressure": 100.0, "history": [[0, 0], [1, 0.5]]}],
            "load_case[0].area[0].history: a load case is",
        ),
        ("load_case", 1, "gravity"): ([0, 0, -9.81], "load_case[1].gravity = [0, 0, -9.81]"),
    }
    for (table, k, key), (value, message) in bad.items():
        data = mast()
        data[table][k][key] = value
        with pytest.raises(ConfigError) as info:
            parse_case(data)
        assert any(p.startswith(message) for p in info.value.problems), info.value.problems
    data = mast()
    data["solver"]["method"] = "dynamic"
    with pytest.raises(ConfigError) as info:
        parse_case(data)
    assert any("[[load_case]] and [[combination]] are static" in p for p in info.value.problems)


def test_a_combination_of_a_combination_and_a_graphs_pressure_are_told_what_to_do():
    """A combination naming a combination is told combinations are not nested (it read as
    if no such name existed); a load case's pressure on a graph is pointed to the case's
    own area loads (it was pointed to [[load.point]])."""
    data = mast()
    data["combination"].append({"name": "twice", "factors": {"ULS_x": 2.0}})
    with pytest.raises(ConfigError) as info:
        parse_case(data)
    assert info.value.problems == [
        "combination[3].factors.ULS_x = 2.0: no [[load_case]] is named 'ULS_x' (a "
        "combination: combinations combine load cases, not combinations) (the load cases: "
        "'wind_x', 'wind_y')"
    ]
    data = mast()
    data["load_case"][0]["pressure"] = 100.0
    with pytest.raises(ConfigError) as info:
        parse_case(data)
    assert any(
        "give a pressure as load_case[0].area (area loads on the net's cells), or use "
        "load_case[0].point or load_case[0].gravity" in p
        for p in info.value.problems
    ), info.value.problems


def test_resolved_case_keeps_the_load_cases(tmp_path):
    case = parse_case(mast())
    again = parse_case(tomllib.loads(case.to_toml()))
    assert again.load_cases == case.load_cases and again.combinations == case.combinations
    assert load_case(_write(tmp_path, mast())).combinations[1].factors == {
        "wind_x": 1.0,
        "wind_y": 1.0,
    }


def test_cases_start_from_a_base_state_under_self_weight(tmp_path):
    """A sagging cable: the base state is its catenary under self-weight; a point load
    case solved from it reaches the equilibrium a separate run under self-weight plus the
    point load reaches from the straight chord (to the solver's tolerance: the paths
    differ), and a combination 0 x the case is the base state itself."""
    data = {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, 0.0],
            "end": [20.0, 0.0, 0.0],
            "length": 20.4,
            "nodes": 21,
        },
        "material": {"EA": 2.0e6, "density": 7850.0, "radius": 0.004},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"rtol": 1e-11, "steps": 3},
    }
    alone = dict(data, load={**data["load"], "point": [{"node": 5, "force": [0, 0, -400.0]}]})
    data["load_case"] = [{"name": "hoist", "point": [{"node": 5, "force": [0, 0, -400.0]}]}]
    data["combination"] = [{"name": "none", "factors": {"hoist": 0.0}}]
    result = run_case(parse_case(data), tmp_path / "c.h5")
    ref = run_case(parse_case(alone), tmp_path / "r.h5")
    hoist, none = result.cases
    assert hoist.converged and none.converged
    scale = np.abs(ref.x - result.x).max()
    assert scale > 0.1  # the point load moves the cable by decimetres
    assert np.allclose(hoist.result.x, ref.x, rtol=0, atol=1e-8 * scale)
    assert np.allclose(hoist.result.tension, ref.tension, rtol=1e-8)
    assert np.allclose(none.result.x, result.x, rtol=0, atol=1e-12)
    assert hoist.numbers["max_displacement_node"] in (4, 5, 6)


def test_the_mast_load_cases_example(tmp_path):
    """configs/structures/mast_load_cases.toml: every case converges; the ice case's
    reactions carry the ice (50 N per metre of unstressed guy: four 25 m guys prestrained
    by 20 kN / EA = 1e-3, 5000 / 1.001 N) and nothing sideways; the
    windward guy governs the tension envelope under the factored wind."""
    case = load_case(CONFIGS / "structures" / "mast_load_cases.toml")
    result = run_case(case, tmp_path / "m.h5")
    names = [r.name for r in result.cases]
    assert names == ["wind_x", "wind_y", "ice", "ULS_wind_x", "ULS_diagonal"]
    assert all(r.converged for r in result.cases)
    ice = result.report.cases["ice"]
    weight = 4 * 50.0 * 25.0 / (1.0 + 20e3 / 2e7)
    assert ice["reaction_resultant"] == pytest.approx([0.0, 0.0, weight], abs=1e-6 * weight)
    with h5py.File(tmp_path / "m.h5") as h5:
        env = h5["envelope"]
        top = int(np.argmax(env["tension_max"][:]))
        governing = env.attrs["cases"].astype(str)[env["tension_max_case"][top]]
        assert env["tension_max"][top] == result.report.cases[governing]["max_tension"]
        assert governing == "ULS_wind_x"
        assert np.all(env["tension_min"][:] <= env["tension_max"][:])
        least = env["tension_min"][:]
    e = result.report.envelope
    assert e["tension_max"]["case"] == "ULS_wind_x" and e["tension_max"]["at"] == top
    assert e["tension_min"]["value"] == least.min() < 0  # the strut
    assert e["displacement_max"]["case"] == "ULS_diagonal"
    r = CliRunner().invoke(
        main,
        [
            "run",
            str(CONFIGS / "structures" / "mast_load_cases.toml"),
            "-o",
            str(tmp_path / "cli.h5"),
        ],
    )
    assert r.exit_code == 0, r.output
    assert (
        f"envelope     largest compression {-least.min():.6g} N (edge 0, ULS_diagonal)" in r.output
    )
    assert f"largest tension {e['tension_max']['value']:.6g} N (edge {top}, ULS_wind_x)" in r.output


def test_a_signal_stops_the_load_cases(tmp_path):
    """An interrupt (Ctrl-C's flag) during the load cases stops them: the one under way
    keeps its last good state, the ones after it are not solved."""
    from catenet.case import build
    from catenet.run.cases import solve_cases
    from catenet.solver import path as sv

    case = parse_case(mast())
    scene = build(case)
    settings = sv.Settings.of(case.solver)
    ws = sv.workspace(scene, settings)
    base = sv.solve(scene, settings, workspace=ws)
    runs = solve_cases(scene, settings, ws, base, scene.cases, interrupt=lambda: True)
    assert [r.name for r in runs] == ["wind_x"]
    assert not runs[0].converged and "interrupt" in runs[0].error
    assert np.array_equal(runs[0].result.x, base.x)  # its last good state: the base


def test_a_load_case_along_a_cable_puts_its_node_in_the_shared_net(tmp_path):
    """A load case's point load at a position along a cable (``cable``, ``at``) splits the
    cable there in the one net every case shares; the case equals a separate run with
    that load in [load] (same net, same start: the prestressed cable is in equilibrium)."""
    cable = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [10, 0, 0]],
            "edge_length": 1.0,
            "cable": [{"name": "c", "nodes": [0, 1], "prestress": 1000.0}],
            "fixed": [0, 1],
        },
        "material": {"EA": 1e6},
    }
    point = {"cable": "c", "at": 0.33, "force": [0, 0, -500.0]}
    with_case = {**cable, "load_case": [{"name": "hook", "point": [point]}]}
    result = run_case(parse_case(with_case), tmp_path / "c.h5")
    alone = run_case(parse_case({**cable, "load": {"point": [point]}}), tmp_path / "a.h5")
    (hook,) = result.cases
    assert len(result.x) == len(alone.x) == 12  # 11 nodes of 1 m edges and one at 3.3 m
    assert np.any(np.isclose(result.x[:, 0], 3.3))
    assert np.array_equal(hook.result.x, alone.x)
    assert np.array_equal(hook.result.tension, alone.tension)
