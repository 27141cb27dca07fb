"""Form finding in the elastic equilibrium (formfind.method = "elastic") with cable
tensions, support reactions, bounds on the rest-length factors and the prestress of
named cables as design variables: the adjoint Jacobian of every target kind against
finite differences, a stay whose horizontal tension is given (the elastic catenary's
rest length), a guyed mast whose guys' prestress is found, bounds, and bad input.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import CONFIGS

from catenet.case import build, parse_case
from catenet.cli import main
from catenet.formfind.case import formfind_scene
from tests.formfind.test_targets import invoke

MAST = CONFIGS / "structures" / "guyed_mast.toml"
W = 7850.0 * math.pi * 0.02**2 * 9.81  # the stay's weight per length [N/m]


def stay(*targets, **formfind) -> dict:
    """A level stay of 100 m span, EA = 1e8 N, 0.02 m steel, under its own weight."""
    return {
        "title": "stay",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [100, 0, 0], "nodes": 21},
        "material": {"EA": 1e8, "density": 7850.0, "radius": 0.02},
        "load": {"gravity": [0, 0, -9.81]},
        "solver": {"rtol": 1e-12},
        "formfind": {"method": "elastic", **formfind},
        "target": list(targets),
    }


def named_stay(*targets, **formfind) -> dict:
    """The stay as a graph of one cable named "stay" (a cable target names it), 5 m edges."""
    data = stay(*targets, **formfind)
    data["geometry"] = {
        "kind": "graph",
        "nodes": [[0, 0, 0], [100, 0, 0]],
        "fixed": [0, 1],
        "edge_length": 5.0,
        "cable": [{"name": "stay", "nodes": [0, 1]}],
    }
    return data


def mast(*targets, **formfind) -> dict:
    """configs/structures/guyed_mast.toml under its own weight too, form-found."""
    data = tomllib.loads(MAST.read_text())
    data.pop("output", None)
    data["material"].update(density=7850.0, radius=0.01)
    data["load"]["gravity"] = [0.0, 0.0, -9.81]
    data["solver"] = {"rtol": 1e-12}
    data["formfind"] = {"method": "elastic", **formfind}
    data["target"] = list(targets)
    return data


# ------------------------------------------------------------------- the adjoint


def equilibria(data: dict, seed: int):
    """The elastic search's equilibria and goals of a case, and a point s near its start."""
    from catenet.formfind.elastic import _Equilibria
    from catenet.formfind.goals import resolve_goals
    from catenet.formfind.variables import Variables
    from catenet.solver.settings import Settings

    case = parse_case(data)
    scene = build(case)
    settings = Settings.of(case.solver)
    goals = resolve_goals(case.targets, scene, 30.0, 1e-30)
    variables = Variables(
        scene, case.formfind.vary or "cables", (None, None), moves=case.formfind.supports
    )
    eq = _Equilibria(scene, settings, variables)
    rng = np.random.default_rng(seed)
    scale = np.full(variables.n, 0.02 if variables.kind == "prestress" else 1e-4)  # (strut: 2 MN)
    scale[variables.n_rest :] = 1e-4  # (the supports' offsets over the size: 3 mm)
    return eq, goals, variables.start + scale * rng.standard_normal(variables.n)


TARGETS = [
    {"node": "top", "point": [0.05, 0.0, 20.0]},
    {"cable": "guy_windward", "tension": 25.0e3},
    {"cable": "guy_lee*", "tension": [0.0, 10.0e3]},  # above the range: its slope counts
    {"support": 2, "reaction": [-1.0e3, 0.0, 9.0e3]},
    {"support": 3, "reaction_z": -1.0e4, "weight": 2.0},
    {"cable": "guy*", "length": 30.0},  # a row per guy
]


MOVES = [  # the windward anchor (a reaction target's support too), every anchor as one
    {"node": 2, "dx": [-3.0, 3.0], "dz": [-1.0, 1.0]},
    {"node": "anchors", "dy": [-2.0, 2.0]},
]


