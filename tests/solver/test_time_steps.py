"""The pieces of the dynamic solver's time stepping, one by one: the step control
(halving after a failure down to the smallest step, growing back after good steps, times
on the grid of the smallest step), the rest test of dynamic relaxation and the time
stepper (a step's predictor, its Newton solve, the retry with fresh factorisations)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import catenet as cn
from catenet.solver.dynamic import (
    ALLOWANCE,
    FAIL_ALLOWANCE,
    GROW_AFTER,
    MAX_CUTS,
    SLOWDOWN,
    StepControl,
    TimeStepper,
    at_rest,
    solve_dynamic,
)
from catenet.solver.integrators import make
from catenet.solver.static import solve_static
from catenet.solver.workspace import Workspace


def test_a_failed_step_is_halved_down_to_the_smallest_step():
    control = StepControl(0.1, 0.0, 10.0)
    assert control.step(0.0) == 0.1
    h = control.step(0.0)
    for cut in range(1, MAX_CUTS + 1):
        assert control.failed(h)  # dt / 2**cut: still a step
        h = control.step(0.0)
        assert h == 0.1 / 2**cut
    assert not control.failed(h)  # dt / 2**(MAX_CUTS + 1): the run fails
    assert control.h == 0.1 / 2 ** (MAX_CUTS + 1)


def test_the_tries_of_a_run_are_bounded():
    """A run may try SLOWDOWN times the steps dt plans plus ALLOWANCE (accepted and failed
    alike), of which half the planned steps plus FAIL_ALLOWANCE may fail; beyond either,
    ``spent`` ends it, and the message says how far it came and why."""
    control = StepControl(0.01, 0.3, 0.5)  # 20 steps planned
    assert control.planned == 20
    assert control.budget == SLOWDOWN * 20 + ALLOWANCE
    assert control.fail_budget == 10 + FAIL_ALLOWANCE >= MAX_CUTS + 1  # a start to the floor
    h = control.step(0.3)
    while True:  # a step that fails and four that pass, over and over
        control.failed(h)
        if control.spent():
            break
        h = control.step(0.3)
        for _ in range(4):
            control.accepted()
    assert control.fails == control.fail_budget + 1 and control.tries < control.budget
    message = control.spent_message(0.31)
    assert "t = 0.31 s of solver.t_end = 0.5 s" in message
    assert f"{control.tries} steps tried ({control.fails} failed)" in message
    assert "solver.dt = 0.01 s plans 20" in message

    control = StepControl(0.01, 0.3, 0.5)
    for _ in range(control.budget):  # every step passes, yet short ones: no end of tries
        control.accepted()
    assert not control.spent()
    control.accepted()
    assert control.spent() and control.fails == 0
    assert StepControl(0.01, 0.0, 0.0301).planned == 4  # a last short step counts


def test_a_shortened_step_grows_back_to_dt_after_good_steps():
    control = StepControl(0.1, 0.0, 10.0)
    control.failed(0.1)
    control.failed(0.05)
    assert control.h == 0.025
    for _ in range(GROW_AFTER - 1):
        control.accepted()
    assert control.h == 0.025  # not yet
    control.accepted()
    assert control.h == 0.05
    for _ in range(GROW_AFTER - 1):
        control.accepted()
    control.failed(control.step(0.0))  # a failure starts the count again
    assert control.h == 0.025
    for _ in range(3 * GROW_AFTER):
        control.accepted()
    assert control.h == 0.1  # never above dt


def test_times_stay_on_the_grid_and_the_last_step_ends_at_t_end():
    """A thousand steps of 0.01 from 0.3 end at 0.3 + 10 within one rounding (a sum of
    steps would drift by about 1e-13); the step before t_end is cut short to reach it."""
    control = StepControl(0.01, 0.3, 10.305)
    t = 0.3
    for _ in range(1000):
        t = control.advance(t, control.step(t))
    assert t == pytest.approx(10.3, rel=1e-15, abs=0.0)
    assert control.step(t) == pytest.approx(0.005, rel=1e-12)
    assert control.advance(t, control.step(t)) == 10.305


def _at_equilibrium(rtol):
    """The sagging cable solved statically to ``rtol``: its net, equilibrium, system,
    potential, free masses (per DOF) and a zero velocity."""
    net, loads = _sagging_cable()
    eq = solve_static(net, loads, rtol=rtol).x
    ws = Workspace(net)
    return (
        net,
        eq,
        ws.system,
        ws.potential(loads),
        np.repeat(net.mass[~net.fixed], 3),
        np.zeros_like(eq),
    )


def test_the_rest_test_asks_for_equilibrium_and_no_inertial_force():
    """At a static equilibrium with no velocity the run is at rest (ratio <= 1); the same
    state moving, or a state off the equilibrium, is not (ratio > 1)."""
    rtol = 1e-8
    net, eq, system, potential, m_free, still = _at_equilibrium(1e-12)
    rest, residual, ratio = at_rest(system, potential, eq, still, m_free, 0.01, rtol)
    assert rest and ratio <= 1.0 and residual <= rtol * potential.f_norm
    moving = still.copy()
    moving[~net.fixed, 2] = 1e-3
    rest, _, ratio = at_rest(system, potential, eq, moving, m_free, 0.01, rtol)
    assert not rest and ratio > 1.0
    off = eq.copy()
    off[~net.fixed, 2] += 1e-4
    rest, residual, ratio = at_rest(system, potential, off, still, m_free, 0.01, rtol)
    assert not rest and ratio > 1.0 and residual > rtol * potential.f_norm


def test_a_state_at_the_round_off_floor_of_its_forces_is_at_rest_if_nothing_moves():
    """A tolerance below what double precision resolves (a long, stiff chain's rtol times
    its load scale can be): the static residual is held to its round-off floor DOF by DOF
    instead, as in a static solve; the inertial force still to rtol, so a state that
    moves is not at rest however small its residual."""
    net, eq, system, potential, m_free, still = _at_equilibrium(1e-13)
    rtol = 1e-20  # rtol * scale: far below the round-off of these forces
    rest, residual, ratio = at_rest(system, potential, eq, still, m_free, 0.01, rtol)
    assert residual > rtol * potential.f_norm
    assert rest and ratio <= 1.0
    creeping = still.copy()  # a velocity of 1e-12 m/s: its inertial force above rtol
    creeping[~net.fixed, 2] = 1e-12
    rest, _, ratio = at_rest(system, potential, eq, creeping, m_free, 0.01, rtol)
    assert not rest and ratio > 1.0
    off = eq.copy()  # 1e-9 m off the equilibrium: forces far above their round-off
    off[~net.fixed, 2] += 1e-9
    rest, _, ratio = at_rest(system, potential, off, still, m_free, 0.01, rtol)
    assert not rest and ratio > 1.0


def _sagging_cable(move=None):
    """A cable under gravity; ``move``: its far end's displacement over 1 s."""
    net = cn.cable([0, 0, 0], [1, 0, 0], 11, cn.Material(EA=1e3, line_density=0.5), length=1.05)
    if move is None:
        return net, cn.Loads(gravity=[0.0, 0.0, -9.81])
    d = np.zeros_like(net.nodes)
    d[-1] = move
    ramp = np.where(net.fixed, 1.0, 0.0)
    return net, cn.Loads(gravity=[0.0, 0.0, -9.81], support_displacement=d, ramp_time=ramp)


