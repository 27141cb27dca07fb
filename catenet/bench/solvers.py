"""Variants of catenet's linear solvers, for measurements only (not used by catenet).

- ``ReanalysingPardiso``: catenet's PARDISO wrapper that repeats the symbolic analysis
  before every factorisation, i.e. what a solver without pattern reuse pays.
- ``SymmetricSuperLU``: SciPy's SuperLU in symmetric mode (ordering of A + A^T, diagonal
  pivots preferred), a proposed setting for catenet's SciPy fallback.
- ``PypardisoSpsolve``: ``pypardiso.spsolve`` on the full matrix every Newton step.

``install(workspace, cls)`` swaps the solver of a ``catenet.static.Workspace``.
"""

from __future__ import annotations

import numpy as np

from catenet.errors import SingularSystemError
from catenet.linsolve import LinearSolver, PardisoSolver, ScipySolver


class ReanalysingPardiso(PardisoSolver):
    name = "pardiso (analyse every factorisation)"

    def factorize(self, data):
        if self._analysed:
            self.release()  # drop the symbolic analysis: the next factorize redoes it
        super().factorize(data)


class SymmetricSuperLU(ScipySolver):
    name = "scipy (SuperLU symmetric mode)"

    def _factorize(self, data):
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
        if self.upper:
            a = a + sp.triu(a, k=1).T
        try:
            self._lu = splu(
                a.tocsc(),
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
        except RuntimeError as exc:
            raise SingularSystemError(
                f"SciPy: {exc}: a mechanism or an all-slack region", nodes=self.weak_nodes()
            ) from None


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
