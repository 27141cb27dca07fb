"""The derivatives of form finding's targets with respect to the force densities, by the
adjoint of the force-density equilibrium.

The free nodes are in equilibrium, R(x, q) = C_f^T Q C x - P(x, q) = 0, with the loads P
(constant, or the self-weight g rho l0 / 2 per edge end, which changes with the shape and
with q). Differentiating, A dx + Bg dq = 0 with A = dR/dx = I_3 (x) D - G_x and
Bg = dR/dq = B - G_q, where D = C_f^T Q C_f (the free nodes' matrix, the fixed ones
eliminated), B's column e holds -u_e at the edge's first free end and +u_e at its second,
and G the weight's derivatives (``catenet.formfind.newton.weight_jacobian``). A target's
residual r(x, q) then changes by

    dr/dq = r_q - r_x A^-1 Bg,

so J^T z (the gradient of 1/2 |r|^2 for z = r) costs one adjoint solve A^T y = r_x^T z,
J v one solve A y = Bg v, and the whole Jacobian min(rows, variables) solves. Every solve
is with the factors of D that the shape was just found with (each coordinate one
back-substitution): without self-weight A is I_3 (x) D; with it, A y = w is the fixed
point y = (I_3 (x) D)^-1 (w + G_x y), whose rate is that of the self-weight's own fixed
point in finding the shape (``catenet.formfind.fdm``), so it converges where the shape
did; where it converges slowly (``SLOW``), A is factorised once by SuperLU. Nothing is
differenced.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import SingularSystemError

if TYPE_CHECKING:
    import scipy.sparse as sp

    from catenet.formfind.fdm import _Shape

log = logging.getLogger(__name__)

FIXED_POINT_ITER = 200  # the self-weight's share of an adjoint solve: iterations at most
# A fixed point whose change falls by less than SLOW per iteration (after SLOW_AFTER of
# them) needs more than 50 for round-off: the adjoint is then factorised by SuperLU (where
# the weight dominates the force densities: the shape's own fixed point is slow there too).
SLOW, SLOW_AFTER = 0.5, 3


class Adjoint:
    """The linearised equilibrium at one state (q, x): ``solve`` (A^-1), ``solve_t``
    (A^-T), ``bg`` (dR/dq, sparse (3 n_f, M)) and the COO triplets of A and Bg that the
    damped step (``catenet.formfind.damped``) assembles."""

    def __init__(self, shape: _Shape, q: np.ndarray, x: np.ndarray):
        import scipy.sparse as sp

        from catenet.formfind.newton import weight_jacobian

        self.shape, self.q = shape, q
        p, net = shape.pattern, shape.net
        self.nf = nf = p.n_free
        self.n3 = n3 = 3 * nf
        u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
        rows, cols, vals = [], [], []
        for f, sign in ((p.a, -1.0), (p.b, 1.0)):
            e = np.flatnonzero(f >= 0)
            for c in range(3):
                rows.append(3 * f[e] + c)
                cols.append(e)
                vals.append(sign * u[e, c])
        self.gx: sp.csr_matrix | None = None
        gx_coo = (np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int64))
        if shape.weighs:
            length = np.linalg.norm(u, axis=1)
            wv, (wr, wc) = weight_jacobian(shape, q, u, length, np.zeros(0, dtype=np.int64))
            on_q = wc >= n3
            rows.append(wr[on_q])
            cols.append(wc[on_q] - n3)
            vals.append(-wv[on_q])
            on_x = ~on_q
            gx_coo = (wv[on_x], wr[on_x], wc[on_x])
            self.gx = sp.csr_matrix((gx_coo[0], (gx_coo[1], gx_coo[2])), shape=(n3, n3))
        self.bg_coo = (np.concatenate(vals), np.concatenate(rows), np.concatenate(cols))
        self.gx_coo = gx_coo
        self.bg: sp.csr_matrix = sp.csr_matrix(
            (self.bg_coo[0], (self.bg_coo[1], self.bg_coo[2])), shape=(n3, net.n_edges)
        )
        self._lu: Any = None  # SuperLU of A: only where the fixed point fails

    def a_coo(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A = I_3 (x) D - G_x as COO (values, rows, columns), always in the same order
        (D's pattern for each coordinate, both triangles, then G_x's entries)."""
        p = self.shape.pattern
        d = p.values(self.q)
        rows = np.repeat(np.arange(p.n_free), np.diff(p.indptr))
        cols = p.indices
        off = rows != cols
        r = np.concatenate([rows, cols[off]])
        c = np.concatenate([cols, rows[off]])
        dv = np.concatenate([d, d[off]])
        gv, gr, gc = self.gx_coo
        return (
            np.concatenate([np.tile(dv, 3), -gv]),
            np.concatenate([3 * r + k for k in range(3)] + [gr]),
            np.concatenate([3 * c + k for k in range(3)] + [gc]),
        )

    def solve(self, w: np.ndarray) -> np.ndarray:
        """A^-1 w for w (3 n_f,) or (3 n_f, k)."""
        return self._solve(w, None if self.gx is None else self.gx)

    def solve_t(self, w: np.ndarray) -> np.ndarray:
        """A^-T w."""
        return self._solve(w, None if self.gx is None else self.gx.T.tocsr(), trans=True)

    def _solve(self, w: np.ndarray, gx, trans: bool = False) -> np.ndarray:
        w = np.asarray(w, dtype=np.float64)
        y = self._by_coordinate(w)
        if gx is None:
            return y
        scale = float(np.max(np.abs(y), initial=0.0))
        last = np.inf
        for k in range(FIXED_POINT_ITER):
            new = self._by_coordinate(w + (gx @ y).reshape(w.shape))
            change = float(np.max(np.abs(new - y), initial=0.0))
            y = new
            if change <= 1e-14 * max(scale, float(np.max(np.abs(y), initial=0.0)), 1e-300):
                return y
            if k >= SLOW_AFTER and change > SLOW * last:  # (the weight dominates: LU)
                break
            last = change
        return self._superlu(w, trans)

    def _superlu(self, w: np.ndarray, trans: bool) -> np.ndarray:
        """A^-1 w (or A^-T w) by SuperLU: where the self-weight's fixed point is slow."""
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        if self._lu is None:
            v, r, c = self.a_coo()
            a = sp.csc_matrix((v, (r, c)), shape=(self.n3, self.n3))
            try:
                self._lu = splu(a)
            except RuntimeError:
                raise SingularSystemError("form finding: the adjoint system is singular") from None
        out: np.ndarray = self._lu.solve(w, trans="T" if trans else "N")
        if not np.all(np.isfinite(out)):
            raise SingularSystemError("form finding: the adjoint solve is not finite")
        return out

    def _by_coordinate(self, w: np.ndarray) -> np.ndarray:
        """(I_3 (x) D)^-1 w: each coordinate (and column) one solve with D's factors."""
        shape = np.shape(w)
        flat = np.asarray(w, dtype=np.float64).reshape(self.nf, -1)  # (f, c [x k])
        out = self.shape.solve(flat)
        if not np.all(np.isfinite(out)):
            raise SingularSystemError("form finding: the adjoint solve is not finite")
        return out.reshape(shape)


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
    solve), both exact with D's factors (``catenet.formfind.krylov.Exact``), and
    ``damped``: the step p of min |J p + r|^2 + mu |p|^2, by conjugate residuals to a
    relative residual (``catenet.formfind.krylov``) or from one sparse factorisation
    (``catenet.formfind.damped``), the fallback. ``steps``: counts shared between
    states (how the steps went); ``layout``: the direct step's from the last state."""

    def __init__(
        self, adj: Adjoint, d_x, d_q, dq_ds, groups=None, layout=None, steps=None, kept=None
    ):
        self.adj, self.d_x, self.d_q = adj, d_x.tocsr(), d_q.tocsr()
        self.rq = (d_q @ dq_ds).tocsr()
        self.bs = (adj.bg @ dq_ds).tocsr()
        self.shape = (d_x.shape[0], dq_ds.shape[1])
        if groups is None:  # (the variable of each edge, from dq_ds's one entry per row)
            groups = dq_ds.tocsr().indices
        self.groups = np.asarray(groups, dtype=np.int64)
        if layout is not None and not layout.fits(adj, self.d_x, self.d_q, self.groups):
            layout = None
        self.layout = layout
        self.steps = new_steps() if steps is None else steps
        self.kept = {} if kept is None else kept  # (the search's: factors kept between states)
        self._exact: Any = None
        self._rows: Any = False  # (not looked at yet)
        self._t: Any = None  # (the transposes, for rmatvec)

    def exact(self):
        """A's exact solves, with D's factors at this state (refactorised if needed)."""
        from catenet.formfind.krylov import Exact

        if self._exact is None:
            self._exact = Exact(self.adj)
        else:
            self._exact.current()
        return self._exact

    def matvec(self, v: np.ndarray) -> np.ndarray:
        self.steps["products"] += 1
        v = np.ravel(v)
        out = -(self.d_x @ self.exact().solve(self.bs @ v))
        return out + self.rq @ v if self.rq.nnz else out

    def rmatvec(self, z: np.ndarray) -> np.ndarray:
        self.steps["products"] += 1
        z = np.ravel(z)
        if self._t is None:
            self._t = tuple(m.T.tocsr() for m in (self.rq, self.bs, self.d_x))
        rq_t, bs_t, d_x_t = self._t
        out = -(bs_t @ self.exact().solve_t(d_x_t @ z))
        return out + rq_t @ z if rq_t.nnz else out

    def damped(self, r: np.ndarray, mu: float, keep: np.ndarray, eta=None) -> np.ndarray:
        """The damped step (0 where not ``keep``): with ``eta`` by conjugate residuals to
        that relative residual where they are worth trying (``krylov.worth_trying``), the
        direct step where they do not get there (logged, counted); without, or where they
        are not tried, the direct step. SingularSystemError where it has none."""
        import time

        from catenet.formfind import krylov

        steps = self.steps
        if eta is not None and self._rows is False:
            self._rows = krylov.Rows.make(self)
        if eta is not None and krylov.worth_trying(self, self._rows):
            start = time.perf_counter()
            before = 0 if self._exact is None else self._exact.refactorizations
            try:
                exact = self.exact()
                p, it = krylov.step(self, exact, r, mu, keep, eta, self._rows)
                steps["iterative"] += 1
                steps["iterations"] += it
                return p
            except (krylov.NotConverged, SingularSystemError) as exc:
                log.info("form finding: the iterative damped step failed (%s): direct step", exc)
                steps["fallbacks"] += 1
            finally:
                steps["iterative_s"] += time.perf_counter() - start
                if self._exact is not None:
                    steps["refactorizations"] += self._exact.refactorizations - before
        if self.layout is None:
            from catenet.formfind.damped import Layout

            self.layout = Layout(self.adj, self.d_x, self.d_q, self.groups, self.shape[1])
        return self.layout.step(self.adj, self.d_x, self.d_q, r, mu, keep)


def new_steps() -> dict:
    """How the damped steps went: taken by conjugate residuals (``iterative``, their
    ``iterations``, ``iterative_s`` seconds), ``fallbacks`` to the direct step, D
    refactorised for a step after a refused trial (``refactorizations``), and the
    products with J or J^T (``products``: a forward or an adjoint solve each)."""
    return {
        "iterative": 0,
        "iterations": 0,
        "products": 0,
        "iterative_s": 0.0,
        "fallbacks": 0,
        "refactorizations": 0,
    }


def jacobian_operator(
    adj: Adjoint, d_x, d_q, dq_ds, groups=None, layout=None, steps=None, kept=None
) -> SparseJacobian:
    """J = dr/ds as a SparseJacobian (see there); ``layout``: the damped step's from the
    last state, kept where it fits (its symbolic analysis reused); ``steps``: the counts
    of the search's damped steps; ``kept``: the search's dict of factors kept between
    states (the preconditioner's, ``catenet.formfind.krylov.Fixed``)."""
    return SparseJacobian(adj, d_x, d_q, dq_ds, groups, layout, steps, kept)


__all__ = ["Adjoint", "SparseJacobian", "jacobian_dense", "jacobian_operator", "new_steps"]
