"""The derivatives of form finding's targets with respect to the force densities, by the
adjoint of the force-density equilibrium.

The free nodes are in equilibrium, R(x, q) = C_f^T Q C x - P(x, q) = 0, with the loads P
(constant, or the self-weight g rho l0 / 2 per edge end, which changes with the shape and
with q). Differentiating, A dx + Bg dq = 0 with A = dR/dx = I_3 (x) D - G_x and
Bg = dR/dq = B - G_q, where D = C_f^T Q C_f, B's column e holds -u_e at the edge's first
free end and +u_e at its second, and G the weight's derivatives
(``catenet.formfind.newton.weight_jacobian``). A target's residual r(x, q) then changes by

    dr/dq = r_q - r_x A^-1 Bg,

so J^T z (the gradient of 1/2 |r|^2 for z = r) costs one adjoint solve A^T y = r_x^T z,
J v one solve A y = Bg v, and the whole Jacobian min(rows, variables) solves. Without
self-weight A is I_3 (x) D, whose factorisation the shape was just solved with (each
coordinate one solve); with it, A is unsymmetric and SuperLU factorises it once per
state. Nothing is differenced.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import scipy.sparse as sp

    from catenet.formfind.fdm import _Shape


class Adjoint:
    """The linearised equilibrium at one state (q, x): ``solve`` (A^-1), ``solve_t``
    (A^-T) and ``bg`` (dR/dq, sparse (3 n_f, M))."""

    def __init__(self, shape: _Shape, q: np.ndarray, x: np.ndarray):
        import scipy.sparse as sp

        from catenet.formfind.newton import weight_jacobian

        self.shape = shape
        p, net = shape.pattern, shape.net
        self.nf = nf = p.n_free
        n3 = 3 * nf
        u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
        rows, cols, vals = [], [], []
        for f, sign in ((p.a, -1.0), (p.b, 1.0)):
            e = np.flatnonzero(f >= 0)
            for c in range(3):
                rows.append(3 * f[e] + c)
                cols.append(e)
                vals.append(sign * u[e, c])
        self.lu = None
        self.a = _matrix_a(p, q)
        if shape.weighs:
            length = np.linalg.norm(u, axis=1)
            wv, (wr, wc) = weight_jacobian(shape, q, u, length, np.zeros(0, dtype=np.int64))
            on_q = wc >= n3
            rows.append(wr[on_q])
            cols.append(wc[on_q] - n3)
            vals.append(-wv[on_q])
            on_x = ~on_q
            self.a = self.a - sp.csr_matrix((wv[on_x], (wr[on_x], wc[on_x])), shape=(n3, n3))
            from scipy.sparse.linalg import splu

            self.lu = splu(self.a.tocsc())
        self.bg: sp.csr_matrix = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(n3, net.n_edges),
        )

    def solve(self, w: np.ndarray) -> np.ndarray:
        """A^-1 w for w (3 n_f,) or (3 n_f, k)."""
        if self.lu is not None:
            return self.lu.solve(np.asarray(w, dtype=np.float64))
        return self._by_coordinate(w)

    def solve_t(self, w: np.ndarray) -> np.ndarray:
        """A^-T w (A is symmetric without self-weight)."""
        if self.lu is not None:
            return self.lu.solve(np.asarray(w, dtype=np.float64), trans="T")
        return self._by_coordinate(w)

    def _by_coordinate(self, w: np.ndarray) -> np.ndarray:
        """(I_3 (x) D)^-1 w: each coordinate (and column) one solve with D's factors."""
        shape = np.shape(w)
        flat = np.asarray(w, dtype=np.float64).reshape(self.nf, -1)  # (f, c [x k])
        out = self.shape.solve(flat)
        if not np.all(np.isfinite(out)):
            from catenet.errors import SingularSystemError

            raise SingularSystemError("form finding: the adjoint solve is not finite")
        return out.reshape(shape)


def _matrix_a(p, q):
    """I_3 (x) D, the DOFs interleaved (3 f + c), as a sparse matrix."""
    import scipy.sparse as sp

    d = sp.csr_matrix((p.values(q), p.indices, p.indptr), shape=(p.n_free, p.n_free))
    d = d + sp.triu(d, k=1).T
    return sp.kron(d, sp.identity(3), format="csr")


