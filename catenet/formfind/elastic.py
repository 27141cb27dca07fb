"""Rest lengths that reach form finding's targets under the elastic equilibrium
(``formfind.method = "elastic"``): a stay whose sag under its own weight is given, a guy
whose tension at rest is given, an anchor whose reaction is given.

The design variables (``catenet.formfind.variables``) are rest-length factors per cable
or per edge, or the prestress of named cables, within bounds; each s gives the rest
lengths l0(s). Each evaluation is catenet's static equilibrium of the net with those rest
lengths (the one solve path, from the last equilibrium), under its loads, its self-weight
included (the mass rho A l0 / 2 per edge end follows l0).

Derivatives by the adjoint of that equilibrium. The free DOFs satisfy R(x, l0) =
grad U(x, l0) - F(l0) = 0, so K dx + (dR/dl0) dl0 = 0 with K the tangent stiffness (the
Hessian of the energy at the equilibrium). Under the linear law an edge pulls its ends
with N t, N = EA (L / l0 - 1) (0 when slack under tension_only), so dR/dl0_e is
-EA L / l0^2 t at its second end and the opposite at its first, less the change of its
weight, rho A g / 2 at each end. A target's row r(x, l0) then changes by

    dr/ds = (r_l0 - r_x K^-1 dR/dl0) dl0/ds,

one solve with K per variable or per row, whichever are fewer. The rows: nodes'
positions and surfaces (r_l0 = 0); an edge's tension N (r_x: dN/dx_b = EA / l0 t,
r_l0 = -EA L / l0^2); a support's reaction R_i = grad_i U - F_i at a fixed node (r_x:
minus the edge's stiffness block K_e = N_L t t^T + N / L (I - t t^T) for each free
neighbour; r_l0 = +-dN/dl0 t - rho A g / 2). A support's offset (``[[formfind.support]]``)
moves its nodes by dx_s: dR = K_fs dx_s, K_fs the columns at the support of the Hessian
over every node (the stretching and the scene's terms: a rod's bending at its end, a
capsule pressing on the support's edge), and the targets its own position enters change
directly. Levenberg-Marquardt within the bounds (``levenberg``) drives it.
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from catenet.errors import ConfigError, ConvergenceError, SingularSystemError

log = logging.getLogger(__name__)


class _Equilibria:
    """The elastic equilibrium for the design variables s, warm-started."""

    def __init__(self, scene, settings, variables):
        self.scene, self.settings, self.variables = scene, settings, variables
        self.x = scene.net.nodes.copy()
        self.key: bytes | None = None
        self.solves = 0
        self.backend = "scipy"  # the equilibria's linear solver, once one is solved

    def __call__(self, s: np.ndarray):
        """(net, scene, x) at s; the state is kept for the Jacobian."""
        from catenet.solver.path import Start, solve

        key = s.tobytes()
        if key != self.key:
            self.key = None
            v = self.variables
            net = self.scene.net.replace(rest_length=v.rest(s))
            start = self.x
            if v.moves:  # the supports where s puts them (the free nodes start as last)
                nodes = v.positions(s)
                net = net.replace(nodes=nodes)
                start = np.where(net.fixed[:, None], nodes, self.x)
            scene = dataclasses.replace(self.scene, net=net)
            result = solve(scene, self.settings, start=Start(x=start))
            self.solves += 1
            self.backend = result.stats.backend or self.backend  # (the equilibria's)
            if not result.converged:
                raise ConvergenceError(f"the equilibrium did not converge: {result.message}")
            self.x = np.asarray(result.x).copy()
            self.now = (net, scene, self.x.copy())
            self.key = key
        return self.now

    def achieved(self, s: np.ndarray, goals) -> np.ndarray:
        net, scene, x = self(s)
        n, length = _forces(net, x)
        return goals.achieved(x, n / length, length, _reaction(net, scene, x, n))

    def jacobian(self, s: np.ndarray, goals) -> np.ndarray:
        """dr/ds (rows, variables) at the equilibrium of s."""
        from scipy.sparse.linalg import splu

        net, scene, x = self(s)
        if np.any(net.law.kind != 0):
            raise ConfigError("formfind.method = 'elastic': takes the linear law only")
        index = np.full(net.n_nodes, -1, dtype=np.int64)
        free = np.flatnonzero(~net.fixed)
        index[free] = np.arange(len(free))
        k_all = _every_node_hessian(net, scene, x)  # (K: its free block; K_fs: columns)
        dofs = np.flatnonzero(np.repeat(index >= 0, 3))  # (the free DOFs, 3 f + c)
        k = k_all[dofs][:, dofs].tocsc()
        n, length = _forces(net, x)
        taut = (length > net.rest_length) | ~np.asarray(net.law.tension_only, dtype=bool)
        dn_dl = np.where(taut, net.EA / net.rest_length, 0.0)
        dn_dl0 = np.where(taut, -net.EA * length / net.rest_length**2, 0.0)
        a = goals.achieved(x, n / length, length, _reaction(net, scene, x, n))
        d_x, d_l0 = goals.partials(x, n / length, a, index, net, dn=(dn_dl, dn_dl0))
        if goals.reacts.any():
            rx, rl = _reaction_partials(goals, a, net, scene, x, n, dn_dl, dn_dl0, index)
            d_x, d_l0 = d_x + rx, d_l0 + rl
        dl0_ds = self.variables.jacobian(s)
        rhs = (_dr_dl0(net, x, scene.loads.gravity, index) @ dl0_ds).toarray()
        direct = (d_l0 @ dl0_ds).toarray()
        if self.variables.moves:  # the supports' offsets: their columns
            _moved_columns(self.variables, goals, a, net, scene, x, n, dn_dl, dn_dl0, index,
                           k_all[dofs], rhs, direct)  # fmt: skip
        try:
            lu = splu(k)
        except RuntimeError:
            raise SingularSystemError("the tangent stiffness is singular") from None
        if d_x.shape[0] <= rhs.shape[1]:
            y = lu.solve(d_x.T.toarray(), trans="T")
            return direct - (rhs.T @ y).T
        return np.asarray(direct - d_x @ lu.solve(rhs))


def _moved_columns(v, goals, a, net, scene, x, n, dn_dl, dn_dl0, index, k_f, rhs, direct):
    """Fills the support offsets' columns of ``rhs`` (dR_f/ds: the free nodes' residual
    as a support moves, K_fs dx_s) and ``direct`` (dr/ds with the free nodes held: the
    tensions, lengths and reactions that the support's own position enters)."""
    every = np.arange(net.n_nodes)  # (every node a column: the supports' too)
    d_all, _ = goals.partials(x, n / _lengths(net, x), a, every, net, dn=(dn_dl, dn_dl0))
    if goals.reacts.any():
        rx, _ = _reaction_partials(goals, a, net, scene, x, n, dn_dl, dn_dl0, every)
        d_all = d_all + rx
    for j in range(len(v.moves)):
        col = v.n_rest + j
        dx = v.moved(j).ravel()  # (only supports move)
        direct[:, col] = d_all @ dx
        rhs[:, col] = k_f @ dx  # (k_f: the free rows of the Hessian over every node)


def _every_node_hessian(net, scene, x: np.ndarray):
    """The Hessian (3N, 3N) of the net's energy, its stretching and the scene's terms
    (rods' bending and twist, obstacles), over every node as if none were held: its
    free rows' columns at a support are K_fs, the change of the free nodes' forces as
    the support moves."""
    from catenet.solver.system import System
    from catenet.terms.stretch import Stretch

    loose = net.replace(fixed=np.zeros(net.n_nodes, dtype=bool), flies=True)
    system = System(loose, (Stretch(loose), *scene.terms), upper=False)
    return system.matrix(system.hessian(x))


def _forces(net, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, L) per edge: the tension under the linear law (0 where slack), the length."""
    from catenet.model import measures

    return measures.tension(net, x), _lengths(net, x)


def _reaction(net, scene, x: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The force each support exerts on the net (N, 3): grad U - F at the fixed nodes."""
    u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    pull = (n / np.linalg.norm(u, axis=1))[:, None] * u
    grad = np.zeros_like(x)
    for c in range(3):
        grad[:, c] = np.bincount(net.edges[:, 1], pull[:, c], net.n_nodes)
        grad[:, c] -= np.bincount(net.edges[:, 0], pull[:, c], net.n_nodes)
    out = np.zeros_like(x)
    force = scene.loads.external_force(net)
    out[net.fixed] = grad[net.fixed] - force[net.fixed]
    return out


def _reaction_partials(goals, a, net, scene, x, n, dn_dl, dn_dl0, index):
    """(dr/dx_f, dr/dl0) of the reaction rows (the others 0)."""
    import scipy.sparse as sp

    u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    length = np.linalg.norm(u, axis=1)
    t = u / length[:, None]
    g = np.zeros(3) if scene.loads.gravity is None else np.asarray(scene.loads.gravity)
    slope = goals.slope(a)
    rows_x, cols_x, vals_x, rows_l, cols_l, vals_l = [], [], [], [], [], []
    for j in np.flatnonzero(goals.reacts):
        i, c = int(goals.node[j]), int(goals.axis[j])
        for end, sign in ((0, -1.0), (1, 1.0)):
            e = np.flatnonzero(net.edges[:, end] == i)
            other = index[net.edges[e, 1 - end]]
            # d(sign N t_c)/dl0 less the weight's share at i
            rows_l.append(np.full(len(e), j))
            cols_l.append(e)
            vals_l.append(
                slope[j] * (sign * dn_dl0[e] * t[e, c] - 0.5 * net.line_density[e] * g[c])
            )
            # d(grad_i)/dx_other = -K_e (row c), at the other end where it has a column
            # (a free node's; every node's for a support that moves: and then its own,
            # d(grad_i)/dx_i = +K_e)
            own = index[i]
            for d in range(3):
                block = dn_dl[e] * t[e, c] * t[e, d] + n[e] / length[e] * (
                    (c == d) - t[e, c] * t[e, d]
                )
                k = other >= 0
                rows_x.append(np.full(int(k.sum()), j))
                cols_x.append(3 * other[k] + d)
                vals_x.append(-slope[j] * block[k])
                if own >= 0:
                    rows_x.append(np.full(len(e), j))
                    cols_x.append(np.full(len(e), 3 * own + d))
                    vals_x.append(slope[j] * block)
    shape = (goals.rows, 3 * int(np.count_nonzero(index >= 0)))
    cat = np.concatenate
    d_x = sp.csr_matrix((cat(vals_x), (cat(rows_x), cat(cols_x))), shape=shape)
    d_l = sp.csr_matrix((cat(vals_l), (cat(rows_l), cat(cols_l))), shape=(goals.rows, net.n_edges))
    return d_x, d_l


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


def formfind_elastic(
    scene, *, targets, vary, tol, max_iter, bounds=(None, None), prefix="formfind.", moves=()
):
    """The rest lengths (factors per cable or edge, or cables' prestress, within
    ``bounds``) and the positions of the supports ``moves`` lets move (the case's
    [[formfind.support]]) whose elastic equilibrium reaches ``targets``: a FormFound
    (method "elastic") at that equilibrium, its ``design``."""
    from catenet.formfind.goals import resolve_goals
    from catenet.formfind.variables import Variables
    from catenet.solver.settings import Settings

    start = time.perf_counter()
    supports = [k for k, t in enumerate(targets) if t.support is not None]
    if supports and scene.terms:
        raise ConfigError(
            f"target[{supports[0]}].support = {targets[supports[0]].support!r}: a reaction "
            "target takes a net of cables under loads and gravity only (this case has "
            "obstacles, rods or springs)"
        )
    settings = dataclasses.replace(Settings.of(scene.case.solver), method="static", steps=1)
    size = float(np.linalg.norm(np.ptp(scene.net.nodes, axis=0))) or 1.0
    goals = resolve_goals(targets, scene, size, tol)
    variables = Variables(scene, vary, bounds, prefix, moves)
    eq = _Equilibria(scene, settings, variables)
    s, message, gradients = _search(eq, goals, max_iter)
    found = _found(eq, goals, s, message, gradients, vary)
    unmet = goals.hard & ~found.design.met
    if unmet.any():  # (no second search here: the weights decide, hard ones must hold)
        from catenet.formfind.design import _unmet_message

        k = int(goals.of[np.argmax(unmet)])
        raise ConfigError(
            _unmet_message(found.design, k).replace(
                "formfind.force_density_min/max", _bounds_named(vary)
            )
        )
    found.wall_time = time.perf_counter() - start
    return found


def _bounds_named(vary: str) -> str:
    return {
        "prestress": "formfind.prestress_min/max",
        "supports": "the ranges of [[formfind.support]]",
    }.get(vary, "formfind.rest_length_factor_min/max")


class _Met(Exception):
    """Every target met."""


class _RanAway(Exception):
    """The search came closer to the targets at a state no cable reaches."""


#: How a search ended that ran to strains no cable has (``_implausible`` says which)
RAN_AWAY = "ran to strains no cable has"


def _search(eq: _Equilibria, goals, max_iter: int):
    """(s, how it ended, gradients) of Levenberg-Marquardt within the bounds."""
    from catenet.formfind.design import COMPROMISE
    from catenet.formfind.levenberg import levenberg

    gradients = [0]
    least = [np.inf]  # the least 1/2 |r|^2 so far

    def residual(s):
        try:
            a = eq.achieved(s, goals)
        except (ConvergenceError, SingularSystemError):
            return np.full(goals.rows, 1e150)  # no equilibrium there: the step is refused
        if goals.met(a).all():
            raise _Met
        r = goals.w * goals.miss(a)
        f = 0.5 * float(r @ r)
        if f < least[0]:
            least[0] = f
            net, _, x = eq(s)
            if _implausible(net, x):  # closer to the targets only by strains no cable
                raise _RanAway  # has: it runs away (a sag above the supports)
        return r

    def jacobian(s):
        gradients[0] += 1
        return eq.jacobian(s, goals)

    s = eq.variables.start.copy()
    try:
        ended = levenberg(residual, jacobian, s, eq.variables.bounds, max_iter)
    except _Met:
        return np.frombuffer(eq.key or s.tobytes()).copy(), "met", gradients[0]
    except _RanAway:  # (the implausible state, reported as such: ``_found``)
        return np.frombuffer(eq.key or s.tobytes()).copy(), RAN_AWAY, gradients[0]
    if ended.why == "max_iter":
        return ended.s, "formfind.max_iter reached", gradients[0]
    return ended.s, COMPROMISE, gradients[0]


def _implausible(net, x: np.ndarray) -> str:
    """Why the equilibrium found is no cable's, as `catenet run` judges a state: an edge
    strained beyond IMPLAUSIBLE times its law's range (``catenet.model.measures``; a
    cable's length asked below its chord: the rest lengths shrink until the linear law
    stretches them to it); "" where every strain is plausible."""
    from catenet.model.measures import IMPLAUSIBLE, implausible_edge, strain

    worst = implausible_edge(net, x)
    if worst < 0:
        return ""
    eps, limit = strain(net, x)[worst], net.law.max_strain()[worst]
    return (
        f"the rest lengths found strain edge {worst} by {float(eps):.3g}, beyond "
        f"{IMPLAUSIBLE:g} times its law's range ({float(limit):.3g}): no cable "
        "reaches that state (a length asked below its chord, or a sag or a pull that only "
        "such a stretch gives)"
    )


def _lengths(net, x: np.ndarray) -> np.ndarray:
    return np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1)


