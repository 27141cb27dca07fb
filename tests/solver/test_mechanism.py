"""A frame that is a mechanism under its loads never ends converged
(``catenet.solver.stability.PathJudge``, rules 5 and 6).

A portal of steel tubes (4 m wide, 3 m high, 0.25 m edges, rigid joints at its corners,
GJ from the section) on pinned feet turns freely about the line through its feet: a mode
without stiffness, which a push across its plane drives. Newton finds the far equilibrium,
the frame swung flat along the push, at any load; which way it gets there, and whether
a member carries round-off tension at the end, hangs on round-off. The verdict must not:
pushed at a corner or at the beam's middle, in three unit systems, from starts moved by
1e-9 of its size, judged by the sparse inertia as by the eigenvalues, and when the first
load step fails and is cut back (its sub-steps and the dynamic relaxation rung judged as
the path they are), it collapses at load factor 0 (exit 1, /result the start). Clamped
feet hold it (exit 0, stable); pushed in its plane with GJ it stands, its mode about
the feet neutral and warned (exit 0, from every start); without GJ the same push
collapses it from every start (rule 6); a bilateral cable given
straight at its rest length and loaded until its edges turn 60 degrees sags into
tension from the same kind of start (exit 0, stable): its sag shrinks with the load, a
mechanism's swing does not. A step whose unloading finds no equilibrium is no collapse.

Marked ``roundoff``: `make test` runs these again with every node moved by 1e-12 of the
net's size and two threads.
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from catenet.cli import main

pytestmark = pytest.mark.roundoff

UNITS = {"SI": (1.0, 1.0), "kN-m": (1.0, 1e-3), "N-mm": (1e3, 1.0)}  # length, force
WIDTH, HEIGHT = 4.0, 3.0
MECHANISM = "the structure is a mechanism under these loads: at load factor 0"


def portal(
    units: str = "SI",
    *,
    at: str = "corner",
    feet: str = "pinned",
    shift=None,
    push=(0.0, 1e3, 0.0),
    gj: bool = True,
) -> dict:
    """The portal (nodes 0, 1 its feet, 2, 3 its corners, 4 the beam's middle), pushed
    with ``push`` [N] (1 kN across its plane, y) ``at`` its corner 3 ("corner"), its
    corner 2 ("left") or its beam's middle; ``shift`` (5, 3) moves its given nodes [m];
    ``gj``: its tubes twist."""
    m, n = UNITS[units]
    nodes = np.array(
        [[0, 0, 0], [WIDTH, 0, 0], [0, 0, HEIGHT], [WIDTH, 0, HEIGHT], [WIDTH / 2, 0, HEIGHT]],
        dtype=float,
    )
    if shift is not None:
        nodes += shift
    supports: dict = {"fixed": [0, 1], "rigid_joints": [2, 3]}
    if feet == "clamped":
        supports["clamped"] = [0, 1]
    return {
        "title": f"portal on {feet} feet",
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": (m * nodes).tolist(),
            "edge_length": 0.25 * m,
            "cable": [
                {"name": "left", "nodes": [0, 2]},
                {"name": "right", "nodes": [1, 3]},
                {"name": "beam", "nodes": [2, 4, 3]},
            ],
        },
        "material": {
            "E": 2.1e11 * n / m**2,
            "G": 8.1e10 * n / m**2,
            "radius": 0.05 * m,
            "inner_radius": 0.045 * m,
            "EI": "section",
            "GJ": "section" if gj else 0.0,
        },
        "supports": supports,
        "load": {
            "point": [{"node": {"corner": 3, "left": 2}.get(at, 4), "force": [n * f for f in push]}]
        },
    }


def run(tmp_path, case: dict, name: str = "case", *args):
    path = tmp_path / f"{name}.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    out = tmp_path / f"{name}.h5"
    result = CliRunner().invoke(main, ["run", str(path), "-o", str(out), "-q", *args])
    return result, out


def assert_collapsed_at_the_start(result, out, units: str) -> None:
    assert result.exit_code == 1, result.output
    assert MECHANISM in result.output, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "collapsed"
        assert not f["result"].attrs["converged"]
        moved = np.linalg.norm(f["result/x"][:] - f["mesh/nodes"][:], axis=1)
    assert moved.max() < 1e-4 * HEIGHT * UNITS[units][0]  # the start kept, not the fallen frame


@pytest.mark.parametrize("units", list(UNITS))
@pytest.mark.parametrize("at", ["corner", "middle"])
def test_a_portal_on_pinned_feet_pushed_across_its_plane_collapses(tmp_path, units, at):
    result, out = run(tmp_path, portal(units, at=at))
    assert_collapsed_at_the_start(result, out, units)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_verdict_holds_from_starts_moved_by_round_off(tmp_path, seed):
    shift = 1e-9 * HEIGHT * np.random.default_rng(seed).uniform(-1.0, 1.0, (5, 3))
    result, out = run(tmp_path, portal(shift=shift))
    assert_collapsed_at_the_start(result, out, "SI")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pushed_in_its_plane_with_gj_it_stands_neutral(tmp_path, seed):
    """With GJ the same push is carried in the plane; the portal still turns freely
    about the line through its feet (its columns' tension and compression give that
    mode nothing): converged, "stable" (no negative stiffness), with a warning that the
    equilibrium is neutral, from every start."""
    rng = np.random.default_rng(seed)
    shift = None if seed == 0 else 1e-9 * HEIGHT * rng.uniform(-1.0, 1.0, (5, 3))
    path = tmp_path / "gj.toml"
    case = portal(at="left", shift=shift, push=(1e3, 0.0, 0.0))
    path.write_bytes(tomli_w.dumps(case).encode())
    out = tmp_path / "gj.h5"
    result = CliRunner().invoke(main, ["run", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "the equilibrium is neutral" in result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        sway = f["result/x"][2] - f["mesh/nodes"][2]
    assert 0.0 < sway[0] < 0.05 * HEIGHT


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_without_gj_pushed_in_its_plane_it_collapses_from_every_start(tmp_path, seed):
    """Without GJ the same push compresses the beam, which turns about the pushed
    column's axis like a pinned strut: the path in the plane is unstable at any load.
    From the exact start Newton stays in the plane and its tangent says so (rule 2);
    from starts moved by 1e-9 it stepped round that state onto one where the frame
    leans 0.4 m out of its plane with a neutral tangent, and ended converged. Rule 6
    (its compressed members push it along its zero modes) makes both a collapse at load
    factor 0, the start kept."""
    rng = np.random.default_rng(seed)
    shift = None if seed == 0 else 1e-9 * HEIGHT * rng.uniform(-1.0, 1.0, (5, 3))
    case = portal(at="left", shift=shift, push=(1e3, 0.0, 0.0), gj=False)
    result, out = run(tmp_path, case)
    assert result.exit_code == 1, result.output
    assert "collapses beyond load factor 0:" in result.output, result.output
    if seed:
        assert "its compressed members push its nodes" in result.output, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "collapsed"
        moved = np.linalg.norm(f["result/x"][:] - f["mesh/nodes"][:], axis=1)
    assert moved.max() < 1e-4 * HEIGHT


def test_a_bilateral_rope_hung_off_the_vertical_swings_to_it(tmp_path):
    """A bilateral steel rope (10 m, 20 edges) between supports 10 mm off the vertical,
    given straight at its rest length: its weight moves it across its chord (along its
    zero modes, 1.6e-3 of its length) as far as rule 6's threshold, but its tension holds
    that move: converged, stable, the horizontal reactions equal and opposite."""
    case = {
        "title": "a rope hung off the vertical",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [0.01, 0, 10], "nodes": 21},
        "material": {"E": 2.1e11, "radius": 0.005, "density": 7850.0, "tension_only": False},
        "load": {"gravity": [0.0, 0.0, -9.81]},
    }
    result, out = run(tmp_path, case)
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        reaction = f["result/reaction"][[0, 20]]
        across = f["result/x"][10, 0] - f["mesh/nodes"][10, 0]
    assert reaction[0, 0] == pytest.approx(-reaction[1, 0], rel=1e-6)
    assert 1e-3 < across < 1e-2  # it moved across its chord, toward the lower support


def test_the_verdict_of_a_large_system_is_the_same(tmp_path, monkeypatch):
    """Above 900 free DOFs the tangent's verdict comes from the inertia of two shifted
    factorisations, not from the eigenvalues: the same collapse (here forced for the
    portal's 117 free DOFs)."""
    import catenet.solver.tangent as tangent

    monkeypatch.setattr(tangent, "DENSE", 10)
    result, out = run(tmp_path, portal())
    assert_collapsed_at_the_start(result, out, "SI")


def test_a_cut_back_path_is_judged_through_its_sub_steps(monkeypatch):
    """Newton given too few iterations for the swing: the load step fails, is cut back,
    and the frame reaches the fallen state by the ladder's rungs; the path they took is
    judged, not only the last sub-step (which starts where the frame has fallen)."""
    import catenet.solver.loadsteps as loadsteps
    from catenet.case import build, parse_case
    from catenet.solver.stability import CollapseError

    cut_back = loadsteps._cut_back
    trails: list = []

    def watched(*args):
        trails.append(args[-1])
        return cut_back(*args)

    monkeypatch.setattr(loadsteps, "_cut_back", watched)
    from catenet.solver.workspace import Workspace

    scene = build(parse_case(portal()))
    ws = Workspace(scene.net, terms=scene.terms)
    with pytest.raises(CollapseError, match=MECHANISM) as caught:
        loadsteps.continuation(scene.net, scene.loads, [1.0], max_iter=30, workspace=ws)
    assert trails and trails[0], "the load step was not cut back"
    moved = np.linalg.norm(caught.value.last_good.x - scene.net.nodes, axis=1)
    assert moved.max() < 1e-4 * HEIGHT


def test_clamped_feet_hold_the_portal(tmp_path):
    result, out = run(tmp_path, portal(feet="clamped"))
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        sway = f["result/x"][3] - f["mesh/nodes"][3]
    assert 0.0 < sway[1] < 0.1 * HEIGHT  # it sways along the push, a little


def test_a_bilateral_cable_given_straight_sags_from_its_neutral_start(tmp_path):
    """Two bilateral neo-Hookean edges of rest length 1 m on a 2 m chord, pulled down at
    their joint by P = 2 N sin(t), N = EA (s - s^-2) / 3 at the stretch s = 1 / cos(t),
    t = 60 degrees: the first load step turns
    them by 60 degrees from a start without transverse stiffness, but halved it turns
    them less and less (at 1/64 of the load by 17 degrees): a sag, not a mechanism. It
    ends there, every edge in tension, stable."""
    ea = 1e5
    t = np.radians(60.0)
    stretch = 1.0 / np.cos(t)
    load = 2.0 * ea * (stretch - stretch**-2) / 3.0 * np.sin(t)
    case = {
        "title": "a rubber rope pulled down",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            "edges": [[0, 1], [1, 2]],
            "fixed": [0, 2],
        },
        "material": {"EA": ea, "tension_only": False, "law": "neo_hookean"},
        "load": {"point": [{"node": 1, "force": [0.0, 0.0, -load]}]},
    }
    result, out = run(tmp_path, case)
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        sag = -f["result/x"][1, 2]
    assert sag == pytest.approx(np.tan(t), rel=1e-6)


def test_a_step_that_cannot_be_unloaded_is_no_collapse(tmp_path):
    """A bilateral steel cable (10 m, 20 edges, EA 1e7 N) given straight at its rest
    length sags under its weight; with solver.max_iter = 5 its load steps are cut back,
    and the solves that unload a step to test it do not converge in 5 iterations either:
    no way back found says nothing of the path (it was called a snap-through). It
    converges, stable, to the sag it has with the default budget."""
    case = {
        "title": "a bilateral cable sagging",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [10, 0, 0], "nodes": 21},
        "material": {"EA": 1e7, "area": 3.1416e-4, "density": 7850.0, "tension_only": False},
        "load": {"gravity": [0.0, 0.0, -9.81]},
    }
    sags = []
    for budget in ("200", "5"):
        result, out = run(tmp_path, case, f"cable{budget}", "--set", f"solver.max_iter={budget}")
        assert result.exit_code == 0, result.output
        with h5py.File(out, "r") as f:
            assert str(f["result"].attrs["stability"]) == "stable"
            sags.append(-float(f["result/x"][10, 2]))
    assert sags[1] == pytest.approx(sags[0], rel=1e-6)