def jacobian_dense(
    adj: Adjoint, d_x: sp.csr_matrix, d_q: sp.csr_matrix, dq_ds: sp.csr_matrix
) -> np.ndarray:
    """J = dr/ds (R, V) whole: by adjoint solves (one per row) or forward solves (one per
    variable), whichever are fewer."""
    rows, nv = d_x.shape[0], dq_ds.shape[1]
    if rows <= nv:
        y = adj.solve_t(d_x.T.toarray())  # (3 n_f, R)
        j_q = d_q.toarray() - (adj.bg.T @ y).T
        return np.asarray(dq_ds.T @ j_q.T).T
    bg = (adj.bg @ dq_ds).toarray()  # (3 n_f, V)
    return np.asarray((d_q @ dq_ds).toarray() - d_x @ adj.solve(bg))


class SparseJacobian:
    """J = dr/ds never formed: ``matvec`` (one forward solve), ``rmatvec`` (one adjoint
    solve), and ``damped``: the step p of min |J p + r|^2 + mu |p|^2 from one sparse
    factorisation of the symmetric saddle-point system in (p, dx, lambda, e)

        [ mu I   0    Bs^T  Rq^T ] [p ]   [ 0 ]
        [ 0      0    A^T   Rx^T ] [dx] = [ 0 ]
        [ Bs     A    0     0    ] [l ]   [ 0 ]
        [ Rq     Rx   0     -I   ] [e ]   [ -r]

    (the linearised equilibrium A dx + Bs p = 0 as a constraint, e = Rx dx + Rq p + r the
    residual after the step), whose size is that of the equilibrium's tangent plus the
    variables and rows: a step costs about one factorisation of the net's size."""

    def __init__(self, adj: Adjoint, d_x, d_q, dq_ds):
        self.adj, self.d_x = adj, d_x.tocsr()
        self.rq = (d_q @ dq_ds).tocsr()
        self.bs = (adj.bg @ dq_ds).tocsr()
        self.shape = (d_x.shape[0], dq_ds.shape[1])

    def matvec(self, v: np.ndarray) -> np.ndarray:
        v = np.ravel(v)
        return self.rq @ v - self.d_x @ self.adj.solve(self.bs @ v)

    def rmatvec(self, z: np.ndarray) -> np.ndarray:
        z = np.ravel(z)
        return self.rq.T @ z - self.bs.T @ self.adj.solve_t(self.d_x.T @ z)

    def damped(self, r: np.ndarray, mu: float, keep: np.ndarray) -> np.ndarray:
        """The damped step (0 where not ``keep``); SingularSystemError where it has none."""
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        from catenet.errors import SingularSystemError

        nv, rows, n3 = self.shape[1], self.shape[0], self.adj.a.shape[0]
        k = sp.diags(keep.astype(np.float64))
        bs, rq = self.bs @ k, self.rq @ k
        diag = sp.diags(np.where(keep, mu, 1.0))
        kkt = sp.bmat(
            [
                [diag, None, bs.T, rq.T],
                [None, sp.csr_matrix((n3, n3)), self.adj.a.T, self.d_x.T],
                [bs, self.adj.a, None, None],
                [rq, self.d_x, None, -sp.identity(rows)],
            ],
            format="csc",
        )
        rhs = np.zeros(kkt.shape[0])
        rhs[nv + 2 * n3 :] = -r
        try:
            sol = splu(kkt).solve(rhs)
        except RuntimeError as exc:  # exactly singular
            raise SingularSystemError(f"SciPy: {exc}") from None
        p = sol[:nv] * keep
        if not np.all(np.isfinite(p)):
            raise SingularSystemError("the damped step is not finite")
        return p


def jacobian_operator(adj: Adjoint, d_x, d_q, dq_ds) -> SparseJacobian:
    """J = dr/ds as a SparseJacobian (see there)."""
    return SparseJacobian(adj, d_x, d_q, dq_ds)


__all__ = ["Adjoint", "SparseJacobian", "jacobian_dense", "jacobian_operator"]
