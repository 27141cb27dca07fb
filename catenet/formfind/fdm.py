"""The force density method on a net: shape from force densities, and force densities
from target forces or lengths.

With a force density q_e = N_e / L_e [N/m] per edge, equilibrium of the free nodes under
nodal loads p is linear (Schek 1974):

    sum over edges e at i of q_e (x_i - x_j) = p_i,   i.e.   D x_f = p_f - C_f^T Q C_x x_x,

with C the edge-node incidence (row e: -1 at its first node, +1 at its second), split
into free (f) and fixed (x) columns, Q = diag(q) and D = C_f^T Q C_f, symmetric positive
definite for q > 0 when every part of the net is held. One factorisation of D serves the
three coordinates. The pattern of D comes from the topology once (``Pattern``); each new
q refills its values, so PARDISO analyses once and refactorises numerically.

Gravity acts on the lumped masses of the net the result describes, m = rho A l0 / 2 per
edge end, and l0 = L / (1 + eps(N)) depends on the shape found: the loads are updated
from the shape and the shape solved again with the same factorisation until they agree
to round-off (the updates mixed, ``catenet.formfind.anderson``), so that the net written
out carries exactly the loads it was found under. A shape only a stretch beyond
IMPLAUSIBLE times the law's range holds is an error (``FormFound.implausible``).

Target forces: the classical update q <- N / L for a start; then, for target forces
(q L = N) and target lengths (L = L_target) alike, Newton on s = log q (q stays
positive), each step one sparse saddle-point solve (``catenet.formfind.newton``: the
Jacobian dL/dq = -diag(1/L) B^T D3^-1 B without forming it). Where Newton stalls (the
targets are not compatible), a small net (up to ``LSQ_EDGES`` edges) gets the best fit by
least squares (scipy.optimize.least_squares, trust region, dense Jacobian) for the
message; a larger one is reported at Newton's best state. Without loads, target lengths
fix q only up to a common factor: the geometric mean of q is then set to ``q`` (default
1 N/m).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError, ConvergenceError
from catenet.formfind.anderson import Anderson
from catenet.formfind.newton import Stalled, newton
from catenet.formfind.tocase import to_case
from catenet.model.measures import line_mass
from catenet.model.net import Net

if TYPE_CHECKING:
    from catenet.scene import Scene

log = logging.getLogger(__name__)

METHODS = ("linear", "forces", "lengths")
GRAVITY_ITER = 100  # load updates of the gravity fixed point
WARM_STEPS = 20  # forces: fixed-point updates before Newton
LSQ_EDGES = 200  # where Newton stalls: least squares (the best fit) up to this many edges


def per_edge(value, m: int, name: str, *, required: bool = True) -> np.ndarray | None:
    """One number or one per edge, each finite and > 0, as an (M,) array; ``name`` is
    the key path messages give."""
    if value is None:
        if required:
            raise ConfigError(f"{name}: missing: one number > 0, or one per edge ({m})")
        return None
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(m, float(arr))
    if arr.shape != (m,):
        raise ConfigError(
            f"{name}: has {arr.size} values: must be one number or one per edge ({m})"
        )
    bad = np.flatnonzero(~(np.isfinite(arr) & (arr > 0)))
    if bad.size:
        k = int(bad[0])
        where = f"{name}[{k}]" if np.ndim(value) else name
        more = f" ({bad.size} edges)" if bad.size > 1 else ""
        raise ConfigError(f"{where} = {float(arr[k])!r}: must be finite and > 0{more}")
    return np.ascontiguousarray(arr)


class Pattern:
    """The sparsity of D (upper triangle, CSR) from the topology, and where each edge's
    force density goes in it."""

    def __init__(self, net: Net):
        self.net = net
        free = ~net.fixed
        self.free_nodes = np.flatnonzero(free)
        nf = len(self.free_nodes)
        index = np.full(net.n_nodes, -1, dtype=np.int64)
        index[self.free_nodes] = np.arange(nf)
        a, b = index[net.edges[:, 0]], index[net.edges[:, 1]]
        self.index, self.a, self.b = index, a, b
        both = (a >= 0) & (b >= 0)
        rows = np.concatenate([np.arange(nf), np.minimum(a, b)[both]])
        cols = np.concatenate([np.arange(nf), np.maximum(a, b)[both]])
        order = np.lexsort((cols, rows))
        pos = np.empty(len(rows), dtype=np.int64)
        pos[order] = np.arange(len(rows))
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=nf))])
        self.indices = cols[order]
        self.nnz = len(rows)
        # Scatter: each edge adds q to the diagonal of its free ends and -q off it.
        ea, eb, eo = np.flatnonzero(a >= 0), np.flatnonzero(b >= 0), np.flatnonzero(both)
        self._edge = np.concatenate([ea, eb, eo])
        self._slot = np.concatenate([pos[a[ea]], pos[b[eb]], pos[nf:]])
        self._sign = np.concatenate([np.ones(len(ea) + len(eb)), -np.ones(len(eo))])

    @property
    def n_free(self) -> int:
        return len(self.free_nodes)

    def values(self, q: np.ndarray) -> np.ndarray:
        return np.bincount(self._slot, weights=self._sign * q[self._edge], minlength=self.nnz)

    def spread(self, w: np.ndarray) -> np.ndarray:
        """C_f^T w: per free node, the sum of w over its edges (+ at the second end)."""
        on_a, on_b = self.a >= 0, self.b >= 0
        n, flat = self.n_free, w.reshape(len(w), -1)
        out = np.empty((n, flat.shape[1]))
        for c in range(flat.shape[1]):  # bincount: a sum per node, far faster than add.at
            out[:, c] = np.bincount(self.b[on_b], flat[on_b, c], n) - np.bincount(
                self.a[on_a], flat[on_a, c], n
            )
        return out.reshape((n, *w.shape[1:]))

    def gather(self, z: np.ndarray) -> np.ndarray:
        """C_f z: per edge, z at its second free end minus z at its first (0 if fixed)."""
        pad = np.concatenate([z, np.zeros((1, *z.shape[1:]))])
        return pad[self.b] - pad[self.a]


@dataclass
class FormFound:
    """A form-found net: positions ``x`` (N, 3), force densities ``q`` (M,), the nodal
    loads ``load`` (N, 3) it carries, and how it was found. ``force`` = q L, ``length``
    = L; ``rest_length()`` and ``to_net()`` under the net's law and EA."""

    net: Net
    x: np.ndarray
    q: np.ndarray
    load: np.ndarray
    method: str = "linear"
    iterations: int = 0
    factorizations: int = 1
    residual: float = 0.0  # largest relative miss of the targets (0: linear)
    wall_time: float = 0.0
    backend: str = ""
    stats: dict = field(default_factory=dict)
    design: Any = None  # method "targets": the targets reached (catenet.formfind.design)
    _rest: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def length(self) -> np.ndarray:
        e = self.x[self.net.edges[:, 1]] - self.x[self.net.edges[:, 0]]
        return np.linalg.norm(e, axis=1)

    @property
    def force(self) -> np.ndarray:
        """Tension N = q L of every edge [N]."""
        return self.q * self.length

    def rest_length(self, name: str = "force_density") -> np.ndarray:
        """Rest lengths l0 = L / (1 + eps) with N(eps) = q L under the net's law (computed
        once); a tension the law cannot carry is a ConfigError naming ``name``."""
        if self._rest is None:
            self._rest = rest_lengths(self.net, self.force, self.length, name)
        return self._rest.copy()

    def implausible(self, weighs: bool) -> str:
        """Why the shape is no cable's, as `catenet run` judges a state: the rest lengths
        that carry its forces strain an edge beyond IMPLAUSIBLE times its law's range
        (``catenet.model.measures``); "" where every strain is plausible. ``weighs``: the
        shape carries its own weight (then such a strain on an edge longer than the
        structure is how the weight stopped growing: each rest length tends to EA / q as
        its edge lengthens; on a shorter one the force densities' own tension)."""
        from catenet.model.measures import IMPLAUSIBLE, implausible_edge

        net = self.net.replace(rest_length=self.rest_length())
        worst = implausible_edge(net, self.x)
        if worst < 0:
            return ""
        eps = float(self.length[worst] / net.rest_length[worst] - 1.0)
        why = (
            f"the shape found strains edge {worst} by {eps:.3g} (tension "
            f"{float(self.force[worst]):.4g} N), beyond {IMPLAUSIBLE:g} times its law's "
            f"range ({float(net.law.max_strain()[worst]):.3g}): no cable reaches that state"
        )
        size = float(np.linalg.norm(np.ptp(self.net.nodes, axis=0))) or 1.0
        if weighs and self.length[worst] > size:  # (a long edge: the weight stretched it)
            return (
                f"{why}; under its own weight the nodes sank until the stretch stopped the "
                f"weight growing (edge {worst} is {float(self.length[worst]):.4g} m long, "
                f"the structure {size:.4g} m across): the weight is too large for these "
                "force densities: raise them"
            )
        return f"{why}: the force densities ask more than the cables carry: lower them"

    def to_net(self) -> Net:
        """The net at the form-found shape, with the rest lengths that carry its forces."""
        return self.net.replace(nodes=self.x, rest_length=self.rest_length())

    def to_case(self, case=None, *, output_file: str | None = None) -> dict:
        """The graph case (a dict of TOML tables) that ``catenet run`` reproduces this
        shape with (see ``catenet.formfind.tocase.to_case``)."""
        return to_case(self, case, output_file=output_file)

    def reaction(self) -> np.ndarray:
        """Force each support exerts on the net (N, 3), 0 at free nodes; reactions and
        loads sum to zero."""
        e = self.x[self.net.edges[:, 1]] - self.x[self.net.edges[:, 0]]
        w = self.q[:, None] * e  # tension times the unit vector from first to second end
        grad = np.zeros_like(self.x)
        np.subtract.at(grad, self.net.edges[:, 0], w)
        np.add.at(grad, self.net.edges[:, 1], w)
        r = np.zeros_like(self.x)
        r[self.net.fixed] = grad[self.net.fixed] - self.load[self.net.fixed]
        return r