def test_a_step_that_fails_after_its_sub_steps_fell_is_a_collapse(monkeypatch):
    """The portal pushed across its plane, its load step failing above load factor 0.7
    however it is cut back (Newton made to fail there): the sub-steps found below it
    swung the frame flat, and they are judged before the failure is said, so the run
    is the collapse they show, not a failure to converge."""
    import catenet.solver.loadsteps as loadsteps
    from catenet.case import build, parse_case
    from catenet.errors import ConvergenceError
    from catenet.solver.stability import CollapseError
    from catenet.solver.workspace import Workspace

    solve = loadsteps.solve_static

    def failing_above(*args, **kwargs):
        if kwargs.get("factor", 1.0) > 0.7:
            raise ConvergenceError("static equilibrium: no convergence in 200 iterations")
        return solve(*args, **kwargs)

    monkeypatch.setattr(loadsteps, "solve_static", failing_above)
    monkeypatch.setattr(loadsteps, "can_relax", lambda *args: False)
    scene = build(parse_case(portal()))
    ws = Workspace(scene.net, terms=scene.terms)
    with pytest.raises(CollapseError, match=MECHANISM) as caught:
        loadsteps.continuation(scene.net, scene.loads, [1.0], workspace=ws)
    moved = np.linalg.norm(caught.value.last_good.x - scene.net.nodes, axis=1)
    assert moved.max() < 1e-4 * HEIGHT


