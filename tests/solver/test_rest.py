"""Dynamic relaxation to rest (solver.t_end = "rest", catenet/solver/relax.py): the
paper's net relaxed at default settings ends in the static equilibrium; its pseudo-time
steps grow; an undamped run and one that spends its steps fail with a message; a run
with a number for t_end keeps its steps of dt."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import CONFIGS

from catenet.case import build, load_case
from catenet.errors import ConvergenceError
from catenet.solver.path import Settings, solve
from catenet.solver.relax import EASY, GROWTH_CAP, HARD, RestControl

FIG4A = CONFIGS / "fig4a_n10_alpha_0.toml"


def scene_and_settings(*overrides: str):
    case = load_case(FIG4A, ["solver.method=dynamic", *overrides])
    return build(case), Settings.of(case.solver)


def run(*overrides: str):
    """The run's result and the times of its steps."""
    scene, settings = scene_and_settings(*overrides)
    times = []
    result = solve(scene, settings, on_step=lambda step: times.append(step.time))
    return result, np.array(times)


def test_the_paper_net_relaxed_at_default_settings_is_the_static_equilibrium():
    static_case = load_case(FIG4A)
    static = solve(build(static_case), Settings.of(static_case.solver))
    relaxed, times = run()
    assert load_case(FIG4A, ["solver.method=dynamic"]).solver.t_end == "rest"
    assert relaxed.converged and relaxed.equilibrium
    # both to rtol = 1e-8 of the load scale: the same state to far below the 1 cm edges
    assert np.max(np.abs(relaxed.x - static.x)) < 1e-8
    assert np.allclose(
        relaxed.reaction, static.reaction, rtol=0, atol=1e-6 * np.abs(static.reaction).max()
    )
    # pseudo-time: the steps grew from dt, so the times are uneven and increasing
    steps = np.diff(np.concatenate([[0.0], times]))
    assert np.all(steps > 0) and steps[0] == pytest.approx(0.01) and steps.max() > 10 * 0.01
    assert relaxed.steps == len(times) < 100


def test_an_explicit_end_time_keeps_steps_of_dt():
    result, times = run("solver.t_end=0.3")
    assert not result.equilibrium and result.time == 0.3
    assert len(times) == 30
    assert np.allclose(times, 0.01 * np.arange(1, 31), rtol=0, atol=1e-15)  # k dt, rounded once


def test_an_undamped_run_to_rest_fails_at_once_with_the_reason():
    scene, settings = scene_and_settings("solver.t_end='rest'", "solver.damping=0")
    with pytest.raises(
        ConvergenceError, match="an undamped run never rests: give solver.t_end or damping"
    ):
        solve(scene, settings)


def test_a_run_that_spends_its_steps_says_so_and_keeps_its_last_step():
    scene, settings = scene_and_settings("solver.max_steps=3")
    with pytest.raises(ConvergenceError) as info:
        solve(scene, settings)
    message = str(info.value)
    assert "not at rest after solver.max_steps = 3 time steps" in message
    assert "give solver.t_end, more solver.damping or a larger solver.max_steps" in message
    good = info.value.last_good
    assert good.steps == 3 and good.time > 0 and np.all(np.isfinite(good.x))


def test_the_step_doubles_while_newton_is_easy_and_follows_the_residual_otherwise():
    c = RestControl(dt=0.01, t0=0.0, max_cuts=20, max_steps=100)
    assert c.step(0.0) == 0.01 and math.isinf(c.t_end)
    c.settled(1.0, EASY)  # the first: no ratio yet, Newton easy
    assert c.h == 0.02
    c.settled(0.9, EASY + 1)  # residual falling 10 %: grows by its ratio only
    assert c.h == pytest.approx(0.02 / 0.9)
    c.settled(1.8, EASY + 1)  # residual doubled: held
    assert c.h == pytest.approx(0.02 / 0.9)
    c.settled(0.1, HARD + 1)  # Newton worked hard: halved
    assert c.h == pytest.approx(0.01 / 0.9)
    c.settled(0.1, HARD + 1)  # ... but not below dt
    assert c.h == 0.01
    for _ in range(40):  # easy steps: up to the cap
        c.settled(1e-3, 1)
    assert c.h == 0.01 * GROWTH_CAP
    c.settled(1e-3, HARD + 1)
    assert c.h == 0.005 * GROWTH_CAP
    assert c.failed(c.h) and c.h == 0.0025 * GROWTH_CAP and math.isnan(c.previous)
    assert c.advance(1.0, 0.25) == 1.25
