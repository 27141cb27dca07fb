"""Stability verdicts that do not hang on round-off (``catenet.solver.stability``).

A generated corpus of models that collapse, in three unit systems, from zero to large
loads: every one ends at a stable equilibrium (exit 0, /result stability "stable") or
exits 1 with a collapse verdict that names the nodes; never exit 0 on a folded state.

- Chains of k = 2..8 pinned bilateral struts stacked into a 30 m mast, guyed at the top
  only, the struts precompressed by the guys' prestress: the joints have negative lateral
  stiffness -N/l, so the given geometry is unstable and any load folds it.
- A shallow three-bar truss (apex h above a ring of radius R, EA per bar): the apex load
  against its height w is P(w) = 3 EA (h^2 - w^2) w / (2 L0^3) (L0 the bars' length, strain
  (w^2 - h^2) / (2 L0^2), vertical share w / L0); dP/dw = 0 at w = h / sqrt(3) gives the
  snap-through load P_cr = EA h^3 / (sqrt(3) L0^3). Below it the truss stands; above it
  the path snaps, and the load factor of the collapse brackets P_cr / P.
- A bilateral cable given on its chord with slack: its straight start is compressed and
  unstable, but it sags into the catenary with every edge in tension: stable, exit 0.
- The guyed mast of docs/howto/guyed-mast.md, stable as one strut edge; with its strut in
  5 m edges it collapses (exit 1) and, with solver.post_collapse, it is followed through
  and labelled post-collapse; its load cases are never reported from a collapsed base.

Every test here is marked ``roundoff``: `make test` runs them again with every node moved
by 1e-12 of the net's size and two threads (tests/conftest.py), and they must pass the
same.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from catenet.cli import main

pytestmark = pytest.mark.roundoff

ROOT = Path(__file__).resolve().parents[2]
MAST = ROOT / "configs" / "structures" / "guyed_mast.toml"

# unit systems: (length factor, force factor): SI, kN-m, N-mm
UNITS = {"SI": (1.0, 1.0), "kN-m": (1.0, 1e-3), "N-mm": (1e3, 1.0)}


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write(tmp_path, case: dict, name: str = "case") -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    return path


def stability(path) -> str:
    with h5py.File(path, "r") as f:
        return str(f["result"].attrs["stability"])


def chain(k: int, load: float, units: str = "SI") -> dict:
    """k pinned struts (EA 1e9 N) stacked into a 30 m mast, three guys (EA 1e7 N,
    prestress 1e4 N) from its top to anchors 20 m away; the struts carry the guys'
    vertical components as prestress; a horizontal load at the top."""
    m, n = UNITS[units]
    height = 30.0
    nodes = [[0.0, 0.0, height * i / k * m] for i in range(k + 1)]
    anchors = [[20.0, 0.0, 0.0], [-10.0, 17.320508, 0.0], [-10.0, -17.320508, 0.0]]
    nodes += [[a * m for a in p] for p in anchors]
    guy = math.hypot(20.0, height)
    compression = 3 * 1e4 * height / guy
    return {
        "title": f"chain of {k} struts",
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": nodes,
            "edges": [[i, i + 1] for i in range(k)] + [[k, k + 1], [k, k + 2], [k, k + 3]],
            "fixed": [0, k + 1, k + 2, k + 3],
            "EA": [1e9 * n] * k + [1e7 * n] * 3,
            "tension_only": [False] * k + [True] * 3,
            "prestress": [-compression * n] * k + [1e4 * n] * 3,
        },
        "material": {"EA": 1e7 * n},
        "load": {"point": [{"node": k, "force": [load * n, 0.0, 0.0]}]},
    }


H, R, EA = 0.5, 10.0, 1e6  # the shallow truss: apex height, ring radius, EA [m, m, N]
L0 = math.hypot(H, R)
P_CR = EA * H**3 / (math.sqrt(3.0) * L0**3)  # its snap-through load [N]


def truss(load: float, units: str = "SI") -> dict:
    m, n = UNITS[units]
    turns = (0.0, 2 * math.pi / 3, 4 * math.pi / 3)
    ring = [[R * math.cos(a), R * math.sin(a), 0.0] for a in turns]
    return {
        "title": "shallow three-bar truss",
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": [[c * m for c in p] for p in [[0.0, 0.0, H], *ring]],
            "edges": [[0, 1], [0, 2], [0, 3]],
            "fixed": [1, 2, 3],
        },
        "material": {"EA": EA * n, "tension_only": False},
        "load": {"point": [{"node": 0, "force": [0.0, 0.0, -load * n]}]},
    }


@pytest.mark.parametrize("units", list(UNITS))
@pytest.mark.parametrize("k", [2, 3, 5, 8])
def test_a_chain_of_struts_never_ends_converged(tmp_path, k, units):
    for load in (0.0, 100.0, 5e3):
        out = tmp_path / f"chain{k}_{load:g}.h5"
        r = invoke("run", write(tmp_path, chain(k, load, units)), "-o", out, "-q")
        assert r.exit_code == 1, r.output
        joints = ", ".join(str(i) for i in range(1, min(k, 11)))
        assert f"nodes {joints}" in r.output, r.output
        if load == 0.0:  # no load: the given geometry is an unstable equilibrium
            assert "unstable" in r.output and stability(out) == "unstable"
        else:  # loaded: the path collapses at once, whatever Newton would reach
            assert "collapses beyond load factor 0:" in r.output, r.output
            assert stability(out) == "collapsed"
            with h5py.File(out, "r") as f:  # the start is kept, not a folded state
                assert not f["result"].attrs["converged"]
                top = f["result/x"][k] - f["mesh/nodes"][k]
                assert np.linalg.norm(top) < 1e-6 * UNITS[units][0]


@pytest.mark.parametrize("units", list(UNITS))
def test_a_shallow_truss_stands_below_its_snap_through_load_and_collapses_above(tmp_path, units):
    below = tmp_path / "below.h5"
    r = invoke("run", write(tmp_path, truss(0.8 * P_CR, units)), "-o", below, "-q")
    assert r.exit_code == 0, r.output
    assert stability(below) == "stable"
    with h5py.File(below, "r") as f:  # still above the ring: w > h / sqrt(3)
        assert f["result/x"][0, 2] > H / math.sqrt(3.0) * UNITS[units][0]
    above = tmp_path / "above.h5"
    load = 1.5 * P_CR
    r = invoke("run", write(tmp_path, truss(load, units)), "-o", above, "-q")
    assert r.exit_code == 1, r.output
    assert "limit point" in r.output and "nodes 0" in r.output
    assert stability(above) == "collapsed"
    with h5py.File(above, "r") as f:
        factor = float(f["result"].attrs["time"])
        assert f["result/x"][0, 2] > 0.0  # the last stable state: not snapped
    # the collapse is bracketed by the halved steps: within 1/2**6 of the load
    assert factor <= P_CR / load <= factor + 1.0 / 64 + 1e-12


def test_a_bilateral_cable_given_slack_on_its_chord_sags_and_is_stable(tmp_path):
    case = {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, 0.0],
            "end": [10.0, 0.0, 0.0],
            "length": 12.0,
            "nodes": 21,
        },
        "material": {"EA": 1e6, "density": 7850.0, "radius": 0.005, "tension_only": False},
        "load": {"gravity": [0.0, 0.0, -9.81]},
    }
    out = tmp_path / "cable.h5"
    r = invoke("run", write(tmp_path, case), "-o", out, "-q")
    assert r.exit_code == 0, r.output
    assert stability(out) == "stable"
    with h5py.File(out, "r") as f:
        assert np.all(f["result/tension"][()] > 0.0)


def test_the_guyed_mast_stands_and_its_split_strut_collapses(tmp_path):
    whole = tmp_path / "whole.h5"
    assert invoke("run", MAST, "-o", whole, "-q").exit_code == 0
    assert stability(whole) == "stable"
    split = tmp_path / "split.h5"
    r = invoke("run", MAST, "-o", split, "--set", "geometry.cable.0.edge_length=5")
    assert r.exit_code == 1, r.output
    assert "converged    yes" not in r.output
    assert "collapses beyond load factor 0" in r.output and "nodes 6, 7, 8" in r.output
    assert stability(split) == "collapsed"
    followed = tmp_path / "followed.h5"
    r = invoke(
        "run",
        MAST,
        "-o",
        followed,
        "--set",
        "geometry.cable.0.edge_length=5",
        "--set",
        "solver.post_collapse=true",
    )
    assert r.exit_code == 0, r.output
    assert "post-collapse" in r.output
    assert stability(followed) == "post-collapse"


def test_an_unloaded_unstable_mast_never_prints_converged_yes(tmp_path):
    out = tmp_path / "zero.h5"
    r = invoke(
        "run",
        MAST,
        "-o",
        out,
        "--set",
        "geometry.cable.0.edge_length=5",
        "--set",
        "load.point.0.force=[0, 0, 0]",
    )
    assert r.exit_code == 1, r.output
    assert "an unstable equilibrium" in r.output and "nodes 6, 7, 8" in r.output
    assert "converged    yes" not in r.output
    assert stability(out) == "unstable"


def test_no_load_case_of_a_collapsed_mast_is_reported(tmp_path):
    cases = ROOT / "configs" / "structures" / "mast_load_cases.toml"
    text = cases.read_text()
    out = tmp_path / "cases.h5"
    r = invoke("run", cases, "-o", out, "--set", "geometry.cable.0.edge_length=5")
    assert r.exit_code == 1, r.output
    assert "converged    yes" not in r.output
    with h5py.File(out, "r") as f:
        assert "cases" not in f
        assert not f["result"].attrs["converged"]
    assert "edge_length" in text  # the --set above splits the strut the case gives


def test_the_verdict_of_small_and_large_systems_agrees(monkeypatch):
    """The dense eigenvalues (small systems) and the factorisation's inertia with the
    margin's shifts (large ones) give the same verdicts."""
    import catenet.solver.tangent as st
    from catenet.case import build, parse_case
    from catenet.solver.workspace import Workspace

    for model, verdict in ((chain(3, 0.0), st.UNSTABLE), (truss(0.0), st.STABLE)):
        scene = build(parse_case(json.loads(json.dumps(model))))
        ws = Workspace(scene.net)
        x = scene.net.nodes.copy()
        dense = st.tangent(ws.system, ws.solver, x).verdict
        monkeypatch.setattr(st, "DENSE", 0)
        sparse = st.tangent(ws.system, ws.solver, x).verdict
        monkeypatch.setattr(st, "DENSE", 900)
        assert dense == verdict
        if getattr(ws.solver, "mtype", None) == -2:
            assert sparse == verdict


