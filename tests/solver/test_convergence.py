"""Models an engineer writes first, at default settings: they converge, or say exactly why.

- A 5-node guyed mast (a 30 m bilateral strut, EA = 1.26e9 N, three guys of EA = 1.6e7 N
  prestressed to T0, the strut precompressed to balance them, a horizontal load F at the
  top) over a grid of F and T0, the unloaded balanced case among them. Its strut at a
  strain of 2e-5 stores so little energy that differences of the total energy are below
  their round-off (sum |N| |e| eps_mach) near the solution: the line search must not trust
  them. The top's displacement is checked against the linear stiffness of the guys.
- A mast of three pinned struts in a chain: a mechanism. The run exits 1, naming the
  joints.
- A failed static run: what it keeps as /result is an equilibrium (its residual is
  checked at its load factor), never an unconverged iterate.
- Contact forces close the global equilibrium: reactions + contact + loads = 0.
"""

from __future__ import annotations

import math
import tomllib

import h5py
import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner
from conftest import small_net

from catenet.case import build, load_case, parse_case
from catenet.cli import main
from catenet.solver.static import Workspace

HEIGHT, RADIUS = 30.0, 20.0
GUY = math.hypot(HEIGHT, RADIUS)
EA_STRUT, EA_GUY = 1.26e9, 1.6e7


def mast(force: float, prestress: float) -> dict:
    """The 5-node guyed mast as written from the README: a graph with per-edge EA,
    tension_only and prestress; guys at 0, 120 and 240 degrees."""
    anchors = [
        [RADIUS * math.cos(a), RADIUS * math.sin(a), 0.0] for a in np.radians([0.0, 120.0, 240.0])
    ]
    strut = -3.0 * prestress * HEIGHT / GUY  # balances the guys' vertical pull
    return {
        "title": "5-node guyed mast",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, HEIGHT], *anchors],
            "edges": [[0, 1], [1, 2], [1, 3], [1, 4]],
            "fixed": [0, 2, 3, 4],
            "EA": [EA_STRUT, EA_GUY, EA_GUY, EA_GUY],
            "tension_only": [False, True, True, True],
            "prestress": [strut, prestress, prestress, prestress],
        },
        "material": {"EA": EA_GUY},
        "load": {"point": [{"node": 1, "force": [force, 0.0, 0.0]}]},
    }


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write(tmp_path, case: dict, name: str = "case") -> str:
    path = tmp_path / f"{name}.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    return str(path)


def imbalance(path) -> float:
    """|sum of reactions + contact forces + applied loads| over the largest of them."""
    from catenet.output import read_result

    with h5py.File(path, "r") as h5:
        reaction = h5["result/reaction"][()]
        contact = h5["result/contact_force"][()]
    res = read_result(path)
    scene = build(parse_case(res.case))
    load = scene.loads.external_force(scene.net, float(res.result_attrs.get("time", 1.0)))
    total = np.sum(reaction + contact + load, axis=0)
    scale = max(np.abs(reaction).max(), np.abs(contact).max(), np.abs(load).max())
    return float(np.linalg.norm(total) / scale) if scale > 0 else float(np.linalg.norm(total))