@pytest.mark.parametrize("roller, push", [(True, "z"), (False, "z"), (False, "y")])
def test_a_failure_from_a_neutral_equilibrium_says_to_hold_its_mode(roller, push):
    """Newton out of iterations after the cut-back ladder, from the last equilibrium: an
    L-frame on a clamped foot without GJ, whose beam turns freely about its column
    unless a roller holds its tip across the plane. Held, the advice is the iteration
    budget; free, the last equilibrium is neutral, which no budget mends (2000
    iterations did not): the advice names the mode's nodes and how to hold them, and
    says that the loads drive that mode where they push the tip across the plane."""
    from catenet.case import build, parse_case
    from catenet.errors import ConvergenceError, LastGood
    from catenet.solver.loadsteps import _advice
    from catenet.solver.stability import PathJudge
    from catenet.solver.workspace import Workspace

    case = {
        "title": "an L-frame",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, HEIGHT], [2.0, 0.0, HEIGHT]],
            "edge_length": 0.25,
            "cable": [{"name": "column", "nodes": [0, 1]}, {"name": "beam", "nodes": [1, 2]}],
        },
        "material": {"E": 2.1e11, "radius": 0.05, "inner_radius": 0.045, "EI": "section"},
        "supports": {"fixed": [0], "clamped": [0], "rigid_joints": [1]},
        "load": {"point": [{"node": 2, "force": [0.0, 100.0 * (push == "y"), -100.0]}]},
    }
    if roller:
        case["supports"]["roller"] = [{"nodes": [2], "normal": [0.0, 1.0, 0.0]}]
    scene = build(parse_case(case))
    judge = PathJudge(Workspace(scene.net, terms=scene.terms), scene.loads)
    judge.begin(scene.net.nodes, True)
    failure = ConvergenceError("static equilibrium: no convergence in 200 iterations")
    said = _advice(failure, 200, True, judge, LastGood(scene.net.nodes, 0.0))
    if roller:
        assert said == "most likely to help: a larger solver.max_iter (now 200)"
    else:
        assert said.startswith("the last equilibrium is neutral: its stiffness has a mode")
        assert "along which Newton found no equilibrium further on" in said
        assert ("which the loads drive" in said) == (push == "y"), said
        assert "hold those nodes (a support, bracing, a clamp, a roller)" in said
        assert "(nodes 2, 20, 19" in said  # the tip first, then the beam toward it


