"""Newton on the force densities: target lengths or forces met to round-off.

The unknowns are s = log q (q stays positive). For force densities q the free nodes sit
at D x_f = p_f - C_f^T Q C_x x_x (``fdm``), with u = C x the edge vectors and L = |u|.
Differentiating the equilibrium C_f^T Q u = p_f (loads held) gives

    D dx_c + C_f^T diag(u_c) dq = 0,   c = x, y, z,

and the lengths change by dL = diag(1/L) sum_c diag(u_c) C_f dx_c. With
B = [C_f^T diag(u_x); C_f^T diag(u_y); C_f^T diag(u_z)] (3 n_f x M) and D3 = I_3 (x) D,
so that dx = -D3^-1 B dq, the Newton step on r = log(L / L_target) (d log L = -r) is the
sparse symmetric (saddle-point) system

    [ D3    B ] [dx]   [    0     ]
    [ B^T   G ] [dq] = [ -L^2 r   ]        G = 0 for target lengths,

and for target forces (N = q L, r = log(N / N_target), d log N = dq / q + dL / L = -r)
the same with G = diag(L^2 / q). Eliminating dx gives back the Jacobian of the lengths,
-diag(1/L) B^T D3^-1 B, without forming it: one sparse factorisation (PARDISO, symmetric
indefinite, or SuperLU) per iteration, whose pattern comes from the topology once. The
step is damped (Levenberg style) until it changes no q by more than a factor e and
lowers the sum of squared misses (Armijo): G gains -mu L^2 / q for lengths, mu L^2 / q
for forces, which bends the step from Newton's (mu = 0) to the classical update
q <- q (L / L_target) or q (N_target / N) as mu grows; mu falls by 3 after each step
taken and grows by 4 after each refused. Edges between two fixed nodes keep their length
and their q does not act: they leave the system (dq = 0). Without loads, target lengths
fix q only up to a common factor: one edge's dq is held at 0 (the caller restores the
mean). Where the net weighs, its load g rho l0 / 2 per edge end changes with the shape
and with q (l0 = L / (1 + eps(q L))): ``weight_jacobian`` adds that to the first block
row (dP = G_x dx + G_q dq), and the then unsymmetric system goes to SuperLU.

A step that cannot lower the misses, or a singular system, means the targets cannot all
be met (``Stalled``, with the best state reached).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from catenet.errors import ConfigError, ConvergenceError, SingularSystemError

if TYPE_CHECKING:
    from catenet.formfind.fdm import _Shape
    from catenet.solver.linear import LinearSolver

log = logging.getLogger(__name__)

MAX_STEP = 1.0  # no force density changes by more than a factor e per step
ARMIJO = 1e-4  # a step must lower the sum of squared misses by this fraction
MU_MIN, MU_MAX = 1e-9, 1e10  # the damping's range


class Stalled(Exception):
    """Newton could not lower the misses further: ``best`` = (x, load, q, r) at the
    smallest miss reached, ``iterations`` spent, ``why`` in words."""

    def __init__(self, why: str, best, iterations: int):
        super().__init__(why)
        self.why, self.best, self.iterations = why, best, iterations


class Kkt:
    """The saddle-point matrix's pattern (upper triangle, CSR) from the topology, its
    values from q, u, L each iteration, and its factorisation."""

    def __init__(self, pattern, backend: str, held: np.ndarray):
        p = pattern
        nf, m = p.n_free, len(p.a)
        self.nf, self.m, self.n = nf, m, 3 * nf + m
        a, b = p.a, p.b
        self.held = held  # edges whose dq is 0 (both ends fixed; the scale edge)
        ea, eb = np.flatnonzero(a >= 0), np.flatnonzero(b >= 0)
        eo = np.flatnonzero((a >= 0) & (b >= 0))
        lo, hi = np.minimum(a[eo], b[eo]), np.maximum(a[eo], b[eo])
        rows, cols = [], []
        for c in range(3):  # D per coordinate: q on both diagonals, -q off
            rows += [3 * a[ea] + c, 3 * b[eb] + c, 3 * lo + c]
            cols += [3 * a[ea] + c, 3 * b[eb] + c, 3 * hi + c]
        for c in range(3):  # B: -u_c at the first free end, +u_c at the second
            rows += [3 * a[ea] + c, 3 * b[eb] + c]
            cols += [3 * nf + ea, 3 * nf + eb]
        diag = np.arange(self.n)  # every diagonal (G, and zeros PARDISO wants present)
        rows.append(diag)
        cols.append(diag)
        keys, self._slot = np.unique(
            np.concatenate(rows) * self.n + np.concatenate(cols), return_inverse=True
        )
        r_u, c_u = keys // self.n, keys % self.n
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(r_u, minlength=self.n))])
        self.indices = c_u
        self.nnz = len(keys)
        self._ea, self._eb, self._eo = ea, eb, eo
        node = np.concatenate([np.repeat(p.free_nodes, 3), p.net.edges[:, 0]])
        self.backend = backend
        self.solver: LinearSolver | None = None
        if backend == "pardiso":
            from catenet.solver.linear import make_solver

            solver: Any = make_solver(
                backend, self.indptr, self.indices, upper=True, dof_node=node, mtype=-2
            )
            solver.iparm[10] = 1  # scaling and weighted matching: saddle points
            solver.iparm[12] = 1
            self.solver = solver
        self.factorizations = 0

    def values(self, q, u, g) -> np.ndarray:
        ea, eb, eo = self._ea, self._eb, self._eo
        keep = np.ones(self.m)
        keep[self.held] = 0.0
        d = [q[ea], q[eb], -q[eo]] * 3
        bv = []
        for c in range(3):
            bv += [-u[ea, c] * keep[ea], u[eb, c] * keep[eb]]
        gd = np.concatenate([np.zeros(3 * self.nf), g])
        gd[3 * self.nf + self.held] = 1.0
        vals = np.concatenate([*d, *bv, gd])
        return np.bincount(self._slot, weights=vals, minlength=self.nnz)

    def solve(self, q, u, g, rhs, weight=None) -> np.ndarray:
        data = self.values(q, u, g)
        self.factorizations += 1
        if weight is not None:  # the weight's share: unsymmetric, SuperLU
            return self._superlu(data, rhs, weight)
        if self.solver is not None:
            try:
                self.solver.factorize(data)
                return self.solver.solve(rhs)
            except SingularSystemError:
                log.debug("form finding: PARDISO on the Newton system failed: SuperLU")
        return self._superlu(data, rhs)

    def _superlu(self, data, rhs, weight=None):
        import scipy.sparse as sp

        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
        a = a + sp.triu(a, k=1).T
        if weight is not None:
            a = a - sp.coo_matrix(weight, shape=(self.n, self.n)).tocsr()
        return superlu_solve(a.tocsc(), rhs)


def superlu_solve(a, rhs: np.ndarray) -> np.ndarray:
    """x of a x = rhs (a: SciPy CSC) by SciPy's SuperLU, refined twice on a (a saddle
    point is often badly scaled); SingularSystemError where a is singular or x is not
    finite."""
    from scipy.sparse.linalg import splu

    try:
        lu = splu(a)
    except RuntimeError as exc:  # exactly singular
        raise SingularSystemError(f"SciPy: {exc}") from None
    x = lu.solve(rhs)
    for _ in range(2):
        x += lu.solve(rhs - a @ x)
    if not np.all(np.isfinite(x)):
        raise SingularSystemError("the system is singular (its solution is not finite)")
    return x


def newton(
    shape: _Shape,
    method: str,
    target: np.ndarray,
    q0: np.ndarray,
    tol: float,
    max_iter: int,
    scale_free: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, float]:
    """Force densities meeting ``target`` (lengths or forces per edge) to the relative
    ``tol``: (x, load, q, iterations, miss). Raises Stalled (see the module docstring)
    or, after ``max_iter`` evaluations, Stalled with why = "max_iter"."""
    p = shape.pattern
    both_fixed = (p.a < 0) & (p.b < 0)
    targets = _Targets(shape, target, method == "forces", ~both_fixed, tol)
    s = np.log(q0)
    now = targets.state(s)
    if now is None:
        raise Stalled("the starting force densities give no shape", None, 1)
    iterations = 1
    if both_fixed.any() and _miss(now.r[both_fixed]) > tol:
        raise Stalled("an edge between two fixed nodes keeps its length", _best(now), iterations)
    held = np.flatnonzero(both_fixed)
    if scale_free:  # a common factor of q changes nothing: hold one edge's q
        free_edges = np.flatnonzero(targets.active)
        held = np.append(held, free_edges[np.argmax(now.q[free_edges])])
    search = _Search(targets, Kkt(p, shape.backend, held), held, scale_free, max_iter)
    mu = MU_MIN
    while True:
        if _miss(now.r) <= tol:
            shape.kkt_factorizations = search.kkt.factorizations
            return now.x, now.load, now.q, iterations, _miss(now.r)
        step, now, mu, iterations = search.damped(s, now, mu, iterations)
        mu = max(mu / 3.0, MU_MIN)
        s = s + step
        log.debug(
            "form finding: Newton %d: largest miss %.3e (damping %.3g)",
            iterations,
            _miss(now.r),
            mu,
        )


class _State(NamedTuple):
    """Force densities ``q``, the shape ``x`` they give with its ``load``, the edge
    vectors ``u``, their ``length`` and the misses ``r`` (the log of what an edge has over
    its target)."""

    q: np.ndarray
    x: np.ndarray
    load: np.ndarray
    u: np.ndarray
    length: np.ndarray
    r: np.ndarray


@dataclass(frozen=True)
class _Targets:
    """What Newton meets: ``target`` lengths (or forces, ``forces``) of the ``shape``'s
    ``active`` edges (not between two fixed nodes) to the relative ``tol``."""

    shape: _Shape
    target: np.ndarray
    forces: bool
    active: np.ndarray
    tol: float

    def state(self, s: np.ndarray) -> _State | None:
        """The state at force densities exp(s); None where there is no shape (a step too
        far: the caller halves it) or an active edge has no length."""
        q = np.exp(np.clip(s, -700.0, 700.0))
        try:
            x, load = self.shape(q)
        except (SingularSystemError, ConvergenceError, ConfigError):
            return None  # a step too far: the caller halves it
        net, active = self.shape.net, self.active
        u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
        length = np.linalg.norm(u, axis=1)
        if not np.all(length[active] > 0):
            return None
        got = q * length if self.forces else length
        r = np.log(got / self.target)
        return _State(q, x, load, u, length, r)

    def merit(self, r: np.ndarray) -> float:
        """Half the sum of the active edges' squared misses."""
        return 0.5 * float(r[self.active] @ r[self.active])


