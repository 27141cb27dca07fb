"""The small-system solver: a bordered band factorised in a Numba kernel, PARDISO where
it does not serve.

Below BAND_MAX_DOF unknowns PARDISO's fixed cost per call (its handle, its checks, its
threads' set-up: about 0.3 ms) outweighs the arithmetic of a net's matrix, whose rows
each couple a node with its few neighbours: ordered by reverse Cuthill-McKee, the matrix
is a band of half width p (a few rows of the net). A free body's four nodes couple with
every node near it and would widen the band to the whole matrix: rows far denser than
the others (BORDER_DEGREE) are taken out as a border, so the matrix is

    [ A  C ]    A (n1 x n1) banded, C (n1 x nb), D (nb x nb) dense,
    [ C' D ]

factorised as A = L L' (LAPACK's band Cholesky, dpbtrf, as SciPy ships it), Y = L^-1 C
and the Schur complement S = D - Y'Y = R R' (``catenet.kernels.banded``).
``benchmarks/solvers_small.py`` measures both solvers on the nets of the drop and sets
BAND_MAX_DOF.

Where the Cholesky factorisation fails (a matrix that is not positive definite: a
singular flat net, an indefinite tangent), that matrix goes to PARDISO (the ``fallback``
solver, with its symbolic analysis made the first time), which factorises symmetric
indefinite matrices, reports their inertia and names a singular system's nodes. Solves
are checked as every solve is (``LinearSolver.solve``: finite values, backward error).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from catenet.kernels.banded import (
    band_cholesky,
    band_cholesky_loops,
    band_solve,
    cuthill_mckee,
    lapack_ready,
)
from catenet.solver.linear import LinearSolver

#: Whether solver.linear = "auto" takes the band below BAND_MAX_DOF. Every path that
#: solves a case (``catenet run``, a sweep's rows, the API) passes "auto" on to the
#: Workspace, so the same case takes the same solver and gives the same numbers on each
#: (tests/sweep/test_sweep_summary.py; ``catenet run`` once resolved "auto" to PARDISO
#: before the Workspace saw it, and its numbers then differed from a sweep's at 1e-13).
AUTO = True
BAND_MAX_DOF = 700  # the band below this many unknowns (benchmarks/solvers_small.py: it
# stops paying between 627 and 864 unknowns, with a box or without, on one thread)
BORDER_DEGREE = 6.0  # a row with more entries than this many times the median: border
BORDER_MAX = 48  # at most this many border rows (else PARDISO)
BAND_COST = 0.25  # the band's n1 p^2 at most this share of a dense factorisation's n^3
BAND_SMALL = 20_000  # ... or at most this many (microseconds: a system so small that a
# PARDISO call costs more than its dense arithmetic: a spring's 3 unknowns took 0.08 ms a
# solve through PARDISO, a tenth of its time step)
SMALL_ZERO = 1e-8  # such a system's pivot below this share of its largest diagonal entry
# is none: PARDISO's own threshold (it perturbs the pivot and the solver says the system is
# singular), which a Cholesky factorisation does not see (a block on a capsule's top, its
# spring unloaded: a pivot of 1e-22 against 5 passed, and Newton stepped along it)


class BandLayout:
    """Where each stored entry of a CSR pattern (upper triangle) goes in the bordered
    band: ``order`` the unknowns' new order (band rows, then border), ``p`` the half
    width, ``nb`` the border's size and the entries' flat places in the band (Fortran
    order), C and D."""

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, n: int):
        rows = np.repeat(np.arange(n), np.diff(indptr))
        cols = np.asarray(indices, dtype=np.int64)
        degree = np.bincount(rows, minlength=n) + np.bincount(cols, minlength=n)
        border = degree > BORDER_DEGREE * max(float(np.median(degree)), 1.0)
        inner = np.flatnonzero(~border)
        outer = np.flatnonzero(border)
        local = np.full(n, -1, dtype=np.int64)
        local[inner] = np.arange(len(inner))
        both = (local[rows] >= 0) & (local[cols] >= 0) & (rows != cols)
        a, b = local[rows[both]], local[cols[both]]
        src, dst = np.concatenate([a, b]), np.concatenate([b, a])
        by = np.argsort(src, kind="stable")
        ptr = np.zeros(len(inner) + 1, dtype=np.int64)
        np.cumsum(np.bincount(src, minlength=len(inner)), out=ptr[1:])
        perm = cuthill_mckee(ptr, np.ascontiguousarray(dst[by]))
        self.order = np.concatenate([inner[perm], outer])
        pos = np.empty(n, dtype=np.int64)
        pos[self.order] = np.arange(n)
        self.n, self.n1, self.nb = n, len(inner), len(outer)
        i, j = np.maximum(pos[rows], pos[cols]), np.minimum(pos[rows], pos[cols])
        n1 = self.n1
        self.p = int((i - j)[i < n1].max(initial=0))
        in_band, in_c, in_d = i < n1, (i >= n1) & (j < n1), j >= n1
        self.band_at, self.band_of = np.flatnonzero(in_band), (j * (self.p + 1) + i - j)[in_band]
        self.c_at, self.c_of = np.flatnonzero(in_c), (j * self.nb + i - n1)[in_c]
        self.d_at, self.d_of = np.flatnonzero(in_d), ((i - n1) * self.nb + j - n1)[in_d]

    def worth(self) -> bool:
        """Whether the band serves: few border rows and a band far below the dense
        matrix's cost, or a system so small that its arithmetic costs less than a PARDISO
        call (``small``)."""
        n = self.n
        return self.nb <= BORDER_MAX and (
            self.n1 * (self.p + 1) ** 2 <= BAND_COST * n**3 or self.small
        )

    @property
    def small(self) -> bool:
        """Whether the system is so small that PARDISO's call costs more than its band."""
        return self.n1 * (self.p + 1) ** 2 <= BAND_SMALL