def _found(eq: _Equilibria, goals, s, message: str, gradients: int, vary: str):
    """The FormFound at the equilibrium of s: q = N / L, every edge taut."""
    from catenet.formfind.design import Design, compromise
    from catenet.formfind.fdm import FormFound

    net, scene, x = eq(s)
    tension, length = _forces(net, x)
    a = eq.achieved(s, goals)
    only = np.asarray(net.law.tension_only, dtype=bool)
    slack = np.flatnonzero(only & ~(tension > 0))
    if slack.size:
        raise ConfigError(
            f"formfind.method = 'elastic': edge {int(slack[0])} is slack in the state found "
            f"({slack.size} edges): form finding writes taut nets"
        )
    v = eq.variables
    d = Design(
        goals=goals,
        achieved=a,
        met=goals.met(a),
        variables=v.n,
        vary=vary,
        evaluations=eq.solves - 1,
        gradients=gradients,
        message=compromise(message, v.at_bound(s)),
        at_bound=v.at_bound(s),
    )
    d.extra.update(values=v.values(s), names=list(v.names), kind=v.kind, moved=len(v.moves))
    d.extra["offsets_at_bound"] = v.bound(s)[v.n_rest :].tolist()
    d.extra["implausible"] = _implausible(net, x)
    return FormFound(
        net=net,
        x=x,
        q=tension / length,
        load=scene.loads.external_force(net),
        method="elastic",
        iterations=d.evaluations,
        factorizations=eq.solves,
        residual=float(np.max(np.abs(d.miss()) / goals.scale)),
        backend=f"{eq.backend}; the adjoint by SciPy's SuperLU",
        design=d,
    )


__all__ = ["formfind_elastic"]