@pytest.mark.parametrize(
    "vary, moves",
    [("prestress", False), ("cables", False), ("edges", False), ("prestress", True),
     ("supports", True)],
)  # fmt: skip
def test_the_elastic_adjoint_jacobian_of_every_target_is_the_finite_differences_one(vary, moves):
    """dr/ds of positions, tensions (a value and a range), the guys' lengths and reactions
    (a vector, one component) by solves with the tangent stiffness, against central
    differences of the equilibria, for the guys' prestress, a rest-length factor per cable
    and per edge, and the anchors' positions (with the prestress, and alone: the
    reactions at a support that moves, the guys' tensions and lengths as it does)."""
    extra = {"support": MOVES} if moves else {}
    eq, goals, s = equilibria(mast(*TARGETS, vary=vary, **extra), seed=1)

    def residual(s):
        return goals.w * goals.miss(eq.achieved(s, goals))

    j = eq.jacobian(s, goals)
    h = 1e-6
    cols = np.arange(len(s)) if len(s) < 12 else np.arange(0, len(s), 4)
    fd = np.column_stack(
        [(residual(s + h * e) - residual(s - h * e)) / (2 * h) for e in np.eye(len(s))[cols]]
    )
    for k in range(len(TARGETS)):  # every target moves with the variables
        assert np.abs(fd[goals.of == k]).max() > 1e-4 * np.abs(fd).max()
    assert np.abs(j[:, cols] - fd).max() <= 1e-6 * np.abs(fd).max()


# ------------------------------------------------------------------- closed forms


def test_a_stay_whose_horizontal_tension_is_given_has_the_elastic_catenary_rest_length(
    tmp_path,
):
    """The support's horizontal reaction -H = -20 kN asked: the rest length found is the
    exact discrete elastic chain's for that H (catenet's model of the catenary) to 1e-8;
    `catenet run` on the case written gives that reaction."""
    import h5py
    from scipy.optimize import brentq

    from catenet.validate.analytic import discrete_catenary

    data = stay({"support": 0, "reaction_x": -20.0e3})
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "support 0 reaction_x" in r.output and "met)" in r.output
    f = formfind_scene(build(parse_case(data)))
    exact = brentq(
        lambda L0: discrete_catenary(L0, 1e8, W, 100.0, 20).H - 20.0e3, 100.0, 130.0, xtol=1e-14
    )
    assert abs(f.net.rest_length.sum() - exact) <= 1e-8 * exact
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/reaction"][0, 0] + 20.0e3) <= 1e-6 * 20.0e3


def test_a_stay_whose_tension_is_bounded_meets_its_range():
    """Every edge of the stay at most 15 kN (it starts taut at about 24 kN): the tension
    found is at most 15 kN, and the edge at the supports (the largest) reaches it."""
    data = stay({"cable": "*", "tension": [0.0, 15.0e3]})
    data["geometry"] = {"kind": "graph", "nodes": [[0, 0, 0], [100, 0, 0]], "fixed": [0, 1]}
    data["geometry"].update(edges=[], cable=[{"name": "stay", "nodes": [0, 1]}], edge_length=5.0)
    data["material"]["prestress"] = 1.0e3
    f = formfind_scene(build(parse_case(data)))
    assert f.design.all_met
    assert f.force.max() <= 15.0e3 * (1 + 1e-9)


# ------------------------------------------------------------------- the mast's prestress


