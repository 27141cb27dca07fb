"""Supports that move in the force density method's target search ([[formfind.support]]
with ``method = "linear"``): the offsets' adjoint columns against finite differences
(with and without self-weight, a reaction at the support that moves), the operator that
borders a large search's Jacobian with them, a ring moved as one (a translation: closed
form), offsets with the force densities, the operator's path end to end, bad input."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from scenes import hypar_on_surface as hypar

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.formfind.case import formfind_scene
from tests.formfind.test_targets import TARGETS, assert_operator_is, invoke, search_at, spider

RING = [37, 38, 39, 40, 41, 42, 43, 44, 45, 46, 47, 48]  # the spider's fixed outer ring


def with_sets(**more) -> dict:
    """The spider's geometry with its outer ring (and more) as node sets."""
    geometry = spider()["geometry"]
    geometry["sets"].update(ring=RING, **more)
    return geometry


def search_with_moves(data: dict, seed: int = 0):
    """test_targets.search_at's search and point, and the number of force densities."""
    search, s = search_at(data, seed)
    return search, s, search.nq


MOVES = [  # a support with a reaction target (its own node's term), a set moved as one
    {"node": 40, "dx": [-1.0, 1.0], "dz": [-2.0, 2.0]},
    {"node": "three", "dz": [-1.0, 1.0]},
]


@pytest.mark.parametrize("gravity", [True, False])
def test_the_offsets_columns_are_the_finite_differences_ones(gravity):
    """dr/ds of every target kind (a position, tensions, cables' lengths, the reaction at
    a support that moves) with respect to the supports' offsets, by one forward adjoint
    solve each, against central differences; with self-weight, whose loads change with
    the lengths of the edges at a moved support."""
    load = (
        {"gravity": [0, 0, -9.81]} if gravity else {"point": [{"node": 0, "force": [0, 0, -3e3]}]}
    )
    data = spider(
        geometry=with_sets(three=[37, 38, 39]),
        target=TARGETS,
        load=load,
        formfind={"vary": "cables", "support": MOVES},
    )
    search, s, n = search_with_moves(data)
    whole = np.asarray(search.jacobian(s))
    assert whole.shape == (search.goals.rows, n + 3)
    h = 1e-6
    fd = np.column_stack(
        [
            (search.residual(s + h * e) - search.residual(s - h * e)) / (2 * h)
            for e in np.eye(len(s))[n:]
        ]
    )
    scale = np.abs(whole).max()
    reaction = np.flatnonzero(search.goals.reacts)
    assert np.abs(fd[reaction]).max() > 0.1 * scale  # (the support's own node counts)
    assert np.abs(whole[:, n:] - fd).max() <= 1e-9 * scale


def test_the_bordered_operator_is_the_whole_jacobian():
    """A large search's Jacobian, an operator, bordered by the offsets' columns: its
    products are the whole Jacobian's and its damped step the SVD's, some variables
    held (an offset among them)."""
    import scipy.sparse as sp

    from catenet.formfind.adjoint import Adjoint, jacobian_operator
    from catenet.formfind.anchors import Bordered

    data = spider(
        geometry=with_sets(three=[37, 38, 39]),
        target=TARGETS,
        load={"gravity": [0, 0, -9.81]},
        formfind={"vary": "edges", "support": MOVES},
    )
    search, s, n = search_with_moves(data, seed=1)
    whole = np.asarray(search.jacobian(s))
    q, x, _, a = search.state(s)
    adj = Adjoint(search.shape, q, x)
    d_x, d_q = search.partials(x, q, a)
    op = Bordered(jacobian_operator(adj, d_x, d_q, sp.diags(q) @ search.p), whole[:, n:])
    r = search.residual(s)
    for held in ([0, 7], [0, 7, n + 1]):
        keep = np.ones(len(s), dtype=bool)
        keep[held] = False
        assert_operator_is(op, whole, r, keep)