def strut_net(split: bool, load: float, units: str = "SI") -> dict:
    """Two prestressed cables (EA 1e6 N, 1 kN) crossing at a centre 2 m up, the centre held
    up by a bilateral strut (EA 1e8 N) from the ground: one edge, or two with a free joint
    between them (nothing holds the joint sideways); a load down on the centre."""
    m, n = UNITS[units]
    nodes = [[0, 0, 2], [-2, 0, 2], [2, 0, 2], [0, -2, 2], [0, 2, 2], [0, 0, 0]]
    edges = [[0, 1], [0, 2], [0, 3], [0, 4]]
    strut = [[5, 6], [6, 0]] if split else [[5, 0]]
    if split:
        nodes.append([0, 0, 1])
    return {
        "title": "net on a strut",
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": [[c * m for c in p] for p in nodes],
            "edges": edges + strut,
            "fixed": [1, 2, 3, 4, 5],
            "EA": [1e6 * n] * 4 + [1e8 * n] * len(strut),
            "tension_only": [True] * 4 + [False] * len(strut),
            "prestress": [1e3 * n] * 4 + [-1.0 * n] * len(strut),
        },
        "material": {"EA": 1e6 * n},
        "load": {"point": [{"node": 0, "force": [0.0, 0.0, -load * n]}]},
    }


