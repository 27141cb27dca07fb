"""Form finding by targets ([[target]], `catenet formfind`): the adjoint Jacobian against
finite differences, the spider net whose centre lies 3 m below its ring, targets met at
the start, incompatible targets (the weighted least-squares compromise, closed form),
hard bounds, tensions, cables' lengths, bounds on the force densities, nodes on a surface,
and bad input.
"""

from __future__ import annotations

import math
import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import CONFIGS
from scenes import hypar_on_surface as hypar

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.formfind.case import formfind_scene
from tests.cli.test_cli_formfind_summary import CHAIN

SPIDER = CONFIGS / "formfind" / "spider.toml"


def spider(**changes) -> dict:
    """The spider net of configs/formfind/spider.toml as a dict; ``changes`` replace its
    top-level tables (``target`` a list of tables, ``formfind`` a table)."""
    data = tomllib.loads(SPIDER.read_text())
    data["geometry"]["file"] = str(CONFIGS / "formfind" / "spider.json")
    data.update(changes)
    return data


def found(data: dict):
    return formfind_scene(build(parse_case(data)))


def invoke(tmp_path, data: dict, *more):
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    out = tmp_path / "out.h5"
    result = CliRunner().invoke(main, ["formfind", str(case), "-o", str(out), *more])
    return result, out


def centre_z(f) -> float:
    return float(f.x[0, 2])


# ------------------------------------------------------------------- the adjoint


def search_at(data: dict, seed: int = 0):
    """The search of a case's targets (its residual and Jacobian as functions of s) and
    a point s near its start (its supports' offsets, [[formfind.support]], within a few
    cm)."""
    from catenet.formfind.anchors import Anchors, support_moves
    from catenet.formfind.design import _groups, _Search
    from catenet.formfind.fdm import _Shape
    from catenet.formfind.goals import resolve_goals

    case = parse_case(data)
    scene = build(case)
    net, loads = scene.net, scene.loads
    force = np.zeros((net.n_nodes, 3)) if loads.force is None else np.array(loads.force)
    shape = _Shape(net, force, loads.gravity, "auto", "q")
    goals = resolve_goals(case.targets, scene, shape.size, 1e-30)  # (never met)
    groups = _groups(scene, case.formfind.vary, "formfind.")
    n = int(groups.max()) + 1
    moves = support_moves(scene, case.formfind.supports, "formfind.")
    anchors = Anchors(net, moves, n, shape.size)
    rng = np.random.default_rng(seed)
    base = np.log(500.0) + 0.3 * rng.standard_normal(n)
    search = _Search(shape, goals, groups, base, anchors)
    s = np.concatenate([0.2 * rng.standard_normal(n), 2e-3 * rng.standard_normal(anchors.n)])
    return search, s


TARGETS = [
    {"node": "centre", "z": -3.0},
    {"node": 14, "point": [4.0, 2.0, -1.5], "weight": 2.0},
    {"cable": "ring1", "tension": [0.0, 100.0]},  # above the range: its slope counts
    {"cable": "radial3", "tension": 900.0},
    {"support": 40, "reaction": [100.0, -200.0, 900.0]},  # (its load and weight too)
    {"cable": "ring1", "length": 40.0},
    {"cable": "radial*", "length": [0.0, 1.0], "weight": 0.5},  # a row per cable, above
]