def _stepper(net, loads, *, integrator="implicit_euler", reuse=False):
    ws = Workspace(net)
    return TimeStepper(
        net, loads, ws, make(integrator, 0.8), 1.0, rtol=1e-8, max_iter=25, reuse=reuse
    )


@pytest.mark.parametrize("integrator", ["implicit_euler", "newmark"])
def test_stepping_by_hand_repeats_solve_dynamic_exactly(integrator):
    """begin, then solve_step and accept step by step: the states solve_dynamic reports,
    bit for bit, with the moving support carrying the net along."""
    net, loads = _sagging_cable(move=[0.0, 0.0, 0.2])
    seen = []
    solve_dynamic(
        net,
        loads,
        dt=0.01,
        damping=1.0,
        t_end=0.05,
        integrator=integrator,
        rho_inf=0.8,
        on_step=lambda k, t, x, v: seen.append((t, x.copy(), v.copy())),
    )
    stepper = _stepper(net, loads, integrator=integrator)
    stepper.begin(None, None, 0.0, None, None)
    control = StepControl(0.01, 0.0, 0.05)
    for t, x, v in seen:
        h = control.step(stepper.t)
        newton, why = stepper.solve_step(h)
        assert newton is not None and newton.converged, why
        stepper.accept(control, h, newton)
        assert stepper.t == t
        assert np.array_equal(stepper.x, x) and np.array_equal(stepper.v, v)
    assert stepper.steps == 5 and stepper.iterations > 0


