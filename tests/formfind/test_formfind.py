"""Form finding (catenet.formfind, `catenet formfind`): the force density method against
closed forms and a plain sparse solve, the nonlinear methods against their targets, and
the case it writes against `catenet run`.

Force density method (Schek, "The force density method for form finding and computation
of general networks", Comput. Methods Appl. Mech. Eng. 3 (1974) 115-134): with q_e = N_e /
L_e, equilibrium of a free node i reads sum_e q_e (x_i - x_j) = p_i, linear in x.
"""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
import pytest
import scipy.sparse as sp
from click.testing import CliRunner
from conftest import CONFIGS
from scipy.sparse.linalg import spsolve

from catenet.case import build, load_case, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.formfind import formfind, to_case, write_formfind
from catenet.model.net import Loads, Net
from catenet.run.runner import run_case

SADDLE = CONFIGS / "formfind" / "saddle.toml"
CORNERS = np.array([[0.0, 0.0, 1.0], [2.0, 0.0, 0.0], [2.0, 2.0, 1.5], [0.0, 2.0, 0.5]])


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def star(q=1.0, EA=1e5) -> Net:
    """One free node (4) joined to four fixed corners at different heights."""
    nodes = np.vstack([CORNERS, [[7.0, -3.0, 9.0]]])  # the free node's position is ignored
    return Net.from_arrays(nodes, [[4, 0], [4, 1], [4, 2], [4, 3]], EA=EA, fixed=[0, 1, 2, 3])