@pytest.mark.parametrize("prestress", [0.0, 1e3, 1e4, 5e4])
@pytest.mark.parametrize("force", [0.0, 1e3, 3e3, 5e3, 6e3, 7e3, 2e4])
def test_the_guyed_mast_converges_at_default_settings(tmp_path, force, prestress):
    case = mast(force, prestress)
    out = tmp_path / "mast.h5"
    r = invoke("run", write(tmp_path, case), "-o", out, "-q")
    assert r.exit_code == 0, r.output
    with h5py.File(out, "r") as h5:
        x = h5["result/x"][()]
        tension = h5["result/tension"][()]
        assert h5["result"].attrs["converged"]
    assert imbalance(out) < 1e-7  # the residual is below rtol = 1e-8 of the force norm
    u = x[1, 0]  # the top's sideways displacement
    if force == 0.0:
        assert abs(u) < 1e-9 and tension[1:] == pytest.approx(prestress, rel=1e-9)
        return
    # While every guy is taut, the top's horizontal stiffness is the guys' axial
    # stiffness, sum EA/L cos^2 = 1.5 EA/L (RADIUS/GUY)^2 for three guys at 120 degrees,
    # plus their and the strut's geometric stiffness T/L (1 + ...) : small against it.
    taut = np.all(tension[1:] > 0)
    k_axial = 1.5 * EA_GUY / GUY * (RADIUS / GUY) ** 2
    k_geometric = 3.0 * prestress / GUY * (1 - 0.5 * (RADIUS / GUY) ** 2) - 3.0 * prestress / GUY
    if taut:
        assert u == pytest.approx(force / (k_axial + k_geometric), rel=2e-2)
    assert u > 0.0


@pytest.mark.roundoff
def test_a_chain_of_struts_is_named_a_mechanism(tmp_path):
    """Three pinned struts stacked into a mast, guyed only at the top: the two joints
    between the struts have no lateral stiffness and the strut's compression pushes them
    out. The run exits 1 and names them."""
    case = {
        "title": "mast of three struts in a chain",
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [0, 0, 10], [0, 0, 20], [0, 0, 30]]
            + [[20.0, 0, 0], [-10.0, 17.320508, 0], [-10.0, -17.320508, 0]],
            "edges": [[0, 1], [1, 2], [2, 3], [3, 4], [3, 5], [3, 6]],
            "fixed": [0, 4, 5, 6],
            "EA": [EA_STRUT] * 3 + [EA_GUY] * 3,
            "tension_only": [False] * 3 + [True] * 3,
            "prestress": [-24961.5] * 3 + [1e4] * 3,
        },
        "material": {"EA": EA_GUY},
        "load": {"point": [{"node": 3, "force": [3e3, 0.0, 0.0]}]},
    }
    r = invoke("run", write(tmp_path, case), "-o", tmp_path / "chain.h5")
    assert r.exit_code == 1, r.output
    assert "mechanism" in r.output and "nodes 1, 2" in r.output
    assert "brace" in r.output  # the fix


def test_an_unsupported_part_is_named(tmp_path):
    case = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [5, 0, 0], [6, 0, 0]],
            "edges": [[0, 1], [1, 2], [3, 4]],
            "fixed": [0, 2],
        },
        "material": {"EA": 1e5, "prestress": 100.0},
    }
    r = invoke("run", write(tmp_path, case), "-o", tmp_path / "free.h5")
    assert r.exit_code == 2, r.output
    assert "nodes [3, 4]" in r.output and "no support" in r.output


def test_a_failed_run_keeps_an_equilibrium(tmp_path, write_case):
    """max_iter = 1 cannot take the paper's flat net to its equilibrium, even in cut-back
    sub-steps or pseudo-time steps: the run fails, saying what it tried and the setting
    most likely to help, and /result holds the last equilibrium found, labelled with its
    load factor (the start at 0 when none was): its residual there is checked."""
    small_case = write_case(small_net("static"))
    out = tmp_path / "failed.h5"
    r = invoke("run", small_case, "-o", out, "--set", "solver.max_iter=1")
    assert r.exit_code == 1, r.output
    assert "cut-back" in r.output and "pseudo-transient" in r.output
    assert "most likely to help: a larger solver.max_iter" in r.output
    assert "load factor" in r.output
    with h5py.File(out, "r") as h5:
        x = h5["result/x"][()]
        factor = float(h5["result"].attrs["time"])
        assert not h5["result"].attrs["converged"]
    case = load_case(small_case)
    scene = build(case)
    ws = Workspace(scene.net, terms=scene.terms)
    ev = ws.potential(scene.loads, factor).evaluate(x)
    assert np.linalg.norm(ev.g) <= max(case.solver.rtol * ev.scale, 10 * ev.floor)