class BandSolver(LinearSolver):
    """The bordered band's Cholesky factorisation, PARDISO (``fallback``) for a matrix it
    does not factorise (module docstring)."""

    name = "pardiso"  # the backend solver.linear = "auto" chose (its small systems banded)
    backend = "auto"  # what solver.linear asked for (a new solver of the same kind)

    def __init__(
        self,
        indptr: ArrayLike,
        indices: ArrayLike,
        *,
        upper: bool,
        dof_node: np.ndarray,
        layout: BandLayout,
        fallback: LinearSolver,
    ):
        super().__init__(indptr, indices, upper=upper, dof_node=dof_node)
        self.layout = layout
        self.fallback = fallback
        self.mtype = fallback.mtype
        lay = layout
        self._band = np.zeros((lay.n1, lay.p + 1))
        self._C = np.zeros((lay.n1, lay.nb))
        self._D = np.zeros((lay.nb, lay.nb))
        self._factored = False
        self._definite = False
        self.stats["band"] = 0

    def _select(self, definite: bool) -> None:
        self._definite = definite

    def positive_definite(self, data: np.ndarray) -> bool:
        """Whether the matrix ``data`` (this pattern) is positive definite: its band's
        Cholesky factorisation in arrays of its own, this solver's factors untouched."""
        band, C, D = np.zeros_like(self._band), np.zeros_like(self._C), np.zeros_like(self._D)
        return self._cholesky(data, band, C, D, 0.0)

    def _cholesky(
        self, data: np.ndarray, band: np.ndarray, C: np.ndarray, D: np.ndarray, zero: float
    ) -> bool:
        """The bordered band's Cholesky factorisation of ``data`` (this pattern) in the
        zeroed arrays band, C, D; whether it succeeded (no pivot at or below ``zero`` of
        the largest diagonal entry)."""
        lay = self.layout
        band.reshape(-1)[lay.band_of] = data[lay.band_at]
        C.reshape(-1)[lay.c_of] = data[lay.c_at]
        D.reshape(-1)[lay.d_of] = data[lay.d_at]
        factorize = band_cholesky if lapack_ready() else band_cholesky_loops
        return bool(factorize(band, C, D, zero))

    def _factorize(self, data: np.ndarray) -> None:
        band, C, D = self._band, self._C, self._D
        band.fill(0.0)
        C.fill(0.0)
        D.fill(0.0)
        zero = SMALL_ZERO if self.layout.small else 0.0
        self._factored = self._cholesky(data, band, C, D, zero)
        if not self._factored:  # not positive definite: PARDISO's (its errors too)
            self.fallback.factorize(data, definite=self._definite)
        else:
            self.stats["band"] += 1

    def _solve(self, b: np.ndarray) -> np.ndarray:
        if not self._factored:
            return self.fallback._solve(b)
        out: np.ndarray = band_solve(
            self._band, self._C, self._D, self.layout.order, np.asarray(b, dtype=np.float64)
        )
        return out

    def negative_eigenvalues(self) -> int | None:
        if self._factored:
            return 0  # a Cholesky factorisation: positive definite
        return self.fallback.negative_eigenvalues()

    def release(self) -> None:
        self._factored = False
        self.fallback.release()


def small_solver(
    indptr: ArrayLike,
    indices: ArrayLike,
    *,
    upper: bool,
    dof_node: np.ndarray,
    fallback: LinearSolver,
) -> LinearSolver:
    """The bordered band over ``fallback`` where the system is small and its band serves
    (symmetric, upper triangle), else ``fallback`` itself."""
    n = np.asarray(indptr).shape[0] - 1
    if not AUTO or not upper or n > BAND_MAX_DOF or n < 2:
        return fallback
    layout = BandLayout(np.asarray(indptr), np.asarray(indices), n)
    if not layout.worth():
        return fallback
    return BandSolver(
        indptr, indices, upper=upper, dof_node=dof_node, layout=layout, fallback=fallback
    )