@pytest.mark.parametrize("n", [6, 12])
def test_the_zero_modes_of_a_neutral_state_are_all_found(n):
    """Rule 6 reads every zero mode of its step's start (``mechanism.zero_modes``): a flat
    bilateral net at rest, whose nodes all move freely across its plane. Below 300 free
    DOFs the tangent's verdict has them all (the whole eigendecomposition); above, it
    finds the eight least only, and they are computed again whole: the same number
    either way, orthonormal, the stiffness nothing along them."""
    import catenet as cn
    from catenet.solver.mechanism import zero_modes
    from catenet.solver.tangent import POSITIVE, _scale, tangent
    from catenet.solver.workspace import Workspace

    material = cn.Material(EA=1e4, line_density=0.1, tension_only=False)
    net = cn.square_net(n, 0.0, 1.0, 0.1, material).net
    ws = Workspace(net)
    t = tangent(ws.system, ws.solver, net.nodes)
    assert t.verdict == "neutral" and t.zero is not None
    assert t.all_zero == (ws.system.n_free < 300), ws.system.n_free
    modes = zero_modes(ws.system, net.nodes, _scale(ws.system), POSITIVE, None)
    across = int(np.count_nonzero(~net.fixed))  # one across the plane per free node
    assert modes.shape[1] >= across
    if t.all_zero:
        assert t.zero.shape[1] == modes.shape[1]
    assert np.allclose(modes.T @ modes, np.eye(modes.shape[1]), atol=1e-10)
    k = ws.system.matrix(ws.system.hessian(net.nodes).copy()).toarray()
    assert np.abs(k @ modes).max() < 1e-9 * np.abs(k).max()