@pytest.mark.parametrize("units", list(UNITS))
def test_a_net_held_up_by_a_strut_stands_on_one_edge_and_folds_on_two(tmp_path, units):
    for load in (0.0, 100.0, 1e4):
        out = tmp_path / "one.h5"
        r = invoke("run", write(tmp_path, strut_net(False, load, units)), "-o", out, "-q")
        assert r.exit_code == 0, r.output
        assert stability(out) == "stable"
        out = tmp_path / "two.h5"
        r = invoke("run", write(tmp_path, strut_net(True, load, units)), "-o", out, "-q")
        assert r.exit_code == 1, r.output
        assert "nodes 6" in r.output
        assert stability(out) == ("unstable" if load == 0.0 else "collapsed")


def slack_guys(load: float) -> dict:
    """A 20 m one-edge mast (EA 1e6 N) held by three guys (EA 1e7 N, 100 N of prestress)
    to anchors 10 m out, a vertical load on its top. The top's vertical stiffness is the
    mast's 5e4 N/m and the guys' 1.07e6 N/m; the guys stretch 2.2e-4 m under their
    prestress and lose it when the top has dropped by 2.5e-4 m: at about 280 N. Then
    nothing holds the top sideways: the mast stands straight but unstable."""
    anchors = [[10.0, 0.0, 0.0], [-5.0, 8.660254, 0.0], [-5.0, -8.660254, 0.0]]
    guy = math.hypot(10.0, 20.0)
    return {
        "title": "mast whose guys go slack",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, 20.0], *anchors],
            "edges": [[0, 1], [1, 2], [1, 3], [1, 4]],
            "fixed": [0, 2, 3, 4],
            "EA": [1e6, 1e7, 1e7, 1e7],
            "tension_only": [False, True, True, True],
            "prestress": [-3 * 100.0 * 20.0 / guy, 100.0, 100.0, 100.0],
        },
        "material": {"EA": 1e7},
        "load": {"point": [{"node": 1, "force": [0.0, 0.0, -load]}]},
    }