@pytest.mark.parametrize("gravity", [True, False])
@pytest.mark.parametrize("vary", ["edges", "cables"])
def test_the_adjoint_jacobian_is_the_finite_differences_one(gravity, vary):
    """J = dr/ds of positions, tensions, cables' lengths and a support's reaction by
    adjoint solves (whole, and as the sparse operator's products) against central
    differences of the residual, with and without self-weight (whose derivative with the
    shape and q enters the adjoint), per edge and per cable."""
    from catenet.formfind.adjoint import SparseJacobian, jacobian_operator

    load = (
        {"gravity": [0, 0, -9.81]} if gravity else {"point": [{"node": 0, "force": [0, 0, -3e3]}]}
    )
    data = spider(target=TARGETS, load=load, formfind={"vary": vary})
    search, s = search_at(data)
    whole = np.asarray(search.jacobian(s))
    h = 1e-6
    cols = np.arange(0, len(s), 5)  # (every fifth variable: a radial's, a ring's)
    fd = np.column_stack(
        [
            (search.residual(s + h * e) - search.residual(s - h * e)) / (2 * h)
            for e in np.eye(len(s))[cols]
        ]
    )
    scale = np.abs(whole).max()
    assert np.abs(fd).max() > 1e-3 * scale
    assert np.abs(whole[:, cols] - fd).max() <= 1e-6 * scale
    q, x, _, a = search.state(s)
    import scipy.sparse as sp

    from catenet.formfind.adjoint import Adjoint

    adj = Adjoint(search.shape, q, x)
    d_x, d_q = search.partials(x, q, a)
    op = jacobian_operator(adj, d_x, d_q, sp.diags(q) @ search.p)
    assert isinstance(op, SparseJacobian)
    keep = np.ones(len(s), dtype=bool)
    keep[::3] = False
    assert_operator_is(op, whole, search.residual(s), keep)


def assert_operator_is(op, whole: np.ndarray, r: np.ndarray, keep: np.ndarray) -> None:
    """The Jacobian operator ``op``'s products are the whole Jacobian's, and its damped
    step (the variables not ``keep`` held) is the SVD's."""
    scale = np.abs(whole).max()
    by_columns = np.column_stack([op.matvec(e) for e in np.eye(whole.shape[1])])
    by_rows = np.vstack([op.rmatvec(e) for e in np.eye(whole.shape[0])])
    assert np.abs(by_columns - whole).max() <= 1e-10 * scale
    assert np.abs(by_rows - whole).max() <= 1e-10 * scale
    mu = 1e-3 * scale**2
    u, sv, vt = np.linalg.svd(whole[:, keep], full_matrices=False)
    expected = np.zeros(whole.shape[1])
    expected[keep] = -(vt.T @ (sv / (sv**2 + mu) * (u.T @ r)))
    step = op.damped(r, mu, keep)
    assert np.abs(step - expected).max() <= 1e-8 * np.abs(expected).max()


# ------------------------------------------------------------------- the spider net


