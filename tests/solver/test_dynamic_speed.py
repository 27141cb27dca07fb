"""Dynamic performance without changing the answer: an obstacle out of reach keeps the
Cholesky factorisation (PARDISO switches to symmetric indefinite only while a non-convex
contact term acts), a kept factorisation's later solves skip the backward-error check its
first solve passed, and ``solver.reuse`` switches modified Newton on from a case."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import catenet as cn
from catenet.case import load_case
from catenet.cli import main
from catenet.errors import SingularSystemError
from catenet.output import read_mesh
from catenet.run.runner import run_case
from catenet.solver.dynamic import solve_dynamic
from catenet.solver.linear import make_solver, pardiso_available
from catenet.solver.static import Workspace
from catenet.terms.contact import SphereBarrier
from tests.conftest import small_net

needs_pardiso = pytest.mark.skipif(not pardiso_available(), reason="MKL PARDISO not available")
SAME = 1e-8  # relative to the largest displacement


def paper_net(n=10, pressure=100.0, gravity=False):
    mat = cn.Material.from_E(10e6, radius=0.01, density=1000.0)
    net = cn.square_net(n, 0.3, 1.0, 0.05, mat).net
    g = np.array([0.0, 0.0, -9.81]) if gravity else None
    return net, cn.Loads(force=cn.pressure_force(net, pressure, 1.0), gravity=g)


def difference(a, b, x0) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a - x0)))


def kinds_seen(ws):
    """Records the PARDISO matrix type of every factorisation of the workspace's solver."""
    seen = []
    solver = ws.solver
    original = solver._factorize

    def spy(data):
        seen.append(solver.kind)
        return original(data)

    solver._factorize = spy
    return seen


@needs_pardiso
def test_an_obstacle_out_of_reach_keeps_cholesky_and_changes_nothing():
    net, loads = paper_net()
    far = SphereBarrier(np.flatnonzero(~net.fixed), [0.0, 0.0, -5.0], 0.5, kappa=1.0, dhat=1e-2)
    kw = {"dt": 1e-2, "damping": 1.0, "t_end": 0.3, "stop_at_equilibrium": False}
    # PARDISO named: its handles are what this is about (below catenet.solver.banded's
    # size, "auto" takes the band for a definite matrix)
    with_ws = Workspace(net, terms=(far,), linear="pardiso")
    without_ws = Workspace(net, linear="pardiso")
    assert with_ws.solver.mtype == -2 and without_ws.solver.mtype == 2  # the sphere is not convex
    seen = kinds_seen(with_ws)
    a = solve_dynamic(net, loads, workspace=with_ws, **kw)
    b = solve_dynamic(net, loads, workspace=without_ws, **kw)
    assert seen and set(seen) == {2}  # never out of reach: every factorisation Cholesky
    assert with_ws.solver.stats["analyse"] == 1  # the indefinite handle was never set up
    assert a.stats.factorize_count == b.stats.factorize_count
    assert difference(a.x, b.x, net.nodes) < 1e-12
    assert with_ws.solver.negative_eigenvalues() == 0  # Cholesky succeeded: definite
    assert with_ws.solver.inertia == (with_ws.system.n_free, 0)


@needs_pardiso
def test_a_net_reaching_a_sphere_switches_to_the_indefinite_factorisation():
    """Falling onto a sphere: Cholesky while out of reach, symmetric indefinite while in
    contact; the same path as a solver that is indefinite throughout (SciPy's LU here)."""
    net, loads = paper_net(pressure=300.0, gravity=True)
    free = np.flatnonzero(~net.fixed)
    kw = {"dt": 1e-2, "damping": 5.0, "t_end": 0.5, "stop_at_equilibrium": False}
    paths = {}
    for linear in ("pardiso", "scipy"):
        ball = SphereBarrier(free, [0.0, 0.0, -0.23], 0.2, kappa=2e3, dhat=0.01)
        ws = Workspace(net, terms=(ball,), linear=linear)
        seen = kinds_seen(ws) if linear == "pardiso" else []
        steps = []
        r = solve_dynamic(
            net, loads, workspace=ws, on_step=lambda k, t, x, v, s=steps: s.append(x.copy()), **kw
        )
        paths[linear] = (r, steps, seen, ws, ball)
    (a, xa, seen, ws, ball), (b, xb, _, _, _) = paths["pardiso"], paths["scipy"]
    assert ball.gap(a.x).min() < ball.dhat  # it touched
    assert seen[0] == 2 and -2 in seen  # Cholesky before the contact, indefinite in it
    assert ws.solver.stats["analyse"] == 2  # one symbolic analysis per handle, kept
    assert len(xa) == len(xb) == a.steps == b.steps == 50
    assert max(difference(x, y, net.nodes) for x, y in zip(xa, xb, strict=True)) < SAME
    ws.solver.release()  # both handles freed; releasing again is harmless
    assert not ws.solver._analysed and not any(h[1] for h in ws.solver._handles.values())
    ws.solver.release()


