"""Material laws: finite differences of every law's energy, force and stiffness, the
reduction to the paper's law at small strain, closed forms at large strain, prestress,
and the input checks.

Closed form of a stretched bar: one edge of rest length l0 along x, fixed at node 0 and
pulled by F at node 1, stays straight; its strain solves EA w'(eps) = F, i.e. for
neo-Hookean F/EA = (lambda - lambda^-2)/3, for Hencky F/EA = ln(lambda)/lambda, for a
table the piecewise-linear N(eps). At eps = 0.5 these differ from the paper's F = EA eps
by 30 % and more, so a right answer is no accident.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import catenet as cn
from catenet.case import build, parse_case
from catenet.errors import ConfigError
from catenet.kernels.laws import density, strain_for_force
from catenet.model.laws import LAWS, Law, table_rows
from catenet.scene import Scene
from catenet.solver.path import Settings, solve
from catenet.terms import Stretch, check_derivatives

TABLE = [[0.02, 40.0], [0.1, 120.0], [0.3, 200.0], [0.6, 500.0]]  # strain, tension [N]
ROWS, TABLE_EA = table_rows(TABLE)


def law(name: str, m: int = 1, tension_only=True) -> Law:
    return Law.uniform(m, name, tension_only=tension_only, table=ROWS if name == "table" else None)


def w(name: str, eps: float):
    lw = law(name)
    return density(lw.kind[0], lw.params[0], lw.table, eps)


def force_closed_form(name: str, eps: float) -> float:
    """N/EA of each law at strain eps, written out independently of the kernels."""
    lam = 1.0 + eps
    if name == "linear":
        return eps
    if name == "neo_hookean":
        return (lam - lam**-2) / 3.0
    if name == "hencky":
        return math.log(lam) / lam
    if eps < 0.0:  # below the table: its first slope, which is EA
        return eps
    strain = [0.0] + [p[0] for p in TABLE]
    tension = [0.0] + [p[1] for p in TABLE]
    if eps > strain[-1]:  # beyond it: its last slope
        slope = (tension[-1] - tension[-2]) / (strain[-1] - strain[-2])
        return (tension[-1] + slope * (eps - strain[-1])) / TABLE_EA
    return float(np.interp(eps, strain, tension)) / TABLE_EA


@pytest.mark.parametrize("name", sorted(LAWS))
def test_density_derivatives_match_finite_differences(name):
    h = 1e-6
    for eps in (-0.3, -0.05, 0.01, 0.05, 0.2, 0.45, 0.5, 0.9, 1.5):
        if name == "table" and any(abs(eps - p[0]) < 1e-3 for p in TABLE):
            continue  # the kinks of the table
        f0, f1, f2 = w(name, eps)
        up, down = w(name, eps + h), w(name, eps - h)
        assert f1 == pytest.approx((up[0] - down[0]) / (2 * h), rel=1e-6, abs=1e-9)
        assert f2 == pytest.approx((up[1] - down[1]) / (2 * h), rel=1e-6, abs=1e-9)
        assert f1 == pytest.approx(force_closed_form(name, eps), rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_every_law_is_the_papers_at_small_strain(name):
    """w(0) = w'(0) = 0 and w''(0) = 1: EA is the small-strain stiffness of every law."""
    assert w(name, 0.0) == pytest.approx((0.0, 0.0, 1.0), abs=1e-15)
    for eps in (1e-6, -1e-6):
        assert w(name, eps)[1] == pytest.approx(eps, rel=2e-6)