def test_the_spider_net_centre_lies_3_m_below_its_ring_by_one_command(tmp_path):
    """configs/formfind/spider.toml: one `catenet formfind` puts the centre 3 m below the
    ring (to 1 mm: met to round-off), reports it, writes /result/targets/0, and `catenet
    run` on the case it writes keeps the centre there."""
    out = tmp_path / "spider.h5"
    runner = CliRunner()
    r = runner.invoke(main, ["formfind", str(SPIDER), "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "target[0]" in r.output and "node 'centre' z" in r.output and "met)" in r.output
    assert "84 force densities (one per edge)" in r.output
    with h5py.File(out) as h5:
        g = h5["result/targets/0"].attrs
        assert g["kind"] == "z" and bool(g["met"]) and list(g["nodes"]) == [0]
        assert abs(float(g["achieved"][0]) + 3.0) < 1e-3
        assert float(g["target"][0]) == -3.0
        assert bool(h5["result/targets"].attrs["met"])
        q = h5["result/force_density"][()]
        assert q.shape == (84,) and np.all(q > 0)
        assert abs(h5["result/x"][0, 2] + 3.0) < 1e-3
    case = out.with_suffix(".toml")
    assert "target[0] node 'centre' z" in case.read_text()
    r = runner.invoke(main, ["run", str(case), "-o", str(tmp_path / "run.h5")])
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/x"][0, 2] + 3.0) < 1e-3


def test_a_target_far_below_the_ring_is_met_and_warned(tmp_path):
    """The spider's centre asked 5 km down: near about 13 N/m the net's weight settles
    kilometres down. The search stopped at -134 m, its damping kept from its first,
    steep Jacobian (gradient descent as the Jacobian shrank), and said it found no shape
    beyond; it meets the target now, exit 0, the shape warned as 177 times its span."""
    r, out = invoke(tmp_path, spider(target=[{"node": "centre", "z": -5000.0}]))
    assert r.exit_code == 0, r.output
    assert "node 'centre' z: -5000 m (target -5000 m" in r.output and "met)" in r.output
    assert "177 times its supports' span" in r.output
    with h5py.File(out) as h5:
        assert abs(h5["result/x"][0, 2] + 5000.0) < 1e-3
        assert bool(h5["result/targets"].attrs["met"])


def test_a_search_stopped_where_the_forces_toward_the_target_give_no_shape(tmp_path, monkeypatch):
    """Where the force densities toward a target give no shape (a weight that does not
    settle below some force density, here made to fail below 40 N/m where the centre 10 m
    down takes some below 30), the search stops at the nearest shape it found and says so,
    exit 0 with a warning: not "least-squares compromise: the targets are not all
    compatible" of its one target."""
    from catenet.errors import ConvergenceError
    from catenet.formfind import fdm

    shape = fdm._Shape.__call__

    def settles_above(self, q, nodes=None):
        if float(np.min(q)) < 40.0:
            raise ConvergenceError("form finding: the self-weight did not settle (stand-in)")
        return shape(self, q, nodes)

    monkeypatch.setattr(fdm._Shape, "__call__", settles_above)
    r, out = invoke(tmp_path, spider(target=[{"node": "centre", "z": -10.0}]))
    assert r.exit_code == 0, r.output
    assert (
        "stopped where the force densities toward the targets give no shape: the "
        "self-weight did not settle" in r.output
    )
    assert "compatible" not in r.output and "least-squares compromise" not in r.output
    assert "the nearest the search got with force densities that give a shape" in r.output
    with h5py.File(out) as h5:
        assert -10.0 < h5["result/x"][0, 2] < -2.0
        assert not bool(h5["result/targets"].attrs["met"])
        assert np.min(h5["result/force_density"][()]) >= 40.0


def test_a_target_met_at_the_start_costs_no_iteration():
    """The centre's z of the start's own shape as the target: no step, one factorisation."""
    start = found(spider(formfind={"method": "linear", "force_density": 500.0}, target=[]))
    z = centre_z(start)
    f = found(spider(target=[{"node": "centre", "z": z}]))
    assert f.design.evaluations == 0 and f.design.gradients == 0
    assert f.factorizations == 1 and f.design.all_met
    assert np.allclose(f.q, 500.0)


def test_incompatible_targets_give_the_weighted_compromise(tmp_path):
    """The centre at z = -3 (weight 1) and at z = -2 (weight 3): least squares puts it at
    (1 (-3) + 9 (-2)) / (1 + 9) = -2.1, says the targets are not met, exits 0."""
    targets = [{"node": "centre", "z": -3.0}, {"node": 0, "z": -2.0, "weight": 3.0}]
    r, out = invoke(tmp_path, spider(target=targets))
    assert r.exit_code == 0, r.output
    assert "not all met" in r.output and "least-squares compromise" in r.output
    assert "NOT met" in r.output
    with h5py.File(out) as h5:
        assert abs(h5["result/x"][0, 2] + 2.1) < 1e-6
        assert not bool(h5["result/targets"].attrs["met"])
        assert not bool(h5["result/targets/1"].attrs["met"])
        assert abs(float(h5["result/targets/1"].attrs["miss"]) - 0.1) < 1e-6


def test_a_hard_bound_is_met_where_a_weighted_target_gives_way():
    """The radials' tension at most 400 N (hard): the weight then hangs the centre lower
    than 3 m below the ring (less tension, more sag): the bound is met, the sag not. (No
    force densities do best: the search ends at formfind.max_iter.)"""
    targets = [
        {"node": "centre", "z": -3.0},
        {"cable": "radial*", "tension": [0.0, 400.0], "hard": True},
    ]
    f = found(spider(formfind={"force_density": 500.0, "max_iter": 20}, target=targets))
    d = f.design
    radial = np.flatnonzero(d.goals.of == 1)
    assert d.met[radial].all() and not d.met[d.goals.of == 0].all()
    tension = f.q * f.length
    assert tension[d.goals.edge[radial]].max() <= 400.0 * (1 + 1e-9)
    assert centre_z(f) < -3.0


def test_a_hard_bound_that_cannot_be_met_exits_2(tmp_path):
    """The same bound with the force densities held within 100 .. 2000 N/m: unreachable."""
    targets = [
        {"node": "centre", "z": -3.0},
        {"cable": "radial*", "tension": [0.0, 400.0], "hard": True},
    ]
    bounds = {"force_density_min": 100.0, "force_density_max": 2000.0, "vary": "cables"}
    r, out = invoke(tmp_path, spider(formfind={"force_density": 500.0, **bounds}, target=targets))
    assert r.exit_code == 2, r.output
    assert "target[1] (cable 'radial*' tension, hard = true): cannot be met" in r.output
    assert "within the bounds" in r.output and "widen formfind.force_density_min" in r.output
    assert not out.exists()


def test_two_hard_targets_that_contradict_each_other_blame_no_bound(tmp_path):
    """The centre asked both 3 m and 4 m down, both hard, no bound given: the error says
    the targets conflict (it advised widening force density bounds nobody had set)."""
    targets = [
        {"node": "centre", "z": -3.0, "hard": True},
        {"node": "centre", "z": -4.0, "hard": True},
    ]
    r, out = invoke(tmp_path, spider(formfind={"force_density": 500.0}, target=targets))
    assert r.exit_code == 2, r.output
    assert "the targets are not all compatible" in r.output
    assert "relax it or the targets it conflicts with, or drop hard" in r.output
    assert "widen" not in r.output and not out.exists()


def test_tensions_and_a_position_are_met_and_kept_by_the_case_written(tmp_path):
    """Every edge of ring1 at 1.5 kN, of ring2 within 0.8 .. 1 kN, the centre 3 m down:
    met; `catenet run` on the case written gives those tensions."""
    targets = [
        {"node": "centre", "z": -3.0},
        {"cable": "ring1", "tension": 1500.0},
        {"cable": "ring2", "tension": [800.0, 1000.0]},
    ]
    r, out = invoke(tmp_path, spider(target=targets))
    assert r.exit_code == 0, r.output
    scene = build(parse_case(spider(target=targets)))
    ring1 = np.flatnonzero(scene.cables.edge == list(scene.cables.names).index("ring1"))
    ring2 = np.flatnonzero(scene.cables.edge == list(scene.cables.names).index("ring2"))
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        tension = h5["result/tension"][()]
        assert np.allclose(tension[ring1], 1500.0, rtol=1e-6)
        assert np.all(
            (tension[ring2] > 800.0 * (1 - 1e-6)) & (tension[ring2] < 1000.0 * (1 + 1e-6))
        )
        assert abs(h5["result/x"][0, 2] + 3.0) < 1e-6


def test_a_support_reaction_is_met_by_the_force_densities(tmp_path):
    """The centre 3 m down and 800 N up at ring node 40: met, written to
    /result/targets/1 and kept by `catenet run` on the case written."""
    targets = [{"node": "centre", "z": -3.0}, {"support": 40, "reaction_z": 800.0}]
    r, out = invoke(tmp_path, spider(target=targets))
    assert r.exit_code == 0, r.output
    assert "support 40 reaction_z: 800 N" in r.output and "NOT met" not in r.output
    with h5py.File(out) as h5:
        t = h5["result/targets/1"].attrs
        assert t["kind"] == "reaction_z" and list(t["nodes"]) == [40] and bool(t["met"])
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/reaction"][40, 2] - 800.0) <= 1e-6 * 800.0


def test_one_force_density_per_cable():
    """vary = "cables": 15 variables (12 radials, 3 rings), every edge of a cable the same."""
    f = found(spider(formfind={"vary": "cables"}, target=[{"node": "centre", "z": -3.0}]))
    assert f.design.variables == 15 and f.design.all_met
    scene = build(parse_case(spider()))
    for c in range(15):
        q = f.q[scene.cables.edge == c]
        assert np.ptp(q) <= 1e-12 * q.max()


def test_bounds_hold_the_force_densities():
    """A centre 0.2 m down needs more force density than 600 N/m allows: every force
    density at most 600 N/m, the target missed (the compromise), said so."""
    data = spider(
        formfind={"force_density": 500.0, "force_density_max": 600.0},
        target=[{"node": "centre", "z": -0.2}],
    )
    f = found(data)
    assert f.q.max() <= 600.0 * (1 + 1e-12)
    assert not f.design.all_met and f.design.at_bound > 0
    assert "compromise" in f.design.message


# ------------------------------------------------------------------- a roof on a surface


def test_a_roof_of_a_thousand_force_densities_lies_on_its_surface(tmp_path):
    """1104 force densities put the 529 free nodes of a weighing hypar roof on the given
    surface (to 1e-9 of its size) within a few tens of adjoint gradients; the offsets
    checked against the surface's triangles directly."""
    data, f = hypar(tmp_path, 24)
    got = formfind_scene(build(parse_case(data, base_dir=tmp_path)))
    d = got.design
    assert d.variables == 1104 and d.all_met and d.gradients <= 30
    free = ~np.asarray(got.net.fixed)
    x = got.x[free]
    # The surface is linear on each triangle of its 1 m grid: interpolate by hand.
    h = 24.0 / 48
    i = np.clip(np.floor((x[:, 0] + 12.0) / h), 0, 47)
    j = np.clip(np.floor((x[:, 1] + 12.0) / h), 0, 47)
    u, v = (x[:, 0] + 12.0) / h - i, (x[:, 1] + 12.0) / h - j
    x0, y0 = -12.0 + i * h, -12.0 + j * h
    z00, z11 = f(x0, y0), f(x0 + h, y0 + h)
    lower = u >= v  # the triangle (i, i + 1, i + m + 2): below the diagonal
    z = np.where(
        lower,
        z00 + u * (f(x0 + h, y0) - z00) + v * (z11 - f(x0 + h, y0)),
        z00 + v * (f(x0, y0 + h) - z00) + u * (z11 - f(x0, y0 + h)),
    )
    assert np.abs(x[:, 2] - z).max() <= 1e-9 * 34.0


# ------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("target", "extra", "message"),
    [
        ({"node": "hub", "z": -3.0}, {}, "target[0].node = 'hub': is neither a node name"),
        ({"node": 40, "z": -3.0}, {}, "target[0].node = 40: node 40 is fixed"),
        ({"node": 0, "z": -3.0, "weight": -1.0}, {}, "target[0].weight = -1.0: must be"),
        ({"node": 0, "zz": -3.0}, {}, "target[0].zz: unknown key"),
        ({"node": 0, "cable": "ring1", "z": 1.0}, {}, "gives both node and cable"),
        ({"node": 0}, {}, "needs x, y, z, point or surface"),
        ({"node": "centre", "z": [1.0, 2.0]}, {}, "has 2 values for the 1 nodes"),
        ({"cable": "guy*", "tension": 1.0}, {}, "target[0].cable = 'guy*': matches no cable"),
        ({"cable": "ring1", "tension": [5.0, 1.0]}, {}, "target[0].tension = [5.0, 1.0]"),
        ({"cable": "ring1", "length": -1.0}, {}, "target[0].length = -1.0: must be a length > 0"),
        ({"cable": "ring1", "length": 4.0, "tension": 1.0}, {}, "in targets of their own"),
        ({"node": 0, "length": 4.0}, {}, "target[0].length = 4.0: a cable's target"),
        ({"cable": "ring1"}, {}, "needs tension or length"),
        ({"support": 40, "length": 4.0, "reaction_z": 1.0}, {}, "target[0].length = 4.0"),
        ({"node": 0, "surface": "nowhere.obj"}, {}, "target[0].surface = 'nowhere.obj': no such"),
        ({"node": 0, "z": 1.0, "within": 0.1}, {}, "target[0].within = 0.1: only with surface"),
        ({"node": 0, "z": 1.0, "smooth": True}, {}, "target[0].smooth = true: only with surface"),
        ({"node": 0, "z": -3.0}, {"method": "forces", "force": 1.0}, "formfind.method = 'forces'"),
        ({"node": 0, "z": -3.0}, {"force_density_min": 5.0, "force_density_max": 1.0}, "must be >"),
    ],
)
def test_bad_targets_exit_2_with_one_message(tmp_path, target, extra, message):
    data = spider(target=[target], formfind={"force_density": 500.0, **extra})
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 2, r.output
    assert message in r.output, r.output
    assert "Traceback" not in r.output and not out.exists()