def guyed_strut(shift: float = 0.0, seed: int = 0) -> dict:
    """A 10 m strut (one edge) on a pinned foot held by three bilateral steel guys (6 mm
    radius, five edges each) to anchors 8 m out, under their weight and 1 kN across at
    its top; ``shift``: every node moved by up to that [m], the rest lengths the exact
    geometry's (given)."""
    top = np.array([0.0, 0.0, 10.0])
    nodes = [[0.0, 0.0, 0.0], top.tolist()]
    cables = []
    for k in range(3):
        a = 2.0 * np.pi * k / 3.0
        anchor = np.array([8.0 * np.cos(a), 8.0 * np.sin(a), 0.0])
        first = len(nodes)
        nodes += [(top + (anchor - top) * j / 5.0).tolist() for j in range(1, 6)]
        ids = [1, *range(first, first + 5)]
        rest = [float(np.linalg.norm(anchor - top)) / 5.0] * 5
        cables.append({"name": f"guy{k}", "nodes": ids, "rest_length": rest})
    moved = np.array(nodes) + shift * np.random.default_rng(seed).uniform(-1, 1, (17, 3))
    return {
        "title": "a strut on bilateral guys",
        "geometry": {
            "kind": "graph",
            "nodes": moved.tolist(),
            "edges": [[0, 1]],
            "rest_length": [10.0],
            "cable": cables,
        },
        "material": {"E": 1.6e11, "radius": 0.006, "density": 7850.0, "tension_only": False},
        "supports": {"fixed": [0, 6, 11, 16]},
        "load": {"gravity": [0.0, 0.0, -9.81], "point": [{"node": 1, "force": [1e3, 0.0, 0.0]}]},
    }


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_strut_on_guys_given_straight_stands_while_they_sag(tmp_path, seed):
    """The guys given straight at their rest length sag under their weight while the
    strut stands on them (their chords stiff: EA / (3 L) against the strut's C / h). From
    that neutral start Newton found the strut mirrored through its pinned foot at every
    load down to 1/64, which rule 5 called a collapse; the step is taken again by the
    net's motion (dynamic relaxation to rest), which stays near, and that is the step's
    end: converged, stable, the top within 2 cm of where it was drawn, the guys sagging
    about 0.19 m. Also from starts moved by 1e-9 of its size with the exact rest lengths
    given (a compression of round-off size: judged as the exact start)."""
    result, out = run(tmp_path, guyed_strut(1e-9 * 12.8 * bool(seed), seed))
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        moved = f["result/x"][:] - f["mesh/nodes"][:]
    assert np.linalg.norm(moved[1]) < 0.02  # the top stays up
    assert 0.1 < np.linalg.norm(moved, axis=1).max() < 0.3  # the guys sag


@pytest.mark.parametrize("steps", [2, 4])
def test_the_strut_on_guys_stands_in_any_number_of_load_steps(tmp_path, steps):
    """The guyed strut above with ``solver.steps``: its first load step (to 1/2 or 1/4
    of the loads) drove the mirrored state as the single step did, and was a collapse
    ("the structure is a mechanism under these loads") because only a step to the full
    loads was taken again by the motion. Now every step is, at its own load factor: the
    same equilibrium as in one step (to 1e-6 m), stable."""
    one, out_one = run(tmp_path, guyed_strut(), "one")
    case = guyed_strut()
    case["solver"] = {"steps": steps}
    result, out = run(tmp_path, case)
    assert one.exit_code == 0 and result.exit_code == 0, result.output
    with h5py.File(out, "r") as f, h5py.File(out_one, "r") as g:
        assert str(f["result"].attrs["stability"]) == "stable"
        assert np.abs(f["result/x"][:] - g["result/x"][:]).max() < 1e-6