@pytest.mark.parametrize("tension_only", [False, True])
@pytest.mark.parametrize("name", sorted(LAWS))
def test_stretch_kernels_of_every_law_pass_finite_differences(name, tension_only):
    rng = np.random.default_rng(5)
    nodes = rng.uniform(-1.0, 1.0, (7, 3))
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 6], [6, 0], [1, 4], [2, 5]])
    length = np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)
    rest = length / rng.uniform(0.8, 1.4, len(edges))  # strains from -0.2 to +0.4
    net = cn.Net.from_arrays(
        nodes,
        edges,
        EA=rng.uniform(1.0, 5.0, len(edges)),
        fixed=[0],
        rest_length=rest,
        law=law(name, len(edges), tension_only),
    )
    x = nodes + 0.01 * rng.standard_normal(nodes.shape)
    grad_err, hess_err = check_derivatives(Stretch(net), x)
    assert grad_err < 1e-7 and hess_err < 1e-6
    grad_err, hess_err = check_derivatives(Stretch(net).with_law(net.law.smoothed(0.05)), x)
    assert grad_err < 1e-7 and hess_err < 1e-6


def bar(name: str, EA: float = 1000.0, l0: float = 2.0):
    lw = law(name, 1, tension_only=False)
    return cn.Net.from_arrays([[0, 0, 0], [l0, 0, 0]], [[0, 1]], EA=EA, fixed=[0], law=lw)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_a_bar_stretched_to_fifty_percent_matches_its_closed_form(name):
    EA, l0, eps = (TABLE_EA if name == "table" else 1000.0), 2.0, 0.5
    F = EA * force_closed_form(name, eps)
    net = bar(name, EA, l0)
    force = np.zeros((2, 3))
    force[1, 0] = F
    r = solve(Scene(net, cn.Loads(force=force)), Settings(rtol=1e-12))
    assert r.converged
    assert r.x[1, 0] == pytest.approx(l0 * (1 + eps), rel=1e-10)
    assert r.tension[0] == pytest.approx(F, rel=1e-10)
    assert r.max_strain == pytest.approx(eps, rel=1e-10)
    if name != "linear":  # the paper's law would have stretched the bar much further/less
        assert abs(F / EA - eps) > 0.1


@pytest.mark.parametrize("name", sorted(LAWS))
def test_the_strain_for_a_force_inverts_the_law(name):
    lw = law(name)
    for eps in (-0.2, 1e-8, 0.03, 0.5, 0.95):
        if name == "table" and eps < 0:
            continue
        target = w(name, eps)[1]
        assert strain_for_force(lw.kind[0], lw.params[0], lw.table, target) == pytest.approx(
            eps, rel=1e-10, abs=1e-15
        )


def cable_case(**material) -> dict:
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [3, 1, 2], "nodes": 13},
        "material": {"EA": 1000.0, **material},
    }


@pytest.mark.parametrize("name", ["linear", "neo_hookean", "hencky", "table"])
@pytest.mark.parametrize("T0", [0.0, 1.0, 150.0])
def test_a_straight_pretensioned_cable_carries_its_prestress_exactly(name, T0):
    """Prestress is the tension in the given (here straight) geometry: pinned at both ends
    and unloaded, the cable is in equilibrium as it is and every edge carries T0."""
    data = cable_case(law=name, prestress=T0)
    if name == "table":
        data["material"] = {"law": "table", "table": TABLE, "prestress": T0, "area": 1e-4}
    scene = build(parse_case(data))
    r = solve(scene, Settings(rtol=1e-12))
    assert r.converged
    assert np.allclose(r.tension, T0, rtol=1e-12, atol=1e-12)
    assert np.array_equal(r.x, scene.net.nodes)


def test_prestress_of_a_strut_is_compression():
    scene = build(parse_case(cable_case(prestress=-20.0, tension_only=False)))
    r = solve(scene, Settings(rtol=1e-12))
    assert np.allclose(r.tension, -20.0, rtol=1e-12)