@needs_pardiso
def test_negative_eigenvalues_come_from_the_indefinite_handle_when_it_is_used():
    # [[2, 0], [0, -1]] (upper triangle): indefinite, one negative eigenvalue.
    indptr, indices = np.array([0, 1, 2]), np.array([0, 1])
    solver = make_solver("pardiso", indptr, indices, upper=True, dof_node=np.zeros(2, int))
    solver.factorize(np.array([2.0, -1.0]))
    assert solver.kind == -2 and solver.negative_eigenvalues() == 1
    np.testing.assert_allclose(solver.solve(np.array([2.0, 1.0])), [1.0, -1.0])
    solver.factorize(np.array([2.0, 1.0]), definite=True)
    assert solver.kind == 2 and solver.negative_eigenvalues() == 0
    np.testing.assert_allclose(solver.solve(np.array([2.0, 1.0])), [1.0, 1.0])
    with pytest.raises(SingularSystemError):  # a caller's wrong promise fails, never lies
        solver.factorize(np.array([2.0, -1.0]), definite=True)
    solver.release()


@pytest.mark.parametrize("linear", ["scipy", pytest.param("pardiso", marks=needs_pardiso)])
def test_only_the_first_solve_of_a_factorisation_checks_its_backward_error(linear, monkeypatch):
    indptr, indices = np.array([0, 2, 3]), np.array([0, 1, 1])  # [[4, 1], [1, 3]]
    solver = make_solver(linear, indptr, indices, upper=True, dof_node=np.zeros(2, int))
    checks = []
    original = solver._check
    monkeypatch.setattr(solver, "_check", lambda b, x: (checks.append(1), original(b, x)))
    solver.factorize(np.array([4.0, 1.0, 3.0]))
    for b in ([1.0, 2.0], [3.0, -1.0], [0.5, 0.5]):
        x = solver.solve(np.array(b))
        np.testing.assert_allclose([4 * x[0] + x[1], x[0] + 3 * x[1]], b, rtol=1e-12)
    assert len(checks) == 1
    solver.factorize(np.array([4.0, 1.0, 3.0]))  # new factors: checked again
    solver.solve(np.array([1.0, 0.0]))
    assert len(checks) == 2
    # A non-finite result of a later solve is still refused.
    monkeypatch.setattr(solver, "_solve", lambda b: np.array([np.nan, 1.0]))
    with pytest.raises(SingularSystemError, match="non-finite"):
        solver.solve(np.array([1.0, 0.0]))


def test_solver_reuse_key_runs_modified_newton_to_the_same_equilibrium(tmp_path, write_case):
    # rtol 1e-10: at rest within 1e-8 of the load scale, two runs can stop 1e-7 apart.
    base = small_net(every=0).replace('method = "dynamic"', 'method = "dynamic"\nrtol = 1e-10')
    fresh = run_case(load_case(write_case(base, "fresh.toml")), tmp_path / "fresh.h5")
    case = load_case(write_case(base.replace("rtol", "reuse = true\nrtol"), "kept.toml"))
    assert case.solver.reuse is True
    assert "reuse = true" in case.to_toml()  # written when set, left out at its default
    assert "reuse" not in load_case(write_case(base, "again.toml")).to_toml()
    kept = run_case(case, tmp_path / "kept.h5")
    assert fresh.equilibrium and kept.equilibrium
    x0 = read_mesh(tmp_path / "fresh.h5").nodes
    assert difference(kept.x, fresh.x, x0) < SAME
    assert kept.stats.factorize_count < 0.5 * fresh.stats.factorize_count
    assert fresh.stats.factorize_count == fresh.iterations  # off by default
    assert load_case(write_case(small_net(), "default.toml")).solver.reuse is False


def test_solver_reuse_must_be_a_boolean(write_case):
    text = small_net().replace('method = "dynamic"', 'method = "dynamic"\nreuse = "yes"')
    r = CliRunner().invoke(main, ["run", str(write_case(text))])
    assert r.exit_code == 2
    assert "solver.reuse" in r.output


def test_a_kept_factorisation_close_to_the_tolerance_is_kept():
    from catenet.solver.newton import REUSE_AHEAD, _converges_soon

    assert REUSE_AHEAD == 2
    assert _converges_soon(1e-6, 1e-5, 1e-8)  # rate 0.1: 1e-8 after two more steps
    assert not _converges_soon(1e-6, 1e-5, 1e-9)  # would take three
    assert not _converges_soon(1e-6, 1.5e-6, 1.0)  # a rate above 1/2 is never trusted


def test_keeping_a_slower_factorisation_near_the_tolerance_saves_factorisations(monkeypatch):
    import catenet.solver.newton as newton

    net, loads = paper_net(pressure=300.0, gravity=True)
    free = np.flatnonzero(~net.fixed)
    kw = {"dt": 1e-2, "damping": 5.0, "t_end": 0.5, "stop_at_equilibrium": False}
    out = {}
    for ahead in (2, 0):  # 0: refresh whenever a kept step cuts less than REUSE_RATE
        monkeypatch.setattr(newton, "REUSE_AHEAD", ahead)
        ball = SphereBarrier(free, [0.0, 0.0, -0.23], 0.2, kappa=2e3, dhat=0.01)
        ws = Workspace(net, terms=(ball,))
        out[ahead] = solve_dynamic(net, loads, workspace=ws, reuse=True, **kw)
    assert out[2].stats.factorize_count < out[0].stats.factorize_count
    assert difference(out[2].x, out[0].x, net.nodes) < SAME
