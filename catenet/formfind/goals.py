"""Targets of form finding resolved on a net: one residual vector and its partial
derivatives.

Each ``[[target]]`` becomes rows of one vector: a node's coordinate (a row per node and
axis: the value a = x_i,c), an edge's tension (a row per edge of the cable: a = q_e L_e,
the force density method's tension; N = q L with q = N / L in the elastic equilibrium),
a cable's length (a row per cable: a = sum of L_e over its edges, a "chain") or a
support's reaction (a row per fixed node and component: its partial derivatives
are ``catenet.formfind.reactions``' and ``catenet.formfind.elastic``'s). A row asks a in [lo, hi]
(lo = hi: a value); its miss is m = a - clip(a, lo, hi) and its residual r = w m / s,
with the target's weight w and its scale s (the net's size for positions, the target
tension for tensions, the largest component asked for a reaction), so that positions
and forces weigh alike. A row is met when |m| <= tol s.

The partial derivatives, with u_e = x_b - x_a and L = |u_e|: da/dx_i,c = 1 for a
position; for a tension dN/dp_e = N_p (the edge's parameter: q, with N_p = L_e; or the
rest length) and dN/dx_b = -dN/dx_a = N_L u_e / L_e (N_L = q_e; EA / l0 elastic); for a
length da/dx_b = -da/dx_a = u_e / L_e summed over its edges (no parameter's). Inside its
range a row's residual is flat (its derivative 0).
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from catenet.case.keys import show
from catenet.case.kinds.base import expand
from catenet.errors import ConfigError

if TYPE_CHECKING:
    import scipy.sparse as sp

#: A range row within this share of its scale of a bound counts in the Jacobian
#: (``Goals.slope``).
EDGE = 1e-4


@dataclass
class Goals:
    """The rows of every target: ``node``/``axis`` (positions, -1 for tensions),
    ``edge`` (tensions, -1 for positions), ``chain`` (a length: its index in ``chains``,
    the edges of one cable, and ``cable``, that cable's; -1 for the others), the range
    ``lo``..``hi``, the scale, the weight (``w``: weight / scale), ``hard`` and which
    target (``of``) each row is."""

    targets: tuple
    node: np.ndarray
    axis: np.ndarray
    edge: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    scale: np.ndarray
    w: np.ndarray
    hard: np.ndarray
    of: np.ndarray
    tol: float
    surface: np.ndarray  # per row: the index in ``surfaces`` (-1: none)
    reacts: np.ndarray  # per row: a support's reaction (node, axis) (bool)
    chain: np.ndarray  # per row: the index in ``chains`` (-1: none)
    surfaces: tuple = ()
    chains: tuple = ()  # per length row's chain: (its cable's index, its edges)

    @property
    def rows(self) -> int:
        return len(self.lo)

    def achieved(
        self, x: np.ndarray, q: np.ndarray, length: np.ndarray, reaction=None
    ) -> np.ndarray:
        """The value of every row at the shape x with force densities q (tension q L) and
        the supports' ``reaction`` (N, 3) (reaction rows: NaN without)."""
        pos = (self.edge < 0) & (self.chain < 0)
        a = np.empty(self.rows)
        a[pos] = x[self.node[pos], self.axis[pos]]
        for j in np.flatnonzero(self.chain >= 0):
            a[j] = float(np.sum(length[self.chains[self.chain[j]][1]]))
        if self.reacts.any():
            r = self.reacts
            a[r] = np.nan if reaction is None else reaction[self.node[r], self.axis[r]]
        ten = self.edge >= 0
        e = self.edge[ten]
        a[ten] = q[e] * length[e]
        for k, field in enumerate(self.surfaces):
            rows = np.flatnonzero(self.surface == k)
            a[rows] = field.offset(x[self.node[rows]])[0]
        return a

    def miss(self, a: np.ndarray) -> np.ndarray:
        return a - np.clip(a, self.lo, self.hi)

    def met(self, a: np.ndarray) -> np.ndarray:
        """Per row: met to tol (relative to its scale)."""
        return np.abs(self.miss(a)) <= self.tol * self.scale

    def slope(self, a: np.ndarray) -> np.ndarray:
        """dr/da per row: the weight, 0 inside a range, except within ``EDGE`` of its
        scale of a bound: a value the search has pushed onto its bound is held there by
        its Jacobian's row (an active constraint), else the next step, blind to it,
        crosses it and is refused, and the search crawls along the bound."""
        band = np.minimum(EDGE * self.scale, 0.25 * (self.hi - self.lo))  # (a narrow range)
        out = (a < self.lo + band) | (a > self.hi - band) | (self.lo == self.hi)
        return np.where(out, self.w, 0.0)

    def partials(
        self, x: np.ndarray, q: np.ndarray, a: np.ndarray, index: np.ndarray, net, dn=None
    ) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """(dr/dx_f, dr/dp): the residual's partial derivatives, sparse, (R, 3 n_free)
        and (R, M), the DOFs of the free nodes interleaved (3 f + c); ``index`` gives a
        node's free index (-1: fixed). p is each edge's parameter: q (``dn`` None), or
        what ``dn`` = (dN/dL, dN/dp) per edge says. Reaction rows are left 0."""
        import scipy.sparse as sp

        n3 = 3 * int(np.count_nonzero(index >= 0))
        slope = self.slope(a)
        rows_x, cols_x, vals_x = [], [], []
        pos = np.flatnonzero((self.edge < 0) & ~self.reacts & (self.chain < 0))  # (a surface's dz)
        rows_x.append(pos)
        cols_x.append(3 * index[self.node[pos]] + self.axis[pos])
        vals_x.append(slope[pos])
        for k, field in enumerate(self.surfaces):  # d(z - f(x, y)) = dz - f_x dx - f_y dy
            rows = np.flatnonzero(self.surface == k)
            grad = field.offset(x[self.node[rows]])[1]
            for c in range(2):
                rows_x.append(rows)
                cols_x.append(3 * index[self.node[rows]] + c)
                vals_x.append(-slope[rows] * grad[:, c])
        ten = np.flatnonzero(self.edge >= 0)
        e = self.edge[ten]
        ends = net.edges[e]
        u = x[ends[:, 1]] - x[ends[:, 0]]
        length = np.linalg.norm(u, axis=1)
        n_l, n_p = (q[e], length) if dn is None else (dn[0][e], dn[1][e])
        g = (slope[ten] * n_l / length)[:, None] * u  # dN/dx_b, weighted
        for end, sign in ((ends[:, 0], -1.0), (ends[:, 1], 1.0)):
            f = index[end]
            free = f >= 0
            for c in range(3):
                rows_x.append(ten[free])
                cols_x.append(3 * f[free] + c)
                vals_x.append(sign * g[free, c])
        for j in np.flatnonzero(self.chain >= 0):  # d(sum L_e) = sum u_e / L_e (dx_b - dx_a)
            along = net.edges[self.chains[self.chain[j]][1]]
            v = x[along[:, 1]] - x[along[:, 0]]
            t = slope[j] * v / np.linalg.norm(v, axis=1)[:, None]
            for end, sign in ((along[:, 0], -1.0), (along[:, 1], 1.0)):
                f = index[end]
                free = f >= 0
                for c in range(3):
                    rows_x.append(np.full(int(free.sum()), j))
                    cols_x.append(3 * f[free] + c)
                    vals_x.append(sign * t[free, c])
        r = self.rows
        d_x = sp.csr_matrix(
            (np.concatenate(vals_x), (np.concatenate(rows_x), np.concatenate(cols_x))),
            shape=(r, n3),
        )
        d_q = sp.csr_matrix((slope[ten] * n_p, (ten, e)), shape=(r, net.n_edges))
        return d_x, d_q

    def outside(self, a: np.ndarray) -> str | None:
        """Where a surface row has no value (its node off the plan): the message."""
        bad = np.flatnonzero(~np.isfinite(a))
        if not bad.size:
            return None
        j = int(bad[0])
        k = int(self.of[j])
        return (
            f"target[{k}].surface = {self.targets[k].surface!r}: node {int(self.node[j])} is "
            f"outside its plan in the shape of the starting force densities ({bad.size} "
            "nodes): the surface must cover the net in plan"
        )

    def select(self, rows: np.ndarray) -> Goals:
        """The goals of these rows only (a mask)."""
        per_row = (
            *("node", "axis", "edge", "lo", "hi", "scale", "w", "hard", "of", "surface"),
            *("reacts", "chain"),
        )
        return Goals(**{**self.__dict__, **{k: getattr(self, k)[rows] for k in per_row}})


class _Rows:
    """The columns of the rows being resolved."""

    def __init__(self):
        names = ("node", "axis", "edge", "lo", "hi", "sc", "w", "hard", "of", "surface")
        self.cols: dict[str, list] = {k: [] for k in (*names, "reacts", "chain")}

    def add(self, k, t, node, axis, edge, lo, hi, scale, surface=-1, reacts=False, chain=-1):
        n, cols = len(lo), self.cols
        for name, v in (("node", node), ("axis", axis), ("edge", edge)):
            cols[name].append(np.broadcast_to(np.asarray(v, dtype=np.int64), (n,)))
        for name, v in (("lo", lo), ("hi", hi)):
            cols[name].append(np.asarray(v, dtype=np.float64))
        for name, v in (("sc", scale), ("w", t.weight / scale), ("hard", t.hard), ("of", k)):
            cols[name].append(np.full(n, v))
        cols["surface"].append(np.full(n, surface))
        cols["reacts"].append(np.full(n, reacts))
        cols["chain"].append(np.full(n, chain))


def resolve_goals(targets, scene, size: float, tol: float) -> Goals:
    """The targets of a case on its built ``scene``; ``size`` scales the positions.
    ConfigError (key path, value) for an unknown node, set or cable, a fixed node, or
    values that do not match the nodes, a support target on a free node."""
    rows = _Rows()
    surfaces: list = []
    chains: list = []
    for k, t in enumerate(targets):
        if t.support is not None:
            _support_rows(rows, k, t, scene)
            continue
        if t.cable is not None and t.length is not None:
            lo, hi = t.length if isinstance(t.length, tuple) else (t.length, t.length)
            for c, edges in _cable_groups(k, t, scene):
                chains.append((c, edges))
                rows.add(k, t, -1, -1, -1, [lo], [hi], hi, chain=len(chains) - 1)
            continue
        if t.cable is not None:
            edges = np.concatenate([e for _, e in _cable_groups(k, t, scene)])
            lo, hi = t.tension if isinstance(t.tension, tuple) else (t.tension, t.tension)
            n = len(edges)
            rows.add(k, t, -1, -1, edges, np.full(n, lo), np.full(n, hi), hi)
            continue
        nodes = _nodes(k, t, scene)
        if t.surface is not None:
            surfaces.append(_surface(k, t, scene.net, nodes))
            d = 0.0 if t.within is None else t.within
            n = len(nodes)
            rows.add(k, t, nodes, 2, -1, np.full(n, -d), np.full(n, d), size, len(surfaces) - 1)
            continue
        given = [(a, getattr(t, a)) for a in ("x", "y", "z")] if t.point is None else []
        if t.point is not None:
            pts = np.asarray(t.point, dtype=np.float64).reshape(-1, 3)
            given = [(a, pts[:, c]) for c, a in enumerate("xyz")]
        for axis, value in given:
            if value is None:
                continue
            what = "point" if t.point is not None else axis
            v = _per_node(k, what, t, value, nodes)
            rows.add(k, t, nodes, "xyz".index(axis), -1, v, v, size)
    if not rows.cols["lo"]:
        raise ConfigError("target: no target")
    arr = {k: np.concatenate(v) for k, v in rows.cols.items()}
    return Goals(
        targets=tuple(targets),
        **{k: arr[k] for k in ("node", "axis", "edge", "lo", "hi", "w", "of", "surface")},
        scale=arr["sc"],
        hard=arr["hard"].astype(bool),
        reacts=arr["reacts"].astype(bool),
        chain=arr["chain"],
        tol=tol,
        surfaces=tuple(surfaces),
        chains=tuple(chains),
    )


def _support_rows(rows: _Rows, k: int, t, scene) -> None:
    """A support's reaction: a row per fixed node and component, scaled by the largest
    component asked (or, all 0, the net's total load)."""
    path = f"target[{k}].support"
    net = scene.net
    nodes = _node_set(path, t.support, scene)
    free = nodes[~net.fixed[nodes]]
    if free.size:
        raise ConfigError(
            f"{path} = {show(t.support)}: node {int(free[0])} is free: a reaction is a fixed "
            "node's (a support of geometry's fixed nodes)"
        )
    values = [t.reaction_of(c) for c in t.components]
    largest, load = max(abs(v) for v in values), _load_scale(scene)
    scale = max(largest, 1e-6 * load) if largest > 0 else load
    for c, v in zip(t.components, values, strict=True):
        n = len(nodes)
        rows.add(k, t, nodes, c, -1, np.full(n, v), np.full(n, v), scale, reacts=True)


def _load_scale(scene) -> float:
    """A force scale of the net: its weight and loads (1 N without): a reaction's scale
    where it is asked to be 0 (1e-6 of it had asked 1e-15 of the load, below the
    round-off of the tensions that make the reaction), and 1e-6 of it at least."""
    net, loads = scene.net, scene.loads
    total = 0.0
    if loads is not None and loads.gravity is not None:
        g = float(np.linalg.norm(loads.gravity))
        total += g * float(np.sum(net.line_density * net.rest_length))
    if loads is not None and loads.force is not None:
        total += float(np.abs(loads.force).sum())
    return total if total > 0 else 1.0


def _surface(k: int, t, net, nodes: np.ndarray):
    """The height field of a surface target, read."""
    from catenet.formfind.surface import read_height_field

    path = f"target[{k}].surface"
    try:
        field = read_height_field(t.surface, t.smooth)
    except ValueError as exc:
        raise ConfigError(f"{path} = {t.surface!r}: {exc}") from None
    return field


def _node_set(path: str, ref, scene) -> np.ndarray:
    """The nodes of a reference (index, name or set); ConfigError where it is none."""
    try:
        nodes = np.asarray(expand(ref, scene.names or {}, scene.sets or {}), dtype=np.int64)
    except KeyError:
        known = [*(scene.names or {}), *(s for s in scene.sets or {} if ":" not in s)]
        accepted = ", ".join(map(repr, known)) or "none: give a node index"
        raise ConfigError(
            f"{path} = {show(ref)}: is neither a node name nor a node set of the net "
            f"(accepted: {accepted})"
        ) from None
    n = scene.net.n_net
    bad = nodes[(nodes < 0) | (nodes >= n)]
    if bad.size:
        raise ConfigError(f"{path} = {show(ref)}: must be a node index in 0..{n - 1}")
    if not nodes.size:
        raise ConfigError(f"{path} = {show(ref)}: the node set is empty")
    return nodes


def _nodes(k: int, t, scene) -> np.ndarray:
    net = scene.net
    path = f"target[{k}].node"
    if t.node is None:  # (a surface: every free node of the net)
        return np.flatnonzero(~net.fixed[: net.n_net])
    nodes = _node_set(path, t.node, scene)
    fixed = nodes[net.fixed[nodes]]
    if fixed.size:
        which = f"node {int(fixed[0])} is" if nodes.size == 1 else f"nodes {fixed[:5].tolist()} are"
        raise ConfigError(
            f"{path} = {show(t.node)}: {which} fixed (a support): a position target is a "
            "free node's (a support stays where it is given, or within the range of its "
            "[[formfind.support]])"
        )
    return nodes


def _per_node(k: int, what: str, t, value, nodes: np.ndarray) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if v.ndim == 0:
        return np.full(len(nodes), float(v))
    if v.shape != (len(nodes),):
        raise ConfigError(
            f"target[{k}].{what} = {show(getattr(t, what))}: has {v.shape[0]} values for the "
            f"{len(nodes)} nodes of {show(t.node)}: give one or one per node"
        )
    return v


def _cable_groups(k: int, t, scene) -> list[tuple[int, np.ndarray]]:
    """The cables a target's ``cable`` (a name or pattern) matches: (index, its edges)
    each. A net without named cables (a ``kind = "cable"`` case, a graph without
    ``[[geometry.cable]]``) is one cable, all its edges, which ``cable = "*"`` names;
    ConfigError for any other name there, or a pattern that matches no cable."""
    path = f"target[{k}].cable"
    cables = scene.cables
    if cables is None or not cables.names:
        if t.cable == "*":
            return [(0, np.arange(scene.net.n_edges))]
        raise ConfigError(
            f"{path} = {t.cable!r}: this net has no named cables (a graph's "
            "[[geometry.cable]] names them); a net without them is one cable, all its "
            'edges: cable = "*"'
        )
    hits = [c for c, n in enumerate(cables.names) if fnmatch.fnmatchcase(n, t.cable)]
    if not hits:
        raise ConfigError(
            f"{path} = {t.cable!r}: matches no cable (the cables: {', '.join(cables.names)})"
        )
    edge = np.asarray(cables.edge)
    return [(c, np.flatnonzero(edge == c)) for c in hits]


__all__ = ["Goals", "resolve_goals"]