def _miss(r: np.ndarray) -> float:
    """The largest relative miss |got / target - 1| of the misses r."""
    return float(np.max(np.abs(np.expm1(r))))


@dataclass(frozen=True)
class _Search:
    """Newton's steps towards the ``targets`` on the saddle-point system ``kkt``: ``held``
    the edges whose dq is 0, ``scale_free`` (the steps' mean taken out), at most
    ``max_iter`` evaluations."""

    targets: _Targets
    kkt: Kkt
    held: np.ndarray
    scale_free: bool
    max_iter: int

    def damped(
        self, s: np.ndarray, now: _State, mu: float, iterations: int
    ) -> tuple[np.ndarray, _State, float, int]:
        """(step, state, damping, iterations) of the step from s (the state ``now``),
        damped from ``mu`` until it lowers the misses; raises Stalled where none does."""
        targets, n3 = self.targets, 3 * self.kkt.nf
        f0 = targets.merit(now.r)
        rhs = np.zeros(self.kkt.n)
        rhs[n3:] = -(now.length**2) * now.r
        rhs[n3 + self.held] = 0.0
        while True:  # damped until the misses fall
            if iterations >= self.max_iter:
                raise Stalled("max_iter", _best(now), iterations)
            step = self.step(now, rhs, mu)
            if step is not None and float(np.max(np.abs(step))) <= MAX_STEP:
                trial = targets.state(s + step)
                iterations += 1
                if trial is not None and (
                    targets.merit(trial.r) <= (1.0 - ARMIJO) * f0 or _miss(trial.r) <= targets.tol
                ):
                    return step, trial, mu, iterations
            mu = max(4.0 * mu, MU_MIN)
            if mu > MU_MAX:
                why = "no step on the force densities lowers the misses further"
                raise Stalled(why, _best(now), iterations)

    def step(self, now: _State, rhs: np.ndarray, mu: float) -> np.ndarray | None:
        """The step on s = log q from ``now`` with the damping ``mu`` (None where the
        system is singular or the step not finite)."""
        shape, n3 = self.targets.shape, 3 * self.kkt.nf
        q, u, length = now.q, now.u, now.length
        g = (1.0 + mu) * length**2 / q if self.targets.forces else -mu * length**2 / q
        try:
            weight = weight_jacobian(shape, q, u, length, self.held) if shape.weighs else None
            step = self.kkt.solve(q, u, g, rhs, weight)[n3:] / q
        except SingularSystemError:
            return None
        if not np.all(np.isfinite(step)):
            return None
        if self.scale_free:
            step -= np.mean(step)
        return step


