"""The damped step of form finding's targets by conjugate residuals with the factors of D
(catenet/formfind/krylov.py) against the direct saddle-point step and the SVD's: the
rows' system preconditioned (every free node on a surface, under self-weight), unpreconditioned
(positions, tensions and a reaction), the variables' system (per cable); the fallback to
the direct step where the iterations do not converge or the step is not finite, said in
the log and the summary; the direct step at once where the iterations do not pay; and a
search at the operator's size that meets its surface both ways.
"""

from __future__ import annotations

import logging
import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from click.testing import CliRunner
from conftest import CONFIGS
from scenes import hypar_on_surface

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.formfind import krylov
from catenet.formfind.case import formfind_scene


@pytest.fixture(autouse=True)
def iterative_on_small_nets(monkeypatch):
    """The iterative step on these small nets too (by default it starts at
    krylov.FROM_DOFS free DOFs: below, the direct one is faster)."""
    monkeypatch.setattr(krylov, "FROM_DOFS", 0)


MIXED = [
    {"node": "centre", "z": -3.0},
    {"node": 14, "point": [4.0, 2.0, -1.5], "weight": 2.0},
    {"cable": "ring1", "tension": [0.0, 100.0]},
    {"cable": "radial3", "tension": 900.0},
    {"support": 40, "reaction": [100.0, -200.0, 900.0]},
]


LOADS = {
    "": {"gravity": [0, 0, -9.81]},
    "tilted": {"gravity": [2.0, -1.0, -9.5]},  # (the self-weight's frame turned)
    "unweighted": {"point": [{"node": 0, "force": [0, 0, -3e3]}]},
}


def spider(vary: str, load: str = "") -> dict:
    data = tomllib.loads((CONFIGS / "formfind" / "spider.toml").read_text())
    data["geometry"]["file"] = str(CONFIGS / "formfind" / "spider.json")
    data.update(target=MIXED, formfind={"vary": vary}, load=LOADS[load])
    return data


def operator(data: dict, base: Path | None = None, seed: int = 0):
    """The sparse Jacobian of a case's targets at a point near its start, the residual
    there, and J whole (from its products)."""
    from catenet.formfind.adjoint import Adjoint, jacobian_operator
    from catenet.formfind.design import _groups, _Search
    from catenet.formfind.fdm import _Shape
    from catenet.formfind.goals import resolve_goals

    case = parse_case(data, base_dir=base)
    scene = build(case)
    net, loads = scene.net, scene.loads
    force = np.zeros((net.n_nodes, 3)) if loads.force is None else np.array(loads.force)
    shape = _Shape(net, force, loads.gravity, "auto", "q")
    goals = resolve_goals(case.targets, scene, shape.size, 1e-30)
    groups = _groups(scene, case.formfind.vary or "edges", "formfind.")
    n = int(groups.max()) + 1
    rng = np.random.default_rng(seed)
    q0 = float(data["formfind"].get("force_density", 500.0))
    search = _Search(shape, goals, groups, np.log(q0) + 0.1 * rng.standard_normal(n))
    s = 0.1 * rng.standard_normal(n)
    r = search.residual(s)
    q, x, _, a = search.state(s)
    d_x, d_q = search.partials(x, q, a)
    op = jacobian_operator(Adjoint(shape, q, x), d_x, d_q, sp.diags(q) @ search.p)
    whole = np.column_stack([op.matvec(e) for e in np.eye(n)])
    op.search, op.s = search, s  # (for a trial elsewhere)
    return op, r, whole


def svd_step(whole, r, mu, keep):
    """The damped step from J whole: -J^T (J J^T + mu)^-1 r or -(J^T J + mu)^-1 J^T r
    (the smaller), which the SVD's formula is."""
    j = whole[:, keep]
    p = np.zeros(whole.shape[1])
    if j.shape[0] <= j.shape[1]:
        p[keep] = -(j.T @ np.linalg.solve(j @ j.T + mu * np.eye(j.shape[0]), r))
    else:
        p[keep] = -np.linalg.solve(j.T @ j + mu * np.eye(j.shape[1]), j.T @ r)
    return p


def largest(whole) -> float:
    """|J|_2^2 (power iterations on J^T J: the damping's scale)."""
    v = np.ones(whole.shape[1])
    for _ in range(50):
        v = whole.T @ (whole @ v)
        top = float(np.linalg.norm(v))
        v /= top
    return top


def hypar(tmp_path, n: int = 12) -> tuple[dict, Path]:
    data, _ = hypar_on_surface(tmp_path, n)
    return data, tmp_path


