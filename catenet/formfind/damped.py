"""The damped Gauss-Newton step of form finding's targets from one sparse symmetric
factorisation, the Jacobian never formed.

The step p of min |J p + r|^2 + mu |p|^2, with J = Rq - Rx A^-1 Bs (the residual's
partial derivatives Rx (rows x 3 n_f) and Rq (rows x variables), the linearised
equilibrium A dx + Bs p = 0 of ``catenet.formfind.adjoint``), is the stationary point of
1/2 |Rx dx + Rq p + r|^2 + mu/2 |p|^2 + l^T (A dx + Bs p): the symmetric system

    [ H      Rq^T Rx   Bs^T ] [p ]   [ -Rq^T r ]
    [ .      Rx^T Rx   A^T  ] [dx] = [ -Rx^T r ]        H = mu I + Rq^T Rq
    [ .      .         0    ] [l ]   [    0    ]

of the variables, the free DOFs and their multipliers (the targets' misses eliminated).
H is diagonal (a row of Rq is one tension's, on one variable); Rx^T Rx couples the DOFs a
row reads (a node's, or an edge's two ends); Bs and A those of the edges: its pattern is
the net's, its size the variables plus twice the free DOFs, factorised once per step by
the linear solver layer: PARDISO, symmetric indefinite with weighted matching, on the
matrix scaled symmetrically (Ruiz, in the max norm); the pivots PARDISO perturbs are
corrected by iterative refinement on the scaled matrix, and where that does not converge
(a saddle point too ill-conditioned for static pivoting) SciPy's SuperLU solves the
step, as it does where MKL is absent. The pattern and the place of every entry in it
come from the topology and the targets once (``Layout``), so PARDISO analyses it once
per search; each step only refills the values. A variable held at a bound keeps p = 0
(its columns' values zero, its H one).
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from catenet.errors import SingularSystemError

log = logging.getLogger(__name__)

FORWARD = 1e-10  # the refinement's last correction, relative to the solution
ROUGH = 1e-7  # where the corrections stall in round-off: enough for a damped step


def _scaling(indptr, indices, data, row, passes: int = 3) -> np.ndarray:
    """Symmetric scaling d (Ruiz's, in the max norm) of the symmetric matrix whose upper
    triangle is given: d_i d_j |a_ij| at most 1, every row's largest near 1."""
    d = np.ones(len(indptr) - 1)
    a = np.abs(data)
    for _ in range(passes):
        s = a * d[row] * d[indices]
        big = np.zeros(len(d))
        np.maximum.at(big, row, s)
        np.maximum.at(big, indices, s)
        d /= np.sqrt(np.where(big > 0, big, 1.0))
    return d


def _refined(solver, indptr, indices, a_data, b, steps: int = 12) -> np.ndarray | None:
    """x of A x = b with the factors of a nearby matrix (``solver``), refined on A (its
    upper triangle ``a_data``) until the corrections are at most FORWARD of x, or stall
    below ROUGH; None where they do not get there."""
    from catenet.kernels.sparse import csr_matvec

    x = solver.solve_unchecked(b)
    ax = np.empty_like(b)
    last = np.inf
    # int32 indices, as the linear solver's: the product then compiles for one signature
    indptr, indices = (np.ascontiguousarray(a, dtype=np.int32) for a in (indptr, indices))
    for _ in range(steps):
        csr_matvec(indptr, indices, a_data, x, True, ax)
        dx = solver.solve_unchecked(b - ax)
        if not np.all(np.isfinite(dx)):
            return None
        x = x + dx
        change = float(np.max(np.abs(dx))) / max(float(np.max(np.abs(x))), 1e-300)
        if change <= FORWARD or (change <= ROUGH and change > 0.5 * last):
            return x
        if change > 0.5 and last < np.inf:  # (diverging: the factors are too far off)
            return None
        last = change
    return None


def _pairs(pa: np.ndarray, pb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every pair (ka, kb) of entries of two CSR matrices on the same row (indices into
    their data), row by row."""
    na, nb = np.diff(pa), np.diff(pb)
    count = na * nb
    row = np.repeat(np.arange(len(na)), count)
    first = np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.int64)
    k = np.arange(int(count.sum()), dtype=np.int64) - np.repeat(first, count)
    nbr = nb[row]
    return pa[row] + k // np.maximum(nbr, 1), pb[row] + k % np.maximum(nbr, 1)


class Layout:
    """The step's matrix: its pattern (upper triangle, CSR), where each contribution goes
    (``_slot``), and its solver (made once: one symbolic analysis)."""

    def __init__(self, adj, d_x, d_q, groups: np.ndarray, n_var: int):
        shape = adj.shape
        self.key = self._key(adj, d_x, d_q, groups)
        self.nv, self.n3 = nv, n3 = n_var, adj.n3
        x0, l0 = nv, nv + n3
        self.n = n = nv + 2 * n3
        self.groups = groups
        self.rq_var = groups[d_q.indices]  # each entry of Rq: its variable
        self.rq_row = np.repeat(np.arange(d_q.shape[0]), np.diff(d_q.indptr))
        hh = _pairs(d_q.indptr, d_q.indptr)
        t = _pairs(d_q.indptr, d_x.indptr)
        xx = _pairs(d_x.indptr, d_x.indptr)
        self._hh, self._t, self._xx = hh, t, xx
        _, bg_r, bg_c = adj.bg_coo
        _, a_r, a_c = adj.a_coo()
        rows = [
            np.arange(n),  # the diagonal (H; zeros PARDISO wants present)
            self.rq_var[hh[0]],
            self.rq_var[t[0]],
            x0 + d_x.indices[xx[0]],
            groups[bg_c],
            x0 + a_c,
        ]
        cols = [
            np.arange(n),
            self.rq_var[hh[1]],
            x0 + d_x.indices[t[1]],
            x0 + d_x.indices[xx[1]],
            l0 + bg_r,
            l0 + a_r,
        ]
        r, c = np.concatenate(rows), np.concatenate(cols)
        self._upper = r <= c  # (the blocks on the diagonal give both triangles)
        keys, self._slot = np.unique(r[self._upper] * n + c[self._upper], return_inverse=True)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(keys // n, minlength=n))])
        self.indices = keys % n
        self.nnz = len(keys)
        net, free = shape.net, shape.pattern.free_nodes
        first = np.unique(groups, return_index=True)[1]  # each variable's first edge
        dof_node = np.concatenate([net.edges[first, 0], np.repeat(free, 3), np.repeat(free, 3)])
        self.backend, self.solver = shape.backend, None
        if shape.backend == "pardiso":
            from catenet.solver.linear import make_solver

            solver: Any = make_solver(
                "pardiso", self.indptr, self.indices, upper=True, dof_node=dof_node, mtype=-2
            )
            solver.iparm[10] = 1  # scaling and weighted matching: a saddle point
            solver.iparm[12] = 1
            solver.perturbed_ok = True  # (refined on the true matrix below)
            self.solver = solver
        self._row = np.repeat(np.arange(n), np.diff(self.indptr)).astype(np.int32)
        self.factorizations = 0
        self.fallbacks = 0  # steps SuperLU solved
        self.seconds = 0.0  # in the steps' solves

    @staticmethod
    def _key(adj, d_x, d_q, groups) -> tuple:
        return (
            id(adj.shape),
            d_x.shape,
            d_x.indptr.tobytes(),
            d_x.indices.tobytes(),
            d_q.indptr.tobytes(),
            d_q.indices.tobytes(),
            groups.tobytes(),
            len(adj.bg_coo[0]),
            len(adj.gx_coo[0]),
        )

    def fits(self, adj, d_x, d_q, groups) -> bool:
        """Whether this layout is that of these partial derivatives."""
        return self._key(adj, d_x, d_q, groups) == self.key

    def step(self, adj, d_x, d_q, r: np.ndarray, mu: float, keep: np.ndarray) -> np.ndarray:
        """The damped step (0 where not ``keep``); SingularSystemError where it has none."""
        nv, n3, n = self.nv, self.n3, self.n
        k = keep.astype(np.float64)
        q = adj.q
        rq = d_q.data * q[d_q.indices] * k[self.rq_var]  # Rq, a held variable's zero
        rx = d_x.data
        bg_v, _, bg_c = adj.bg_coo
        a_v = adj.a_coo()[0]
        diag = np.zeros(n)
        diag[:nv] = np.where(keep, mu, 1.0)
        hh, t, xx = self._hh, self._t, self._xx
        vals = np.concatenate(
            [
                diag,
                rq[hh[0]] * rq[hh[1]],
                rq[t[0]] * rx[t[1]],
                rx[xx[0]] * rx[xx[1]],
                bg_v * q[bg_c] * k[self.groups[bg_c]],
                a_v,
            ]
        )
        data = np.bincount(self._slot, weights=vals[self._upper], minlength=self.nnz)
        rhs = np.zeros(n)
        rhs[:nv] = -np.bincount(self.rq_var, rq * r[self.rq_row], nv)
        rhs[nv : nv + n3] = -(d_x.T @ r)
        self.factorizations += 1
        start = time.perf_counter()
        sol = self._solve(data, rhs)
        self.seconds += time.perf_counter() - start
        p = sol[:nv] * k
        if not np.all(np.isfinite(p)):
            raise SingularSystemError("the damped step is not finite")
        return p

    def _solve(self, data: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """The step's system solved: PARDISO on the scaled matrix (pivots perturbed
        where it must), refined on it; SuperLU where that does not converge."""
        if self.solver is not None:
            d = _scaling(self.indptr, self.indices, data, self._row)
            scaled = data * d[self._row] * d[self.indices]
            try:
                self.solver.factorize(scaled)
                y = _refined(self.solver, self.indptr, self.indices, scaled, d * rhs)
                if y is not None:
                    return d * y
            except SingularSystemError as exc:
                log.debug("form finding: PARDISO on the damped step failed (%s)", exc)
            log.debug("form finding: the damped step by SuperLU")
        self.fallbacks += 1
        return self._superlu(data, rhs)

    def _superlu(self, data: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        import scipy.sparse as sp

        from catenet.formfind.newton import superlu_solve

        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
        return superlu_solve((a + sp.triu(a, k=1).T).tocsc(), rhs)


__all__ = ["Layout"]