def weight_coefficients(shape, q, length) -> tuple[np.ndarray, np.ndarray]:
    """(a, c) per edge: the change of half its mass, rho l0 / 2 = a dL + c dq, with
    l0 = L / (1 + eps(q L)) (see ``weight_jacobian``)."""
    net = shape.net
    tension = q * length
    eps = net.law.strain_for_tension(tension, net.EA)
    h = 1e-6
    slope = (
        net.law.strain_for_tension(tension * (1 + h), net.EA)
        - net.law.strain_for_tension(tension * (1 - h), net.EA)
    ) / (2 * h * tension)
    den = (1.0 + eps) ** 2
    half = 0.5 * net.line_density
    return half * (1.0 + eps - tension * slope) / den, half * (-(length**2) * slope) / den


def weight_jacobian(shape, q, u, length, held):
    """The self-weight's change with the unknowns, as COO (values, (rows, cols)) in the
    first block row: dP_f = G_x dx + G_q dq. The load at a free end of edge e is
    g rho_e l0_e / 2 with l0 = L / (1 + eps(N)), N = q L, so that dl0 = a dL + c dq with
    a = (1 + eps - N eps') / (1 + eps)^2, c = -L^2 eps' / (1 + eps)^2 and dL = n . (dx_b -
    dx_a), n = u / L."""
    p = shape.pattern
    n3 = 3 * p.n_free
    a, c = weight_coefficients(shape, q, length)
    c[held] = 0.0
    n = u / length[:, None]
    g = np.asarray(shape.gravity, dtype=np.float64)
    vals, rows, cols = [], [], []
    ends = ((p.a, -1.0), (p.b, 1.0))
    for i, _ in ends:  # the row node: a free end that carries half the weight
        ei = np.flatnonzero(i >= 0)
        for cc in range(3):
            rows.append(3 * i[ei] + cc)
            cols.append(n3 + ei)
            vals.append(g[cc] * c[ei])
            for j, sign in ends:  # the column node: a free end whose motion changes L
                ej = ei[j[ei] >= 0]
                for d in range(3):
                    rows.append(3 * i[ej] + cc)
                    cols.append(3 * j[ej] + d)
                    vals.append(g[cc] * a[ej] * sign * n[ej, d])
    return np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))


def _best(now: _State) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x, load, q, r) of a state."""
    return now.x, now.load, now.q, now.r