def test_the_guys_prestress_that_holds_the_mast_top_upright_under_its_load(tmp_path):
    """The top pushed 10 kN downwind: the four guys' prestress (one variable each) that
    keep it at x = 0 with the mast's foot carrying 90 kN; found, reported, and the case
    written keeps the top there and the foot's reaction."""
    import h5py

    data = mast(
        {"node": "top", "x": 0.0},
        {"support": "foot", "reaction_z": 9.0e4},
        vary="prestress",
    )
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "4 prestresses (one per cable): " in r.output and "met)" in r.output
    with h5py.File(out) as h5:
        g = h5["result/targets"].attrs
        assert g["found_kind"] == "prestress" and list(g["names"])[0] == "guy_windward"
        assert len(g["found"]) == 4
        t = h5["result/targets/1"].attrs
        assert t["kind"] == "reaction_z" and list(t["nodes"]) == [0] and bool(t["met"])
        assert abs(float(t["achieved"][0]) - 9.0e4) <= 1e-6 * 9.0e4
    assert "4 prestresses by cable" in out.with_suffix(".toml").read_text()
    f = formfind_scene(build(parse_case(data)))
    d = f.design
    assert d.all_met and d.variables == 4 and d.extra["names"][0] == "guy_windward"
    wind, lee = d.extra["values"][:2]
    assert wind > 20.0e3 > lee > 0  # the windward guy pulls the top back
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/x"][1, 0]) <= 1e-6
        assert abs(h5["result/reaction"][0, 2] - 9.0e4) <= 1e-6 * 9.0e4


def test_bounds_hold_the_prestress_and_the_rest_length_factors():
    """The top at x = 0 needs more windward prestress than 21 kN allows: every prestress
    within [19, 21] kN, the target missed (the compromise), the bound reported; the
    rest-length factors likewise within [0.9999, 1.0001]."""
    data = mast({"node": "top", "x": 0.0}, vary="prestress", prestress_min=19e3, prestress_max=21e3)
    f = formfind_scene(build(parse_case(data)))
    v = f.design.extra["values"]
    assert np.all((v >= 19e3 * (1 - 1e-12)) & (v <= 21e3 * (1 + 1e-12)))
    assert not f.design.all_met and f.design.at_bound > 0
    data = mast(
        {"node": "top", "x": 0.0}, rest_length_factor_min=0.9999, rest_length_factor_max=1.0001
    )
    f = formfind_scene(build(parse_case(data)))
    c = f.design.extra["values"]
    assert np.all((c >= 0.9999 * (1 - 1e-12)) & (c <= 1.0001 * (1 + 1e-12)))
    assert f.design.at_bound > 0


# ------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("target", "extra", "message"),
    [
        ({"cable": "stay*", "tension": 1e3}, {}, "target[0].cable = 'stay*': matches no cable"),
        ({"support": "top", "reaction_z": 1.0}, {}, "target[0].support = 'top': node 1 is free"),
        ({"support": 0}, {}, "needs reaction = [Rx, Ry, Rz] or any of"),
        ({"reaction_z": 1.0}, {}, "target[0].reaction_z = 1.0: a support's target: give support"),
        ({"support": 0, "reaction": [1, 2, 3], "reaction_z": 1.0}, {}, "give reaction or its"),
        ({"support": 0, "node": 1, "reaction_z": 1.0}, {}, "support takes reaction"),
        ({"node": "top", "x": 0.0}, {"prestress_min": 5.0, "prestress_max": 1.0}, "must be >"),
        (
            {"node": "top", "x": 0.0},
            {"rest_length_factor_min": 1.1, "rest_length_factor_max": 0.9},
            "formfind.rest_length_factor_max = 0.9: must be > formfind.rest_length_factor_min",
        ),
        ({"node": "top", "x": 0.0}, {"prestress_min": 5.0}, "formfind.prestress_min = 5.0: bounds"),
        (
            {"node": "top", "x": 0.0, "hard": True},
            {"vary": "prestress", "prestress_min": 19e3, "prestress_max": 21e3},
            "hard = true): cannot be met to formfind.tol",
        ),
        (
            {"node": "top", "x": 0.0},
            {"vary": "prestress", "rest_length_factor_max": 2.0},
            "formfind.rest_length_factor_max = 2.0: bounds rest-length factors",
        ),
        ({"node": "top", "x": 0.0}, {"vary": "supports"}, "needs [[formfind.support]] tables"),
        (
            {"node": "top", "x": 0.0},
            {"support": [{"node": "top", "dx": [-1.0, 1.0]}]},
            "formfind.support[0].node = 'top': node 1 is free",
        ),
        (
            {"node": "top", "x": 0.0},
            {"support": [{"node": 2}]},
            "formfind.support[0]: needs dx, dy or dz",
        ),
        (
            {"node": "top", "x": 0.0},
            {"support": [{"dx": [-1.0, 1.0]}]},
            "formfind.support[0].node: missing: the fixed node (index, name or node set",
        ),
        (
            {"node": "top", "x": 0.0},
            {"support": [{"node": 2, "dx": [-1.0, float("inf")]}]},
            "formfind.support[0].dx = [-1.0, inf]: must be [low, high] with low < high, both",
        ),
        (
            {"node": "top", "x": 0.0},
            {"support": [{"node": 2, "dz": [1.0, -1.0]}]},
            "formfind.support[0].dz = [1.0, -1.0]: must be [low, high] with low < high, both",
        ),
        (
            {"node": "top", "x": 0.0},
            {"support": [{"node": "anchors", "dz": [-1, 1]}, {"node": 3, "dz": [-1, 1]}]},
            "formfind.support[1].node = 3: node 3 moves along z in formfind.support[0] too",
        ),
    ],
)
def test_bad_elastic_targets_exit_2_with_one_message(tmp_path, target, extra, message):
    r, out = invoke(tmp_path, mast(target, **extra))
    assert r.exit_code == 2, r.output
    assert message in r.output, r.output
    assert "Traceback" not in r.output and not out.exists()


