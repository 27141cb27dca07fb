"""The static ladder's last rung, dynamic relaxation to rest (``rung.relax_to_rest``).

The untuned corpus's wire mooring line, seed 6 (756 m in 397 m of water, EA 1.2e8 N,
about 195 N/m submerged; the corpus writes it with 50-400 nodes), refined to 2000 edges:
every stage of the static continuation ladder fails on it (the smoothed tension-only law
at mu / 10 oscillates between two states, and the stages after it start from there; the
load-step cut-back and the damped pseudo-transient solve fail the same way), while
dynamic relaxation to rest follows the line's motion to its equilibrium. A line given
slack (longer than its chord) is relaxed right after its first failure
(``rung.hangs_slack``): smaller load steps cannot help it. That last rung
is checked here against the elastic catenary with seabed (``seabed_catenary``): fairlead
and horizontal tension to 1e-4, the touchdown within one edge, as
tests/validate/test_seabed_catenary.py holds the chain of the issue. docs/validation.md
gives the history.
"""

from __future__ import annotations

import math

import corpus
import numpy as np
import pytest

import catenet.solver.dynamic as dynamic
import catenet.solver.loadsteps as loadsteps
import catenet.solver.rung as rung
from catenet.case import build, parse_case
from catenet.errors import ConvergenceError
from catenet.solver.path import Settings, solve
from catenet.validate.seabed import seabed_catenary


def mooring(seed: int, edges: int | None = None) -> dict:
    """The corpus's mooring line ``seed`` (tables), with ``edges`` edges if given."""
    case = corpus.generate(seed, "mooring")["case"]
    if edges is not None:
        case["geometry"]["nodes"] = edges + 1
    return case


def closed_form_errors(tables: dict, r, scene) -> tuple[float, float, float, float]:
    """(relative error of the fairlead tension and of H, touchdown error over an edge,
    the edge) of catenet's result ``r`` against ``seabed_catenary`` of the same line,
    in the case's own units (the closed form does not care)."""
    g, m = tables["geometry"], tables["material"]
    L, EA = g["length"], m["EA"]
    w = m["density"] * m["area"] * -tables["load"]["gravity"][2]
    X, h = g["end"][0] - g["start"][0], g["end"][2] - g["start"][2]
    exact = seabed_catenary(L, EA, w, X, h)
    net = scene.net
    fixed = np.flatnonzero(net.fixed)
    fair = fixed[np.argmax(r.x[fixed, 2])]
    T = float(np.linalg.norm(r.reaction[fair]))
    H = float(math.hypot(*r.reaction[fair, :2]))
    (bed,) = [t for t in scene.terms if type(t).__name__ == "PlaneBarrier"]
    on_bed = bed.nodes[bed.gap(r.x) < bed.dhat]
    free_on_bed = on_bed[~net.fixed[on_bed]]
    x_TD = float(np.max(r.x[free_on_bed, 0])) if free_on_bed.size else 0.0
    edges = len(net.rest_length)
    edge = L / edges * (1.0 + exact.H / EA)
    return (
        T / exact.fairlead_tension - 1.0,
        H / exact.H - 1.0,
        (x_TD - exact.x_TD) / edge,
        edge,
    )


def run(tables: dict, **solver):
    tables = {**tables, "solver": solver} if solver else tables
    case = parse_case(tables)
    scene = build(case)
    return solve(scene, Settings.of(case.solver)), scene


@pytest.mark.slow  # about 15 s: the first rung fails, then the line is relaxed
def test_the_refined_wire_line_converges_at_default_settings_to_the_closed_form():
    tables = mooring(6, 2000)
    r, scene = run(tables)
    assert r.converged and r.equilibrium, r.message
    dT, dH, dx, edge = closed_form_errors(tables, r, scene)
    text = f"T {dT:+.2e}, H {dH:+.2e}, touchdown {dx:+.2f} edges of {edge:.3f} m"
    assert abs(dT) < 1e-4 and abs(dH) < 1e-4 and abs(dx) <= 1.0, text