def rest_lengths(net: Net, force: np.ndarray, length: np.ndarray, name: str) -> np.ndarray:
    eps = net.law.strain_for_tension(force, net.EA)
    l0 = length / (1.0 + eps)
    bad = np.flatnonzero(~(np.isfinite(l0) & (l0 > 0)))
    if bad.size:
        k = int(bad[0])
        raise ConfigError(
            f"{name}: edge {k} (nodes {net.edges[k].tolist()}) would carry N = "
            f"{force[k]:.6g} N, which its law (EA = {net.EA[k]:.6g} N) cannot carry with a "
            f"positive rest length ({bad.size} edges in all): lower the force densities or "
            "targets"
        )
    return l0


class _Shape:
    """The shape for given force densities: factorisation, loads, solves."""

    def __init__(self, net, force, gravity, linear: str, q_name: str):
        from catenet.solver.linear import make_solver, resolve_backend

        self.net, self.force, self.gravity, self.q_name = net, force, gravity, q_name
        self.pattern = p = Pattern(net)
        self.backend = resolve_backend(linear)
        self.solver = None
        if p.n_free:
            self.solver = make_solver(
                self.backend, p.indptr, p.indices, upper=True, dof_node=p.free_nodes, mtype=2
            )
        self.factorizations = 0
        self.factored: np.ndarray | None = None  # the q whose D the solver holds
        self.checked = False  # a solve with these factors passed its check
        self.masses: np.ndarray | None = None  # the last shape's lumped masses (a start)
        self.kkt_factorizations = 0  # Newton's on the force densities (formfind/newton.py)
        self.solves = 0
        self.size = float(np.linalg.norm(np.ptp(net.nodes, axis=0))) or 1.0
        self.weighs = gravity is not None and bool(np.any(net.line_density > 0))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """D^-1 b for b (n_f, k): the first solve after a factorisation checked (its
        backward error), the later ones in one call, their values checked finite."""
        self.solves += b.shape[1]
        solver = self.solver
        if solver is None:  # (a net without free nodes has nothing to solve)
            raise RuntimeError("no free nodes: nothing to solve")
        if not self.checked:
            self.checked = True
            return np.column_stack([solver.solve(np.ascontiguousarray(c)) for c in b.T])
        out = solver.solve_many(b)
        if not np.all(np.isfinite(out)):  # (the checked solve names the nodes)
            return np.column_stack([solver.solve(np.ascontiguousarray(c)) for c in b.T])
        return out

    def __call__(self, q: np.ndarray, nodes=None) -> tuple[np.ndarray, np.ndarray]:
        """Positions (N, 3) and the loads (N, 3) at them, for force densities q, the
        fixed nodes where ``nodes`` (N, 3) puts them (None: the net's)."""
        net, p = self.net, self.pattern
        x = (net.nodes if nodes is None else nodes).copy()
        load = self.force.copy()
        if self.solver is None:
            return x, load
        self.factored = None
        self.solver.factorize(p.values(q))
        self.factorizations += 1
        self.factored, self.checked = q, False
        fixed_part = np.zeros((net.n_edges, 3))
        ends = net.edges
        fa, fb = net.fixed[ends[:, 0]], net.fixed[ends[:, 1]]
        fixed_part[fa] -= q[fa, None] * x[ends[fa, 0]]  # -C_x x_x, weighted
        fixed_part[fb] += q[fb, None] * x[ends[fb, 1]]
        rhs_fixed = -p.spread(fixed_part)
        g = None if not self.weighs else np.asarray(self.gravity, dtype=np.float64)
        mass = np.zeros(net.n_nodes)  # the lumped masses the loads carry (the unknown)
        if g is not None:  # from the last shape's, else the given net's rest lengths' (a
            mass = self._start_masses() if self.masses is None else self.masses  # pendant:
            load = self.force + mass[:, None] * g[None, :]  # not its unloaded point)
        mixing = Anderson()
        for _ in range(GRAVITY_ITER):
            x[p.free_nodes] = self.solve(load[p.free_nodes] + rhs_fixed)
            if g is None:
                return x, load
            new = self._masses(x, q)
            weight = new[:, None] * g[None, :]
            change = float(np.max(np.abs(self.force + weight - load)))
            if change <= 1e-14 * max(float(np.max(np.abs(self.force + weight))), 1e-300):
                load = self.force + weight
                x[p.free_nodes] = self.solve(load[p.free_nodes] + rhs_fixed)
                self.masses = new
                return x, load
            mass = mixing.mix(mass, new)
            load = self.force + mass[:, None] * g[None, :]
        raise ConvergenceError(
            f"form finding: the self-weight did not settle after {GRAVITY_ITER} load "
            "updates (the weight is too large for these force densities): raise them"
        )

    def _start_masses(self) -> np.ndarray:
        """The given net's lumped masses: rho l0 / 2 per edge end of its rest lengths."""
        return line_mass(self.net, self.net.rest_length)

    def _masses(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The nodes' lumped masses (N,) at x: rho l0 / 2 per edge end, l0 the rest
        length that carries q L under the net's law (ConfigError for edges of zero
        length: nodes that coincide carry no length to weigh)."""
        net = self.net
        _zero_lengths(net, x, self.size, self.q_name)
        length = _lengths(net, x)
        return line_mass(net, rest_lengths(net, q * length, length, self.q_name))


def _lengths(net: Net, x: np.ndarray) -> np.ndarray:
    return np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1)


def _zero_lengths(net: Net, x: np.ndarray, size: float, name: str) -> None:
    length = _lengths(net, x)
    zero = np.flatnonzero(~(length > 1e-12 * size))
    if zero.size:
        pairs = ", ".join(f"{k} (nodes {net.edges[k].tolist()})" for k in zero[:5])
        more = f" and {zero.size - 5} more" if zero.size > 5 else ""
        raise ConfigError(
            f"{name}: the shape found has edges of zero length: {pairs}{more}: their nodes "
            "coincide; choose force densities that keep them apart (e.g. uniform q)"
        )


def formfind(
    scene_or_net: Scene | Net,
    q=None,
    *,
    loads=None,
    method: str = "linear",
    force=None,
    length=None,
    tol: float = 1e-9,
    max_iter: int = 100,
    linear: str = "auto",
    prefix: str = "",
) -> FormFound:
    """The shape of a net by the force density method (see the module docstring).

    ``scene_or_net``: a case's Scene (its net and loads) or a Net (then ``loads``, a
    ``catenet.model.net.Loads``, may give point forces and gravity). The net gives the topology,
    the fixed nodes and their positions, EA, the law and the line density; the positions
    of its free nodes are ignored. ``q`` [N/m]: one force density for every edge or one
    per edge (required for ``method = "linear"``; the start otherwise). ``method``:
    "linear", "forces" (targets ``force`` [N]) or "lengths" (targets ``length`` [m]),
    each one number or one per edge, met to the relative tolerance ``tol`` within
    ``max_iter`` iterations. ``prefix`` goes before key names in messages ("formfind."
    for a case). Raises ConfigError for bad input or targets that cannot be met.
    """
    start = time.perf_counter()
    net = scene_or_net if isinstance(scene_or_net, Net) else scene_or_net.net
    if loads is None and not isinstance(scene_or_net, Net):
        loads = scene_or_net.loads
    if method not in METHODS:
        raise ConfigError(f"{prefix}method = {method!r}: must be one of {', '.join(METHODS)}")
    if loads is not None and loads.moves_supports:
        raise ConfigError("supports.move: form finding holds the fixed nodes where they are")
    m = net.n_edges
    q_name = f"{prefix}force_density"
    q = per_edge(q, m, q_name, required=method == "linear")
    const = np.zeros((net.n_nodes, 3)) if loads is None or loads.force is None else loads.force
    gravity = None if loads is None else loads.gravity
    shape = _Shape(net, np.array(const, dtype=np.float64), gravity, linear, q_name)
    if method == "linear":
        x, load = shape(q)
        iterations, residual = 1, 0.0
    else:
        target_name = f"{prefix}{'force' if method == 'forces' else 'length'}"
        target = per_edge(force if method == "forces" else length, m, target_name)
        if not (isinstance(tol, (int, float)) and 0 < tol < 1):
            raise ConfigError(f"{prefix}tol = {tol!r}: must be a number > 0 and < 1")
        x, load, q, iterations, residual = _targets(
            shape, method, target, q, float(tol), int(max_iter), target_name
        )
    _zero_lengths(net, x, shape.size, q_name)
    found = FormFound(
        net=net,
        x=x,
        q=q,
        load=load,
        method=method,
        iterations=iterations,
        factorizations=shape.factorizations,
        residual=residual,
        backend=shape.backend,
        stats={"solves": shape.solves, "n_free": shape.pattern.n_free},
    )
    found.rest_length(q_name)  # the law must carry every force: say so now (kept)
    why = found.implausible(shape.weighs)
    if why:
        raise ConvergenceError(f"form finding: {why}")
    found.wall_time = time.perf_counter() - start
    log.info(
        "form found (%s): %d factorisations, %d solves, %.3g s",
        method,
        found.factorizations,
        shape.solves,
        found.wall_time,
    )
    return found


def _targets(shape: _Shape, method, target, q0, tol, max_iter, name):
    """Force densities that meet the targets: Newton on s = log q (``newton``); where
    it stalls on a small net, least squares gives the best fit the message reports."""
    from scipy.optimize import least_squares

    net, p = shape.net, shape.pattern
    m = net.n_edges
    if q0 is None:  # forces: N / L of the given geometry; lengths: 1 N/m
        geo = _lengths(net, net.nodes)
        ok = geo > 0
        q0 = np.ones(m) if method == "lengths" or not ok.all() else target / geo
    if method == "forces":  # the classical update q <- N / L: cheap, near the answer fast
        for _ in range(min(WARM_STEPS, max_iter)):
            x, _ = shape(q0)
            q0 = target / np.maximum(_lengths(net, x), 1e-300 * shape.size)
    spent = shape.factorizations
    scale_free = method == "lengths" and not np.any(shape.force) and not shape.weighs
    try:
        x, load, q, iterations, miss = newton(
            shape, method, target, q0, tol, max(max_iter - spent, 1), scale_free
        )
        return x, load, _mean_kept(shape, method, q, q0), iterations + spent, miss
    except Stalled as exc:
        if exc.best is None or m > LSQ_EDGES or exc.why == "max_iter":
            raise _unmet(net, method, target, exc, tol, name, spent, max_iter) from None
        log.info("form finding: Newton stalled (%s): least squares", exc.why)
        stall = exc
    cache: dict = {}

    def state(s):
        key = s.tobytes()
        if cache.get("key") != key:
            q = np.exp(np.clip(s, -700.0, 700.0))
            x, load = shape(q)
            u = x[net.edges[:, 1]] - x[net.edges[:, 0]]
            length = np.linalg.norm(u, axis=1)
            cache.update(key=key, q=q, x=x, load=load, u=u, L=length)
        return cache

    def residual(s):
        c = state(s)
        if method == "forces":
            return c["q"] * c["L"] / target - 1.0
        return c["L"] / target - 1.0

    def jacobian(s):  # dense (a small net): exact trust-region steps
        c = state(s)
        q, u = c["q"], c["u"]
        length = np.maximum(c["L"], 1e-300)
        inv = shape.solve(np.eye(p.n_free))
        k_full = p.gather(p.gather(inv).T)  # C_f D^-1 C_f^T, (M, M)
        j_len = -sum(np.outer(u[:, c] / length, u[:, c]) * k_full for c in range(3))
        if method == "forces":
            return (np.diag(length) + q[:, None] * j_len) * (q / target[:, None])
        return j_len * (q / target[:, None])

    fit = least_squares(
        residual,
        np.log(q0),
        jac=jacobian,
        method="trf",
        tr_solver="exact",
        ftol=1e-15,
        xtol=1e-15,
        gtol=1e-15,
        max_nfev=max(max_iter - spent - stall.iterations, 1),  # (what the budget leaves)
    )
    c = state(fit.x)
    miss = float(np.max(np.abs(residual(fit.x))))
    if not miss <= tol:
        best = (c["x"], c["load"], c["q"], np.log1p(residual(fit.x)))
        why = "max_iter" if fit.status == 0 else stall.why  # (0: out of evaluations)
        stall = Stalled(why, best, stall.iterations + int(fit.nfev))
        raise _unmet(net, method, target, stall, tol, name, spent, max_iter)
    q, x, load = c["q"], c["x"], c["load"]
    return x, load, _mean_kept(shape, method, q, q0), int(fit.nfev) + spent, miss


def _unmet(net, method, target, stall, tol, name, spent, max_iter) -> ConfigError:
    """The message for targets not met: the worst edge at the best state reached."""
    prefix = name[: name.rfind(".") + 1]
    if stall.best is None:
        return ConfigError(f"{name}: cannot be met: {stall.why}: give other targets")
    x, r = stall.best[0], stall.best[-1]
    worst = int(np.argmax(np.abs(r)))
    length = _lengths(net, x)[worst]
    q = stall.best[2][worst]
    got, what = (q * length, "tension") if method == "forces" else (length, "length")
    miss = float(abs(math.expm1(r[worst])))
    iterations = stall.iterations + spent
    if stall.why == "max_iter":
        why = f"{prefix}max_iter = {max_iter} reached: raise it"
    else:
        why = f"{stall.why}: the targets are not compatible"
    return ConfigError(
        f"{name}: cannot be met to {prefix}tol = {tol:g}: edge {worst} (nodes "
        f"{net.edges[worst].tolist()}) has {what} {got:.9g}, target {target[worst]:.9g} "
        f"(relative miss {miss:.2e} after {iterations} iterations; {why}): give reachable "
        f"targets ({HINTS[method == 'lengths']})"
    )


HINTS = (  # what makes target forces (lengths) unreachable
    "at each free node the tensions must balance its load: a cable under its weight or a "
    "load cannot carry one tension throughout",
    "an edge between fixed nodes keeps its length; a free node's edges must close up",
)


def _mean_kept(shape: _Shape, method: str, q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Target lengths without loads fix q only up to a factor: the start's geometric mean
    (the shape does not change)."""
    if method == "lengths" and not np.any(shape.force) and not shape.weighs:
        mean = math.exp(float(np.mean(np.log(q0))))
        return q * (mean / math.exp(float(np.mean(np.log(q)))))
    return q