def test_a_mast_whose_guys_go_slack_collapses_where_they_do(tmp_path):
    out = tmp_path / "mast.h5"
    r = invoke("run", write(tmp_path, slack_guys(100.0)), "-o", out, "-q")
    assert r.exit_code == 0, r.output
    assert stability(out) == "stable"
    r = invoke("run", write(tmp_path, slack_guys(1e4)), "-o", out, "-q")
    assert r.exit_code == 1, r.output
    assert "is unstable" in r.output and "nodes 1" in r.output
    assert stability(out) == "collapsed"
    with h5py.File(out, "r") as f:  # the last stable state: bracketed below ~280 N
        factor = float(f["result"].attrs["time"])
    assert 150.0 <= factor * 1e4 <= 280.0


def test_a_failed_post_collapse_resolve_keeps_the_last_equilibrium(monkeypatch):
    """The guyed mast in two load steps, followed through (solver.post_collapse): the
    second step is made to collapse (``_follow`` says so) and Newton from the bracket's end
    is made to fail; the error carries the first step's equilibrium at load factor 0.5
    (continuation's callers write it; without it they fell back to the start)."""
    import catenet.solver.loadsteps as loadsteps
    from catenet.case import build, load_case
    from catenet.errors import ConvergenceError
    from catenet.solver.path import Settings
    from catenet.solver.workspace import Workspace

    case = load_case(MAST, ["solver.post_collapse=true"])
    scene = build(case)
    real_static, real_follow = loadsteps.solve_static, loadsteps._follow
    first = []

    def failing_resolve(*args, relaxed=False, **kwargs):
        if relaxed:
            raise ConvergenceError("no convergence in 200 iterations (made to fail)")
        r = real_static(*args, relaxed=relaxed, **kwargs)
        first.append(r.x.copy())
        return r

    def collapsing(judge, net, loads, x0, f0, f1, r, last, settings, depth):
        if f1 < 1.0:
            return real_follow(judge, net, loads, x0, f0, f1, r, last, settings, depth)
        return "made to collapse", f0, x0, r

    monkeypatch.setattr(loadsteps, "solve_static", failing_resolve)
    monkeypatch.setattr(loadsteps, "_follow", collapsing)
    settings = Settings.of(case.solver)
    ws = Workspace(scene.net, terms=scene.terms)
    with pytest.raises(ConvergenceError, match="made to fail") as failed:
        loadsteps.continuation(
            scene.net, scene.loads, [0.5, 1.0], rtol=settings.rtol, workspace=ws, post_collapse=True
        )
    good = failed.value.last_good
    assert good is not None and good.time == 0.5, good
    assert np.array_equal(good.x, first[0])