def grid(n: int, a: float, boundary) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An n x n grid on [-a, a]^2: nodes (boundary ones at z = boundary(x, y), inner at
    0), edges along both directions, and the boundary mask."""
    s = np.linspace(-a, a, n)
    x, y = np.meshgrid(s, s)
    edge = np.zeros((n, n), bool)
    edge[[0, -1], :] = edge[:, [0, -1]] = True
    z = np.where(edge, boundary(x, y), 0.0)
    nodes = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    k = np.arange(n * n).reshape(n, n)
    edges = np.vstack(
        [
            np.column_stack([k[:, :-1].ravel(), k[:, 1:].ravel()]),
            np.column_stack([k[:-1, :].ravel(), k[1:, :].ravel()]),
        ]
    )
    return nodes, edges, edge.ravel()


def graph_case(nodes, edges, fixed, formfind_table, **sections) -> dict:
    data = {
        "title": "test net",
        "geometry": {
            "kind": "graph",
            "nodes": np.asarray(nodes).tolist(),
            "edges": np.asarray(edges).tolist(),
            "fixed": np.flatnonzero(fixed).tolist()
            if np.asarray(fixed).dtype == bool
            else list(fixed),
        },
        "material": {"E": 160e9, "radius": 0.006},
        "formfind": formfind_table,
    }
    data.update(sections)
    return data


# --------------------------------------------------------------------------- closed forms


def test_single_node_is_the_weighted_mean_of_its_neighbours():
    """Free node with edges to four fixed corners: sum_e q_e (x - c_e) = p gives
    x = (sum q_e c_e + p) / sum q_e; equal q: the mean of the corners, and a load p in z
    shifts z by p / (4 q)."""
    net = star()
    found = formfind(net, 3.0)
    assert np.allclose(found.x[4], CORNERS.mean(axis=0), rtol=0, atol=1e-14)
    np.testing.assert_allclose(found.force, 3.0 * np.linalg.norm(CORNERS - found.x[4], axis=1))
    q = np.array([1.0, 2.0, 3.0, 4.0])
    assert np.allclose(formfind(net, q).x[4], q @ CORNERS / q.sum(), atol=1e-14)
    p = np.zeros((5, 3))
    p[4, 2] = -6.0
    loaded = formfind(net, 3.0, loads=Loads(force=p))
    assert loaded.x[4, 2] - found.x[4, 2] == pytest.approx(-6.0 / (4 * 3.0), abs=1e-14)
    assert np.allclose(loaded.x[4, :2], found.x[4, :2], atol=1e-14)
    # Reactions plus loads sum to zero (and reactions sit at fixed nodes only).
    r = loaded.reaction()
    assert np.all(r[4] == 0.0)
    assert np.allclose(r.sum(axis=0) + p.sum(axis=0), 0.0, atol=1e-12)


def test_linear_method_against_a_plain_sparse_solve():
    """A random net with per-edge q and loads against D x_f = p_f - C_f^T Q C_x x_x built
    here with scipy.sparse and solved with spsolve."""
    rng = np.random.default_rng(7)
    nodes, edges, fixed = grid(9, 2.0, lambda x, y: 0.3 * np.sin(x) * np.cos(y))
    q = rng.uniform(0.5, 5.0, len(edges))
    p = rng.normal(size=(len(nodes), 3))
    net = Net.from_arrays(nodes, edges, EA=1e6, fixed=fixed)
    found = formfind(net, q, loads=Loads(force=p), linear="scipy")
    m, n = len(edges), len(nodes)
    C = sp.csr_matrix(
        (
            np.r_[-np.ones(m), np.ones(m)],
            (np.r_[np.arange(m), np.arange(m)], np.r_[edges[:, 0], edges[:, 1]]),
        ),
        shape=(m, n),
    )
    free = ~fixed
    Cf, Cx = C[:, free], C[:, fixed]
    Q = sp.diags(q)
    D = (Cf.T @ Q @ Cf).tocsc()
    want = spsolve(D, p[free] - Cf.T @ (Q @ (Cx @ nodes[fixed])))
    np.testing.assert_allclose(found.x[free], want, rtol=0, atol=1e-12)
    assert np.array_equal(found.x[fixed], nodes[fixed])
    auto = formfind(net, q, loads=Loads(force=p))  # PARDISO where available
    np.testing.assert_allclose(auto.x, found.x, rtol=0, atol=1e-12)
    assert auto.factorizations == 1


def test_saddle_is_the_hypar_and_all_in_tension(tmp_path):
    """The classic hyperbolic paraboloid: corners alternately high and low, boundary held
    on the straight edges between them, uniform q on a square grid. x y is discretely
    harmonic on the grid (the 5-point Laplacian of x y is 0) and so are x and y, so the
    free nodes sit exactly at z = x y / 9 (corners at z = +-1, a = 3) on their grid
    points. The shape is symmetric under (x, y) -> (-x, -y) and antisymmetric under
    x -> -x; every edge is in tension."""
    out = tmp_path / "saddle.h5"
    done = invoke("formfind", SADDLE, "-o", out)
    assert done.exit_code == 0, done.output
    assert "linear (one factorisation)" in done.output
    with h5py.File(out, "r") as h5:
        x = h5["result/x"][()]
        tension = h5["result/tension"][()]
        reaction = h5["result/reaction"][()]
        assert h5["result"].attrs["converged"]
        assert h5["trajectory/x"].shape[0] == 1
    assert np.allclose(x[:, 2], x[:, 0] * x[:, 1] / 9.0, rtol=0, atol=1e-12)
    grid_pts = np.round((x[:, :2] + 3.0) / 0.5)
    assert np.allclose(x[:, :2], grid_pts * 0.5 - 3.0, atol=1e-12)
    order = np.lexsort((grid_pts[:, 0], grid_pts[:, 1]))
    z = x[order, 2].reshape(13, 13)
    assert np.allclose(z, z[::-1, ::-1], atol=1e-12)  # (x, y) -> (-x, -y)
    assert np.allclose(z, -z[:, ::-1], atol=1e-12)  # x -> -x
    assert np.all(tension > 0)
    assert np.allclose(reaction.sum(axis=0), 0.0, atol=1e-8 * tension.max())
    # The case written beside it runs to the same shape and forces.
    case = load_case(out.with_suffix(".toml"))
    assert case.geometry.kind == "graph" and case.formfind is None
    res = run_case(case, tmp_path / "rerun.h5")
    assert res.converged
    np.testing.assert_allclose(res.x, x, rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.tension, tension, rtol=1e-8)


# --------------------------------------------------------------------------- the roof


def roof_case(n: int = 71) -> dict:
    """A cable-net roof of 2 n (n - 1) edges (9940 for n = 71) on a 30 m square with a
    saddle boundary, under its own weight and a point load at the centre."""
    nodes, edges, fixed = grid(n, 15.0, lambda x, y: 3.0 * (x**2 - y**2) / 225.0)
    centre = int(np.argmin(np.linalg.norm(nodes[:, :2], axis=1)))
    return graph_case(
        nodes,
        edges,
        fixed,
        {"force_density": 2.0e4},
        material={"E": 160e9, "radius": 0.008, "density": 7850.0},
        load={"gravity": [0.0, 0.0, -9.81], "point": [{"node": centre, "force": [0, 0, -5e3]}]},
    )


def test_roof_of_ten_thousand_edges_reruns_to_its_shape_and_forces(tmp_path):
    """Form-found under self-weight and a point load, the written case run again with
    `catenet run` (no further load) reproduces the shape and forces to 1e-8. The weight
    in the run comes from the rest lengths written: form finding updated it until it
    matched them."""
    case = parse_case(roof_case(), source=str(tmp_path / "roof.toml"))
    assert case.geometry.estimate_size()[1] == 9940
    written = write_formfind(case, tmp_path / "roof.h5")
    found = written.found
    assert found.factorizations == 1 and np.all(found.force > 0)
    rerun = load_case(written.case_file)
    assert rerun.output.file == str(tmp_path / "roof_run.h5")
    res = run_case(rerun)
    assert res.converged
    size = float(np.ptp(found.x, axis=0).max())
    assert np.max(np.abs(res.x - found.x)) <= 1e-8 * size
    np.testing.assert_allclose(res.tension, found.force, rtol=1e-8)
    # Reactions plus loads sum to zero, in the file and in the rerun.
    scene = build(rerun)
    load = scene.loads.external_force(scene.net)
    with h5py.File(written.result_file, "r") as h5:
        reaction = h5["result/reaction"][()]
    scale = float(np.abs(load).sum())
    assert np.allclose(reaction.sum(axis=0) + load.sum(axis=0), 0.0, atol=1e-10 * scale)
    assert np.allclose(res.reaction.sum(axis=0) + load.sum(axis=0), 0.0, atol=1e-8 * scale)
    assert np.allclose(found.reaction(), reaction, atol=1e-8 * scale)


# --------------------------------------------------------------------------- nonlinear


@pytest.mark.parametrize("method", ["forces", "lengths"])
def test_nonlinear_methods_meet_their_targets(method, tmp_path):
    """Targets taken from a linear form finding with other force densities are met to
    formfind.tol; with a load, the forces are recovered as well."""
    nodes, edges, fixed = grid(11, 2.0, lambda x, y: 0.4 * x * y)
    rng = np.random.default_rng(1)
    q_true = rng.uniform(1.0, 3.0, len(edges))
    p = np.zeros((len(nodes), 3))
    p[~fixed, 2] = -0.2
    net = Net.from_arrays(nodes, edges, EA=1e6, fixed=fixed)
    truth = formfind(net, q_true, loads=Loads(force=p))
    target = truth.force if method == "forces" else truth.length
    found = formfind(net, loads=Loads(force=p), method=method, tol=1e-10, **{method[:-1]: target})
    got = found.force if method == "forces" else found.length
    assert np.max(np.abs(got / target - 1)) <= 1e-10
    assert found.residual <= 1e-10 and found.factorizations > 1
    # Equilibrium of the result at every free node.
    r = found.reaction()
    assert np.allclose(r.sum(axis=0) + p.sum(axis=0), 0.0, atol=1e-9)
    # Through a case: the table's targets, then the written case reruns to them.
    ff = {"method": method, method[:-1]: target.tolist(), "tol": 1e-10}
    points = [{"node": int(i), "force": p[i].tolist()} for i in np.flatnonzero(~fixed)]
    data = graph_case(nodes, edges, fixed, ff, material={"EA": 1e6}, load={"point": points})
    written = write_formfind(parse_case(data), tmp_path / f"{method}.h5")
    res = run_case(load_case(written.case_file), tmp_path / "rerun.h5")
    np.testing.assert_allclose(res.x, written.found.x, rtol=0, atol=1e-8)
    if method == "forces":
        np.testing.assert_allclose(res.tension, target, rtol=1e-8)


def test_target_lengths_without_load_keep_the_mean_force_density():
    """Without loads, target lengths fix q only up to a factor: its geometric mean is
    force_density."""
    net = star()
    truth = formfind(net, [1.0, 2.0, 3.0, 4.0])
    found = formfind(net, 5.0, method="lengths", length=truth.length, tol=1e-12)
    assert np.exp(np.mean(np.log(found.q))) == pytest.approx(5.0, rel=1e-12)
    np.testing.assert_allclose(found.q / found.q[0], [1, 2, 3, 4], rtol=1e-8)


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "q, message",
    [
        (-1.0, "force_density = -1.0: must be finite and > 0"),
        (float("nan"), "force_density = nan: must be finite and > 0"),
        ([1.0, 2.0], "force_density: has 2 values: must be one number or one per edge (4)"),
        ([1.0, 2.0, -3.0, 1.0], "force_density[2] = -3.0: must be finite and > 0"),
    ],
)
def test_bad_force_densities_from_python(q, message):
    with pytest.raises(ConfigError) as err:
        formfind(star(), q)
    assert message in str(err.value)


def test_coincident_nodes_are_named():
    """A free node hanging from one fixed node without load: q (x - x_fixed) = 0 puts it
    on that node."""
    net = Net.from_arrays(
        [[0, 0, 0], [1, 0, 0], [0.5, 0.5, 0], [0.5, 1.0, 0]],
        [[0, 2], [1, 2], [3, 1]],
        EA=1.0,
        fixed=[0, 1],
    )
    with pytest.raises(ConfigError, match=r"edges of zero length: 2 \(nodes \[3, 1\]\)"):
        formfind(net, 1.0)


def test_unreachable_targets_and_forces_beyond_the_law():
    net = star()
    with pytest.raises(ConfigError, match=r"length: cannot be met to tol = 1e-09: edge"):
        formfind(net, method="lengths", length=[1.5, 1.5, 1.6, 1.7])
    hencky = Net.from_arrays(net.nodes, net.edges, EA=10.0, fixed=net.fixed, law=_law(4, "hencky"))
    with pytest.raises(ConfigError, match=r"edge 0 .* cannot carry with a positive rest length"):
        formfind(hencky, 100.0)  # N = q L > EA / e, Hencky's peak


def _law(m, name):
    from catenet.model.laws import Law

    return Law.uniform(m, name)


def write_toml(path, data):
    import tomli_w

    path.write_text(tomli_w.dumps(data))
    return path


def test_cli_bad_input_exits_2_with_the_key_path(tmp_path):
    nodes, edges, fixed = grid(5, 1.0, lambda x, y: x * y)
    case = write_toml(tmp_path / "c.toml", graph_case(nodes, edges, fixed, {"force_density": -2}))
    done = invoke("formfind", case, "-o", tmp_path / "o.h5")
    assert done.exit_code == 2
    assert "formfind.force_density = -2: must be a number, finite and > 0" in done.output
    assert not (tmp_path / "o.h5").exists() and not (tmp_path / "o.toml").exists()
    done = invoke(
        "formfind", case, "-o", tmp_path / "o.h5", "--set", "formfind.force_density=[1, 2]"
    )
    assert done.exit_code == 2 and "formfind.force_density: has 2 values" in done.output
    done = invoke("formfind", case, "--set", "formfind.method=forces")
    assert done.exit_code == 2
    assert "formfind.force: missing: method = 'forces' needs its targets" in done.output
    data = graph_case(nodes, edges, fixed, {"force_density": 1.0})
    data["material"]["prestress"] = 10.0
    data["geometry"]["prestrain"] = 0.01
    done = invoke("formfind", write_toml(tmp_path / "p.toml", data))
    assert done.exit_code == 2
    assert "material.prestress = 10.0: form finding gives every edge its tension" in done.output
    assert "geometry.prestrain = 0.01: form finding derives the rest lengths" in done.output
    del data["formfind"]
    done = invoke("formfind", write_toml(tmp_path / "n.toml", {**data, "material": {"EA": 1}}))
    assert done.exit_code == 2 and "formfind: missing: the case needs a [formfind]" in done.output


def test_run_and_sweep_refuse_a_form_finding_case(tmp_path):
    done = invoke("run", SADDLE, "-o", tmp_path / "x.h5")
    assert done.exit_code == 2
    assert "is a form-finding case: find its shape with `catenet formfind" in done.output
    done = invoke("sweep", SADDLE, "-p", "formfind.force_density=1,2", "-o", tmp_path / "sw")
    assert done.exit_code == 2 and "is a form-finding case" in done.output


def test_written_case_round_trips_and_keeps_settings(tmp_path):
    data = tomllib.loads(SADDLE.read_text())
    data["geometry"]["file"] = str(SADDLE.with_name("saddle.json"))
    data["solver"] = {"rtol": 1e-10, "linear": "scipy"}
    case = parse_case(data, source="saddle.toml")
    written = write_formfind(case, tmp_path / "s.h5")
    back = written.case
    assert back.solver.rtol == 1e-10 and back.solver.linear == "scipy"
    assert back.material.E == 160e9 and back.material.density == 7850.0
    text = written.case_file.read_text()
    assert text.startswith("# Form found by `catenet formfind saddle.toml`")
    assert parse_case(tomllib.loads(text)) == back
    from_python = to_case(written.found)  # a net from Python: EA per edge, linear law
    assert parse_case(from_python).geometry.rest_length == back.geometry.rest_length


@pytest.mark.parametrize("method", ["forces"])
def test_nonlinear_methods_converge_by_newton_without_the_fallback(method, caplog):
    """Newton on log q (GMRES on the Jacobian operator, one factorisation per iterate)
    meets the targets; the least squares stays a fallback it does not need here."""
    import logging

    nodes, edges, fixed = grid(11, 2.0, lambda x, y: 0.4 * x * y)
    rng = np.random.default_rng(2)
    net = Net.from_arrays(nodes, edges, EA=1e6, fixed=fixed)
    truth = formfind(net, rng.uniform(1.0, 3.0, len(edges)))
    target = truth.force if method == "forces" else truth.length
    with caplog.at_level(logging.INFO, logger="catenet.formfind.fdm"):
        found = formfind(net, 2.0, method=method, tol=1e-10, **{method[:-1]: target})
    assert not [m for m in caplog.messages if "least squares" in m]
    got = found.force if method == "forces" else found.length
    assert np.max(np.abs(got / target - 1)) <= 1e-10
    assert found.factorizations == found.iterations < 60


def test_target_lengths_on_a_roof_of_a_thousand_edges_converge_by_newton(caplog):
    """A 1012-edge saddle roof, target lengths from a linear form finding with force
    densities spread over a factor 3, started from uniform q: damped Newton on log q (one
    sparse saddle-point solve per step) meets every length to 1e-9, without the least
    squares, and the shape is the one the lengths came from."""
    import logging

    nodes, edges, fixed = grid(23, 15.0, lambda x, y: 3.0 * (x**2 - y**2) / 225.0)
    assert len(edges) == 1012
    net = Net.from_arrays(nodes, edges, EA=8e6, fixed=fixed)
    truth = formfind(net, np.random.default_rng(0).uniform(1e4, 3e4, len(edges)))
    with caplog.at_level(logging.INFO, logger="catenet.formfind.fdm"):
        found = formfind(net, 2e4, method="lengths", length=truth.length, tol=1e-9)
    assert not [m for m in caplog.messages if "least squares" in m]
    assert np.max(np.abs(found.length / truth.length - 1)) <= 1e-9
    assert found.residual <= 1e-9 and found.iterations < 60
    np.testing.assert_allclose(found.x, truth.x, rtol=0, atol=1e-6)
    # Lengths fix q up to a factor only (and not at all between two fixed nodes): the
    # ratios of the others are the truth's.
    acts = ~(fixed[edges[:, 0]] & fixed[edges[:, 1]])
    ratio = found.q[acts] / truth.q[acts]
    np.testing.assert_allclose(ratio / ratio.mean(), 1.0, rtol=1e-6)


def test_incompatible_target_lengths_are_reported_with_the_worst_edge():
    """Every edge of a 220-edge saddle net asked to be 0.1 m long while the boundary
    spans 4 m: no force densities give that; Newton's damped steps stop lowering the
    misses and the message names the worst edge, its length and the target."""
    nodes, edges, fixed = grid(11, 2.0, lambda x, y: 0.4 * x * y)
    net = Net.from_arrays(nodes, edges, EA=1e6, fixed=fixed)
    free = ~(fixed[edges[:, 0]] & fixed[edges[:, 1]])
    target = np.where(free, 0.1, formfind(net, 1.0).length)  # boundary edges as they are
    with pytest.raises(ConfigError) as err:
        formfind(net, method="lengths", length=target, max_iter=200)
    msg = str(err.value)
    assert msg.startswith("length: cannot be met to tol = 1e-09: edge ")
    assert "target 0.1" in msg and "the targets are not compatible" in msg
    # An edge between fixed nodes whose target differs from its length is named at once.
    target[~free] *= 1.5
    with pytest.raises(ConfigError, match="an edge between two fixed nodes keeps its length"):
        formfind(net, method="lengths", length=target)


@pytest.mark.parametrize("method", ["forces", "lengths"])
def test_targets_under_self_weight_converge_with_the_weights_jacobian(method):
    """A heavy net (its weight comparable to its tension): the Newton system carries the
    weight's change with the shape and the force densities (l0 = L / (1 + eps(q L))),
    so the targets are met to 1e-9 in a few steps, not at a linear rate."""
    nodes, edges, fixed = grid(11, 2.0, lambda x, y: 0.4 * x * y)
    net = Net.from_arrays(nodes, edges, EA=1e6, fixed=fixed, line_density=0.5)
    loads = Loads(gravity=np.array([0.0, 0.0, -9.81]))
    truth = formfind(net, np.random.default_rng(3).uniform(10, 30, len(edges)), loads=loads)
    target = truth.force if method == "forces" else truth.length
    found = formfind(net, 20.0, loads=loads, method=method, **{method[:-1]: target})
    got = found.force if method == "forces" else found.length
    assert np.max(np.abs(got / target - 1)) <= 1e-9
    assert found.iterations <= 40  # (forces: 20 of them the fixed-point start)
    np.testing.assert_allclose(found.x, truth.x, rtol=0, atol=1e-7)