@pytest.mark.parametrize(
    "material, message",
    [
        ({"law": "rubber"}, "material.law = 'rubber': must be one of 'linear', 'neo_hookean'"),
        ({"law": "table"}, "material.table: missing"),
        ({"law": "table", "table": [[0.1, 5.0], [0.05, 9.0]]}, "strains must increase strictly"),
        ({"law": "table", "table": [[0.1, 5.0], [0.2, 4.0]]}, "tensions must not decrease"),
        ({"law": "table", "table": [[0.1, 0.0]]}, "the first must be > 0"),
        ({"law": "table", "table": "steel"}, "must be [[strain, tension], ...]"),
        ({"table": [[0.1, 5.0]]}, "material.table: only with material.law = 'table'"),
        ({"prestress": -5.0}, "tension-only cables carry no compression"),
        ({"prestress": float("nan")}, "material.prestress = nan: must be finite"),
    ],
)
def test_bad_laws_and_prestress_are_refused_with_their_key(material, message):
    data = cable_case(**material)
    if material.get("law") == "table":
        del data["material"]["EA"]
        data["material"]["area"] = 1e-4
    with pytest.raises(ConfigError) as info:
        parse_case(data)
    assert message in str(info.value)


def test_prestress_beyond_what_the_law_carries_is_refused():
    """Hencky's force peaks at EA/e: a prestress above it has no rest length."""
    with pytest.raises(ConfigError, match="edge 0 cannot carry it under law 'hencky'"):
        build(parse_case(cable_case(law="hencky", prestress=500.0)))
    data = cable_case(prestress=5.0)
    data["geometry"]["length"] = 3.0
    with pytest.raises(ConfigError, match="give it or geometry.length, not both"):
        parse_case(data)


@pytest.mark.parametrize("force", [380.0, 500.0])
def test_a_load_beyond_the_laws_peak_fails_saying_so(tmp_path, force):
    """A 1 m Hencky tether (EA 1000 N, ten edges) hung from a support, its end pulled by
    more than the law's peak force EA/e = 367.88 N: no equilibrium exists. The run fails
    (exit 1) naming the edge past the peak and the peak force, not the round-off that
    its runaway iterate shows, and the last equilibrium it reports carries about the
    peak (the cut-back's load factor, within its 1/32 steps)."""
    from click.testing import CliRunner

    from catenet.case import dumps_toml
    from catenet.cli import main

    data = {
        "geometry": {"kind": "graph", "nodes": [[0, 0, 0], [0, 0, -1.0]], "fixed": [0],
                     "edge_length": 0.1, "cable": [{"name": "tether", "nodes": [0, 1]}]},
        "material": {"EA": 1000.0, "law": "hencky"},
        "load": {"point": [{"node": 1, "force": [0, 0, -force]}]},
        "solver": {"steps": 10},
    }  # fmt: skip
    path = tmp_path / "tether.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "t.h5"), "-q"])
    assert r.exit_code == 1, r.output
    assert "past the peak of its hencky law" in r.output
    assert "peaks at EA / e = 367.879 N" in r.output and "round-off" not in r.output
    factor = float(re.search(r"last equilibrium: load factor ([0-9.]+)", r.output)[1])
    assert 1000.0 / math.e * (1 - 1 / 16) < factor * force <= 1000.0 / math.e


def test_prestress_then_load_gives_the_loaded_pretensioned_cable():
    """A pretensioned straight cable under a small midpoint load: the deflection follows
    from the tension T0 + EA eps of the two straight halves (Eq. 17 with prestress):
    F = 2 N sin(theta), N = T0 + EA (sec(theta) (1 + T0/EA) - 1) for a horizontal cable."""
    T0, EA, L, F = 200.0, 1e4, 2.0, 30.0
    data = {
        "geometry": {"kind": "cable", "start": [-1, 0, 0], "end": [1, 0, 0], "nodes": 3},
        "material": {"EA": EA, "prestress": T0},
        "load": {"point": [{"node": "midpoint", "force": [0, 0, -F]}]},
    }
    r = solve(build(parse_case(data)), Settings(rtol=1e-12))
    d = -r.x[1, 2]
    half = L / 2
    length = math.hypot(half, d)
    l0 = half / (1 + T0 / EA)
    N = EA * (length / l0 - 1)
    assert r.tension == pytest.approx([N, N], rel=1e-10)
    assert 2 * N * d / length == pytest.approx(F, rel=1e-10)


# ------------------------------------------------------------------ Material carries its law