def test_a_ring_moved_as_one_puts_the_centre_3_m_below_by_translation(tmp_path):
    """The force densities kept (vary = "supports"), the whole ring moved as one: the
    net is translated, self-weight and all, so the ring moves by the centre's height
    found with the ring in place less 3 m. The written case holds the ring there and
    `catenet run` reproduces the centre."""
    plain = spider(formfind={"force_density": 500.0})
    plain.pop("target")
    plain = formfind_scene(build(parse_case(plain)))
    z0 = float(plain.x[0, 2])
    data = spider(
        geometry=with_sets(),
        formfind={
            "force_density": 500.0,
            "vary": "supports",
            "support": [{"node": "ring", "dz": [-10.0, 10.0]}],
        },
    )
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "design       1 support offset\n" in r.output
    assert "moved        support 'ring' dz: -" in r.output and "met)" in r.output
    with h5py.File(out) as h5:
        g = h5["result/targets"]
        assert g.attrs["found_kind"] == "offset"
        assert list(g.attrs["names"]) == ["support 'ring' dz"]
        dz = float(g.attrs["found"][0])
        assert dz == pytest.approx(-3.0 - z0, rel=1e-9)
        x = h5["result/x"][...]
        assert np.allclose(x[RING, 2], dz, rtol=0, atol=1e-12)
        assert x[0, 2] == pytest.approx(-3.0, abs=1e-9)
        assert np.allclose(h5["result/force_density"][...], 500.0)
    case = out.with_suffix(".toml")
    assert "(met; 1 support offset):" in case.read_text()
    again = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "run.h5")])
    assert again.exit_code == 0, again.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert h5["result/x"][0, 2] == pytest.approx(-3.0, abs=1e-6)


def test_offsets_and_force_densities_together_meet_a_reaction_and_a_height(tmp_path):
    """One support's height and the cables' force densities: the centre 3 m below the
    ring and that support's vertical reaction, both met; the run reproduces them."""
    data = spider(
        target=[
            {"node": "centre", "z": -3.0},
            {"support": 40, "reaction_z": 900.0},
        ],
        load={"gravity": [0, 0, -9.81]},
        formfind={
            "force_density": 500.0,
            "vary": "cables",
            "support": [{"node": 40, "dz": [-2.0, 2.0]}],
        },
    )
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 0, r.output
    assert "design       15 force densities (one per cable)" in r.output
    assert r.output.count("met)") == 2
    with h5py.File(out) as h5:
        found = h5["result/targets"].attrs["found"]
        assert h5["result/targets"].attrs["found_kind"] == "force_density"
        assert len(found) == 16 and abs(found[-1]) > 1e-3  # (the support moved)
        assert h5["result/x"][40, 2] == pytest.approx(found[-1], abs=1e-12)
    again = CliRunner().invoke(
        main, ["run", str(out.with_suffix(".toml")), "-o", str(tmp_path / "run.h5")]
    )
    assert again.exit_code == 0, again.output
    with h5py.File(tmp_path / "run.h5") as h5:
        assert h5["result/x"][0, 2] == pytest.approx(-3.0, abs=1e-6)
        assert h5["result/reaction"][40, 2] == pytest.approx(900.0, rel=1e-6)


def test_a_large_search_with_a_moving_border_meets_the_surface(tmp_path):
    """480 force densities and 225 free nodes (the operator's path, bordered by the
    offset's column), the surface 0.3 m above the border: met, the border moved within
    its range."""
    data, f = hypar(tmp_path, 16)
    obj = tmp_path / "surface.obj"
    lines = [
        f"v {' '.join(t.split()[1:3])} {float(t.split()[3]) + 0.3!r}" if t.startswith("v ") else t
        for t in obj.read_text().splitlines()
    ]
    obj.write_text("\n".join(lines) + "\n")
    data["geometry"]["sets"] = {"border": data["geometry"]["fixed"]}
    data["formfind"]["support"] = [{"node": "border", "dz": [-1.0, 1.0]}]
    (tmp_path / "case.toml").write_text(dumps_toml(data))
    got = formfind_scene(build(parse_case(data, base_dir=tmp_path)))
    d = got.design
    assert d.variables == 481 and d.extra["moved"] == 1 and d.all_met
    assert "steps" in d.extra  # (the operator's damped steps were taken)
    assert -1.0 <= d.extra["values"][-1] <= 1.0