def test_supports_move_only_in_a_search_for_targets(tmp_path):
    """The force density method moves supports for [[target]] tables
    (tests/formfind/test_targets_supports.py); form finding alone keeps them."""
    data = mast(support=[{"node": 2, "dx": [-1.0, 1.0]}])
    data["formfind"].update(method="linear", force_density=1.0e3)
    r, _ = invoke(tmp_path, data)
    assert r.exit_code == 2 and "formfind.support = " in r.output
    assert "the supports move to meet [[target]] tables: add them" in r.output


def test_a_stay_whose_anchor_moves_for_its_sag_has_the_elastic_catenarys_span(tmp_path):
    """The stay of 100 m rest length (vary = "supports": its rest lengths kept), its far
    anchor free to move along x: the span found is the exact discrete elastic chain's
    whose sag is 2 m, to 1e-9 of it; the summary names the offset, the result file
    holds it, and `catenet run` on the case written keeps the sag."""
    import h5py
    from scipy.optimize import brentq

    from catenet.validate.analytic import discrete_catenary

    data = stay({"node": "midpoint", "z": -2.0}, vary="supports")
    data["formfind"]["support"] = [{"node": "end", "dx": [-5.0, 5.0]}]
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "moved        support 'end' dx: -" in r.output and "met)" in r.output
    span = brentq(
        lambda L: discrete_catenary(100.0, 1e8, W, L, 20).sag - 2.0, 99.0, 99.999, xtol=1e-14
    )
    with h5py.File(out) as h5:
        g = h5["result/targets"].attrs
        assert list(g["names"]) == ["support 'end' dx"] and g["found_kind"] == "offset"
        assert g["found"][0] == pytest.approx(span - 100.0, rel=1e-9)
        assert h5["result/x"][20, 0] == pytest.approx(span, rel=1e-12)
    header = out.with_suffix(".toml").read_text().split("\n\n")[0]
    assert "(met; 1 support offset):" in header and "#   moved support 'end' dx: -" in header
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/x"][10, 2] + 2.0) <= 1e-9 * 100.0


def test_the_guys_prestress_and_an_anchors_height_are_reported_apart(tmp_path):
    """The mast's four guys' prestress and its windward anchor's height found together:
    the summary counts four prestresses in N (the offset in m was counted as a fifth)
    and names the anchor's offset on its own line."""
    data = mast(
        {"node": "top", "x": 0.0},
        {"support": "foot", "reaction_z": 9.0e4},
        vary="prestress",
        support=[{"node": 2, "dz": [-2.0, 2.0]}],
    )
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    line = next(x for x in r.output.splitlines() if x.startswith("design"))
    low = float(line.split(": ")[1].split(" .. ")[0])
    assert "4 prestresses (one per cable): " in line and low > 1e3, line
    assert "moved        support 2 dz: " in r.output


