"""The pieces of the dynamic solver's time stepping, one by one: the step control
(halving after a failure down to the smallest step, growing back after good steps, times
on the grid of the smallest step) and the rest test of dynamic relaxation."""

from __future__ import annotations

import numpy as np
import pytest

import catenet as cn
from catenet.solver.dynamic import GROW_AFTER, MAX_CUTS, StepControl, at_rest
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


def test_the_rest_test_asks_for_equilibrium_and_no_inertial_force():
    """At a static equilibrium with no velocity the run is at rest (ratio <= 1); the same
    state moving, or a state off the equilibrium, is not (ratio > 1)."""
    net = cn.cable([0, 0, 0], [1, 0, 0], 11, cn.Material(EA=1e3, line_density=0.5), length=1.05)
    loads = cn.Loads(gravity=[0.0, 0.0, -9.81])
    rtol = 1e-8
    eq = solve_static(net, loads, rtol=1e-12).x
    ws = Workspace(net)
    potential = ws.potential(loads)
    system = ws.system
    m_free = np.repeat(net.mass[~net.fixed], 3)
    still = np.zeros_like(eq)
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