def test_targets_need_a_formfind_table_and_a_net_without_cables_is_one(tmp_path):
    data = spider(target=[{"node": 0, "z": -3.0}])
    del data["formfind"]
    r, _ = invoke(tmp_path, data)
    assert r.exit_code == 2 and "target: form finding's targets need a [formfind]" in r.output
    r, _ = invoke(tmp_path, spider(formfind={"vary": "cables"}, target=[]))
    assert r.exit_code == 2 and "formfind.vary = 'cables': only with [[target]]" in r.output
    data, _ = hypar(tmp_path, 2)  # no named cables: the net is one cable, one force
    data["formfind"]["vary"] = "cables"  # density (as the elastic method's one factor;
    f = formfind_scene(build(parse_case(data, base_dir=tmp_path)))  # refused before)
    assert f.design.variables == 1 and np.ptp(f.q / f.q[0]) < 1e-12


# ------------------------------------------------------------------- the elastic problem


def stay(sag: float = 2.0, n: int = 20, **formfind) -> dict:
    """A level stay of 100 m span, EA = 1e8 N, 0.02 m steel, under its own weight; its
    midpoint asked ``sag`` below the supports (formfind.method = "elastic")."""
    return {
        "title": "stay",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [100, 0, 0], "nodes": n + 1},
        "material": {"EA": 1e8, "density": 7850.0, "radius": 0.02},
        "load": {"gravity": [0, 0, -9.81]},
        "solver": {"rtol": 1e-12},
        "formfind": {"method": "elastic", **formfind},
        "target": [{"node": "midpoint", "z": -sag}],
    }


