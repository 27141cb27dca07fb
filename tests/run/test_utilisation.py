"""Utilisation of tension components (catenet.model.design: EN 1993-1-11, 6.2) on a
cable whose tensions are known in closed form, per case, combination and envelope, and
the keys' bad values."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.model.design import Design
from catenet.run.runner import run_case

T0 = 1000.0  # N, the prestress
P = 400.0  # N, the load case's pull along the cable
F_MIN = 20.0e3  # N, the breaking load


def pulled(**design) -> dict:
    """A straight cable along x, prestressed to T0, pinned at both ends; the load case
    "pull" pulls its midpoint along the cable by P, the combination "ULS" by 1.5 P.

    Along a straight line the linear law is exact: the midpoint moves by u, the left half
    stretches by u and the right half shortens by u, so EA u / l0 on each side and
    equilibrium T_left - T_right = P give T_left = T0 + P / 2, T_right = T0 - P / 2
    (both halves alike: no other solution)."""
    data = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [10, 0, 0], "nodes": 3},
        "material": {"EA": 1.0e6, "prestress": T0, "breaking_load": F_MIN},
        "load_case": [{"name": "pull", "point": [{"node": "midpoint", "force": [P, 0, 0]}]}],
        "combination": [{"name": "ULS", "factors": {"pull": 1.5}}],
        "solver": {"rtol": 1e-12},
    }
    if design:
        data["design"] = design
    return data


def expected(t, gamma_R=1.0, k_e=1.0, load_factor=1.0, factor=1.5, proof=None):
    """EN 1993-1-11's F_Ed / F_Rd, written out: F_Rd = min(k_e F_min / (1.5 gamma_R),
    F_k / gamma_R), F_Ed = gamma_F T."""
    rd = k_e * F_MIN / (factor * gamma_R)
    if proof is not None:
        rd = min(rd, proof / gamma_R)
    return load_factor * np.maximum(t, 0.0) / rd


def test_utilisation_of_a_cable_of_known_tension_in_every_case(tmp_path):
    out = tmp_path / "pull.h5"
    result = run_case(parse_case(pulled()), out)
    tensions = {
        "result": [T0, T0],
        "cases/pull": [T0 + P / 2, T0 - P / 2],
        "cases/ULS": [T0 + 0.75 * P, T0 - 0.75 * P],
    }
    with h5py.File(out) as h5:
        for group, t in tensions.items():
            np.testing.assert_allclose(h5[group]["tension"][:], t, rtol=1e-9)
            np.testing.assert_allclose(h5[group]["utilisation"][:], expected(np.array(t)), 1e-9)
        # over the cases (not the base): the left half in ULS, the right one in "pull"
        np.testing.assert_allclose(
            h5["envelope/utilisation_max"][:], expected(np.array([T0 + 0.75 * P, T0 - P / 2]))
        )
        cases = list(h5["envelope"].attrs["cases"])
        governs = [cases[k] for k in h5["envelope/utilisation_max_case"][:]]
        assert governs == ["ULS", "pull"]
        top = h5["result"].attrs["max_utilisation"]
    # 1000 N x 1.5 x 1.0 / 20 kN: the base state's utilisation (gamma_R = 1.00 by default)
    assert top == pytest.approx(0.075, rel=1e-9)
    assert result.report.envelope["utilisation_max"]["case"] == "ULS"
    assert result.report.cases["ULS"]["max_utilisation"] == pytest.approx(
        expected(T0 + 0.75 * P), rel=1e-9
    )


def test_design_factors_and_proof_load_change_the_rule_as_documented(tmp_path):
    factors = {"gamma_R": 1.0, "k_e": 0.9, "load_factor": 1.1, "breaking_factor": 1.6}
    data = pulled(**factors)
    data["material"]["proof_load"] = 12.0e3  # F_k / gamma_R = 12 kN < 0.9 x 20 / 1.6 kN
    out = tmp_path / "factors.h5"
    run_case(parse_case(data), out)
    with h5py.File(out) as h5:
        u = h5["cases/pull/utilisation"][:]
    want = expected(
        np.array([T0 + P / 2, T0 - P / 2]),
        gamma_R=1.0,
        k_e=0.9,
        load_factor=1.1,
        factor=1.6,
        proof=12.0e3,
    )
    np.testing.assert_allclose(u, want, rtol=1e-9)
    assert 1.1 * (T0 + P / 2) / 11.25e3 == pytest.approx(u[0], rel=1e-9)  # 0.9 x 20 / 1.6


def test_a_strut_in_compression_and_a_slack_edge_have_utilisation_zero():
    d = Design.uniform(3, 1000.0)
    np.testing.assert_allclose(d.utilisation(np.array([-50.0, 0.0, 100.0])), [0, 0, 0.15])
    none = Design.uniform(2, None)
    assert np.isnan(none.utilisation(np.array([10.0, 20.0]))).all() and not none.given


def graph_with_cables() -> dict:
    """Two cables meeting at a hanging node: "stay" with its own breaking load, "tie"
    with none."""
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [4, 0, -3], [8, 0, 0]],
            "edges": [],
            "fixed": [0, 2],
            "cable": [
                {"name": "stay", "nodes": [0, 1], "material": {"breaking_load": 5.0e3}},
                {"name": "tie", "nodes": [1, 2]},
            ],
        },
        "material": {"EA": 1.0e6},
        "load": {"point": [{"node": 1, "force": [0, 0, -600.0]}]},
    }


def test_cables_own_materials_give_their_breaking_loads_and_the_summary_names_them(tmp_path):
    out = tmp_path / "graph.h5"
    result = run_case(parse_case(graph_with_cables()), out)
    with h5py.File(out) as h5:
        t = h5["result/tension"][:]
        u = h5["result/utilisation"][:]
        per_cable = h5["result/cable_max_utilisation"][:]
    assert np.isnan(u[1]) and np.isnan(per_cable[1])
    assert u[0] == pytest.approx(t[0] * 1.5 / 5.0e3, rel=1e-12)
    assert per_cable[0] == pytest.approx(u[0], rel=1e-12)
    s = result.report.summary
    assert s["max_utilisation_cable"] == "stay" and s["max_utilisation_edge"] == 0
    # the printed summary names the cable and the state
    path = tmp_path / "graph.toml"
    from catenet.case import dumps_toml

    path.write_text(dumps_toml(graph_with_cables()))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "g2.h5")])
    assert res.exit_code == 0, res.output
    line = next(x for x in res.output.splitlines() if x.startswith("utilisation"))
    assert f"{u[0]:.4g}" in line and "cable stay" in line and "the base state" in line


def test_without_a_breaking_load_the_summary_says_so_and_the_file_holds_nan(tmp_path):
    data = graph_with_cables()
    del data["geometry"]["cable"][0]["material"]
    path = tmp_path / "none.toml"
    from catenet.case import dumps_toml

    path.write_text(dumps_toml(data))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "none.h5")])
    assert res.exit_code == 0, res.output
    assert "utilisation  not checked: no material gives breaking_load" in res.output
    with h5py.File(tmp_path / "none.h5") as h5:
        assert np.isnan(h5["result/utilisation"][:]).all()
        assert "max_utilisation" not in h5["result"].attrs


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"material": {"breaking_load": -5.0}}, "material.breaking_load = -5.0: must be"),
        ({"material": {"proof_load": 1e3}}, "material.proof_load = 1000.0: needs material."),
        ({"design": {"gamma_R": 0}}, "design.gamma_R = 0: must be"),
        ({"design": {"gama_R": 1.0}}, "design.gama_R"),
    ],
)
def test_bad_design_keys_are_one_clear_message_each(change, message):
    data = pulled()
    data["material"].pop("breaking_load")
    for section, keys in change.items():
        data.setdefault(section, {}).update(keys)
    with pytest.raises(ConfigError) as err:
        parse_case(data)
    assert any(message in p for p in err.value.problems), err.value.problems


def test_design_keys_round_trip_through_the_resolved_case():
    data = graph_with_cables()
    data["material"]["breaking_load"] = F_MIN
    data["design"] = {"gamma_R": 0.9}
    case = parse_case(data)
    again = parse_case(case.to_dict())
    assert again.design == case.design and again.material.breaking_load == F_MIN
    cable = again.geometry.cables[0].material.as_dict()
    assert cable == {"breaking_load": 5.0e3}
    assert "design" not in parse_case(graph_with_cables()).to_dict()  # defaults: not written


def test_support_capacities_give_each_support_its_utilisation(tmp_path):
    """The pulled cable's start carries the left half's tension: |R| = T0, T0 + P / 2,
    T0 + 0.75 P in the base state, "pull" and "ULS"; against a 4 kN capacity."""
    data = pulled()
    data["design"] = {"support": [{"node": "start", "capacity": 4.0e3}]}
    out = tmp_path / "anchored.h5"
    result = run_case(parse_case(data), out)
    with h5py.File(out) as h5:
        for group, r in (("result", T0), ("cases/pull", T0 + P / 2), ("cases/ULS", T0 + 0.75 * P)):
            u = h5[group]["support_utilisation"][:]
            assert u[0] == pytest.approx(r / 4.0e3, rel=1e-9) and np.isnan(u[1:]).all()
        env = h5["envelope/support_utilisation_max"][:]
        assert env[0] == pytest.approx((T0 + 0.75 * P) / 4.0e3, rel=1e-9)
    top = result.report.envelope["support_utilisation_max"]
    assert (top["at"], top["case"]) == (0, "ULS")
    assert result.report.summary["max_support_utilisation_node"] == 0


@pytest.mark.parametrize(
    ("support", "message"),
    [
        ({"node": "midpoint", "capacity": 1e3}, "node 1 is not a support"),
        ({"node": 7, "capacity": 1e3}, "design.support[0].node = 7"),
        ({"node": "start", "capacity": -1.0}, "design.support[0].capacity = -1.0: must be"),
    ],
)
def test_bad_support_capacities_exit_2_with_one_message(support, message, tmp_path):
    from catenet.case import dumps_toml

    data = pulled()
    data["design"] = {"support": [support]}
    case = tmp_path / "bad.toml"
    case.write_text(dumps_toml(data))
    res = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "bad.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output and not (tmp_path / "bad.h5").exists()