@pytest.mark.parametrize(
    "case",
    ["hypar", "spider edges", "spider cables", "spider edges tilted", "spider edges unweighted"],
)
def test_the_iterative_step_is_the_direct_one(case, tmp_path):
    """To eta = 1e-10 the step by conjugate residuals is the direct (saddle-point) step
    and the SVD's within 1e-7 of the step's size, every variable held at a bound kept at
    0: the hypar on its surface under self-weight (rows' system, preconditioned), the
    spider's mixed targets per edge (rows' system, no preconditioner) and per cable (the
    variables' system); gravity off the z axis (the self-weight's system Z in a turned
    frame) and no self-weight (A = I_3 (x) D). The damping is the search's first (1e-6 of
    |J|^2) and 1e-3 of it."""
    if case == "hypar":
        op, r, whole = operator(*hypar(tmp_path))
    else:
        op, r, whole = operator(spider(*case.split()[1:]))
    rows, n = whole.shape
    assert (rows <= n) == (case != "spider cables")
    preconditioned = case == "hypar"
    keep = np.ones(n, dtype=bool)
    keep[::7] = False
    scale = largest(whole)
    for mu in (1e-6 * scale, 1e-3 * scale):
        expected = svd_step(whole, r, mu, keep)
        direct = op.damped(r, mu, keep)
        iterative = op.damped(r, mu, keep, eta=1e-10)
        size = np.abs(expected).max()
        assert np.abs(direct - expected).max() <= 1e-7 * size
        assert np.abs(iterative - expected).max() <= 1e-7 * size
        assert np.all(iterative[~keep] == 0.0)
    steps = op.steps
    assert steps["iterative"] == 2 and steps["fallbacks"] == 0 and steps["iterations"] > 0
    assert (op._rows is not None) == preconditioned


def test_a_step_after_a_refused_trial_refactorises_d_at_its_own_state():
    """A trial shape solved between two steps (a refused one: the shape's solver then
    holds the trial's D): the next iterative step refactorises D at its own state and
    is still the SVD's step."""
    op, r, whole = operator(spider("edges"))
    keep = np.ones(whole.shape[1], dtype=bool)
    mu = 1e-6 * largest(whole)
    first = op.damped(r, mu, keep, eta=1e-10)
    op.search.residual(op.s + 0.5)  # (a trial: D factorised at other force densities)
    again = op.damped(r, 4.0 * mu, keep, eta=1e-10)
    expected = svd_step(whole, r, 4.0 * mu, keep)
    assert np.abs(again - expected).max() <= 1e-7 * np.abs(expected).max()
    assert np.abs(first - again).max() > 0  # (another damping: another step)
    assert op.steps["refactorizations"] == 1 and op.steps["fallbacks"] == 0


@pytest.mark.parametrize("why", ["small net", "no preconditioner"])
def test_where_iterations_do_not_pay_the_direct_step_is_taken_at_once(why, monkeypatch):
    """Fewer free DOFs than krylov.FROM_DOFS, or no preconditioner (the spider's mixed
    rows) on more unknowns than krylov.MAX_ITER: the direct step, no iterations tried."""
    op, r, whole = operator(spider("edges"))
    if why == "small net":
        monkeypatch.setattr(krylov, "FROM_DOFS", 3 * op.adj.nf + 1)
    else:
        monkeypatch.setattr(krylov, "MAX_ITER", min(whole.shape) - 1)
    keep = np.ones(whole.shape[1], dtype=bool)
    mu = 1e-6 * largest(whole)
    step = op.damped(r, mu, keep, eta=1e-10)
    expected = svd_step(whole, r, mu, keep)
    assert np.abs(step - expected).max() <= 1e-7 * np.abs(expected).max()
    assert op.steps["iterative"] == 0 and op.steps["fallbacks"] == 0
    assert op.layout is not None and op.layout.factorizations == 1


@pytest.mark.parametrize("how", ["iterations", "not finite"])
def test_the_direct_step_is_taken_and_said_where_the_iterations_fail(
    how, tmp_path, monkeypatch, caplog
):
    """Conjugate residuals cut to 3 iterations (short of eta = 1e-10), or a solve that
    gives NaN: the step is the direct one, counted as a fallback, and the log says why."""
    op, r, whole = operator(*hypar(tmp_path))
    keep = np.ones(whole.shape[1], dtype=bool)
    mu = 1e-6 * largest(whole)
    if how == "iterations":
        monkeypatch.setattr(krylov, "MAX_ITER", 3)
    else:
        monkeypatch.setattr(krylov.Exact, "solve", lambda self, w: np.full_like(w, np.nan))
    with caplog.at_level(logging.INFO, logger="catenet.formfind.adjoint"):
        step = op.damped(r, mu, keep, eta=1e-10)
    assert np.all(np.isfinite(step))
    expected = svd_step(whole, r, mu, keep)
    assert np.abs(step - expected).max() <= 1e-7 * np.abs(expected).max()
    assert op.steps["fallbacks"] == 1 and op.steps["iterative"] == 0
    said = [m for m in caplog.messages if "iterative damped step failed" in m]
    assert len(said) == 1
    assert ("after 3 iterations" in said[0]) == (how == "iterations")