def test_a_length_below_its_chord_is_no_compromise(tmp_path):
    """The stay asked 99 m long across its 100 m span: the rest lengths shrink until the
    linear law stretches them to it (strains far beyond its range, which `catenet run`
    then refuses); formfind says so and exits 1 (it exited 0, a "compromise")."""
    data = named_stay({"cable": "*", "length": 99.0})
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 1, r.output
    assert "beyond 10 times its law's range" in r.output and "below its chord" in r.output
    assert out.exists()  # (its last iterate written)


def test_prestress_belongs_to_the_elastic_method(tmp_path):
    data = mast({"node": "top", "x": 0.0}, vary="prestress")
    data["formfind"]["method"] = "linear"
    r, _ = invoke(tmp_path, data)
    assert r.exit_code == 2 and "formfind.vary = 'prestress': only with method" in r.output
    r, _ = invoke(tmp_path, stay({"node": "midpoint", "z": -2.0}, vary="prestress"))
    assert r.exit_code == 2 and "no cable of this case has a prestress > 0" in r.output


def test_the_written_stay_carries_only_the_loads_it_was_given(tmp_path):
    """A stay under its own weight alone, its sag given: the case written has gravity and
    no point load (the weight recomputed from the rest lengths found left forces of 1e-13
    N at its nodes, written as [[load.point]] entries the case never had), and it
    reproduces the shape."""
    import h5py

    data = stay({"node": "midpoint", "z": -2.0})
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    written = tomllib.loads(out.with_suffix(".toml").read_text())
    assert written["load"] == {"gravity": [0, 0, -9.81]}
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/x"][10, 2] + 2.0) <= 1e-9


def test_a_stay_whose_length_is_given_has_the_elastic_catenary_rest_length(tmp_path):
    """The stay's length in its equilibrium asked (100.2 m across 100 m: its edges
    stretched and sagging): the rest length found is the exact discrete elastic chain's
    whose stretched length is 100.2 m to 1e-8; the result file's target names the cable
    and its length, and `catenet run` on the case written keeps it."""
    import h5py
    from scipy.optimize import brentq

    from catenet.validate.analytic import discrete_catenary

    def stretched(L0: float) -> float:
        c = discrete_catenary(L0, 1e8, W, 100.0, 20)
        return float(np.sum(np.hypot(np.diff(c.x), np.diff(c.z))))

    data = named_stay({"cable": "*", "length": 100.2})
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "cable '*' length: 100.2 m (target 100.2 m, miss" in r.output and "met)" in r.output
    f = formfind_scene(build(parse_case(data)))
    exact = brentq(lambda L0: stretched(L0) - 100.2, 99.0, 100.2, xtol=1e-14)
    assert abs(f.net.rest_length.sum() - exact) <= 1e-8 * exact
    with h5py.File(out) as h5:
        t = h5["result/targets/0"].attrs
        assert t["kind"] == "length" and list(t["cables"]) == [0] and bool(t["met"])
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        x = h5["result/x"][()]
    edges = build(parse_case(data)).net.edges
    length = np.linalg.norm(x[edges[:, 1]] - x[edges[:, 0]], axis=1).sum()
    assert abs(length - 100.2) <= 1e-9 * 100.2  # (formfind.tol of the target)


# ------------------------------------------------------------------- with rods and obstacles


def rod_mast(*targets, **formfind) -> dict:
    """The guyed mast as a rod: 10 edges of EI = 2e7 N m^2 (its Euler load 490 kN over
    its 64 kN), pinned at its foot."""
    data = mast(*targets, **formfind)
    rod = data["geometry"]["cable"][0]
    rod["edge_length"] = 2.0
    rod["material"] = {"EA": 2.0e10, "tension_only": False, "EI": 2.0e7}
    return data