def test_a_mechanism_is_said_once(tmp_path, caplog):
    """Three pinned struts in a row between two supports, the first joint pushed along
    them: a mechanism, which the load path's many solves (its step, the halved steps that
    judge it: 7 of them) each find unstable. It is said once, by the collapse's error: no
    warning on the way, none repeated; a path that ends unstable (the unloaded chain of
    ``chain``) says so once, at its end, and the command's error after it."""
    import catenet as cn
    from catenet.solver.loadsteps import continuation
    from catenet.solver.stability import CollapseError

    net = cn.Net.from_arrays(
        [[x, 0.0, 0.0] for x in (0.0, 1.0, 2.0, 3.0)],
        [[0, 1], [1, 2], [2, 3]],
        EA=1e6,
        fixed=[0, 3],
        tension_only=False,
    )
    force = np.zeros((4, 3))
    force[1, 0] = 1000.0
    with caplog.at_level("WARNING", logger="catenet"), pytest.raises(CollapseError):
        continuation(net, cn.Loads(force=force), [1.0])
    assert "unstable" not in caplog.text, caplog.text
    # unloaded, the given geometry is the unstable end of the path: said once there
    r = invoke("run", write(tmp_path, chain(3, 0.0), "chain"), "-o", tmp_path / "c.h5")
    assert r.exit_code == 1 and r.output.count("negative eigenvalues") == 1, r.output


@pytest.mark.parametrize("units", list(UNITS))
def test_a_rod_beyond_its_euler_load_is_no_mechanism(tmp_path, units):
    """A pinned rod (EI = 1 N m^2, L = 1 m) precompressed by P: below its Euler load
    pi^2 EI / L^2 = 9.87 N it stands; beyond it (20 N) the equilibrium is unstable, and
    the message says the load exceeds a buckling load of the structure as modelled (the
    load factor reached), never that the rod needs the bending stiffness it has. Without
    EI, the same strut is a mechanism, and adding EI is the advice."""
    m, n = UNITS[units]

    def rod(prestress: float, EI: float) -> dict:
        return {
            "title": "a pinned rod",
            "units": units,
            "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [m, 0, 0], "nodes": 11},
            "material": {
                "EA": 1e5 * n,
                "EI": EI * n * m * m,
                "prestress": prestress * n,
                "tension_only": False,
            },
        }

    r = invoke("run", write(tmp_path, rod(-5.0, 1.0)), "-o", tmp_path / "a.h5", "-q")
    assert r.exit_code == 0, r.output
    r = invoke("run", write(tmp_path, rod(-20.0, 1.0)), "-o", tmp_path / "b.h5", "-q")
    assert r.exit_code == 1, r.output
    assert "exceed a buckling (limit) load of the structure as modelled (at load factor 1)" in (
        r.output
    )
    assert "mechanism" not in r.output and "give it bending stiffness" not in r.output
    r = invoke("run", write(tmp_path, rod(-20.0, 0.0)), "-o", tmp_path / "c.h5", "-q")
    assert r.exit_code == 1, r.output
    assert "a mechanism" in r.output and "give it bending stiffness (material.EI" in r.output


def test_a_strut_loaded_on_a_slider_beyond_its_euler_load_is_said_to_buckle(tmp_path):
    """A pinned rod (EI = 1 N m^2, L = 1 m) pushed along its axis at a slider end by
    1.05 x pi^2 EI / L^2: the load path collapses as a rod beyond its buckling load, not
    as a mechanism to be made of one edge (the slider's end moves with the bow, and the
    message took it for a pinned strut's node)."""
    case = {
        "title": "a strut on a slider",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 21},
        "material": {"EA": 1e5, "EI": 1.0, "tension_only": False},
        "supports": {
            "fixed": ["start"],
            "slider": [{"nodes": "end", "direction": [1, 0, 0]}],
        },
        "load": {"point": [{"node": "end", "force": [-1.05 * math.pi**2, 0, 0]}]},
    }
    r = invoke("run", write(tmp_path, case), "-o", tmp_path / "s.h5", "-q")
    assert r.exit_code == 1, r.output
    assert "exceed a buckling (limit) load of the structure as modelled" in r.output
    assert "make a strut one edge" not in r.output
