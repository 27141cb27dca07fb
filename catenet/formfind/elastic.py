"""Rest lengths that reach form finding's targets under the elastic equilibrium
(``formfind.method = "elastic"``): a stay whose sag under its own weight is given.

The design variables are s = log c, a factor c on the rest lengths l0 of each cable
(``vary = "cables"``, the default here; a cable case is one cable) or of each edge; the
start is the case's own rest lengths. Each evaluation is catenet's static equilibrium of
the net with those rest lengths (the one solve path, from the last equilibrium), under
its loads, its self-weight included (the mass rho A l0 / 2 per edge end follows l0).

Derivatives by the adjoint of that equilibrium. The free DOFs satisfy R(x, l0) =
grad U(x, l0) - F(l0) = 0, so K dx + (dR/dl0) dl0 = 0 with K the tangent stiffness (the
Hessian of the energy at the equilibrium). Under the linear law an edge pulls its ends
with N t, N = EA (L / l0 - 1) (0 when slack under tension_only), so dR/dl0_e is
-EA L / l0^2 t at its second end and the opposite at its first, less the change of its
weight, rho A g / 2 at each end. A target's row r then changes by dr/ds = -r_x K^-1
(dR/dl0) diag(l0) P: one solve with K per variable or per row, whichever are fewer
(the whole Jacobian; few variables here). Levenberg-Marquardt (``levenberg``) drives it.
Targets here are nodes' positions (x, y, z, point, surface).
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from catenet.errors import ConfigError, ConvergenceError, SingularSystemError

log = logging.getLogger(__name__)


class _Equilibria:
    """The elastic equilibrium for rest-length factors (one per group), warm-started."""

    def __init__(self, scene, settings, groups: np.ndarray):
        self.scene, self.settings, self.groups = scene, settings, groups
        self.l0 = scene.net.rest_length.copy()
        self.x = scene.net.nodes.copy()
        self.key: bytes | None = None
        self.solves = 0

    def __call__(self, s: np.ndarray):
        """(net, x) of the factors exp(s); the state is kept for the Jacobian."""
        from catenet.solver.path import Start, solve

        key = s.tobytes()
        if key != self.key:
            self.key = None
            c = np.exp(np.clip(s, -50.0, 50.0))[self.groups]
            net = self.scene.net.replace(rest_length=self.l0 * c)
            scene = dataclasses.replace(self.scene, net=net)
            result = solve(scene, self.settings, start=Start(x=self.x))
            self.solves += 1
            if not result.converged:
                raise ConvergenceError(f"the equilibrium did not converge: {result.message}")
            self.x = np.asarray(result.x).copy()
            self.now = (net, scene, self.x.copy())
            self.key = key
        return self.now

    def jacobian(self, s: np.ndarray, goals) -> np.ndarray:
        """dr/ds (rows, variables) at the equilibrium of s."""
        import scipy.sparse as sp

        from catenet.solver.workspace import Workspace

        net, scene, x = self(s)
        if np.any(net.law.kind != 0):
            raise ConfigError("formfind.method = 'elastic': takes the linear law only")
        ws = Workspace(net, linear="scipy", terms=scene.terms)
        k = ws.system.matrix(ws.system.hessian(x)).tocsc()
        index = np.full(net.n_nodes, -1, dtype=np.int64)
        free = np.flatnonzero(~net.fixed)
        index[free] = np.arange(len(free))
        length = np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1)
        a = goals.achieved(x, np.zeros(net.n_edges), length)
        d_x, _ = goals.partials(x, np.zeros(net.n_edges), a, index, net)
        d_r = _dr_dl0(net, x, scene.loads.gravity, index)  # (3 n_f, M)
        c = np.exp(s)[self.groups]
        m = net.n_edges
        dl0_ds = sp.csr_matrix((self.l0 * c, (np.arange(m), self.groups)), shape=(m, len(s)))
        rhs = (d_r @ dl0_ds).toarray()
        from scipy.sparse.linalg import splu

        try:
            lu = splu(k)
        except RuntimeError:
            raise SingularSystemError("the tangent stiffness is singular") from None
        if d_x.shape[0] <= rhs.shape[1]:
            y = lu.solve(d_x.T.toarray(), trans="T")
            return -(rhs.T @ y).T
        return np.asarray(-(d_x @ lu.solve(rhs)))


def _dr_dl0(net, x, gravity, index):
    """dR/dl0 (3 n_f, M) of the free DOFs: the edges' pull and their weight."""
    import scipy.sparse as sp

    u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    length = np.linalg.norm(u, axis=1)
    l0 = net.rest_length
    taut = (length > l0) | ~np.asarray(net.law.tension_only, dtype=bool)
    # R = grad U - F; grad U is N t at the second end, -N t at the first, with
    # N = EA (L / l0 - 1): dN/dl0 = -EA L / l0^2
    pull = np.where(taut, net.EA * length / l0**2, 0.0)[:, None] * u / length[:, None]
    g = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=np.float64)
    weight = 0.5 * net.line_density[:, None] * g[None, :]  # dF/dl0 at each end
    rows, cols, vals = [], [], []
    e = np.arange(net.n_edges)
    for end, sign in ((net.edges[:, 0], 1.0), (net.edges[:, 1], -1.0)):
        f = index[end]
        ok = f >= 0
        for c in range(3):
            rows.append(3 * f[ok] + c)
            cols.append(e[ok])
            vals.append(sign * pull[ok, c] - weight[ok, c])
    n3 = 3 * int(np.count_nonzero(index >= 0))
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(n3, net.n_edges),
    )