def test_a_stay_with_a_given_sag_has_the_elastic_catenary_rest_length(tmp_path):
    """The rest length found for a 2 m sag is the exact discrete elastic chain's (the
    catenary with its weight lumped at the nodes: catenet's model of it) to 1e-8; `catenet
    run` on the case written keeps the midpoint 2 m down."""
    import math

    from analytic import discrete_catenary
    from scipy.optimize import brentq

    r, out = invoke(tmp_path, stay())
    assert r.exit_code == 0, r.output
    assert "1 rest-length factors (one per cable)" in r.output
    with h5py.File(out) as h5:
        assert bool(h5["result/targets/0"].attrs["met"])
    f = found(stay())
    w = 7850.0 * math.pi * 0.02**2 * 9.81
    exact = brentq(
        lambda L0: discrete_catenary(L0, 1e8, w, 100.0, 20).sag - 2.0, 100.0, 101.0, xtol=1e-14
    )
    assert abs(f.net.rest_length.sum() - exact) <= 1e-8 * exact
    assert f.design.gradients <= 10
    run = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert abs(h5["result/x"][10, 2] + 2.0) < 1e-8


def test_the_elastic_adjoint_jacobian_is_the_finite_differences_one():
    """dr/ds of node targets by one solve with the tangent stiffness, a rest-length factor
    per edge, against central differences of the equilibria (self-weight follows l0)."""
    from catenet.formfind.elastic import _Equilibria
    from catenet.formfind.goals import resolve_goals
    from catenet.formfind.variables import Variables
    from catenet.solver.settings import Settings

    data = stay(n=8, vary="edges")
    data["target"] = [{"node": 3, "point": [40.0, 0.0, -1.0]}, {"node": "midpoint", "z": -2.0}]
    case = parse_case(data)
    scene = build(case)
    settings = Settings.of(case.solver)
    goals = resolve_goals(case.targets, scene, 100.0, 1e-30)
    eq = _Equilibria(scene, settings, Variables(scene, "edges", (None, None)))
    s = 1e-3 * np.random.default_rng(1).standard_normal(8)

    def residual(s):
        return goals.w * goals.miss(eq.achieved(s, goals))

    j = eq.jacobian(s, goals)
    h = 1e-6
    fd = np.column_stack([(residual(s + h * e) - residual(s - h * e)) / (2 * h) for e in np.eye(8)])
    assert np.abs(j - fd).max() <= 1e-6 * np.abs(fd).max()


