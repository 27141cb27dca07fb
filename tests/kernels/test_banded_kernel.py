"""The bordered band's kernels (catenet/kernels/banded.py) against a dense solve: a
random positive definite band with a border that couples only to the band's lower rows
(as a free body couples to the nodes near it), and one that is not positive definite."""

from __future__ import annotations

import numpy as np

from catenet.kernels.banded import band_cholesky, band_solve


def bordered(seed: int, n1: int = 40, p: int = 5, nb: int = 6, first: int = 17):
    """(dense matrix, band storage, C, D): A banded of half width p, C non-zero from row
    ``first`` on, the whole diagonally dominant."""
    rng = np.random.default_rng(seed)
    n = n1 + nb
    A = np.zeros((n, n))
    for d in range(1, p + 1):
        off = rng.normal(size=n1 - d)
        A[np.arange(d, n1), np.arange(n1 - d)] = off
    C = np.zeros((n1, nb))
    C[first:] = rng.normal(size=(n1 - first, nb))
    A[n1:, :n1] = C.T
    S = rng.normal(size=(nb, nb))
    A[n1:, n1:] = np.tril(S @ S.T)
    A = A + np.tril(A, -1).T
    A[np.diag_indices(n)] += np.abs(A).sum(axis=1) + 1.0
    L = np.zeros((n1, p + 1))
    for d in range(p + 1):
        L[: n1 - d, d] = np.diagonal(A[:n1, :n1], -d)
    return A, L, A[:n1, n1:].copy(), np.tril(A[n1:, n1:]).copy()


def test_the_bordered_band_solves_as_a_dense_solve():
    for seed in range(3):
        A, L, C, D = bordered(seed)
        assert band_cholesky(L, C, D)
        b = np.random.default_rng(10 + seed).normal(size=A.shape[0])
        order = np.arange(A.shape[0])
        x = band_solve(L, C, D, order, b)
        assert np.abs(x - np.linalg.solve(A, b)).max() <= 1e-12 * np.abs(x).max()
        perm = np.random.default_rng(seed).permutation(A.shape[0])  # the unknowns' order
        original = np.empty_like(A)  # row and column order[i] of it: the band's i
        original[np.ix_(perm, perm)] = A
        _, L, C, D = bordered(seed)
        assert band_cholesky(L, C, D)
        y = band_solve(L, C, D, perm, b)
        assert np.abs(original @ y - b).max() <= 1e-12 * np.abs(b).max()


def test_a_matrix_that_is_not_positive_definite_is_refused():
    A, L, C, D = bordered(0)
    L[7, 0] = -1.0  # a negative pivot in the band
    assert not band_cholesky(L, C, D)
    _, L, C, D = bordered(1)
    D[:] = 0.0
    np.fill_diagonal(D, 1e-3)  # the Schur complement D - Y'Y indefinite
    assert not band_cholesky(L, C, D)