def test_a_mechanism_still_collapses_in_several_load_steps(tmp_path):
    """The inverted pendulum below in four load steps: the motion's rest at the first
    step's load hangs it upside down too, so the collapse stands, at load factor 0."""
    case = {
        "title": "an inverted pendulum",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]],
            "edges": [[0, 1]],
            "rest_length": [3.0],
            "fixed": [0],
        },
        "material": {"E": 1.6e11, "radius": 0.01, "density": 7850.0, "tension_only": False},
        "load": {"point": [{"node": 1, "force": [1.0, 0.0, -1e3]}]},
        "solver": {"steps": 4},
    }
    result, out = run(tmp_path, case)
    assert result.exit_code == 1, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "collapsed"
        assert f["result"].attrs["time"] == 0.0  # the load factor of the last stable state


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pinned_strut_pushed_down_collapses_from_a_start_at_round_off(tmp_path, seed):
    """One bilateral edge upright on a pinned foot, 1 kN down on its top: an inverted
    pendulum. Given at its rest length with its nodes moved by 1e-9 (a compression of
    round-off size), its start was called unstable but a guess, the path ended hanging
    upside down in tension, and the run said converged: a guessed start's path that turns
    an edge over (beyond 135 degrees) folded, it did not sag. A collapse at load factor 0
    from every start, as from the exact geometry (the strut turns 180 degrees at any
    load)."""
    shift = 3e-9 * np.random.default_rng(seed).uniform(-1.0, 1.0, (2, 3)) * bool(seed)
    case = {
        "title": "an inverted pendulum",
        "geometry": {
            "kind": "graph",
            "nodes": (np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]]) + shift).tolist(),
            "edges": [[0, 1]],
            "rest_length": [3.0],
            "fixed": [0],
        },
        "material": {"E": 1.6e11, "radius": 0.01, "tension_only": False},
        "load": {"point": [{"node": 1, "force": [0.0, 0.0, -1e3]}]},
    }
    result, out = run(tmp_path, case)
    assert result.exit_code == 1, result.output
    assert "the load path collapses beyond load factor 0:" in result.output, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "collapsed"


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 20240607])
def test_a_portal_loaded_down_collapses_when_its_unloaded_start_drifts(seed):
    """The portal on pinned feet with GJ, 2 kN down at its beam's middle: an inverted
    pendulum about the line through its feet (docs/howto/rods.md). Its nodes moved by
    1e-9 of its size after the scene is built (as the round-off pass moves them), the
    given geometry is no equilibrium at load factor 0, and Newton's unloaded solve from
    it drifted 160 degrees along the frame's free turn (round-off called that turn's
    stiffness, 1.1e-13 of the scale, stable); judged from there the path ended hanging
    upside down, "converged" (from other starts that solve failed, and the first step
    went unjudged). A drift along the given geometry's modes softer than 1e-9 is now no
    start, nor is a failed unloaded solve: the path is judged from the given geometry and fails, a
    collapse at load factor 0 (or, from some starts, a failure whose last equilibrium
    is the neutral start: exit 1 either way, never "converged"). From seed 4 the path
    ended hanging, "converged", "stable": the first step's Newton end drove the turn
    (a collapse), and the motion's rest, the same hanging state, was judged again after
    the judge's cache of the last two states had lost the start's neutral verdict (its
    round-off eigenvalue, -2e-5 of the scale: "unstable", which that rule does not
    judge); the start's verdict is now kept apart."""
    import catenet
    from catenet.case import build, parse_case
    from catenet.errors import ConvergenceError
    from catenet.solver.stability import CollapseError

    case = {
        "title": "a portal on pinned feet, loaded down",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [4.0, 0.0, 3.0], [4.0, 0.0, 0.0]],
            "edge_length": 0.25,
            "sets": {"feet": [0, 3], "corners": [1, 2]},
            "cable": [
                {"name": "left", "nodes": [0, 1]},
                {"name": "beam", "nodes": [1, 2]},
                {"name": "right", "nodes": [2, 3]},
            ],
        },
        "material": {
            "E": 2.1e11, "radius": 0.05, "inner_radius": 0.045, "density": 7850.0,
            "EI": "section", "G": 8.1e10, "GJ": "section",
        },
        "supports": {"fixed": ["feet"], "rigid_joints": ["corners"]},
        "load": {"point": [{"cable": "beam", "at": 0.5, "force": [0.0, 0.0, -2000.0]}]},
    }  # fmt: skip
    scene = build(parse_case(case))
    nodes = scene.net.nodes
    size = float(np.max(np.ptp(nodes, axis=0)))
    nodes += 1e-9 * size * np.random.default_rng(seed).uniform(-1.0, 1.0, nodes.shape)
    with pytest.raises(ConvergenceError) as failed:
        catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    if isinstance(failed.value, CollapseError):
        assert failed.value.factor == 0.0
