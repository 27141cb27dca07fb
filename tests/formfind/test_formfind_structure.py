"""The case `catenet formfind` writes keeps the structure of a graph case: its cables (by
name, with their materials and the rest length of each edge), node sets, the loads' node
references, so that `catenet run` on it reports per cable exactly what form finding
found; the rest lengths of cables given per edge; the compiled loop of strains for
tensions gives what the scalar kernel gives."""

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
from catenet.kernels.laws import strain_for_force
from catenet.model.laws import Law, table_rows
from catenet.run.runner import run_case


def roof_case() -> dict:
    """The hypar roof with steel cables (one heavier), loads on a set, along a cable and
    over the area, to be form found at a uniform force density."""
    data = hypar_roof(edge_length=0.5)
    data["material"] = {"E": 160e9, "radius": 0.006, "density": 7850.0}
    data["geometry"]["cable"][2]["material"] = {"radius": 0.008}
    data["geometry"]["sets"]["mid"] = {"near": [0, 0, 0]}
    data["formfind"] = {"method": "linear", "force_density": 1e4}
    data["load"] = {
        "gravity": [0, 0, -9.81],
        "point": [
            {"node": "mid", "force": [0, 0, -1000.0]},
            {"cable": "y0", "at": 0.3, "force": [0, 0, -500.0]},
        ],
        "area": [{"pressure": 100.0}],
    }
    data["output"] = {"probe": "center"}
    return data


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ff")
    case = parse_case(roof_case(), source=str(tmp / "roof.toml"))
    return case, write_formfind(case, tmp / "found.h5"), tmp


def test_the_written_case_keeps_cables_materials_sets_and_load_nodes(written):
    case, w, _ = written
    back = w.case
    names = [c.name for c in case.geometry.cables]
    assert [c.name for c in back.geometry.cables] == names
    assert back.geometry.cables[2].material.as_dict() == {"radius": 0.008}
    assert back.geometry.edge_length is None  # every cable written as split
    scene, again = build(case), build(back)
    assert np.array_equal(again.net.edges, scene.net.edges)
    assert np.array_equal(again.cables.edge, scene.cables.edge)
    assert np.array_equal(again.net.EA, scene.net.EA)
    assert np.array_equal(again.net.line_density, scene.net.line_density)
    for name in ("border", "mid"):
        assert again.sets[name] == scene.sets[name]
    points = back.load.points
    assert points[0].node == "mid" and points[1].node == scene.at_nodes[1]
    assert back.load.gravity == case.load.gravity
    assert back.output.probe == scene.names["center"] == again.probe  # not moved
    total = build(back).loads.external_force(again.net)
    found = w.found.load
    assert np.allclose(total, found, rtol=0, atol=1e-12 * np.abs(found).max())


def test_running_it_reports_per_cable_what_form_finding_found(written, tmp_path):
    _, w, _ = written
    res = run_case(w.case, tmp_path / "run.h5")
    assert res.converged
    assert np.abs(res.x - w.found.x).max() <= 1e-9
    with h5py.File(w.result_file) as h5:
        found = h5["result/cable_max_tension"][:]
        names = h5["mesh"].attrs["cable_names"].astype(str).tolist()
    per_cable = res.report.cables
    assert list(per_cable) == names
    got = np.array([per_cable[n].max_tension for n in names])
    np.testing.assert_allclose(got, found, rtol=1e-9)
    r = CliRunner().invoke(main, ["run", str(w.case_file), "-o", str(tmp_path / "cli.h5")])
    assert r.exit_code == 0, r.output
    for name in names:
        assert f"cable        {name}: max tension" in r.output


def test_snow_on_the_written_case_is_reported_per_cable(written, tmp_path):
    _, w, _ = written
    data = tomllib.loads(w.case_file.read_text())
    data["load"]["area"] = [{"pressure": 800.0}]
    res = run_case(parse_case(data), tmp_path / "snow.h5")
    assert res.converged and set(res.report.cables) == {c.name for c in w.case.geometry.cables}


def test_cable_rest_lengths_per_edge_are_checked(tmp_path):
    data = hypar_roof()
    data["geometry"]["cable"][0]["rest_length"] = [1.0, 2.0]
    with pytest.raises(ConfigError) as info:
        build(parse_case(data))
    assert info.value.problems == [
        "geometry.cable[0].rest_length: 2 values: the cable has 6 edges after splitting "
        "(one value per edge, in order)"
    ]
    data["geometry"]["cable"][0]["prestress"] = 10.0
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path)])
    assert r.exit_code == 2
    assert (
        "geometry.cable[0].rest_length = [1.0, 2.0]: gives the rest lengths: give it or "
        "prestress, not both" in r.output
    )


@pytest.mark.parametrize("law", ["linear", "neo_hookean", "hencky", "table"])
def test_strains_for_tensions_are_the_scalar_kernels(law):
    rng = np.random.default_rng(3)
    m = 40
    table = table_rows([[0.01, 100.0], [0.05, 300.0], [0.2, 600.0]])[0] if law == "table" else None
    only = rng.random(m) < 0.5
    lw = Law.uniform(m, law, tension_only=only, table=table)
    tension = rng.normal(0.0, 200.0, m)
    EA = rng.uniform(5e3, 2e4, m)
    got = lw.strain_for_tension(tension, EA)
    for k in range(m):
        want = (
            np.nan
            if only[k] and tension[k] < 0
            else strain_for_force(lw.kind[k], lw.params[k], lw.table, tension[k] / EA[k])
        )
        assert (np.isnan(got[k]) and np.isnan(want)) or got[k] == want