def test_the_predictor_puts_the_supports_at_t_plus_h_and_carries_the_net():
    """With a support moving, the predictor has it at its place at t + h and moves the
    free nodes next to it with it (more than the far ones)."""
    net, loads = _sagging_cable(move=[0.0, 0.0, 0.5])
    stepper = _stepper(net, loads)
    stepper.begin(None, None, 0.0, None, None)
    x_trial = stepper.predict(0.1)
    assert np.array_equal(x_trial[net.fixed], loads.support_positions(net, time=0.1))
    lift = x_trial[:, 2] - net.nodes[:, 2]
    assert lift[-2] > lift[1] > 0.0  # the free nodes follow, the nearest most


def test_a_failed_step_is_retried_fresh_only_with_a_kept_factorisation_and_once():
    net, loads = _sagging_cable()
    plain = _stepper(net, loads)
    plain.begin(None, None, 0.0, None, None)
    assert not plain.refresh(0.01, "forced")  # nothing kept: the step is cut instead
    kept = _stepper(net, loads, reuse=True)
    kept.begin(None, None, 0.0, None, None)
    assert kept.refresh(0.01, "forced") and kept.fresh  # once more with fresh ones
    assert not kept.refresh(0.01, "forced") and not kept.fresh  # then cut


def test_a_step_cut_below_the_smallest_step_fails_with_the_last_state():
    net, loads = _sagging_cable()
    stepper = _stepper(net, loads)
    stepper.begin(None, None, 0.0, None, None)
    control = StepControl(0.01, 0.0, 1.0)
    stepper.cut(control, 0.01, "forced", None)  # halved: still a step
    assert control.h == 0.005
    with pytest.raises(cn.ConvergenceError, match="failed even with h") as info:
        stepper.cut(control, 0.01 / 2**MAX_CUTS, "forced", None)
    assert np.array_equal(info.value.state, stepper.x)


def test_a_run_whose_accurate_steps_are_spent_says_which_step_failed(monkeypatch):
    """Steps chosen by accuracy whose tries run out on a step beyond the tolerance: the
    message ends on that step, its length and its error (it ended "...; the last failed
    step", the sentence cut)."""
    from catenet.case import build, parse_case
    from catenet.errors import ConvergenceError
    from catenet.solver import adaptive
    from catenet.solver.path import Settings, solve

    monkeypatch.setattr(adaptive, "MAX_TRIES", 3)
    monkeypatch.setattr(adaptive, "ALLOWANCE", 0)
    case = parse_case({
        "geometry": {"kind": "graph", "nodes": [[0, 0, 0], [1.0, 0, 0]], "edges": [[0, 1]],
                     "fixed": [0]},
        "material": {"EA": 1e4, "area": 1e-4, "density": 1e4},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "dynamic", "t_end": 2.0, "tolerance": 1e-6, "damping": 0.0},
    })  # fmt: skip
    with pytest.raises(ConvergenceError) as caught:
        solve(build(case), Settings.of(case.solver))
    message = str(caught.value)
    assert "would not finish in reasonable time" in message
    assert re.search(
        r"the last failed step: [0-9.e+-]+ s, its error [0-9.e+-]+ times the "
        r"tolerance$",
        message,
    ), message