def test_the_corpus_line_is_solved_by_the_first_rung_to_the_closed_form():
    """At the corpus's own refinement (390 nodes) Newton's first rung converges, so the
    last one is never reached: the same closed form, H to the discretisation's error
    (lumped weights, second order in the edge: 2.4e-4 at 389 edges of 1.9 m, as the
    100-edge chain of test_seabed_catenary.py is 4.3e-4 off; the refined line above
    holds 1e-4)."""
    tables = mooring(6)
    r, scene = run(tables)
    assert r.converged and r.equilibrium
    dT, dH, dx, _ = closed_form_errors(tables, r, scene)
    assert abs(dT) < 1e-4 and abs(dH) < 3e-4 and abs(dx) <= 1.0, (dT, dH, dx)


def _failing_unless_relaxed(monkeypatch):
    """Every static solve of the ladder fails except Newton from the rest state (the
    rung's polish), so that a small line reaches the last rung at once."""
    real = loadsteps.solve_static
    calls = []

    def static(*args, relaxed=False, **kwargs):
        calls.append(relaxed)
        if not relaxed:
            raise ConvergenceError("no convergence in 200 iterations (made to fail)")
        return real(*args, relaxed=True, **kwargs)

    monkeypatch.setattr(loadsteps, "solve_static", static)
    monkeypatch.setattr(rung, "solve_static", static)  # the rung's polish
    return calls


def taut(tables: dict, share: float = 0.98) -> dict:
    """The line given taut: its length ``share`` of the chord (no longer slack)."""
    g = dict(tables["geometry"])
    g["length"] = share * math.dist(g["start"], g["end"])
    return {**tables, "geometry": g}


@pytest.mark.parametrize(
    "given, tries",
    [
        # a slack line from its slack start: the failed step is relaxed at once
        ("slack", 1 + 1),
        # a taut one: first, cut-backs, pseudo-time, rest
        ("taut", 1 + loadsteps.CUTBACKS + 1 + 1),
    ],
)
def test_the_last_rung_finds_the_first_rungs_equilibrium(monkeypatch, given, tries):
    """Where every other rung fails, dynamic relaxation to rest and Newton from there
    reach the equilibrium Newton finds directly: the same state to 1e-7 of the line. A
    line given slack (longer than its chord) is relaxed right after its first failure:
    its equilibrium hangs far from the start at any load, so smaller load steps are not
    tried first; a line given taut goes down the whole ladder."""
    tables = mooring(6, 200) if given == "slack" else taut(mooring(6, 200))
    direct, _ = run(tables)
    calls = _failing_unless_relaxed(monkeypatch)
    r, _ = run(tables)
    assert calls[-1] is True and calls.count(True) == 1
    assert len(calls) == tries
    assert r.converged and r.equilibrium
    assert r.iterations > direct.iterations
    length = tables["geometry"]["length"]
    assert np.max(np.abs(r.x - direct.x)) < 1e-7 * length
    scale = np.abs(direct.reaction).max()
    assert np.allclose(r.reaction, direct.reaction, rtol=0.0, atol=1e-6 * scale)


def test_the_last_rung_says_it_was_tried_when_it_fails(monkeypatch):
    """When the relaxation fails too (it never comes to rest), the message lists it among
    what was tried, and the last good state is the start at load factor 0."""
    _failing_unless_relaxed(monkeypatch)

    def restless(*args, **kwargs):
        raise ConvergenceError("no rest within solver.max_steps = 20000 time steps")

    monkeypatch.setattr(dynamic, "solve_dynamic", restless)
    with pytest.raises(ConvergenceError, match="dynamic relaxation to rest") as failed:
        run(mooring(6, 200))
    assert "pseudo-transient" in str(failed.value)
    assert failed.value.last_good.time == 0.0


