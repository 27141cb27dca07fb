"""configs/structures/hypar_principal.toml as a user runs it: a hypar roof whose cables
follow the principal curvatures, form found to target forces per family (a table by
cable), then its dead load, snow and wind as load cases from the prestressed state, with
factored combinations and the envelope.

Checks of physics, not of numbers seen once:
- every edge of the form-found state carries its family's target (hanging 45 kN, arching
  60 kN, the ring 1 kN), and the written case, run without load, stays there;
- the snow on plan totals the pressure times the plan area the ring closes, 24 m x 24 m;
  the dead load totals its cladding pressure times that area plus the cables' weight;
- in every load case and combination the reactions balance the loads it applies (static
  equilibrium of the whole roof: the prestress is internal);
- a combination is the nonlinear solution under the factored loads: it equals a load case
  given those loads directly (same solve path) and a plain run under them, and differs
  from the factored sum of its cases' displacements;
- the envelope is the largest and least tension and the largest displacement over the
  cases, with the governing case;
- with too little prestress in the arching family, the wind from x slackens some of
  its edges (and none of the hanging family's): each case's slack count is the number of
  its edges without tension, and the summary reports them.
"""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
import pytest

from catenet.case import build, load_case, parse_case
from catenet.formfind import write_formfind
from catenet.run.runner import run_case
from tests.conftest import CONFIGS

HYPAR = CONFIGS / "structures" / "hypar_principal.toml"
TARGETS = {"hang": 45e3, "arch": 60e3}
RING = 1e3
PLAN = 24.0 * 24.0  # m^2: the square the ring closes


@pytest.fixture(scope="module")
def roof(tmp_path_factory):
    """The form-found roof (formfind), the case it wrote, and the run of that case with
    all its load cases."""
    tmp = tmp_path_factory.mktemp("hypar")
    written = write_formfind(load_case(HYPAR), tmp / "hypar.h5")
    result = run_case(written.case, tmp / "hypar_run.h5")
    return written, result, tmp


def families(scene) -> dict[str, np.ndarray]:
    """The edges of each family (by the cables' names) and of the ring (own edges)."""
    names = np.array(scene.cables.names)
    edge = np.asarray(scene.cables.edge)
    out = {f: np.isin(edge, np.flatnonzero(np.char.startswith(names, f))) for f in TARGETS}
    out["ring"] = edge < 0
    return out


def test_the_form_found_forces_are_the_targets(roof):
    written, result, _ = roof
    scene = build(written.case)
    fam = families(scene)
    assert fam["hang"].sum() == fam["arch"].sum() == 11 * 12 * 2 and fam["ring"].sum() == 48
    with h5py.File(written.result_file) as h5:
        found = h5["result/tension"][()]
    for family, target in TARGETS.items():
        np.testing.assert_allclose(found[fam[family]], target, rtol=1e-8)
    np.testing.assert_allclose(found[fam["ring"]], RING, rtol=1e-8)
    # The written case, run without load, stays in the form-found state.
    assert result.converged
    np.testing.assert_allclose(result.tension, found, rtol=1e-8, atol=0)
    assert np.abs(result.x - written.found.x).max() <= 1e-9 * 24
    # The crossings lie near the hypar z = x^2/72 - y^2/96 (the targets are not its force
    # densities exactly: equal tension along each cable, not equal horizontal force).
    free = ~scene.net.fixed
    x, y, z = result.x[free].T
    assert np.abs(z - (x * x / 72 - y * y / 96)).max() < 0.15


def test_the_snow_and_dead_load_totals(roof):
    written, _, _ = roof
    scene = build(written.case)
    loads = {c.name: c.force for c in scene.cases}
    snow = loads["snow"].sum(axis=0)
    assert snow[2] == pytest.approx(-800.0 * PLAN, rel=1e-12)
    assert np.abs(snow[:2]).max() <= 1e-12 * 800.0 * PLAN
    weight = (scene.net.line_density * scene.net.rest_length).sum() * 9.81
    assert loads["dead"].sum(axis=0)[2] == pytest.approx(-(300.0 * PLAN + weight), rel=1e-12)
    # Wind: normal to the roof, in two halves with pressure and suction; the halves meet
    # along the middle cable and cover the roof once.
    assert loads["wind_x"][:, 0].any() and loads["wind_x"][:, 2].any()


def test_every_case_balances_its_loads(roof):
    written, result, tmp = roof
    scene = build(written.case)
    loads = {c.name: c.force for c in scene.cases}
    assert [r.name for r in result.cases] == [c.name for c in scene.cases]
    assert len(result.cases) == 7 and all(r.converged for r in result.cases)
    with h5py.File(tmp / "hypar_run.h5") as h5:
        for name, force in loads.items():
            reaction = h5[f"cases/{name}/reaction"][()]
            scale = np.abs(force).sum() + np.abs(reaction).sum()  # the solver's tolerance
            assert np.abs(reaction.sum(axis=0) + force.sum(axis=0)).max() <= 1e-8 * scale, name
            free = ~scene.net.fixed
            assert not reaction[free].any(), name


