"""Force densities that reach form finding's targets (``[[target]]``).

The design variables are s = log q (so q stays positive), one per edge or one per cable
(``vary``), within optional bounds on q; q = exp(P s) with P the edges' assignment. The
targets' residual r(s) (``catenet.formfind.goals``) is minimised in the least-squares
sense by SciPy's trust region reflective method (``least_squares``, bounds honoured
exactly) with the Jacobian of ``catenet.formfind.adjoint``: whole (one solve per row or
per variable, whichever are fewer) up to ``DENSE`` of them, else as a linear operator
(LSMR's products: one solve each). Each new s costs one factorisation of D.

It stops as soon as every row is met to ``tol`` (a start that meets them costs no
iteration); otherwise where the least squares can lower the misses no further: the
compromise the weights choose, which the report says. Hard targets left unmet then
get a second search on their rows alone from there: Gauss-Newton's least-norm steps,
the least change of the force densities that meets them (each search at most
``max_iter`` evaluations); one still unmet is a ConfigError.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from catenet.errors import ConfigError, ConvergenceError, SingularSystemError
from catenet.formfind.adjoint import (
    Adjoint,
    SparseJacobian,
    jacobian_dense,
    jacobian_operator,
    new_steps,
)
from catenet.formfind.anchors import Anchors, Bordered, support_moves
from catenet.formfind.goals import Goals
from catenet.formfind.levenberg import levenberg

log = logging.getLogger(__name__)

DENSE = 200  # whole Jacobians up to this many solves; beyond, a linear operator
# Targets unmet with force densities this many times their start (or as many times below
# it): the search ran towards forces without bound, where no optimum lies (a node asked
# to lie where the loads cannot hold it); no least-squares compromise.
RUNAWAY = 1e6
RAN_AWAY = "the force densities ran away"


class _Met(Exception):
    """Every target met: the search stops here."""


@dataclass
class Design:
    """What the search found: per row the value ``achieved`` (a) and whether ``met``; the
    design variables (``variables``, their ``kind``), how it went."""

    goals: Goals
    achieved: np.ndarray
    met: np.ndarray
    variables: int
    vary: str
    evaluations: int = 0
    gradients: int = 0
    rounds: int = 0
    message: str = ""
    bounds: tuple = (None, None)
    at_bound: int = 0
    extra: dict = field(default_factory=dict)

    @property
    def all_met(self) -> bool:
        return bool(self.met.all())

    def miss(self) -> np.ndarray:
        return self.goals.miss(self.achieved)


class _Search:
    """The residual and its Jacobian as functions of s, sharing one state per s."""

    def __init__(self, shape, goals: Goals, groups, base: np.ndarray, anchors=None):
        import scipy.sparse as sp

        m = shape.net.n_edges
        self.shape, self.goals = shape, goals
        if groups is None:  # (the force densities kept: the supports' offsets alone)
            self.base = base
            self.p = sp.csr_matrix((m, 0))
        else:
            self.base = base[groups]  # log q of each edge at s = 0
            n_var = len(base)
            self.p = sp.csr_matrix((np.ones(m), (np.arange(m), groups)), shape=(m, n_var))
        self.nq = self.p.shape[1]
        self.anchors = anchors or Anchors(shape.net, [], self.nq, shape.size)
        self.key: bytes | None = None
        self.now: tuple = (None, None, None, None)  # (q, x, load, lengths) of ``key``
        self.groups = groups
        self.gradients = 0
        self.best: tuple | None = None
        self.layout = None  # the direct damped step's pattern and solver, kept between states
        self.steps = new_steps()  # how the damped steps went
        self.kept: dict = {}  # factors kept between states (the iterative step's)
        self.last: SparseJacobian | None = None  # the last sparse Jacobian
        self.blocked: str | None = None  # why a state tried since the best had no shape

    def state(self, s: np.ndarray):
        """(q, x, load, a) at s: the shape solved once per s (the goals' values ``a``
        each time: the goals may change between searches)."""
        key = s.tobytes()
        if key != self.key or self.shape.factored is not self.now[0]:
            self.key = None  # (also where a damped step refactorised D at another state)
            q = np.exp(np.clip(self.base + self.p @ s[: self.nq], -700.0, 700.0))
            x, load = self.shape(q, self.anchors.positions(s))
            u = x[self.shape.net.edges[:, 1]] - x[self.shape.net.edges[:, 0]]
            self.now = (q, x, load, np.linalg.norm(u, axis=1))
            self.key = key  # (the shape's factors are this state's)
            a = self._achieved(x, q, load, self.now[3])
            r = self.goals.w * self.goals.miss(a)
            if np.all(np.isfinite(r)) and (self.best is None or r @ r < self.best[0]):
                self.best = (float(r @ r), s.copy())
                self.blocked = None
        q, x, load, length = self.now
        return q, x, load, self._achieved(x, q, load, length)

    def partials(self, x, q, a):
        """(dr/dx_f, dr/dq) at the state (x, q) whose values are ``a``, reactions'
        included."""
        index = self.shape.pattern.index
        d_x, d_q = self.goals.partials(x, q, a, index, self.shape.net)
        if self.goals.reacts.any():
            from catenet.formfind import reactions

            rx, rq = reactions.partials(self.goals, a, self.shape, x, q, index)
            d_x, d_q = (d_x + rx).tocsr(), (d_q + rq).tocsr()
        return d_x, d_q

    def _achieved(self, x, q, load, length) -> np.ndarray:
        reaction = None
        if self.goals.reacts.any():
            from catenet.formfind.reactions import reaction as support_force

            reaction = support_force(self.shape.net, x, q, load)
        return self.goals.achieved(x, q, length, reaction)

    def residual(self, s: np.ndarray) -> np.ndarray:
        try:
            q, x, load, a = self.state(s)
        except (SingularSystemError, ConvergenceError, ConfigError) as exc:
            self.blocked = str(exc)
            return np.full(self.goals.rows, 1e150)  # no shape there: the step is refused
        if not np.all(np.isfinite(a)):
            return np.full(self.goals.rows, 1e150)  # a node off a surface's plan: refused
        if self.goals.met(a).all():
            raise _Met
        return self.goals.w * self.goals.miss(a)

    def jacobian(self, s: np.ndarray):
        import scipy.sparse as sp

        q, x, _, a = self.state(s)  # (the shape's factors are the last state's)
        self.gradients += 1
        adj = Adjoint(self.shape, q, x)
        d_x, d_q = self.partials(x, q, a)
        cols = self.anchors.columns(self, adj, x, q, a, d_x) if self.anchors.n else None
        if not self.nq:
            return cols
        dq_ds = sp.diags(q) @ self.p
        if min(d_x.shape[0], dq_ds.shape[1]) <= DENSE:
            j = jacobian_dense(adj, d_x, d_q, dq_ds)
            return j if cols is None else np.hstack([j, cols])
        if isinstance(self.last, SparseJacobian):  # (its direct step's layout, if made)
            self.layout = self.last.layout or self.layout
        op = jacobian_operator(
            adj, d_x, d_q, dq_ds, self.groups, self.layout, self.steps, self.kept
        )
        self.last = op
        return op if cols is None else Bordered(op, cols)


def design(shape, goals: Goals, q0, groups, bounds, max_iter: int, vary: str, moves=()) -> Design:
    """The force densities (one per group: ``groups`` (M,) the variable of each edge;
    None: q0 kept) and the offsets of the supports ``moves`` (``catenet.formfind.
    anchors``) that reach ``goals`` from ``q0`` (M,), q within ``bounds`` (low, high;
    None: open), at most ``max_iter`` evaluations; the state reached is
    ``Design.extra["state"]``."""
    log_lo = -np.inf if bounds[0] is None else math.log(bounds[0])
    log_hi = np.inf if bounds[1] is None else math.log(bounds[1])
    if groups is None:
        base, n_q = np.log(q0), 0
    else:
        n_q = int(groups.max()) + 1
        base = np.bincount(groups, np.log(q0), n_q) / np.bincount(groups, minlength=n_q)
        base = np.clip(base, log_lo, log_hi)  # the start; s = log q - base
    anchors = Anchors(shape.net, list(moves), n_q, shape.size)
    a_lo, a_hi, a_start = anchors.bounds()
    lo = np.concatenate([np.full(n_q, log_lo) - base[:n_q], a_lo])
    hi = np.concatenate([np.full(n_q, log_hi) - base[:n_q], a_hi])
    s = np.concatenate([np.zeros(n_q), a_start])
    n_var = len(s)
    search = _Search(shape, goals, groups, base, anchors)
    q, x, load, a = search.state(s)
    outside = goals.outside(a)
    if outside is not None:
        raise ConfigError(outside)
    rounds, message = 0, "met at the start"
    if not goals.met(a).all():
        message, s = _search(search, s, (lo, hi), max_iter)
        q, x, load, a = search.state(s)
    if (goals.hard & ~goals.met(a)).any():  # the least change that meets the hard ones
        rounds = 1
        search.goals = goals.select(goals.hard)
        search.best = None
        why, s = _search(search, s, (lo, hi), max_iter)
        search.goals = goals
        q, x, load, a = search.state(s)
        if why != "met":
            message = f"{why} on the hard targets alone"
    evaluations = shape.factorizations - 1
    bound = (s <= lo + 1e-12) | (s >= hi - 1e-12)
    at_bound = int(np.count_nonzero(bound))
    message = compromise(message, at_bound)
    out = Design(
        goals=goals,
        achieved=a,
        met=goals.met(a),
        variables=n_var,
        vary=vary,
        evaluations=evaluations,
        gradients=search.gradients,
        rounds=rounds,
        message=message,
        bounds=bounds,
        at_bound=at_bound,
    )
    out.extra["state"] = (q, x, load)
    if anchors.n:  # the variables found: the force densities (N/m), then the offsets (m)
        out.extra.update(
            values=np.concatenate([np.exp(base[:n_q] + s[:n_q]), anchors.offsets(s)]),
            names=[""] * n_q + [name for _, _, name, _ in anchors.moves],
            kind="force_density" if n_q else "offset",
            moved=anchors.n,
            offsets_at_bound=bound[n_q:].tolist(),
        )
    if search.last is not None:  # how the damped steps went (benchmarks read it)
        lay = search.last.layout or search.layout
        out.extra["steps"] = {
            **search.steps,
            "factorizations": 0 if lay is None else lay.factorizations,
            "by_superlu": 0 if lay is None else lay.fallbacks,
            "direct_s": 0.0 if lay is None else lay.seconds,
        }
    return out


#: How a search that met not every target ended (its stationary point)
COMPROMISE = "least-squares compromise: the targets are not all compatible"
#: How a search ended that stopped at its best where a step on from it found no shape
BLOCKED = "stopped where the force densities toward the targets give no shape"


def compromise(message: str, at_bound: int) -> str:
    """The compromise's message said where bounds hold variables (their share of why the
    targets are not met: a single target can be met without them)."""
    if not message.startswith(COMPROMISE) or not at_bound:
        return message
    return (
        "least-squares compromise within the bounds: the targets are not all met there "
        f"({at_bound} variable{'s' if at_bound > 1 else ''} at a bound)"
        + message[len(COMPROMISE) :]
    )


def _search(search: _Search, s0: np.ndarray, bounds, budget: int) -> tuple[str, np.ndarray]:
    """(how it ended, s) of Levenberg-Marquardt from s0 (``catenet.formfind.levenberg``)."""
    try:
        ended = levenberg(search.residual, search.jacobian, s0, bounds, max(budget, 1))
    except _Met:
        return "met", np.frombuffer(search.key or s0.tobytes()).copy()
    best = search.best
    s = ended.s if best is None else best[1]
    if ended.why == "max_iter":
        return "formfind.max_iter reached", s
    if search.blocked is not None:  # a step on from the best found no shape
        return f"{BLOCKED}: {_first_clause(search.blocked)}", s
    return COMPROMISE, s


def _first_clause(message: str) -> str:
    """A shape's error as a clause: without its prefix and its advice."""
    clause = message.removeprefix("form finding: ")
    return clause.split(": raise")[0].split(": lower")[0].rstrip(". ")