def draped_stay(*targets, **formfind) -> dict:
    """The stay over a fixed ball near its first anchor, every edge a capsule
    (``solver.edge_contact``): the ball presses on the edge from the anchor."""
    data = stay(*targets, **formfind)
    data["obstacle"] = [{"kind": "sphere", "center": [4.0, 0.0, -1.25], "radius": 1.0}]
    data["obstacle"][0]["distance"] = 0.05
    data["solver"]["edge_contact"] = True
    return data


@pytest.mark.parametrize("scene", ["rod", "obstacle"])
def test_supports_move_with_rods_and_obstacles_by_the_exact_jacobian(scene):
    """A support's offset enters through every term's stiffness at it (the rod's bending
    at the mast's foot end, the capsule pressing on the anchor's edge): the Jacobian's
    columns against central differences (h = 1e-7: their truncation error at 1e-6 is
    2e-7 here, the Jacobian exact)."""
    if scene == "rod":
        targets = ({"node": "top", "point": [0.05, 0.0, 20.0]}, {"cable": "guy_*", "length": 26.0})
        data = rod_mast(*targets, vary="prestress", support=MOVES)
    else:
        targets = ({"node": 10, "z": -2.0}, {"node": 2, "z": -0.4})
        data = draped_stay(*targets, vary="cables", support=[{"node": 0, "dz": [-1, 1]}])
    eq, goals, s = equilibria(data, seed=1)
    assert eq(s)[1].terms  # (the bending or the contact is on)

    def residual(s):
        return goals.w * goals.miss(eq.achieved(s, goals))

    j = eq.jacobian(s, goals)
    h = 1e-7
    fd = np.column_stack(
        [(residual(s + h * e) - residual(s - h * e)) / (2 * h) for e in np.eye(len(s))]
    )
    moved = np.arange(eq.variables.n_rest, len(s))
    assert np.abs(fd[:, moved]).max() > 1e-3 * np.abs(fd).max()
    assert np.abs(j - fd).max() <= 1e-8 * np.abs(fd).max()


def test_a_rod_masts_windward_anchor_moves_to_hold_its_top_plumb(tmp_path):
    """The rod mast under its 10 kN wind, its windward anchor free along x and z: the
    anchor found brings the top back over its foot; `catenet run` on the case written
    holds it there."""
    import h5py

    data = rod_mast({"node": "top", "x": 0.0}, vary="supports")
    data["formfind"]["support"] = [{"node": 2, "dx": [-5.0, 5.0], "dz": [-3.0, 3.0]}]
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "moved        support 2 dx: " in r.output and "met)" in r.output
    with h5py.File(out) as h5:  # (docs/howto/form-finding-targets.md: 12.7 mm out, 16.8 down)
        found = h5["result/targets"].attrs["found"]
        assert found == pytest.approx([-0.0126640, -0.0167968], abs=1e-7)
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/x"][1, 0]) <= 1e-8 * 30.0


def test_a_sag_and_a_pull_met_by_rest_length_and_anchor_follow_their_valley():
    """The stay's 2 m sag and 58 kN pull, by its rest length and its far anchor's
    position together: both move the slack almost alike (they differ by the stay's
    stretch), so the misses lie in a narrow curved valley where Gauss-Newton's steps are
    refused. Levenberg-Marquardt's geodesic acceleration (formfind/levenberg.py) bends
    the steps along it: met in 19 Jacobians (45 without it)."""
    data = stay({"node": "midpoint", "z": -2.0}, {"support": 0, "reaction_x": -58.0e3})
    data["formfind"].update(vary="cables", support=[{"node": "end", "dx": [-5.0, 5.0]}])
    d = formfind_scene(build(parse_case(data))).design
    assert d.all_met and d.message == "met"
    assert d.gradients <= 25 and d.evaluations <= 45