def formfind_elastic(scene, *, targets, vary, tol, max_iter, prefix="formfind."):
    """The rest lengths (a factor per cable or per edge) whose elastic equilibrium reaches
    ``targets``: a FormFound (method "elastic") at that equilibrium, its ``design``."""
    from catenet.formfind.design import _groups
    from catenet.formfind.goals import resolve_goals
    from catenet.solver.settings import Settings

    start = time.perf_counter()
    bad = [k for k, t in enumerate(targets) if t.cable is not None]
    if bad:
        raise ConfigError(
            f"target[{bad[0]}].cable = {targets[bad[0]].cable!r}: method = 'elastic' takes "
            "node targets (x, y, z, point, surface)"
        )
    settings = dataclasses.replace(Settings.of(scene.case.solver), method="static", steps=1)
    size = float(np.linalg.norm(np.ptp(scene.net.nodes, axis=0))) or 1.0
    goals = resolve_goals(targets, scene, size, tol)
    groups = np.zeros(scene.net.n_edges, dtype=np.int64)
    if vary == "edges" or (scene.cables is not None and scene.cables.names):
        groups = _groups(scene, vary, prefix)
    eq = _Equilibria(scene, settings, groups)
    s, message, gradients = _search(eq, goals, int(groups.max()) + 1, max_iter)
    found = _found(eq, goals, s, message, gradients, vary)
    found.wall_time = time.perf_counter() - start
    return found


class _Met(Exception):
    """Every target met."""


def _search(eq: _Equilibria, goals, n_var: int, max_iter: int):
    """(s, how it ended, gradients) of Levenberg-Marquardt on the factors' logs."""
    from catenet.formfind.levenberg import levenberg

    gradients = [0]

    def residual(s):
        try:
            net, _, x = eq(s)
        except (ConvergenceError, SingularSystemError):
            return np.full(goals.rows, 1e150)  # no equilibrium there: the step is refused
        a = goals.achieved(x, np.zeros(net.n_edges), _lengths(net, x))
        if goals.met(a).all():
            raise _Met
        return goals.w * goals.miss(a)

    def jacobian(s):
        gradients[0] += 1
        return eq.jacobian(s, goals)

    s = np.zeros(n_var)
    free = (np.full(n_var, -np.inf), np.full(n_var, np.inf))
    try:
        ended = levenberg(residual, jacobian, s, free, max_iter)
    except _Met:
        return np.frombuffer(eq.key or s.tobytes()).copy(), "met", gradients[0]
    if ended.why == "max_iter":
        return ended.s, "formfind.max_iter reached", gradients[0]
    return ended.s, "least-squares compromise: the targets are not all compatible", gradients[0]


def _lengths(net, x: np.ndarray) -> np.ndarray:
    return np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1)


def _found(eq: _Equilibria, goals, s, message: str, gradients: int, vary: str):
    """The FormFound at the equilibrium of s: q = N / L, every edge taut."""
    from catenet.formfind.design import Design
    from catenet.formfind.fdm import FormFound
    from catenet.model import measures

    net, scene, x = eq(s)
    length = _lengths(net, x)
    a = goals.achieved(x, np.zeros(net.n_edges), length)
    tension = measures.tension(net, x)
    slack = np.flatnonzero(~(tension > 0))
    if slack.size:
        raise ConfigError(
            f"formfind.method = 'elastic': edge {int(slack[0])} is slack in the state found "
            f"({slack.size} edges): form finding writes taut nets"
        )
    d = Design(
        goals=goals,
        achieved=a,
        met=goals.met(a),
        variables=len(s),
        vary=vary,
        evaluations=eq.solves - 1,
        gradients=gradients,
        message=message,
    )
    return FormFound(
        net=net,
        x=x,
        q=tension / length,
        load=scene.loads.external_force(net),
        method="elastic",
        iterations=d.evaluations,
        factorizations=eq.solves,
        residual=float(np.max(np.abs(d.miss()) / goals.scale)),
        backend="scipy",
        design=d,
    )


__all__ = ["formfind_elastic"]