def test_contact_forces_close_the_equilibrium_of_the_net_on_a_sphere(tmp_path):
    out = tmp_path / "sphere.h5"
    r = invoke("run", "configs/contact/net_on_sphere.toml", "-o", out, "-q")
    assert r.exit_code == 0, r.output
    with h5py.File(out, "r") as h5:
        contact = h5["result/contact_force"][()]
        assert np.abs(contact).max() > 0  # the sphere carries part of the load
        assert np.all(contact[:, 2] >= 0)  # and pushes up
    assert imbalance(out) < 1e-7  # the residual is below rtol = 1e-8 of the force norm


def test_the_springs_of_the_stretched_start_pass_the_derivative_check():
    from catenet.terms import check_derivatives
    from catenet.terms.stretch import Springs

    scene = build(parse_case(tomllib.loads(small_net("static"))))
    rng = np.random.default_rng(1)
    x = scene.net.nodes + 0.01 * rng.standard_normal(scene.net.nodes.shape)
    springs = Springs(scene.net, rng.uniform(0.5, 2.0, scene.net.n_edges))
    grad_error, hessian_error = check_derivatives(springs, x)
    assert grad_error < 1e-7 and hessian_error < 1e-7


@pytest.mark.parametrize("edge", [0.01, 0.002, 0.001])
def test_newton_from_the_flat_net_does_not_slow_down_with_refinement(edge):
    """The paper's n = 34 net from its flat, unstressed start: the stretched start (a
    force density shape, scaled to the least potential along it) gives Newton a
    transverse stiffness at once; 7, 8 and 10 iterations at 1 cm, 2 mm and 1 mm edges
    (the flat start took 11, 15 and 14, and more than 600 at 0.2 mm: 12 now)."""
    from catenet.solver.path import Settings, solve

    case = load_case("configs/fig4g_n34_alpha_0.toml", [f"geometry.edge_length={edge}"])
    r = solve(build(case), Settings.of(case.solver))
    assert r.converged and r.iterations <= 10
    assert r.stats.factorize_count <= 12  # the springs' solve and one per iteration


def test_the_pseudo_transient_rung_reaches_the_equilibrium_newton_cannot(tmp_path, write_case):
    """With max_iter = 3 Newton cannot solve the flat net's load step, nor its cut-back
    sub-steps; the damped pseudo-transient solve, whose pseudo-time steps are each an easy
    problem, reaches the same equilibrium as the default run."""
    case = write_case(small_net("static"))
    runs = {}
    for budget in (3, 200):
        out = tmp_path / f"budget{budget}.h5"
        r = invoke("run", case, "-o", out, "-q", "--set", f"solver.max_iter={budget}")
        assert r.exit_code == 0, r.output
        with h5py.File(out, "r") as h5:
            runs[budget] = h5["result/x"][()]
    assert np.max(np.abs(runs[3] - runs[200])) < 1e-8


def test_a_net_far_from_the_origin_is_never_converged_above_its_loads():
    """A cable 1e5 m from the origin under loads far below the round-off of its forces
    there (EA eps_mach |x| / l0): the run may end at that floor, but then it says so
    (not converged: the floor exceeds the loads), never "converged" with a residual
    above the loads."""
    import catenet as cn

    mat = cn.Material(EA=1e6, line_density=0.0)
    cab = cn.cable([1e5, 0.0, 0.0], [1e5 + 10.0, 0.0, 0.0], 61, mat)
    force = np.zeros((61, 3))
    force[1:-1, 2] = -1e-6
    r = cn.solve_static(cab, cn.Loads(force=force), raise_on_failure=False)
    f_norm = float(np.linalg.norm(force))
    assert not (r.converged and r.residual > f_norm), (r.message, r.residual, f_norm)