def formfind_targets(
    scene,
    q=None,
    *,
    targets,
    vary="edges",
    bounds=(None, None),
    tol=1e-9,
    max_iter=100,
    linear="auto",
    prefix="formfind.",
    moves=(),
):
    """The shape of a case's ``scene`` whose force densities (and the offsets of the
    supports ``moves``: [[formfind.support]]) reach ``targets`` (the case's [[target]]
    tables): a FormFound with method "targets" and its ``design``. ``q``: the start (one
    number, one per edge; None: ``_default_start``); ``vary = "supports"`` keeps it.
    ConfigError for bad input and hard targets unmet."""
    import time

    from catenet.formfind.fdm import FormFound, _Shape, _zero_lengths, per_edge
    from catenet.formfind.goals import resolve_goals

    start = time.perf_counter()
    net, loads = scene.net, scene.loads
    if loads is not None and loads.moves_supports:
        raise ConfigError("supports.move: form finding holds the fixed nodes where they are")
    q_name = f"{prefix}force_density"
    const = np.zeros((net.n_nodes, 3)) if loads is None or loads.force is None else loads.force
    gravity = None if loads is None else loads.gravity
    shape = _Shape(net, np.array(const, dtype=np.float64), gravity, linear, q_name)
    if not shape.pattern.n_free:
        raise ConfigError("target: every node is fixed: nothing to form find")
    goals = resolve_goals(targets, scene, shape.size, tol)
    groups = None if vary == "supports" else _groups(scene, vary, prefix)
    q0 = per_edge(q, net.n_edges, q_name, required=False)
    if q0 is None:
        q0 = np.full(net.n_edges, _default_start(shape))
    moved = support_moves(scene, moves, prefix)
    d = design(shape, goals, q0, groups, bounds, max_iter, vary, moved)
    q, x, load = d.extra.pop("state")
    ratio = np.log(q / q0)
    if not d.all_met and float(np.max(np.abs(ratio))) > np.log(RUNAWAY):
        d.message = RAN_AWAY
        d.extra["ran"] = float(np.exp(ratio[np.argmax(np.abs(ratio))]))  # q / q0 at most
    _zero_lengths(net, x, shape.size, q_name)
    unmet = goals.hard & ~d.met
    if unmet.any():
        raise ConfigError(_unmet_message(d, int(goals.of[np.argmax(unmet)])))
    rel = np.abs(d.miss()) / goals.scale
    found = FormFound(
        net=net,
        x=x,
        q=q,
        load=load,
        method="targets",
        iterations=d.evaluations,
        factorizations=shape.factorizations,
        residual=float(rel.max()),
        backend=shape.backend,
        stats={"solves": shape.solves, "n_free": shape.pattern.n_free},
        design=d,
    )
    found.rest_length(q_name)
    d.extra["implausible"] = found.implausible(shape.weighs)
    found.wall_time = time.perf_counter() - start
    log.info(
        "targets: %s after %d evaluations, %d gradients", d.message, d.evaluations, d.gradients
    )
    return found


