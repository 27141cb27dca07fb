"""Modified Newton: the factorisation kept across iterations and time steps gives the same
equilibrium as a fresh one per iteration, with fewer factorisations; a time step that
fails with a kept factorisation is retried with fresh ones before its step is halved."""

from __future__ import annotations

import numpy as np
import pytest

import catenet as cn
import catenet.solver.stepper as stepper
from catenet.solver.dynamic import solve_dynamic
from catenet.solver.newton import NewtonResult, Reuse, solve_newton
from catenet.solver.static import Workspace, solve_static
from catenet.terms.contact import SphereBarrier

SAME = 1e-8  # relative to the largest displacement


def paper_net(n=10, edge=0.05, pressure=100.0):
    mat = cn.Material.from_E(10e6, radius=0.01, density=1000.0)
    net = cn.square_net(n, 0.3, 1.0, edge, mat).net
    return net, cn.Loads(force=cn.pressure_force(net, pressure, 1.0))


def falling_on_a_sphere():
    net, _ = paper_net()
    loads = cn.Loads(force=cn.pressure_force(net, 300.0, 1.0), gravity=np.array([0, 0, -9.81]))
    ball = SphereBarrier(np.flatnonzero(~net.fixed), [0.0, 0.0, -0.23], 0.2, kappa=2e3, dhat=0.01)
    return net, loads, ball


def difference(a, b, x0) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a - x0)))


def run(net, loads, reuse, terms=(), **kw):
    ws = Workspace(net, terms=terms)
    r = solve_dynamic(net, loads, workspace=ws, reuse=reuse, **kw)
    return r, ws.solver.stats["factorize"]


def test_dynamic_relaxation_reaches_the_same_equilibrium_with_fewer_factorisations():
    net, loads = paper_net()
    # rtol 1e-10: at rest within 1e-8 of the load scale, two runs can stop 1e-7 apart
    # (both as far from the static equilibrium); tighter, they agree to 1e-8 and better.
    kw = {"dt": 1e-2, "damping": 1.0, "t_end": 40.0, "rtol": 1e-10}
    kept, n_kept = run(net, loads, True, **kw)
    fresh, n_fresh = run(net, loads, False, **kw)
    assert kept.equilibrium and fresh.equilibrium
    assert difference(kept.x, fresh.x, net.nodes) < SAME
    exact = solve_static(net, loads, rtol=1e-12).x
    assert difference(kept.x, exact, net.nodes) < SAME
    assert n_kept < 0.5 * n_fresh
    assert n_fresh == fresh.iterations  # one factorisation per Newton iteration


def test_a_net_falling_on_a_sphere_follows_the_same_path_with_fewer_factorisations():
    net, loads, ball = falling_on_a_sphere()
    kw = {"dt": 1e-2, "damping": 5.0, "t_end": 0.5, "stop_at_equilibrium": False}
    paths = {}
    for reuse in (True, False):
        seen = []
        r, count = run(
            net, loads, reuse, (ball,), on_step=lambda k, t, x, v, s=seen: s.append(x.copy()), **kw
        )
        paths[reuse] = (r, count, seen)
    (kept, n_kept, a), (fresh, n_fresh, b) = paths[True], paths[False]
    assert kept.steps == fresh.steps == len(a) == 50
    assert ball.gap(kept.x).min() < ball.dhat  # it touched
    assert min(ball.gap(x).min() for x in a) > 0.0  # and never entered
    assert max(difference(x, y, net.nodes) for x, y in zip(a, b, strict=True)) < SAME
    assert n_kept < n_fresh


def test_static_newton_with_a_kept_factorisation_finds_the_same_equilibrium():
    net, loads = paper_net()
    exact = solve_static(net, loads).x
    ws = Workspace(net)
    potential = ws.potential(loads)
    rng = np.random.default_rng(1)
    start = exact.copy()
    start[~net.fixed] += rng.normal(0.0, 2e-3, (int(np.count_nonzero(~net.fixed)), 3))
    results = {}
    for reuse in (None, Reuse()):
        x = start.copy()
        r = solve_newton(potential, x, rtol=1e-10, max_iter=200, reuse=reuse)
        assert r.converged
        results[reuse is None] = (x, r)
    (x_fresh, r_fresh), (x_kept, r_kept) = results[True], results[False]
    assert difference(x_kept, x_fresh, net.nodes) < SAME
    assert r_kept.reused > 0 and r_fresh.reused == 0
    # (from a far start Newton's quadratic steps beat kept ones: static runs keep it off)
    # A second solve from the same start keeps the first one's matrix from the outset.
    keep = Reuse()
    x = start.copy()
    solve_newton(potential, x, rtol=1e-10, max_iter=200, reuse=keep)
    x = start.copy()
    again = solve_newton(potential, x, rtol=1e-10, max_iter=200, reuse=keep)
    assert again.converged and again.reused > 0
    assert difference(x, x_fresh, net.nodes) < SAME


def test_a_kept_factorisation_is_dropped_when_another_solve_factorises():
    net, loads = paper_net()
    ws = Workspace(net)
    potential = ws.potential(loads)
    keep = Reuse()
    x = solve_static(net, loads, workspace=ws).x
    potential.factorize(x, 0.0)
    keep.mark(potential, 0.0)
    assert keep.valid(potential, 0.0) and not keep.valid(potential, 1.0)
    potential.factorize(x, 0.0)  # someone else's factorisation on the shared solver
    assert not keep.valid(potential, 0.0)
    keep.mark(potential, 0.0)
    keep.keep(0.01)  # a new key (a new h) drops it
    assert not keep.valid(potential, 0.0)


def _failing(monkeypatch, fail):
    """Wraps the dynamic solver's Newton: ``fail(call, kept)`` makes a call fail."""
    calls = []
    real = stepper.solve_newton

    def wrapped(potential, x, **kw):
        kept = kw.get("reuse") is not None and kw["reuse"].valid(potential, 0.0)
        calls.append(kept)
        if fail(len(calls), kept):
            return NewtonResult(False, 1, 1.0, 0.0, [1.0], "forced failure", 0, int(kept))
        return real(potential, x, **kw)

    monkeypatch.setattr(stepper, "solve_newton", wrapped)
    return calls


def test_a_step_failing_with_a_kept_factorisation_is_retried_fresh_at_the_same_h(monkeypatch):
    net, loads = paper_net()
    failed = []

    def fail(call, kept):
        if kept and not failed:
            failed.append(call)
            return True
        return False

    calls = _failing(monkeypatch, fail)
    times = []
    r = solve_dynamic(
        net, loads, dt=1e-2, damping=1.0, t_end=0.1, stop_at_equilibrium=False, reuse=True,
        on_step=lambda k, t, x, v: times.append(t),
    )  # fmt: skip
    assert failed and r.steps == 10  # no step was halved
    assert np.allclose(np.diff([0.0, *times]), 1e-2)
    assert calls[failed[0]] is False  # the retry had no kept factorisation


def test_a_step_failing_fresh_as_well_is_halved(monkeypatch):
    net, loads = paper_net()
    failed = []

    def fail(call, kept):
        if (kept and not failed) or (len(failed) == 1 and call == failed[0] + 1):
            failed.append(call)
            return True
        return False

    _failing(monkeypatch, fail)
    times = []
    r = solve_dynamic(
        net, loads, dt=1e-2, damping=1.0, t_end=0.1, stop_at_equilibrium=False, reuse=True,
        on_step=lambda k, t, x, v: times.append(t),
    )  # fmt: skip
    assert len(failed) == 2 and r.converged
    assert min(np.diff([0.0, *times])) == pytest.approx(5e-3)  # halved after the fresh retry
