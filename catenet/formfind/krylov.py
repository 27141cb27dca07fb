"""The damped Gauss-Newton step of form finding's targets by conjugate residuals (``cr``),
with the factors of the free nodes' matrix D = C_f^T Q C_f that the shape was found with.

The step p of min |J p + r|^2 + mu |p|^2, J = Rq - Rx A^-1 Bs (``catenet.formfind.
adjoint``), solves the smaller of two symmetric positive definite systems: with fewer rows
than variables (J J^T + mu I) z = -r, p = J^T z (the rows' system); else (J^T J + mu I) p
= -J^T r. Each product with J or J^T is one solve with A, exact (``Exact``): without
self-weight A = I_3 (x) D, one back-substitution per coordinate; the self-weight g m(x),
whose masses change with the edges' lengths, adds A = I_3 (x) D - g (x) G with G (n_f x
3 n_f), so in the frame (e1, e2, g/|g|) the two coordinates across g are D's and the one
along it is Z = D - |g| G_g's (G_g = G's columns along g, n_f x n_f, factorised once per
gradient by SuperLU): three back-substitutions per solve, no fixed point.

Where every row reads the position of its own free node (a surface, a coordinate of every
free node) the rows' system is preconditioned: moving D^-1 past the rows' per-node
directions N (N A^-1 ~ D^-1 N, exact where N is the same at neighbouring nodes and the
weight is light) gives J J^T ~ D^-1 E E^T D^-1 with E = N Bs, sparse (D's pattern), so
M^-1 = D (E E^T + mu D^2)^-1 D (exact in its mu part): one sparse Cholesky factorisation
of D's size per step (``Fixed``: D^2's pattern, made and analysed once per search).

Below ``FROM_DOFS`` free DOFs the direct step is the faster (benchmarks/targets.py: the
saddle point is small, the back-substitutions' fixed cost large) and is taken at once.
Without that preconditioner the iterations are tried only on a system of at most
``MAX_ITER`` unknowns (the iterations then end within about that many); a larger one
takes the direct step at once. The iterations stop at the relative residual ``eta`` the
caller asks (the forcing term of an inexact Levenberg-Marquardt), at most ``MAX_ITER``
(conjugate residuals, ``cr``: each iteration minimises the preconditioned residual);
the residual is then recomputed from the products and the step accepted only where it is
finite and within ``eta`` (they aim at ``eta`` / ``MARGIN``), else ``NotConverged`` says
why and the caller takes the direct step
(``catenet.formfind.damped``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import SingularSystemError

if TYPE_CHECKING:
    from catenet.formfind.adjoint import SparseJacobian

ENABLED = True  # False: every damped step direct (benchmarks/targets.py --direct)
FROM_DOFS = 3000  # free DOFs from which the steps are iterative (below, direct: faster)
MAX_ITER = 300  # iterations at most (then the direct step)
MARGIN = 4.0  # the iterations aim at eta / MARGIN; the step is accepted within eta


class NotConverged(Exception):
    """The iterative step did not reach its tolerance (the message says how far)."""


class Exact:
    """A^-1 and A^-T with D's factors (refactorised where the shape's solver has moved on
    to another state's q), the self-weight by Z's factors (see the module docstring)."""

    def __init__(self, adj):
        self.adj, self.shape = adj, adj.shape
        self.nf = adj.nf
        self.refactorizations = 0
        self.current()
        self.z_lu: Any = None
        if adj.gx is not None:
            self._weight()

    def current(self) -> None:
        """D's factors at this state's q: the shape's solver refactorised where it moved
        on (a refused trial's shape came since)."""
        shape, q = self.shape, self.adj.q
        now = getattr(shape, "factored", None)
        if now is q or (now is not None and np.array_equal(now, q)):
            return
        shape.solver.factorize(shape.pattern.values(q))  # (a refused trial's factors)
        shape.factored, shape.checked = q, False
        self.refactorizations += 1

    def _weight(self) -> None:
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        g = np.asarray(self.shape.gravity, dtype=np.float64)
        norm = float(np.linalg.norm(g))
        hat = g / norm
        c = int(np.argmax(np.abs(g)))
        val, row, col = self.adj.gx_coo  # rows 3 i + k of G_x: g_k times G's row i
        on = row % 3 == c
        val, i, j, axis = val[on] / g[c], row[on] // 3, col[on] // 3, col[on] % 3
        other = np.eye(3)[np.argsort(np.abs(hat))[:2]]
        e1 = other[0] - hat * (other[0] @ hat)
        e1 /= np.linalg.norm(e1)
        self.frame = np.vstack([e1, np.cross(hat, e1), hat])  # rows: e1, e2, g/|g|
        self.g = norm
        shape = (self.nf, self.nf)
        part = [sp.csr_matrix((val * f[axis], (i, j)), shape=shape) for f in self.frame]
        self.g1, self.g2, gg = part
        self.g1t, self.g2t = self.g1.T.tocsr(), self.g2.T.tocsr()
        p = self.shape.pattern
        d = sp.csr_matrix((p.values(self.adj.q), p.indices, p.indptr), shape=(self.nf,) * 2)
        z = (d + sp.triu(d, k=1).T - norm * gg).tocsc()
        try:
            self.z_lu = splu(z, permc_spec="MMD_AT_PLUS_A")
        except RuntimeError:
            raise SingularSystemError("form finding: the self-weight's Z is singular") from None

    def _d(self, w: np.ndarray) -> np.ndarray:
        out = self.shape.solve(w)
        if not np.all(np.isfinite(out)):
            raise SingularSystemError("form finding: a solve with D is not finite")
        return out

    def _z(self, w: np.ndarray, trans: str) -> np.ndarray:
        out: np.ndarray = self.z_lu.solve(w, trans=trans)
        if not np.all(np.isfinite(out)):
            raise SingularSystemError("form finding: a solve with Z is not finite")
        return out

    def solve(self, w: np.ndarray) -> np.ndarray:
        """A^-1 w, w (3 n_f,) with the DOFs interleaved."""
        w3 = w.reshape(self.nf, 3)
        if self.z_lu is None:
            return self._d(w3).ravel()
        f = w3 @ self.frame.T  # (e1, e2, g) components
        y12 = self._d(f[:, :2])
        yg = self._z(f[:, 2] + self.g * (self.g1 @ y12[:, 0] + self.g2 @ y12[:, 1]), "N")
        return (np.column_stack([y12, yg]) @ self.frame).ravel()

    def solve_t(self, w: np.ndarray) -> np.ndarray:
        """A^-T w."""
        w3 = w.reshape(self.nf, 3)
        if self.z_lu is None:
            return self._d(w3).ravel()
        f = w3 @ self.frame.T
        yg = self._z(f[:, 2], "T")
        rhs = f[:, :2] + self.g * np.column_stack([self.g1t @ yg, self.g2t @ yg])
        return (np.column_stack([self._d(rhs), yg]) @ self.frame).ravel()


class Rows:
    """The rows' preconditioner M^-1 = D (E E^T + mu D^2)^-1 D (module docstring),
    where every row reads one free node of its own and every free node has one; None
    from ``make`` elsewhere."""

    def __init__(self, jac: SparseJacobian, node: np.ndarray):
        import scipy.sparse as sp

        p = jac.adj.shape.pattern
        d = sp.csr_matrix((p.values(jac.adj.q), p.indices, p.indptr), shape=(p.n_free,) * 2)
        d = (d + sp.triu(d, k=1).T).tocsr()
        self.d_rows = d[node][:, node].tocsr()  # D in the rows' order
        self.e = (jac.d_x @ jac.bs).tocsr()
        self.dd: Any = None  # D^2 in the rows' order
        kept = jac.kept.get("rows")  # (the factors of the last state's: its analysis)
        if kept is None or not np.array_equal(kept.node, node):
            kept = jac.kept["rows"] = Fixed(self.d_rows, node, jac.adj.shape)
        self.factors = kept

    @staticmethod
    def make(jac: SparseJacobian) -> Rows | None:
        d_x, rq = jac.d_x, jac.rq
        rows, n3 = d_x.shape
        if rows != n3 // 3 or np.any(rq.data) or np.any(np.diff(d_x.indptr) == 0):
            return None
        if np.any(np.add.reduceat(np.abs(d_x.data), d_x.indptr[:-1]) == 0):
            return None  # (a row inside its range: D^-1 does not commute past a subset)
        node = d_x.indices // 3
        first = node[d_x.indptr[:-1]]
        if np.any(node != np.repeat(first, np.diff(d_x.indptr))):
            return None  # (a row reads two nodes)
        if len(np.unique(first)) != rows:
            return None
        return Rows(jac, first)

    def factorize(self, mu: float, keep: np.ndarray) -> None:
        import scipy.sparse as sp

        e = self.e @ sp.diags(keep.astype(np.float64))
        ee = (e @ e.T).tocsr()
        floor = 1e-12 * float(ee.diagonal().max(initial=0.0))  # (a node no edge moves)
        if self.dd is None:
            self.dd = (self.d_rows @ self.d_rows).tocsr()
        s = ee + mu * self.dd + sp.identity(ee.shape[0]) * floor
        try:
            self.factors.factorize(s)
        except SingularSystemError:
            raise NotConverged("its preconditioner is singular") from None

    def __call__(self, z: np.ndarray) -> np.ndarray:
        return self.d_rows @ self.factors.solve(self.d_rows @ z)


class Fixed:
    """The rows' preconditioner's matrix (symmetric positive definite) on a pattern made
    once per search (D^2's: every pair of nodes two edges apart), factorised by the linear
    solver layer (PARDISO: its analysis once), refilled per step."""

    def __init__(self, d_rows, node: np.ndarray, shape):
        import scipy.sparse as sp

        from catenet.solver.linear import make_solver

        ones = d_rows.copy()
        ones.data[:] = 1.0
        upper = sp.triu(ones @ ones).tocsr()  # (positive: no entry cancels)
        upper.sort_indices()
        n = self.n = upper.shape[0]
        self.node = node
        rows = np.repeat(np.arange(n), np.diff(upper.indptr))
        self.keys = rows * n + upper.indices  # (sorted: CSR by rows, columns sorted)
        net_node = shape.pattern.free_nodes[node]  # (errors name the net's nodes)
        self.solver = make_solver(
            shape.backend, upper.indptr, upper.indices, upper=True, dof_node=net_node, mtype=2
        )

    def factorize(self, m) -> None:
        """Factorises the symmetric m (its upper triangle on the pattern)."""
        m = m.tocoo()
        up = m.row <= m.col
        key = m.row[up].astype(np.int64) * self.n + m.col[up]
        pos = np.minimum(np.searchsorted(self.keys, key), len(self.keys) - 1)
        if np.any(self.keys[pos] != key):
            raise SingularSystemError("form finding: the preconditioner left its pattern")
        self.solver.factorize(np.bincount(pos, m.data[up], len(self.keys)))

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.solver.solve(b)


def cr(apply, b: np.ndarray, eta: float, precondition=None) -> tuple[np.ndarray, int]:
    """x of A x = b (A symmetric positive definite, ``apply``: x -> A x) by conjugate
    residuals (preconditioned by the symmetric positive definite ``precondition``, P):
    each iteration minimises the residual's P-norm over its Krylov space, where
    conjugate gradients minimise the error's A-norm and let the residual wander, so a
    loose tolerance on the residual (an inexact step's ``eta``) is met in fewer
    iterations (measured, not guaranteed where P is not the identity: the residual's
    2-norm may then rise): the hypar of 10224 force densities on its surface takes 422
    where conjugate gradients took 554, and 221 where they took 287 on the smooth surface
    (the same steps and gradients; Saad, Iterative Methods for Sparse Linear Systems,
    6.8).
    One product with A and one with P per iteration, as CG. To the relative residual
    eta / MARGIN, then recomputed (within eta, finite); the iterations taken.
    NotConverged where it does not get there."""
    x = np.zeros_like(b)
    norm_b = float(np.linalg.norm(b))
    if norm_b == 0.0:
        return x, 0
    goal = eta / MARGIN * norm_b
    apply_p = precondition if precondition is not None else (lambda v: v)
    res = b.copy()
    z = np.array(apply_p(res))  # (a copy: without a preconditioner, P res is res)
    d = z.copy()
    az = apply(z)
    ad = az.copy()
    zaz = float(z @ az)
    it = 0
    while it < MAX_ITER:
        q = apply_p(ad)  # P A d
        dapad = float(ad @ q)
        if not (np.isfinite(dapad) and dapad > 0.0 and np.isfinite(zaz) and zaz > 0.0):
            raise NotConverged(
                f"the operator or its preconditioner is not positive definite "
                f"(d.A.P.A.d = {dapad:.3g}, z.A.z = {zaz:.3g})"
            )
        alpha = zaz / dapad
        x += alpha * d
        res -= alpha * ad
        z -= alpha * q
        it += 1
        if float(np.linalg.norm(res)) <= goal:
            break
        az = apply(z)
        zaz, old = float(z @ az), zaz
        beta = zaz / old
        d = z + beta * d
        ad = az + beta * ad
    true = float(np.linalg.norm(b - apply(x)))
    if not (np.all(np.isfinite(x)) and true <= eta * norm_b):
        raise NotConverged(
            f"relative residual {true / norm_b:.2e} after {it} iterations (tolerance {eta:.1e})"
        )
    return x, it


def worth_trying(jac: SparseJacobian, rows: Rows | None) -> bool:
    """Whether the iterative step is tried (module docstring): a net of ``FROM_DOFS``
    free DOFs or more, preconditioned, or a system of at most MAX_ITER unknowns."""
    if not ENABLED or jac.adj.n3 < FROM_DOFS:
        return False
    return rows is not None or min(jac.shape) <= MAX_ITER


def step(jac: SparseJacobian, exact: Exact, r, mu, keep, eta, rows) -> tuple[np.ndarray, int]:
    """The damped step to the relative residual eta (module docstring), and the
    iterations; ``rows``: the rows' preconditioner (``Rows.make``) or None."""
    k = keep.astype(np.float64)
    jv, jtz = jac.matvec, jac.rmatvec

    n_rows, n_var = jac.shape
    if n_rows <= n_var:
        if rows is not None:
            rows.factorize(mu, keep)
        z, it = cr(lambda z: jv(k * jtz(z)) + mu * z, -r, eta, rows)
        p = k * jtz(z)
    else:
        p, it = cr(lambda v: k * jtz(jv(k * v)) + mu * v, -(k * jtz(r)), eta)
        p *= k
    if not np.all(np.isfinite(p)):
        raise NotConverged("the step is not finite")
    return p, it


__all__ = [
    "ENABLED",
    "FROM_DOFS",
    "MAX_ITER",
    "Exact",
    "NotConverged",
    "Rows",
    "cr",
    "step",
    "worth_trying",
]