@pytest.mark.parametrize(
    ("formfind", "message"),
    [
        (
            {"force_density": 500.0, "support": [{"node": 40, "dz": [-1, 1]}]},
            "the supports move to meet [[target]] tables: add them",
        ),
        (
            {"method": "forces", "force": 1e3, "support": [{"node": 40, "dz": [-1, 1]}]},
            "only in a search for [[target]] (method = 'elastic' or 'linear'; this is 'forces')",
        ),
        (
            {"force_density": 500.0, "vary": "supports", "force_density_min": 1.0},
            "formfind.vary = 'supports': needs [[formfind.support]] tables",
        ),
    ],
)
def test_bad_support_moves_exit_2_with_one_message(tmp_path, formfind, message):
    data = spider(formfind=formfind)
    if "force" in formfind or "vary" not in formfind and "support" in formfind:
        data.pop("target")
    r, out = invoke(tmp_path, data)
    assert r.exit_code == 2, r.output
    assert message in r.output, r.output
    assert "Traceback" not in r.output and not out.exists()


def test_force_density_bounds_with_the_offsets_alone_are_refused(tmp_path):
    data = spider(
        geometry=with_sets(),
        formfind={
            "force_density": 500.0,
            "vary": "supports",
            "force_density_max": 1e4,
            "support": [{"node": "ring", "dz": [-10.0, 10.0]}],
        },
    )
    r, _ = invoke(tmp_path, data)
    assert r.exit_code == 2 and "formfind.force_density_max = 10000.0: bounds the force" in r.output
    assert "not varied here" in r.output


def hung_cable(dx) -> dict:
    """A 40 m cable of ten 4 m edges under 2 kN at each inner node, one force density for
    it; its far anchor moves along it by dx for the middle 3 m down and a 45 kN pull at
    the near one. By hand: the pull H = q h (h the edges' horizontal length) and the
    middle's sag, the simple beam's moment 12.5 P h over H, give h = 3 H / (12.5 P) =
    5.4 m (dx = +14 m) and q = H / h = 8333.33 N/m."""
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[4.0 * i, 0.0, 0.0] for i in range(11)],
            "cable": [{"name": "main", "nodes": list(range(11))}],
            "sets": {"mid": [5]},
        },
        "material": {"EA": 1.0e8},
        "supports": {"fixed": [0, 10]},
        "load": {"point": [{"node": i, "force": [0, 0, -2000.0]} for i in range(1, 10)]},
        "formfind": {
            "force_density": 1.0e4,
            "vary": "cables",
            "support": [{"node": 10, "dx": dx}],
        },
        "target": [{"node": "mid", "z": -3.0}, {"support": 0, "reaction_x": -45000.0}],
    }


def test_an_offset_held_at_its_range_is_said_so_on_its_own_line(tmp_path):
    """The cable's targets are met by hand at dx = +14 m; dx in [0, 10] m holds the
    anchor at 10 m (a compromise). The offset's line says it is at a bound, the force
    density's line does not (the offset had been counted as a force density at a
    bound)."""
    r, _ = invoke(tmp_path, hung_cable([0.0, 10.0]))
    assert r.exit_code == 0, r.output
    line = r.output.split("design       ")[1].split("\n")[0]
    assert line.startswith("1 force densities (one per cable)") and "at a bound" not in line
    assert "moved        support 10 dx: +10 m (at a bound of its range)" in r.output
    assert "(1 variable at a bound)" in r.output


def test_the_hung_cables_anchor_is_found_by_hand(tmp_path):
    r, out = invoke(tmp_path, hung_cable([-20.0, 20.0]))
    assert r.exit_code == 0, r.output
    with h5py.File(out) as h5:
        found = h5["result/targets"].attrs["found"]
        assert found[0] == pytest.approx(45000.0 / 5.4, rel=1e-9)
        assert found[1] == pytest.approx(14.0, abs=1e-8)


def test_a_hard_target_the_offsets_range_stops_names_that_range(tmp_path):
    """The force densities kept, the ring allowed only up (dz in [0.5, 2] m): the
    centre cannot come 3 m below, and the message names the range that stops it (it had
    named formfind.force_density_min/max, which nothing here varies)."""
    data = spider(
        geometry=with_sets(),
        target=[{"node": "centre", "z": -3.0, "hard": True}],
        formfind={
            "force_density": 500.0,
            "vary": "supports",
            "support": [{"node": "ring", "dz": [0.5, 2.0]}],
        },
    )
    r, _ = invoke(tmp_path, data)
    assert r.exit_code == 2, r.output
    assert "widen the ranges of [[formfind.support]] or drop hard" in r.output
    assert "force_density_min" not in r.output
