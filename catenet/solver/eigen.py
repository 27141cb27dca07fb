"""The eigensolvers of a modal analysis (``catenet.solver.modes``) on its ``Operator``
(``catenet.solver.modal``): every mode by a dense solver (``dense_modes``; massless
DOFs condensed out where K - sigma M is not positive definite to round-off), the lowest
by shift-invert Lanczos (``lanczos_modes``, ARPACK with the kept factorisation), and
the Rayleigh-Ritz step that makes the shapes M-orthonormal (``rayleigh_ritz``)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConvergenceError

if TYPE_CHECKING:
    from catenet.solver.linear import LinearSolver
    from catenet.solver.modal import Operator

TOL = 1e-10  # ARPACK: relative accuracy of the Ritz values (refined by Rayleigh-Ritz after)


def _condensed(op: Operator, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every mode of a net with massless DOFs whose K - sigma M is not positive definite
    to round-off (a zero mode of a frictionless body beside massless strings: whether the
    Cholesky of K - sigma M passes then hangs on the processor's round-off). The massless
    DOFs carry no inertia, so condensing them out is exact: K* = K_mm - K_m0 K_00^-1
    K_0m on the massive DOFs, then K* phi = w^2 M_mm phi, and phi_0 = -K_00^-1 K_0m phi.
    Raises ConvergenceError where the massless part itself is singular or indefinite
    (a massless mechanism: no frequency exists)."""
    import scipy.linalg as sl

    k = op.k.toarray()
    massive = np.abs(m).sum(axis=1) > 0.0
    zero = ~massive
    k00 = k[np.ix_(zero, zero)]
    try:
        factor = sl.cho_factor(k00)
    except np.linalg.LinAlgError:
        raise ConvergenceError(
            "modes: the stiffness is indefinite where free nodes have no mass (a massless "
            "mechanism): give those nodes mass (material.density) or tension"
        ) from None
    coupling = k[np.ix_(zero, massive)]
    solved = sl.cho_solve(factor, coupling)
    reduced = k[np.ix_(massive, massive)] - coupling.T @ solved
    lam, sub = sl.eigh(0.5 * (reduced + reduced.T), m[np.ix_(massive, massive)])
    vec = np.zeros((k.shape[0], sub.shape[1]))
    vec[massive] = sub
    vec[zero] = -solved @ sub
    return lam, vec


def dense_modes(op: Operator, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Every mode, by a dense symmetric eigensolver (small nets): M phi = mu (K - sigma M)
    phi, mu = 1 / (w^2 - sigma), which allows massless DOFs (mu = 0: w infinite)."""
    import scipy.linalg as sl

    a = (op.k - sigma * op.mm).toarray()
    m = op.mm.toarray()
    try:
        mu, vec = sl.eigh(m, a)
    except np.linalg.LinAlgError:  # K - sigma M not positive definite to round-off
        if not (op.m > 0).all():
            return _condensed(op, m)
        lam, vec = sl.eigh(op.k.toarray(), m)
        return lam, vec
    keep = mu > 1e-12 * max(float(mu.max(initial=0.0)), 1e-300)  # else: no mass, w infinite
    mu, vec = mu[keep], vec[:, keep] / np.sqrt(mu[keep])  # phi^T M phi = 1
    order = np.argsort(-mu)
    return sigma + 1.0 / mu[order], vec[:, order]


def lanczos_modes(
    op: Operator,
    solver: LinearSolver,
    sigma: float,
    count: int,
    stats: dict[str, Any],
    unstable: Callable[[str], None],
) -> tuple[np.ndarray, np.ndarray]:
    """The lowest modes by shift-invert Lanczos, asking again for more while zero modes
    take the places of real ones (they are nearest the shift, so every one is found
    before the first real mode). ``unstable(why)`` raises for a negative omega^2 that
    the factorisation's inertia shows."""
    start = time.perf_counter()
    solver = op.factorized(solver, sigma)
    stats["factorize_seconds"] = time.perf_counter() - start
    negative = solver.negative_eigenvalues()
    stats["negative"] = negative
    if negative:  # Sylvester: that many omega^2 below sigma < 0; confirmed beyond the margin
        beyond = op.factorized(solver, -op.negative).negative_eigenvalues()
        if beyond:
            unstable(f"{beyond} negative omega^2 (the inertia of K + {op.negative:.3g} M)")
        solver = op.factorized(solver, sigma)  # zero modes within round-off: go on
    limit = op.n - 1  # ARPACK: k < n
    k = min(count, limit)
    solves = 0
    while True:
        lam, vec, used = _lanczos(op, solver, sigma, k)
        solves += used
        zero = int(np.count_nonzero(lam < op.zero))
        if len(lam) - zero >= count or k >= limit:
            break
        k = min(limit, count + zero if zero < k else 2 * k)
    stats["solves"] = solves
    stats["lanczos_seconds"] = time.perf_counter() - start
    return lam, vec


def _lanczos(
    op: Operator, solver: LinearSolver, sigma: float, k: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """k eigenpairs nearest sigma by ARPACK with OPinv = the kept factorisation."""
    from scipy.sparse.linalg import ArpackError, LinearOperator, eigsh

    n = op.n
    used = [0]

    def inverse(b: np.ndarray) -> np.ndarray:
        used[0] += 1
        return solver.solve(np.asarray(b, dtype=np.float64).ravel())

    k_matrix = op.k
    opinv = LinearOperator((n, n), matvec=inverse, dtype=np.float64)
    m_op = LinearOperator((n, n), matvec=lambda v: op.mm @ np.ravel(v), dtype=np.float64)
    v0 = np.random.default_rng(12345).standard_normal(n) * (op.m > 0)
    ncv = min(n, max(2 * k + 1, k + 20))
    try:
        lam, vec = eigsh(
            k_matrix, k=k, M=m_op, sigma=sigma, which="LM", OPinv=opinv, v0=v0, ncv=ncv,
            tol=TOL, mode="normal",
        )  # fmt: skip
    except ArpackError as exc:
        raise ConvergenceError(f"modes: the Lanczos iteration (ARPACK) failed: {exc}") from None
    order = np.argsort(lam)
    return lam[order], vec[:, order], used[0]


def rayleigh_ritz(op: Operator, vec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The best eigenpairs in the span of ``vec``: an M-orthonormal basis of it (the
    directions of no mass, massless DOFs' infinite modes, left out), then the
    eigenpairs of K in that basis, so that the shapes are M-orthonormal to round-off
    and the w^2 are Rayleigh quotients."""
    import scipy.linalg as sl

    if vec.shape[1] == 0:
        return np.zeros(0), vec
    mr = vec.T @ (op.mm @ vec)
    w, u = sl.eigh(0.5 * (mr + mr.T))
    keep = w > 1e-10 * max(float(w.max(initial=0.0)), 1e-300)
    basis = vec @ (u[:, keep] / np.sqrt(w[keep]))
    kr = basis.T @ (op.k @ basis)
    lam, y = sl.eigh(0.5 * (kr + kr.T))
    return lam, basis @ y