def _default_start(shape) -> float:
    """A force density that carries the loads with a small sag: the total load over the
    mean edge length (a cable of n edges under its weight W then sags about L / 8; 1 N/m
    without loads)."""
    net = shape.net
    total = float(np.abs(shape.force).sum())
    if shape.weighs:
        g = float(np.linalg.norm(shape.gravity))
        total += g * float(np.sum(net.line_density * net.rest_length))
    if total <= 0:
        return 1.0
    ends = net.nodes[net.edges[:, 1]] - net.nodes[net.edges[:, 0]]
    mean = float(np.mean(np.linalg.norm(ends, axis=1)))
    return total / (mean if mean > 0 else shape.size)


def _groups(scene, vary: str, prefix: str) -> np.ndarray:
    """The design variable of each edge: its own (``edges``), or its cable's (``cables``:
    a graph's own edges keep one each; a net without named cables is one cable, as in
    the elastic method: a ``kind = "cable"`` stay's one force density)."""
    m = scene.net.n_edges
    if vary == "edges":
        return np.arange(m)
    cables = scene.cables
    if cables is None or not cables.names:
        return np.zeros(m, dtype=np.int64)
    edge = np.asarray(cables.edge)
    n = len(cables.names)
    own = edge < 0
    out = edge.copy()
    out[own] = n + np.arange(int(own.sum()))
    groups = np.unique(out, return_inverse=True)[1]  # (a cable without edges: none)
    return groups.astype(np.int64)


def _unmet_message(d: Design, k: int) -> str:
    t = d.goals.targets[k]
    rows = np.flatnonzero(d.goals.of == k)
    worst = rows[np.argmax(np.abs(d.miss()[rows]))]
    lo, hi = d.goals.lo[worst], d.goals.hi[worst]
    want = f"{lo:.9g}" if lo == hi else f"[{lo:.9g}, {hi:.9g}]"
    offsets = int(sum(d.extra.get("offsets_at_bound", ())))
    widen = ["formfind.force_density_min/max"] if d.at_bound > offsets else []
    widen += ["the ranges of [[formfind.support]]"] if offsets else []
    fix = (
        f"relax it, widen {' or '.join(widen)} or drop hard"
        if widen
        else "relax it or the targets it conflicts with, or drop hard (no bound holds it)"
    )
    return (
        f"target[{k}] ({t.describe()}, hard = true): cannot be met to formfind.tol: reaches "
        f"{d.achieved[worst]:.9g}, target {want} ({d.message}): {fix}"
    )
