"""The small-system solver (catenet/solver/banded.py): the bordered band's Cholesky
factorisation solves a step's matrix of a net with a free box as PARDISO does (to
round-off), checked as every solve; a matrix that is not positive definite goes to
PARDISO (its inertia, its singular-system error); "auto" picks it below BAND_MAX_DOF
(in ``catenet run`` as in a sweep and the API), "pardiso" never."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from scenes import paper_net

from catenet.case import build, parse_case
from catenet.errors import SingularSystemError
from catenet.solver.banded import BAND_MAX_DOF, BandSolver
from catenet.solver.linear import PardisoSolver, make_solver, pardiso_available
from catenet.solver.workspace import Workspace
from catenet.terms import Inertia

pytestmark = pytest.mark.skipif(not pardiso_available(), reason="MKL's PARDISO is missing")
ROOT = Path(__file__).resolve().parents[2]


def _step_matrix(shift: float = 0.0):
    case = tomllib.loads((ROOT / "benchmarks" / "peers" / "mujoco_drop.toml").read_text())
    case["geometry"]["n"] = 6
    case["geometry"]["edge_length"] = 0.5 / 6
    scene = build(parse_case(case))
    ws = Workspace(scene.net, terms=scene.terms)
    free = ws.system.free_dofs
    m = np.repeat(scene.net.mass[~scene.net.fixed], 3)
    inertia = Inertia(free)
    inertia.set_step(m / 1e-4, scene.net.nodes.reshape(-1)[free])
    x = scene.net.nodes.copy()
    x[:, 2] -= 0.002 * np.cos(3.0 * x[:, 0])
    data = ws.system.hessian(x, None, (inertia,)).copy()
    if shift:
        diag = ws.system.indices == np.repeat(
            np.arange(ws.system.n_free), np.diff(ws.system.indptr)
        )
        data[diag] -= shift
    return ws, data


def test_auto_bands_a_small_step_and_solves_it_as_pardiso_does():
    ws, data = _step_matrix()
    band = ws.solver
    assert isinstance(band, BandSolver) and band.layout.nb == 12  # the box's four nodes
    s = ws.system
    pardiso = make_solver("pardiso", s.indptr, s.indices, upper=True, dof_node=band.dof_node)
    assert isinstance(pardiso, PardisoSolver)
    b = np.random.default_rng(0).normal(size=s.n_free)
    band.factorize(data, definite=False)
    pardiso.factorize(data, definite=False)
    x_band, x_pardiso = band.solve(b), pardiso.solve(b)
    assert band.stats["band"] == 1 and band.fallback.stats["factorize"] == 0
    assert np.abs(x_band - x_pardiso).max() <= 1e-10 * np.abs(x_pardiso).max()
    assert band.negative_eigenvalues() == 0


def test_an_indefinite_matrix_goes_to_pardiso_with_its_inertia():
    ws, data = _step_matrix()
    big = float(np.abs(data).max())
    ws, data = _step_matrix(shift=1e-3 * big)
    band = ws.solver
    band.factorize(data, definite=False)
    assert band.stats["band"] == 0 and band.fallback.stats["factorize"] == 1
    b = np.ones(ws.system.n_free)
    x = band.solve(b)  # checked: a small backward error
    assert np.all(np.isfinite(x)) and band.negative_eigenvalues() > 0


def test_a_singular_flat_net_raises_as_pardiso_does():
    sq, _ = paper_net(6, edge=0.1)
    ws = Workspace(sq.net)
    assert isinstance(ws.solver, BandSolver)
    data = ws.system.hessian(sq.net.nodes, None, ()).copy()  # slack and flat: singular
    with pytest.raises(SingularSystemError):
        ws.solver.factorize(data)
        ws.solver.solve(np.ones(ws.system.n_free))


def test_a_system_of_a_few_unknowns_takes_the_band_and_its_round_off_pivots_pardiso():
    """A spring's three unknowns: dense, so no band "worth" its cost against a dense
    factorisation, but a PARDISO call cost 0.08 ms a solve there, far above the arithmetic:
    the band serves. A pivot at round-off of the largest diagonal entry (a direction
    without stiffness beside a stiff one) goes to PARDISO, which says the system is
    singular, as it does where it solves alone."""
    import catenet as cn
    from catenet.solver.banded import small_solver

    nodes = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    net = cn.Net.from_arrays(nodes, [[0, 1]], EA=100.0, fixed=[0])
    s = Workspace(net).system
    assert isinstance(Workspace(net).solver, BandSolver) and s.n_free == 3
    assert len(s.indices) == 6  # the upper triangle of a dense 3 x 3
    args = (s.indptr, s.indices)
    dof_node = np.repeat([1], 3)  # symmetric indefinite behind it (a step with contact)
    pardiso = make_solver("pardiso", *args, upper=True, dof_node=dof_node, mtype=-2)
    band = small_solver(*args, upper=True, dof_node=dof_node, fallback=pardiso)
    assert isinstance(band, BandSolver)
    band.factorize(np.array([5.0, 0.0, 0.0, 1e-3, 0.0, 2.0]))
    assert band.stats["band"] == 1
    assert np.allclose(band.solve(np.array([5.0, 1e-3, 2.0])), 1.0)
    with pytest.raises(SingularSystemError):  # 1e-22 against 5: none
        band.factorize(np.array([5.0, 0.0, 0.0, 1e-22, 0.0, 2.0]))
        band.solve(np.ones(3))
    assert band.stats["band"] == 1  # (PARDISO raised it)


def test_pardiso_alone_above_the_threshold_or_when_asked():
    sq, _ = paper_net(34)  # about 1e4 DOF
    assert Workspace(sq.net).system.n_free > BAND_MAX_DOF
    assert isinstance(Workspace(sq.net).solver, PardisoSolver)
    assert isinstance(
        Workspace(paper_net(6, edge=0.1)[0].net, linear="pardiso").solver, PardisoSolver
    )


def test_catenet_run_takes_the_band_as_the_api_does(tmp_path):
    """``catenet run`` passes "auto" on to its workspace: a small case takes the band (as
    a sweep's row and ``catenet.solve`` do: the same solver, the same numbers), its
    report names the backend that served."""
    from catenet.case import load_case
    from catenet.run.runner import run_case

    seen = {}
    case = load_case(ROOT / "configs" / "structures" / "guyed_mast.toml")
    done = run_case(case, tmp_path / "mast.h5", on_done=lambda s, ws, r: seen.update(ws=ws))
    solver = seen["ws"].solver
    assert isinstance(solver, BandSolver) and solver.stats["band"] > 0
    assert done.converged and done.report.backend == "pardiso"


def _bordered(n1: int, p: int, nb: int, seed: int = 0):
    """A positive definite bordered band (its band storage, C, D) and the whole matrix."""
    rng = np.random.default_rng(seed)
    L = 0.1 * rng.standard_normal((n1, p + 1))
    L[:, 0] = 2.0 * p
    for j in range(n1):
        L[j, n1 - j :] = 0.0  # (entries past the matrix's end)
    C = np.zeros((n1, nb))
    C[n1 // 2 :] = 0.1 * rng.standard_normal((n1 - n1 // 2, nb))
    D = 10.0 * p * np.eye(nb)
    A = np.zeros((n1 + nb, n1 + nb))
    for d in range(p + 1):
        A[np.arange(d, n1), np.arange(n1 - d)] = L[: n1 - d, d]
    A[n1:, :n1] = C.T
    A[n1:, n1:] = D
    return L, C, D, A + np.tril(A, -1).T


@pytest.mark.parametrize("n1, p, nb", [(40, 5, 0), (363, 60, 12), (200, 33, 3)])
def test_the_bands_factors_by_lapack_and_by_loops_agree_and_solve_the_matrix(n1, p, nb):
    """The band's Cholesky factor by LAPACK's dpbtrf (blocked) and by plain loops agree
    to round-off, and the bordered solve with either solves the whole matrix."""
    from catenet.kernels.banded import (
        band_cholesky,
        band_cholesky_loops,
        band_solve,
        lapack_ready,
    )

    assert lapack_ready()
    L, C, D, A = _bordered(n1, p, nb)
    b = np.random.default_rng(1).normal(size=n1 + nb)
    order = np.arange(n1 + nb)
    factors = []
    for factorize in (band_cholesky, band_cholesky_loops):
        f = (L.copy(), C.copy(), D.copy())
        assert factorize(*f)
        x = band_solve(*f, order, b)
        assert np.abs(A @ x - b).max() <= 1e-13 * np.abs(b).max()
        factors.append(f)
    for got, loops in zip(factors[0], factors[1], strict=True):
        assert np.abs(got - loops).max(initial=0.0) <= 1e-14 * np.abs(loops).max(initial=1.0)


@pytest.mark.parametrize("bad", [-1.0, np.nan])
def test_a_pivot_that_is_not_positive_fails_both_factorisations(bad):
    """A negative or NaN diagonal is no Cholesky factor: False (the solver then takes
    PARDISO), by LAPACK (which passes a NaN pivot on: checked after it) as by loops; a
    band stored out of order (not C-contiguous) is factorised by the loops."""
    from catenet.kernels.banded import band_cholesky, band_cholesky_loops

    L, C, D, _ = _bordered(50, 4, 2)
    L[7, 0] = bad
    assert not band_cholesky(L.copy(), C.copy(), D.copy())
    assert not band_cholesky_loops(L.copy(), C.copy(), D.copy())
    good, _, _, _ = _bordered(50, 4, 0)
    strided = np.asfortranarray(good)
    assert band_cholesky(strided, np.zeros((50, 0)), np.zeros((0, 0)))
    expected = good.copy()
    band_cholesky_loops(expected, np.zeros((50, 0)), np.zeros((0, 0)))
    assert np.array_equal(strided, expected)


def test_the_bands_definiteness_test_agrees_with_a_dense_cholesky_and_keeps_its_factors():
    """``BandSolver.positive_definite`` (a tension-only net's end state checked for a mode
    without stiffness, by the band in a fraction of a millisecond where the dense
    factorisation took 13 ms at 615 DOF): a step's matrix is, the same shifted below its
    least eigenvalue is not, and the solver's own factorisation solves as before."""
    ws, data = _step_matrix()
    band = ws.solver
    assert isinstance(band, BandSolver)
    dense = ws.system.dense(data)
    least = float(np.linalg.eigvalsh(dense)[0])
    band.factorize(data, definite=False)
    b = np.random.default_rng(1).normal(size=ws.system.n_free)
    before = band.solve(b)
    assert band.positive_definite(data)
    shifted = data.copy()
    shifted[ws.system.diag_pos] -= 1.01 * least
    assert not band.positive_definite(shifted)
    assert np.array_equal(band.solve(b), before)
