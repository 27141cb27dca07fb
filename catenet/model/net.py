"""The discrete net (nodes, edges, rest lengths, stiffness, supports, masses) and its loads.

Both are plain containers of arrays, validated once when built; solvers never change them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from catenet.errors import ConfigError
from catenet.model.guides import Elastic, Guides
from catenet.model.laws import Law, tension_switches
from catenet.model.limits import MAGNITUDE, too_large
from catenet.model.motions import support_positions


def _as_array(name: str, value, dtype, shape_tail: tuple[int, ...]) -> np.ndarray:
    try:
        arr = np.ascontiguousarray(value, dtype=dtype)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ConfigError(
            f"{name}: cannot be read as an array of {np.dtype(dtype).name}: {exc}"
        ) from None
    if arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
        want = "(n, " + ", ".join(map(str, shape_tail)) + ")" if shape_tail else "(n,)"
        raise ConfigError(f"{name}: shape {arr.shape}: must be {want}")
    return arr


@dataclass(frozen=True, eq=False)
class Net:
    """A cable net: ``N`` nodes joined by ``M`` straight elastic edges.

    Attributes
    ----------
    nodes : (N, 3) float64, reference positions [m]
    edges : (M, 2) int64, node indices of each edge
    rest_length : (M,) float64, unstressed length l0 of each edge [m]
    EA : (M,) float64, axial stiffness [N]
    line_density : (M,) float64, mass per unstressed length rho*A [kg/m]
    fixed : (N,) bool, pinned nodes (all three DOFs)
    law : the material law of every edge, its tension-only switches included
        (``from_arrays``' default: the paper's linear law); ``tension_only`` says whether
        every edge is tension-only
    point_mass : (N,) float64, lumped masses added at the nodes [kg] (corner masses of
        a tether net), or None; part of ``mass``, so gravity and inertia act on them
    bodies : how many of the last nodes are the centres of rigid bodies (no edges, their
        mass in ``point_mass``; ``catenet.terms.body``), 0 for a net alone
    flies : parts of the net may have no support (a net flying free, dynamic runs only:
        its rigid-body motion is inertia's to hold); False: every part needs one
    guides : nodes on rollers and sliders (``catenet.model.guides.Guides``: held in some
        directions only; never fixed nodes), or None
    springs : elastic supports (``catenet.model.guides.Elastic``: a spring toward the
        node's given position; ``catenet.terms.supports.ElasticSupport``), or None
    """

    nodes: np.ndarray
    edges: np.ndarray
    rest_length: np.ndarray
    EA: np.ndarray
    line_density: np.ndarray
    fixed: np.ndarray
    law: Law
    point_mass: np.ndarray | None = None
    bodies: int = 0
    flies: bool = False
    guides: Guides | None = None
    springs: Elastic | None = None

    @property
    def tension_only(self) -> bool:
        """Whether every edge carries no compression (slack when eps < 0): the law's."""
        return self.law.all_tension_only

    @classmethod
    def from_arrays(
        cls,
        nodes,
        edges,
        *,
        EA,
        fixed,
        rest_length=None,
        line_density=0.0,
        tension_only: bool | Sequence[bool] = True,
        law: Law | None = None,
        point_mass=None,
        bodies: int = 0,
        flies: bool = False,
        guides: Guides | None = None,
        springs: Elastic | None = None,
    ) -> Net:
        """Build and validate a net. Scalars broadcast over edges; ``fixed`` is a list of
        node indices or an (N,) bool mask; ``rest_length`` defaults to the initial lengths;
        ``law`` (one entry per edge) defaults to the paper's linear law with
        ``tension_only`` (a bool, or one per edge; ignored where a law is given); ``point_mass``
        (N,) [kg] adds to the lumped masses; ``flies``: parts without a support are
        allowed (dynamic runs); ``guides``, ``springs``: rollers and sliders, springs."""
        nodes = _as_array("nodes", nodes, np.float64, (3,))
        edges = _as_array("edges", edges, np.int64, (2,))
        n, m = len(nodes), len(edges)
        problems = []
        if n < 2:
            problems.append(f"nodes: {n} nodes: a net needs at least 2")
        if m < 1:
            problems.append("edges: empty: a net needs at least one edge")
        if problems:
            raise ConfigError(problems)
        if not np.all(np.abs(nodes) <= MAGNITUDE):
            bad = np.flatnonzero(~(np.abs(nodes) <= MAGNITUDE).all(axis=1))[:5].tolist()
            problems.append(
                f"nodes: non-finite or huge coordinates at nodes {bad}: must be finite, "
                f"within {too_large()}"
            )
            raise ConfigError(problems)
        bad = np.flatnonzero((edges < 0).any(axis=1) | (edges >= n).any(axis=1))
        if bad.size:
            e = int(bad[0])
            problems.append(f"edges[{e}] = {edges[e].tolist()}: node indices must be in 0..{n - 1}")
            raise ConfigError(problems)
        loops = np.flatnonzero(edges[:, 0] == edges[:, 1])
        if loops.size:
            e = int(loops[0])
            problems.append(
                f"edges[{e}] = {edges[e].tolist()}: an edge must join two different nodes"
            )
        _duplicate_edges(edges, problems)
        length = np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)
        if rest_length is None:
            l0 = length.copy()
            zero = np.flatnonzero(~(l0 > 0))
            if zero.size and not loops.size:
                e = int(zero[0])
                problems.append(
                    f"edges[{e}] = {edges[e].tolist()}: zero length and no rest_length given: "
                    "nodes of an edge must be distinct points"
                )
        else:
            l0 = _broadcast("rest_length", rest_length, m, problems)
        EA = _broadcast("EA", EA, m, problems)
        rho_a = _broadcast("line_density", line_density, m, problems, allow_zero=True)
        mask = _fixed_mask(fixed, n, problems)
        if law is not None and len(law.kind) != m:
            problems.append(f"law: {len(law.kind)} entries: must have one per edge ({m})")
        if point_mass is not None:
            point_mass = _broadcast("point_mass", point_mass, n, problems, allow_zero=True)
        held = _partial(guides, springs, n, mask, problems)  # rollers, sliders, springs
        only = tension_switches(tension_only, m, problems)
        if problems:
            raise ConfigError(problems)
        if law is None:
            law = Law.uniform(m, tension_only=only)
        net = cls(nodes, edges, l0, EA, rho_a, mask, law, point_mass, bodies, bool(flies), *held)
        net._check_supported()
        return net

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_net(self) -> int:
        """The nodes of the net itself: all but the trailing body centres."""
        return len(self.nodes) - self.bodies

    @property
    def n_edges(self) -> int:
        return len(self.edges)

    @cached_property
    def mass(self) -> np.ndarray:
        """Lumped nodal masses m_i = sum over edges at i of rho A l0 / 2 [kg], plus the
        point masses."""
        half = 0.5 * self.line_density * self.rest_length
        m = np.zeros(self.n_nodes)
        np.add.at(m, self.edges[:, 0], half)
        np.add.at(m, self.edges[:, 1], half)
        if self.point_mass is not None:
            m += self.point_mass
        return m

    @cached_property
    def axial_stiffness(self) -> np.ndarray:
        """Per node, half the sum of EA/l0 of its edges [N/m]: the scale of K's diagonal."""
        half = 0.5 * self.EA / self.rest_length
        k = np.zeros(self.n_nodes)
        np.add.at(k, self.edges[:, 0], half)
        np.add.at(k, self.edges[:, 1], half)
        return k

    def replace(self, **changes) -> Net:
        """A copy with ``changes`` (any of ``from_arrays``' arguments: nodes, edges, EA,
        fixed, rest_length, line_density, tension_only, law, point_mass, bodies),
        validated as a new net; everything else, the material law, point masses and
        bodies included, carried over. The one way to copy a net. ``tension_only`` sets
        every edge's switch of the law kept; other ``edges`` without a ``law`` get the
        linear law (with the net's switch, if every edge had it)."""
        fields: dict[str, Any] = dict(
            nodes=self.nodes,
            edges=self.edges,
            EA=self.EA,
            fixed=self.fixed,
            rest_length=self.rest_length,
            line_density=self.line_density,
            tension_only=self.tension_only,
            law=self.law,
            point_mass=self.point_mass,
            bodies=self.bodies,
            flies=self.flies,
            guides=self.guides,
            springs=self.springs,
        )
        unknown = set(changes) - set(fields)
        if unknown:
            raise TypeError(f"Net.replace: unknown fields {sorted(unknown)}")
        if "law" not in changes:
            if "edges" in changes:
                fields["law"] = None  # a law per edge does not fit other edges
            elif "tension_only" in changes:  # every edge's switch, the law kept
                only = tension_switches(changes["tension_only"], self.n_edges)
                fields["law"] = self.law.with_tension_only(only)
        fields.update(changes)
        nodes, edges = fields.pop("nodes"), fields.pop("edges")
        return Net.from_arrays(nodes, edges, **fields)

    def same_as(self, other: Net | None) -> bool:
        """Whether ``other`` is the same net: every array equal, the law's included."""
        if other is self:
            return True
        if other is None or self.bodies != other.bodies:
            return False
        arrays = (
            (self.nodes, other.nodes),
            (self.edges, other.edges),
            (self.rest_length, other.rest_length),
            (self.EA, other.EA),
            (self.fixed, other.fixed),
            (self.line_density, other.line_density),
        )
        if not all(_equal(mine, theirs) for mine, theirs in arrays):
            return False
        a, b = self.law, other.law
        laws = ((a.kind, b.kind), (a.params, b.params), (a.table, b.table))
        if not all(_equal(mine, theirs) for mine, theirs in laws):
            return False
        if not _equal(a.tension_only, b.tension_only) or a.smooth != b.smooth:
            return False
        if (self.guides is None) != (other.guides is None):
            return False
        if self.guides is not None and not self.guides.same_as(other.guides):
            return False
        if (self.springs is None) != (other.springs is None):
            return False
        if self.springs is not None and not self.springs.same_as(other.springs):
            return False
        pa, pb = self.point_mass, other.point_mass
        return (pa is None and pb is None) or (pa is not None and pb is not None and _equal(pa, pb))

    def with_rest_length(self, rest_length, law: Law | None = None) -> Net:
        """A copy with other rest lengths (pretension, or a cable of another length) and,
        if given, another material law."""
        return self.replace(rest_length=rest_length, law=self.law if law is None else law)

    def with_point_mass(self, point_mass) -> Net:
        """A copy with these point masses (N,) [kg] at the nodes (replacing any)."""
        return self.replace(point_mass=point_mass)

    def with_body_nodes(self, positions, masses) -> Net:
        """The net with free nodes added after its own, at ``positions`` (B, 3), each with
        its point mass ``masses`` (B,) [kg] and no edge: the nodes of moving balls and free
        rigid bodies, counted in ``bodies``."""
        positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        nb = len(positions)
        point = np.zeros(self.n_nodes) if self.point_mass is None else self.point_mass
        return Net.from_arrays(
            np.vstack([self.nodes, positions]),
            self.edges,
            EA=self.EA,
            fixed=np.concatenate([self.fixed, np.zeros(nb, bool)]),
            rest_length=self.rest_length,
            line_density=self.line_density,
            tension_only=self.tension_only,
            law=self.law,
            point_mass=np.concatenate([point, np.asarray(masses, dtype=np.float64)]),
            bodies=self.bodies + nb,
            flies=self.flies,
            guides=self.guides,
            springs=self.springs,
        )

    def with_guides(self, *guides: Guides) -> Net:
        """A copy with these nodes on rollers and sliders besides the net's own
        (``Guides.roller``, ``Guides.slider``)."""
        return self.replace(guides=Guides.join([self.guides, *guides]))

    def with_springs(self, *springs: Elastic) -> Net:
        """A copy with these elastic supports besides the net's own (``Elastic.of``)."""
        return self.replace(springs=Elastic.join([self.springs, *springs]))

    @property
    def supported(self) -> np.ndarray:
        """(N,) bool: the nodes a support holds in some direction (fixed, guided or on
        a spring)."""
        mask = self.fixed.copy()
        if self.guides is not None:
            mask[self.guides.nodes] = True
        if self.springs is not None:
            mask[self.springs.held_nodes] = True
        return mask

    def components(self) -> np.ndarray:
        """Connected-component label (0, 1, ... in order of first node) of every node
        (``components``)."""
        return components(self.n_nodes, self.edges)

    def _check_supported(self) -> None:
        """Every connected part with a free node needs a support, or it is a mechanism."""
        problems = []
        degree = np.bincount(self.edges.ravel(), minlength=self.n_nodes)
        lonely = np.flatnonzero((degree == 0) & ~self.fixed)
        if self.guides is not None and np.isin(self.guides.nodes, lonely).any():
            problems.append("guides: a node on a roller or slider needs an edge")
        lonely = lonely[lonely < self.n_nodes - self.bodies]  # a body's centre has none
        if lonely.size:
            problems.append(
                f"nodes {lonely[:10].tolist()}: belong to no edge: every free node needs an "
                "edge (join them to the net, fix them, e.g. as posts, or leave them out)"
            )
        if self.flies:  # a free flight: parts without support are the point
            if problems:
                raise ConfigError(problems)
            return
        labels = self.components()
        supported = np.zeros(labels.max() + 1, bool)
        supported[labels[self.supported]] = True
        loose = np.flatnonzero(~supported[labels] & (degree > 0))
        if loose.size:
            problems.append(
                f"nodes {loose[:10].tolist()}{' ...' if loose.size > 10 else ''}: "
                "a part of the net has no support (a mechanism): fix at least one of its nodes "
                "or hold it by rollers, sliders or springs (a dynamic run, solver.method = "
                "'dynamic', lets it fly free)"
            )
        if not self.supported.any():
            problems.append(
                "supports: no node is fixed: a net without supports moves as a rigid body and "
                "has no static equilibrium: fix at least one node, or let it fly in a dynamic "
                "run (solver.method = 'dynamic')"
            )
        if problems:
            raise ConfigError(problems)


def _duplicate_edges(edges: np.ndarray, problems: list) -> None:
    """A problem for an edge listed more than once (either way round)."""
    key = np.sort(edges, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    if (counts > 1).any():
        dup = key[first[np.argmax(counts > 1)]].tolist()
        problems.append(f"edges: {dup} appears {int(counts.max())} times: edges must be unique")


def _partial(guides, springs, n: int, mask: np.ndarray, problems: list) -> tuple:
    """The rollers and sliders, the springs (each None where there are none), their
    problems on a net of ``n`` nodes pinned at ``mask`` added to ``problems``."""
    if guides is not None and not problems:
        problems.extend(guides.check(n, mask))
    if springs is not None and not problems:
        problems.extend(springs.check(n))
    guides = guides if guides is not None and len(guides) else None
    springs = springs if springs is not None and len(springs) else None
    return guides, springs


def _equal(a, b) -> bool:
    return np.shape(a) == np.shape(b) and bool(np.array_equal(a, b))


def _broadcast(name, value, m, problems, allow_zero=False) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(m, float(arr))
    if arr.shape != (m,):
        problems.append(f"{name}: shape {arr.shape}: must be a scalar or one value per edge ({m})")
        return np.zeros(m)
    ok = (np.abs(arr) <= MAGNITUDE) & ((arr >= 0) if allow_zero else (arr > 0))
    if not ok.all():
        e = int(np.flatnonzero(~ok)[0])
        need = ">= 0" if allow_zero else "> 0"
        problems.append(
            f"{name}[{e}] = {float(arr[e])!r}: must be finite and {need}, within {too_large()}"
        )
    return np.ascontiguousarray(arr)


def _fixed_mask(fixed, n, problems) -> np.ndarray:
    arr = np.asarray(fixed)
    if arr.dtype == bool:
        if arr.shape != (n,):
            problems.append(f"fixed: mask of shape {arr.shape}: must be ({n},)")
            return np.zeros(n, bool)
        return arr.copy()
    try:
        idx = np.asarray(arr, dtype=np.int64).ravel()
    except (TypeError, ValueError):
        problems.append(f"fixed = {fixed!r}: must be a list of node indices")
        return np.zeros(n, bool)
    bad = idx[(idx < 0) | (idx >= n)]
    if bad.size:
        problems.append(f"fixed: node {int(bad[0])}: node indices must be in 0..{n - 1}")
        return np.zeros(n, bool)
    mask = np.zeros(n, bool)
    mask[idx] = True
    return mask


@dataclass(frozen=True, eq=False)
class Loads:
    """What acts on a net: nodal forces, gravity and prescribed support motion, each
    constant or following a time history (``catenet.model.histories.History``) in dynamic runs.

    Attributes
    ----------
    force : (N, 3) constant nodal forces [N] (pressure and point loads), or None
    gravity : (3,) acceleration [m/s^2] acting on the lumped masses, or None (not computed)
    support_displacement : (N, 3) final displacement of fixed nodes [m], or None
    ramp_time : (N,) time over which each support moves linearly to its final place
        in a dynamic run [s] (0: at once); static runs reach the final place directly
    parts : ((N, 3) force, History) pairs: forces that follow a history in dynamic runs
    gravity_history : the history of gravity, or None (constant)
    gravity_factor : the factor of gravity's history at the time frozen loads were taken
        (``at``; 1 otherwise): what buoyancy, the displaced water's weight, scales by
    support_history : (node indices, History or Sine) pairs: supports whose displacement
        is factor(t) times ``support_displacement`` in dynamic runs (instead of a ramp); a
        static run takes a sine motion at t = 0
    vessels : (node indices, ``catenet.model.motions.Vessel``) pairs: supports carried by
        a vessel's rigid motion (a static run takes it at t = 0)

    Static runs (``time`` None) take every load and displacement at its full value: a
    history's factor is used in dynamic runs only.
    """

    force: np.ndarray | None = None
    gravity: np.ndarray | None = None
    support_displacement: np.ndarray | None = None
    ramp_time: np.ndarray | None = field(default=None)
    parts: tuple = ()
    gravity_history: Any = None
    gravity_factor: float = 1.0
    support_history: tuple = ()
    vessels: tuple = ()  # (node indices, catenet.model.motions.Vessel) pairs

    def external_force(
        self, net: Net, factor: float = 1.0, time: float | None = None
    ) -> np.ndarray:
        """Total external nodal force (N, 3) at ``time`` (each history's factor then;
        None: every load in full), scaled by a load factor."""
        f = np.zeros((net.n_nodes, 3))
        if self.force is not None:
            f += self.force
        for force, history in self.parts:
            s = 1.0 if time is None else history(time)
            if s != 0.0:
                f += s * force
        if self.gravity is not None:
            g = 1.0 if time is None or self.gravity_history is None else self.gravity_history(time)
            if g != 0.0:
                f += (g * net.mass)[:, None] * np.asarray(self.gravity)[None, :]
        if factor != 1.0:
            f *= factor
        return f

    def weight_scale(self, time: float | None = None) -> float:
        """The factor gravity acts with at ``time`` (None: as built, its history aside):
        what weight-like terms (water's buoyancy) scale by."""
        g = 1.0 if time is None or self.gravity_history is None else self.gravity_history(time)
        return self.gravity_factor * g

    @property
    def varies(self) -> bool:
        """Whether the external force follows a history (dynamic runs evaluate it at
        every step)."""
        return bool(self.parts) or (self.gravity is not None and self.gravity_history is not None)

    def support_positions(self, net: Net, *, time: float | None = None, factor: float = 1.0):
        """Positions of the fixed nodes (K, 3): at ``time`` along each ramp, history or
        vessel (dynamic), or at ``factor`` of the final displacement (static continuation)
        (``catenet.model.motions.support_positions``)."""
        return support_positions(self, net, time, factor)

    def at(self, net: Net, time: float) -> Loads:
        """The loads frozen at ``time``: every force at its value then (gravity included)
        and the supports where they are then, as constant loads of a static solve."""
        disp = None
        if self.support_displacement is not None:
            disp = np.zeros((net.n_nodes, 3))
            disp[net.fixed] = self.support_positions(net, time=time) - net.nodes[net.fixed]
        return Loads(
            force=self.external_force(net, time=time),
            support_displacement=disp,
            gravity_factor=self.weight_scale(time),
        )

    def settle_time(self) -> float:
        """Time after which nothing changes: every support has reached its final place
        and every history its last point."""
        t = 0.0
        if self.support_displacement is not None and self.ramp_time is not None:
            t = float(np.max(self.ramp_time, initial=0.0))
        ends = [h.end for _, h in (*self.parts, *self.support_history, *self.vessels)]
        if self.gravity is not None and self.gravity_history is not None:
            ends.append(self.gravity_history.end)
        return max([t, *ends])

    @property
    def has_histories(self) -> bool:
        timed = self.parts or self.support_history or self.vessels
        return bool(timed or self.gravity_history is not None)

    @property
    def moves_supports(self) -> bool:
        return self.support_displacement is not None and bool(np.any(self.support_displacement))


def components(n: int, edges: np.ndarray) -> np.ndarray:
    """Connected-component label (0, 1, ... in order of first node) of each of n nodes
    joined by ``edges`` (M, 2): union-find in NumPy, every edge hooking the larger of its
    two roots under the smaller, then pointer jumping until every node points at its root
    (a few passes; no SciPy on a run's path)."""
    parent = np.arange(n)
    i, j = edges[:, 0], edges[:, 1]
    while True:
        ri, rj = parent[i], parent[j]
        differ = ri != rj
        if not differ.any():
            break
        lo, hi = np.minimum(ri, rj)[differ], np.maximum(ri, rj)[differ]
        parent[hi] = lo  # roots only, always to a smaller index: no cycles
        while True:
            up = parent[parent]
            if np.array_equal(up, parent):
                break
            parent = up
    root = parent == np.arange(n)
    return (np.cumsum(root) - 1)[parent]