def test_elastic_form_finding_needs_targets(tmp_path):
    data = stay()
    del data["target"]
    r, _ = invoke(tmp_path, data)
    assert r.exit_code == 2 and "formfind.method = 'elastic': finds rest lengths" in r.output


def test_a_chain_whose_length_is_given_has_the_hand_force_density(tmp_path):
    """A 10 m chain of 1 m edges, one force density for it (vary = "cables"), 40 N at its
    middle, its length asked to be 10.5 m: two straight halves of 5.25 m, so the middle
    sags z = sqrt(5.25^2 - 5^2) and holds 40 N when 2 q z = 40 N m (q = 100 / z N/m); the
    result file's target names cable 0 and the length found."""
    text = CHAIN_LENGTH
    case = tmp_path / "chain.toml"
    case.write_text(text)
    out = tmp_path / "c.h5"
    r = CliRunner().invoke(main, ["formfind", str(case), "-o", str(out)])
    assert r.exit_code == 0, r.output
    z = math.sqrt(5.25**2 - 25.0)
    with h5py.File(out) as h5:
        assert h5["result/force_density"][()] == pytest.approx(100.0 / z, rel=1e-9)
        t = h5["result/targets/0"].attrs
        assert t["kind"] == "length" and list(t["cables"]) == [0]
        assert float(t["achieved"][0]) == pytest.approx(10.5, rel=1e-9)