def model_net(dx) -> dict:
    """A 1.2 m model net in N-mm: three cables each way at 300 mm, 100 N of prestress,
    20 N at its centre, its east bar moved by dx (mm); targets: the centre 12 mm down,
    the middle cables' tensions in [150, 250] N."""
    at = [(i, j) for j in range(5) for i in range(5) if 0 < i < 4 or 0 < j < 4]
    nodes = [[300.0 * i, 300.0 * j, 0.0] for i, j in at]
    k = {p: n for n, p in enumerate(at)}
    cables = [{"name": f"x{j}", "nodes": [k[i, j] for i in range(5)]} for j in (1, 2, 3)]
    cables += [{"name": f"y{i}", "nodes": [k[i, j] for j in range(5)]} for i in (1, 2, 3)]
    rim = [k[p] for p in at if p[0] in (0, 4) or p[1] in (0, 4)]
    return {
        "units": "N-mm",
        "geometry": {
            "kind": "graph",
            "nodes": nodes,
            "cable": cables,
            "sets": {"east": [k[4, j] for j in (1, 2, 3)], "centre": [k[2, 2]]},
        },
        "material": {"E": 2.0e5, "radius": 0.5, "density": 7.85e-9, "prestress": 100.0},
        "supports": {"fixed": rim},
        "load": {"gravity": [0, 0, -9810.0], "point": [{"node": "centre", "force": [0, 0, -20.0]}]},
        "formfind": {
            "method": "elastic",
            "rest_length_factor_min": 0.995,
            "rest_length_factor_max": 1.005,
            "support": [{"node": "east", "dx": dx}],
        },
        "target": [
            {"node": "centre", "z": -12.0},
            {"cable": "x2", "tension": [150.0, 250.0]},
            {"cable": "y2", "tension": [150.0, 250.0]},
        ],
    }


@pytest.mark.parametrize("dx", [[-20.0, 20.0], [1.0, 20.0]])
def test_a_tension_range_pushed_onto_its_bound_holds_there_while_the_rest_is_met(dx):
    """From the east bar's range [1, 20] mm (its start 1 mm out), y2's tension reaches
    its lower bound of 150 N while the centre is still 0.08 mm high: its row, 0 inside
    the range, had let every next step cross the bound, each refused, and the search
    crawled along it to max_iter, 'not met'. Within 1e-4 of its scale of a bound a
    range row counts in the Jacobian (goals.EDGE) and the targets are met."""
    d = formfind_scene(build(parse_case(model_net(dx)))).design
    assert d.all_met and d.message == "met" and d.gradients <= 20


def test_a_reaction_asked_to_be_zero_is_met_beyond_round_off():
    """The mast's foot free to slide, no horizontal reaction asked there, its top over
    it: met (a zero reaction had been measured against 1e-6 of the load, so met only to
    1e-15 of it, below the round-off of the tensions that make it: never)."""
    data = mast(
        {"node": "top", "x": 0.0},
        {"support": "foot", "reaction_x": 0.0},
        vary="supports",
        support=[{"node": 2, "dx": [-5.0, 5.0]}, {"node": "foot", "dx": [-5.0, 5.0]}],
    )
    d = formfind_scene(build(parse_case(data))).design
    assert d.all_met and d.message == "met" and d.gradients <= 10


def test_the_names_line_up_with_the_variables_found(tmp_path):
    """A single cable (no named cables: one factor for all) and its anchor: `found` holds
    the factor and the offset, `names` an empty name and the offset's (it had held the
    offset's name alone, so that a reader pairing them mislabelled the factor)."""
    import h5py

    data = stay({"node": "midpoint", "z": -2.0}, {"support": 0, "reaction_x": -58.0e3})
    data["formfind"].update(vary="cables", support=[{"node": "end", "dx": [-5.0, 5.0]}])
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    with h5py.File(out) as h5:
        g = h5["result/targets"].attrs
        assert len(g["found"]) == 2 and list(g["names"]) == ["", "support 'end' dx"]