def test_an_interrupted_load_step_is_not_cut_back():
    import catenet as cn
    from catenet.errors import Interrupted
    from catenet.solver.newton import interruptible

    sq = cn.square_net(6, 0.0, 1.0, 0.1, cn.Material(EA=1e4, line_density=0.1))
    loads = cn.Loads(force=cn.pressure_force(sq.net, 1.0, 10.0))
    with interruptible(lambda: True), pytest.raises(Interrupted) as info:
        cn.continuation(sq.net, loads, [1.0])
    assert "cut-back" not in str(info.value)
    assert info.value.last_good is not None and info.value.last_good.time == 0.0


def test_a_neutral_equilibrium_is_not_called_a_mechanism(tmp_path):
    """A straight bilateral cable at its rest length, unloaded: in equilibrium, neutral
    (no transverse stiffness) but with no negative stiffness: exit 0, not a mechanism."""
    case = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 11},
        "material": {"EA": 100.0, "tension_only": False},
    }
    r = invoke("run", write(tmp_path, case), "-o", tmp_path / "neutral.h5")
    assert r.exit_code == 0, r.output
    assert "mechanism" not in r.output


def test_a_graph_with_ea_per_edge_needs_no_material_table(tmp_path):
    """EA on every edge of the geometry is the whole stiffness: [material] may be left
    out (its other keys keep their defaults), and the answer is the same."""
    with_table = mast(3e3, 1e4)
    without = {k: v for k, v in with_table.items() if k != "material"}
    tops = []
    for name, case in (("with", with_table), ("without", without)):
        out = tmp_path / f"{name}.h5"
        r = invoke("run", write(tmp_path, case, name), "-o", out, "-q")
        assert r.exit_code == 0, r.output
        with h5py.File(out, "r") as h5:
            tops.append(h5["result/x"][1])
    assert np.array_equal(tops[0], tops[1])


def test_a_free_body_beside_a_wire_does_not_excuse_the_wire_residual(tmp_path):
    """A 200 kg crate resting statically on a table, a 2.1 m steel wire hanging beside it:
    the crate's rigidity puts round-off of about 1 N into the global floor of the forces.
    Convergence at round-off is decided DOF by DOF, so the wire is held to its own floor:
    its reactions carry its weight as they do without the crate."""
    wire = {
        "title": "a wire beside a crate on a table",
        "geometry": {
            "kind": "cable",
            "start": [-3.0, 0.0, 2.0],
            "end": [-1.0, 0.0, 2.0],
            "length": 2.1,
            "nodes": 21,
        },
        "material": {"E": 200e9, "radius": 0.003, "density": 7850.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "static"},
    }
    crate = {
        **wire,
        "obstacle": [
            {"kind": "box", "center": [1.0, 0.0, 0.9], "half_size": [0.8, 0.6, 0.1]},
            {
                "kind": "box",
                "center": [1.0, 0.0, 1.26],
                "half_size": [0.5, 0.4, 0.25],
                "mass": 200.0,
            },
        ],
    }
    weight = 7850.0 * math.pi * 0.003**2 * 2.1 * 9.81
    results = {}
    for name, case in (("alone", wire), ("crate", crate)):
        out = tmp_path / f"{name}.h5"
        r = invoke("run", write(tmp_path, case, name), "-o", out, "-q")
        assert r.exit_code == 0, r.output
        with h5py.File(out, "r") as h5:
            assert h5["result"].attrs["converged"]
            results[name] = (h5["result/reaction"][()], h5["result/x"][:21])
            contact = h5["result/contact_force"][()]
        if name == "crate":
            assert contact[:, 2].sum() == pytest.approx(200.0 * 9.81, rel=1e-6)
    for reaction, _ in results.values():
        assert reaction[:, 2].sum() == pytest.approx(weight, rel=1e-6)
    assert np.abs(results["crate"][1] - results["alone"][1]).max() < 1e-7