def test_a_combination_is_solved_under_the_factored_loads(roof, tmp_path):
    """ULS_snow = 1.35 dead + 1.5 snow + 0.9 wind_x: the same as a load case that gives
    those loads directly, and as a plain run under them (the base state is the given,
    form-found geometry); not the factored sum of the cases' displacements."""
    written, result, _ = roof
    data = tomllib.loads(written.case_file.read_text())
    cases = {c["name"]: c for c in data["load_case"]}
    dead, snow, wind = cases["dead"], cases["snow"], cases["wind_x"]
    direct = {
        "gravity": [1.35 * g for g in dead["gravity"]],
        "area": [
            {**dead["area"][0], "pressure": 1.35 * dead["area"][0]["pressure"]},
            {**snow["area"][0], "pressure": 1.5 * snow["area"][0]["pressure"]},
            *({**a, "pressure": 0.9 * a["pressure"]} for a in wind["area"]),
        ],
    }
    by_name = {r.name: r.result for r in result.cases}
    combo = by_name["ULS_snow"]
    # As a load case of its own, from the same base state.
    one = dict(data, load_case=[{"name": "direct", **direct}])
    one.pop("combination")
    got = run_case(parse_case(one), tmp_path / "direct.h5").cases[0].result
    span = 24.0
    assert np.abs(got.x - combo.x).max() <= 1e-9 * span
    np.testing.assert_allclose(got.tension, combo.tension, rtol=1e-7, atol=1e-6 * RING)
    # As a plain run: the factored loads as its [load].
    plain = {k: v for k, v in data.items() if k not in ("load_case", "combination")}
    plain["load"] = direct
    run = run_case(parse_case(plain), tmp_path / "plain.h5")
    assert run.converged
    assert np.abs(run.x - combo.x).max() <= 1e-8 * span
    # Nonlinear: not the factored sum of the cases' responses.
    x0 = result.x
    summed = sum(f * (by_name[n].x - x0) for n, f in (("dead", 1.35), ("snow", 1.5)))
    summed = summed + 0.9 * (by_name["wind_x"].x - x0)
    assert np.abs(summed - (combo.x - x0)).max() > 1e-3 * np.abs(combo.x - x0).max()


def test_the_envelope_is_over_the_cases(roof):
    written, result, tmp = roof
    with h5py.File(tmp / "hypar_run.h5") as h5:
        names = h5["envelope"].attrs["cases"].astype(str).tolist()
        t = np.array([h5[f"cases/{n}/tension"][()] for n in names])
        x = np.array([h5[f"cases/{n}/x"][()] for n in names])
        env = {k: h5[f"envelope/{k}"][()] for k in h5["envelope"]}
        nodes = h5["mesh/nodes"][()]
    assert names == [r.name for r in result.cases]
    assert np.array_equal(env["tension_max"], t.max(axis=0))
    assert np.array_equal(env["tension_min"], t.min(axis=0))
    u = np.linalg.norm(x - nodes, axis=2)
    assert np.array_equal(env["displacement_max"], u.max(axis=0))
    assert np.array_equal(env["tension_max_case"], t.argmax(axis=0))
    # The summary's extremes are the envelope's; snow leading loads the hanging cables most.
    top = result.report.envelope["tension_max"]
    assert top["value"] == t.max() and top["case"] == names[int(np.argmax(t.max(axis=1)))]
    assert top["case"] == "ULS_snow"
    fam = families(build(written.case))
    assert env["tension_max"][fam["hang"]].min() > TARGETS["hang"]
    far = result.report.envelope["displacement_max"]
    assert far["value"] == pytest.approx(u.max(), rel=1e-15)


def test_slack_edges_are_counted_per_case(tmp_path):
    """Form found with 1 kN in the arching cables, the roof loses the arching family's
    tension under the wind from x: the edges without tension are counted per case, in
    the file and in the summary, and all of them are arching cables'."""
    case = load_case(HYPAR, ['formfind.force = { "hang*" = 45e3, "arch*" = 1e3, edges = 1e3 }'])
    written = write_formfind(case, tmp_path / "weak.h5")
    result = run_case(written.case, tmp_path / "weak_run.h5")
    fam = families(build(written.case))
    slack_somewhere = False
    for run in result.cases:
        slack = run.result.tension <= 0
        assert run.numbers["slack_edges"] == int(slack.sum()), run.name
        assert not slack[fam["hang"]].any() and not slack[fam["ring"]].any()
        slack_somewhere |= bool(slack.any())
        with h5py.File(tmp_path / "weak_run.h5") as h5:
            assert h5[f"cases/{run.name}"].attrs["slack_edges"] == slack.sum()
    assert slack_somewhere
    assert result.report.cases["ULS_wind_x"]["slack_edges"] > 0