def test_a_search_by_conjugate_residuals_meets_the_surface_as_the_direct_one(tmp_path, monkeypatch):
    """The hypar of 480 force densities (225 nodes on the surface: the sparse operator)
    by `catenet formfind`: every node on the surface, the summary counting the steps by
    conjugate residuals; the same search with every step direct (the iterations
    refused, the summary says so) meets it too, and the force densities found agree to
    1e-5 (more variables than rows: they are the least-norm steps' path, each iterative
    step solved to 1e-6 of the first misses; measured 3.5e-7)."""
    data, _ = hypar_on_surface(tmp_path, 16)
    case = tmp_path / "roof.toml"
    case.write_text(dumps_toml(data))
    runner = CliRunner()
    r = runner.invoke(main, ["formfind", str(case), "-o", str(tmp_path / "a.h5")])
    assert r.exit_code == 0, r.output
    assert "met:" in r.output and "by conjugate residuals" in r.output and ", 0 direct" in r.output
    first = formfind_scene(build(parse_case(data, base_dir=tmp_path)))
    assert first.design.all_met and first.design.extra["steps"]["fallbacks"] == 0
    monkeypatch.setattr(krylov, "MAX_ITER", 0)
    r = runner.invoke(main, ["formfind", str(case), "-o", str(tmp_path / "b.h5")])
    assert r.exit_code == 0, r.output
    assert "0 by conjugate residuals (0 iterations)" in r.output
    assert "where they did not converge)" in r.output
    direct = formfind_scene(build(parse_case(data, base_dir=tmp_path)))
    steps = direct.design.extra["steps"]
    assert direct.design.all_met and steps["iterative"] == 0 and steps["fallbacks"] > 0
    assert np.abs(np.log(first.q / direct.q)).max() < 1e-5


def _cg(a, b, tol):
    """Textbook conjugate gradients to the relative residual tol: the iterations."""
    x, r = np.zeros_like(b), b.copy()
    d, rr, it = r.copy(), float(r @ r), 0
    while np.sqrt(rr) > tol * np.linalg.norm(b):
        ad = a @ d
        alpha = rr / float(d @ ad)
        x += alpha * d
        r -= alpha * ad
        rr, old = float(r @ r), rr
        d = r + (rr / old) * d
        it += 1
    return it


def test_conjugate_residuals_meet_a_loose_tolerance_in_fewer_iterations_than_gradients():
    """``krylov.cr`` minimises the residual over the same Krylov space in which
    conjugate gradients minimise the error's A-norm: to a loose relative residual it
    takes fewer iterations than conjugate gradients to the same one (a system of 300
    unknowns, eigenvalues from 1 to 1e3: 38 against 52 at 0.3 when measured), no more to
    a tight one, its true residual within the tolerance; with a preconditioner it meets
    the tolerance too. The preconditioner may be the identity (it returns its argument:
    the residual is not updated twice)."""
    rng = np.random.default_rng(7)
    n = 300
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    a = (q * np.logspace(0, 3, n)) @ q.T
    b = rng.standard_normal(n)
    jacobi = 1.0 / np.diag(a)
    for eta in (0.3, 0.1, 1e-2, 1e-4):
        x, it = krylov.cr(lambda v: a @ v, b, eta)
        assert np.linalg.norm(b - a @ x) <= eta * np.linalg.norm(b)
        gradients = _cg(a, b, eta / krylov.MARGIN)
        assert 0 < it <= gradients, (eta, it, gradients)
        if eta >= 0.1:
            assert it < gradients, (eta, it, gradients)
        x, _ = krylov.cr(lambda v: a @ v, b, eta, lambda v: v)  # (P = I, the same array)
        assert np.linalg.norm(b - a @ x) <= eta * np.linalg.norm(b)
        x, _ = krylov.cr(lambda v: a @ v, b, eta, lambda v: jacobi * v)
        assert np.linalg.norm(b - a @ x) <= eta * np.linalg.norm(b)
