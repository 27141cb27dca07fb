"""Variants of catenet's linear solvers, for measurements only (not used by catenet).

- ``ReanalysingPardiso``: catenet's PARDISO wrapper that repeats the symbolic analysis
  before every factorisation, i.e. what a solver without pattern reuse pays.
- ``PypardisoSpsolve``: ``pypardiso.spsolve`` on the full matrix every Newton step.
- ``CheckingEverySolve``, ``IndefiniteThroughout``: catenet's wrapper as it was before
  two speed-ups of dynamic runs (``python -m benchmarks reuse`` measures both against today's).

``install(workspace, cls)`` swaps the solver of a ``catenet.solver.static.Workspace``.
"""

from __future__ import annotations

import numpy as np

from catenet.errors import SingularSystemError
from catenet.solver.linear import LinearSolver, PardisoSolver


class ReanalysingPardiso(PardisoSolver):
    name = "pardiso (analyse every factorisation)"

    def factorize(self, data, definite=False):
        if self._analysed:
            self.release()  # drop the symbolic analysis: the next factorize redoes it
        super().factorize(data, definite)


class PypardisoSpsolve(LinearSolver):
    name = "pypardiso.spsolve (re-analyses)"

    def _factorize(self, data):
        import scipy.sparse as sp

        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
        if self.upper:
            a = a + sp.triu(a, k=1).T
        self._a = a.tocsr()

    def _solve(self, b):
        import pypardiso

        try:
            return np.asarray(pypardiso.spsolve(self._a, np.asarray(b, dtype=np.float64)))
        except ValueError as exc:  # "Matrix A is singular, because it contains empty rows"
            raise SingularSystemError(f"pypardiso: {exc}") from None


def install(workspace, cls, **kwargs):
    """Replaces the linear solver of ``workspace`` by ``cls`` on the same pattern."""
    system = workspace.system
    dof_node = np.flatnonzero(~system.net.fixed).repeat(3)
    workspace.solver = cls(
        system.indptr, system.indices, upper=system.upper, dof_node=dof_node, **kwargs
    )
    return workspace


class CheckingEverySolve(PardisoSolver):
    """catenet's PARDISO wrapper as it was before the backward-error check was left to
    each factorisation's first solve: every solve checked (a matrix-vector product more)."""

    name = "pardiso (every solve checked)"

    def solve(self, b):
        self._checked = False
        return super().solve(b)


class IndefiniteThroughout(PardisoSolver):
    """catenet's PARDISO wrapper as it was before it kept Cholesky for the matrices of an
    obstacle out of reach: a non-convex term makes every factorisation indefinite."""

    name = "pardiso (indefinite throughout)"

    def _select(self, definite):
        pass