def _builders(material):
    """The net of every builder under ``material``: a cable, the paper's square net and
    a graph (a triangle with a tail)."""
    nodes = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.5, 0.0], [1.0, 0.5, -1.0]]
    edges = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]]
    return {
        "cable": cn.cable([0, 0, 0], [3, 1, 2], 7, material),
        "square_net": cn.square_net(4, 0.3, 1.0, 0.2, material).net,
        "graph": cn.graph(nodes, edges, [0, 1, 2], material),
    }


@pytest.mark.parametrize("name", ["linear", "neo_hookean", "hencky", "table"])
def test_every_builder_makes_its_net_under_the_materials_law(name):
    """A Material carries its law: each builder gives every edge that law (the table's
    rows, the tension-only switch), and ``Net.tension_only`` is the law's."""
    ea = TABLE_EA if name == "table" else 1000.0
    table = TABLE if name == "table" else None
    for only in (True, False):
        material = cn.Material(EA=ea, tension_only=only, law=name, table=table)
        for kind, net in _builders(material).items():
            law = net.law
            assert np.all(law.kind == LAWS[name].id), kind
            assert np.all(law.tension_only == only) and net.tension_only is only, kind
            if name == "table":
                np.testing.assert_array_equal(law.table, ROWS)
                assert np.all(law.params[:, 1] == len(ROWS))
            else:
                assert law.kernel_kind is None if name == "linear" else law.kernel_kind is not None


@pytest.mark.parametrize("name", ["linear", "neo_hookean", "hencky", "table"])
def test_a_prestressed_material_gives_every_builder_its_tension_in_the_given_geometry(name):
    """With ``prestress`` T0 every edge's tension in the net as built is T0 (the rest
    lengths come from the law's inverse), whatever the builder; the same builders without
    it give the unstressed rest lengths."""
    t0 = 150.0
    ea = TABLE_EA if name == "table" else 1000.0
    table = TABLE if name == "table" else None
    plain = _builders(cn.Material(EA=ea, law=name, table=table))
    stressed = _builders(cn.Material(EA=ea, law=name, table=table, prestress=t0))
    for kind, net in stressed.items():
        tension = Stretch(net).tension(net.nodes)
        np.testing.assert_allclose(tension, t0, rtol=1e-12, err_msg=kind)
        assert np.all(net.rest_length < plain[kind].rest_length), kind
        np.testing.assert_allclose(Stretch(plain[kind]).tension(net.nodes), 0.0, atol=1e-12 * ea)


def test_a_prestress_the_law_cannot_carry_names_its_key_and_edge():
    material = cn.Material(EA=1000.0, law="hencky", prestress=500.0)  # Hencky peaks at EA/e
    with pytest.raises(ConfigError, match="material.prestress = 500.0: cannot be met: edge 0 "):
        cn.cable([0, 0, 0], [1, 0, 0], 3, material)


def test_uniform_and_per_cable_materials_build_the_same_net():
    """One path for uniform and per-cable laws: a cable case, and a graph of the same
    polyline whose only cable takes [material] (law and prestress) give the same law,
    rest lengths and stiffness on every edge."""
    material = {"EA": 1000.0, "law": "neo_hookean", "prestress": 40.0, "tension_only": False}
    cable = build(parse_case(cable_case(**material))).net
    graph = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [3, 1, 2]],
            "cable": [{"name": "c", "nodes": [0, 1], "edge_length": 3.8 / 12}],
        },
        "material": material,
        "supports": {"fixed": [0, 1]},
    }
    net = build(parse_case(graph)).net
    assert net.n_edges == cable.n_edges == 12
    order = np.argsort(net.nodes[:, 0], kind="stable")  # the graph numbers its ends first
    np.testing.assert_allclose(net.nodes[order], cable.nodes, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(net.law.kind, cable.law.kind)
    np.testing.assert_array_equal(net.law.tension_only, cable.law.tension_only)
    np.testing.assert_allclose(np.sort(net.rest_length), np.sort(cable.rest_length), rtol=1e-12)
    np.testing.assert_array_equal(net.EA, cable.EA)