CHAIN_LENGTH = CHAIN.replace("force_density = 100.0", 'force_density = 100.0\nvary = "cables"') + (
    '\n[[target]]\ncable = "chain"\nlength = 10.5\n'
)  # (the summary's chain of tests/cli, one force density, its length asked)


def test_a_slow_self_weight_fixed_point_gives_way_to_one_factorisation():
    """Where the weight outweighs the force densities (the spider at 30 N/m under its
    own weight) the adjoint's fixed point converges slowly: after a few iterations A is
    factorised once instead (formfind/adjoint.py, SLOW), and the solve is exact; at
    500 N/m the fixed point does it alone."""
    import scipy.sparse as sp

    from catenet.formfind.adjoint import SLOW_AFTER, Adjoint
    from catenet.formfind.fdm import _Shape

    scene = build(parse_case(spider(load={"gravity": [0, 0, -9.81]})))
    net = scene.net
    w = np.random.default_rng(0).standard_normal(3 * int(np.count_nonzero(~net.fixed)))
    for q, slow in ((30.0, True), (500.0, False)):
        shape = _Shape(net, np.zeros((net.n_nodes, 3)), scene.loads.gravity, "auto", "q")
        x, _ = shape(np.full(net.n_edges, q))
        before = shape.solves
        adj = Adjoint(shape, np.full(net.n_edges, q), x)
        y = adj.solve(w)
        a = sp.csr_matrix((adj.a_coo()[0], adj.a_coo()[1:]), shape=(len(w), len(w)))
        assert np.abs(a @ y - w).max() <= 1e-13 * np.abs(w).max()
        assert (adj._lu is not None) == slow
        if slow:  # (3 coordinates a solve)
            assert shape.solves - before <= 3 * (SLOW_AFTER + 2)