def test_an_interrupted_last_rung_keeps_the_last_equilibrium(monkeypatch):
    """Two load steps: the first converges at load factor 0.5, every static solve of the
    second fails, and its last rung (dynamic relaxation) is interrupted: the run's last
    good state is the first step's equilibrium at 0.5, not the relaxation's motion (a
    state at a pseudo-time, no equilibrium) nor the start."""
    from catenet.errors import Interrupted

    real = loadsteps.solve_static
    solved = []

    def static(*args, relaxed=False, **kwargs):
        if not solved:
            solved.append(real(*args, relaxed=relaxed, **kwargs))
            return solved[0]
        raise ConvergenceError("no convergence in 200 iterations (made to fail)")

    def interrupted(net, loads, **kwargs):
        moved = kwargs["x0"] + 0.1  # somewhere on the way to rest
        raise Interrupted("interrupted at t = 0.37 s", iterations=7, state=moved)

    monkeypatch.setattr(loadsteps, "solve_static", static)
    monkeypatch.setattr(dynamic, "solve_dynamic", interrupted)
    with pytest.raises(Interrupted) as stopped:
        run(mooring(6, 200), steps=2)
    good = stopped.value.last_good
    assert good.time == 0.5 and np.array_equal(good.x, solved[0].x)


@pytest.mark.parametrize("max_iter", [1, 24])
def test_a_newton_budget_below_a_time_steps_is_respected(monkeypatch, max_iter):
    """A ``solver.max_iter`` below the 25 iterations a time step may take: the last rung
    is not tried (it would not keep the budget), the run fails as before."""
    calls = _failing_unless_relaxed(monkeypatch)
    with pytest.raises(ConvergenceError) as failed:
        run(mooring(6, 200), max_iter=max_iter)
    assert "and dynamic relaxation to rest" not in str(failed.value) and True not in calls
    assert "pseudo-transient" in str(failed.value)


def test_the_rung_takes_the_loads_as_a_static_run_does():
    """Dynamic relaxation as a static rung sees every load and support displacement at its
    full value from its first step: histories (of gravity, of a support's motion) and
    ramps are a dynamic run's, which a static run ignores."""
    from catenet.case import load_case
    from tests.conftest import CONFIGS

    case = load_case(CONFIGS / "friction" / "mooring_pulled.toml")
    scene = build(case)
    tables = mooring(6, 50)
    tables["load"]["history"] = [[0.0, 0.0], [5.0, 1.0]]
    line = build(parse_case(tables))
    for net, loads in ((scene.net, scene.loads), (line.net, line.loads)):
        assert loads.varies or loads.support_history
        held = rung.held(loads)
        assert not (held.varies or held.support_history) and held.ramp_time is None
        static = loads.external_force(net)
        for t in (0.0, 1.0, 7.0):
            assert np.array_equal(held.external_force(net, time=t), static)
            assert np.array_equal(held.support_positions(net, time=t), loads.support_positions(net))


@pytest.mark.parametrize("jitter", [0.0, 1e-12])
def test_slack_is_decided_with_a_margin_over_round_off(jitter):
    """A cable given at its rest length (a flat, unstressed start) is not slack, whatever
    1e-12 m of round-off its nodes carry; one given 1 % longer than its chord is, with the
    same jitter, and only from the unloaded start."""
    from catenet.errors import LastGood

    rng = np.random.default_rng(5)
    for length, slack in ((None, False), (1.01, True)):
        g = {"kind": "cable", "start": [0, 0, 0], "end": [10, 0, 0], "nodes": 21}
        if length is not None:
            g["length"] = 10.0 * length
        material = {"EA": 1e6, "area": 1e-4, "density": 7850.0}
        case = {"geometry": g, "material": material, "load": {"gravity": [0, 0, -9.81]}}
        net = build(parse_case(case)).net
        x = net.nodes + jitter * rng.standard_normal(net.nodes.shape)
        assert rung.hangs_slack(net, LastGood(x, 0.0)) is slack
        assert rung.hangs_slack(net, LastGood(x, 0.5)) is False
