"""Rods: the edges of a net that bend, as arrays (``catenet.kernels.bending``).

A rod is a polyline of edges with bending stiffness EI > 0: consecutive edges of one
line (a cable of a graph, a cable of the square net, the single cable) that share a
node. Every interior node of a rod is a hinge (i, j, k) between its edges (i, j) and
(j, k); a closed line (its last edge ends where its first begins) bends at that node
too. Where lines meet (a joint of two cables) or where an edge belongs to no line (a
graph's own edges), nothing bends: such joints are pins. A clamp holds the tangent of a
rod's end edge at its given direction.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import Net

#: How a rod's natural curvature is taken: straight, or that of the given geometry.
NATURAL = ("straight", "given")


@dataclass(frozen=True, eq=False)
class Rods:
    """The hinges and clamps of a net's rods.

    hinges : (H, 3) int64, nodes (i, j, k) of each hinge, j the interior node
    EI : (H,) bending stiffness of each hinge [N m^2]
    voronoi : (H,) its Voronoi length (l1 + l2) / 2 from the rest lengths [m]
    s0 : (H,) its natural |t2 - t1| (0: straight)
    clamps : (C, 2) int64, the clamped node c and the other node o of its end edge
    tangent : (C, 3) the held unit tangent (from c to o, in the given geometry)
    clamp_EI : (C,) the end edge's EI [N m^2]; clamp_length : (C,) its rest length [m]
    spring : (C,) a rotational spring's stiffness k [N m/rad] where the clamp is elastic
        (``supports.rotational``: the moment k theta for the end's turn theta from its given
        direction, while theta is small), NaN where it is rigid (``kc``)
    """

    hinges: np.ndarray
    EI: np.ndarray
    voronoi: np.ndarray
    s0: np.ndarray
    clamps: np.ndarray
    tangent: np.ndarray
    clamp_EI: np.ndarray
    clamp_length: np.ndarray
    spring: np.ndarray | None = None

    @property
    def k(self) -> np.ndarray:
        """Each hinge's k = EI / (l1 + l2) [N m]."""
        return self.EI / (2.0 * self.voronoi)

    @property
    def kc(self) -> np.ndarray:
        """Each clamp's kc [N m] in kc |t - t0|^2 (about kc theta^2 for the end edge's turn
        theta): EI / l where it is rigid (the end edge bent against its mirror image over
        l: compliance l / (2 EI) per moment); a rotational spring k in series with that,
        kc = 1 / (2 (1 / k + l / (2 EI))), so that the end edge turns by M / k at the
        support plus its own bending, and the foot's turn is M / k to O(l^2)."""
        rigid = self.clamp_EI / self.clamp_length
        if self.spring is None:
            return rigid
        with np.errstate(divide="ignore", invalid="ignore"):
            sprung = 0.5 / (1.0 / self.spring + 0.5 / rigid)
        return np.where(np.isnan(self.spring), rigid, sprung)

    @property
    def rigid(self) -> np.ndarray:
        """(C,) bool: each clamp rigid (not a rotational spring): it holds the twist too."""
        if self.spring is None:
            return np.ones(len(self.clamps), dtype=bool)
        return np.isnan(self.spring)

    def __len__(self) -> int:
        return len(self.hinges) + len(self.clamps)


def rod_hinges(edges: np.ndarray, line: np.ndarray, bends: np.ndarray) -> np.ndarray:
    """(H, 5): the edges a, b and the nodes i, j, k of every hinge: consecutive edges of
    one line (``line`` >= 0), both bending, a = (i, j) and b = (j, k) in that order."""
    out = []
    by_line: dict[int, list[int]] = {}
    for e in np.flatnonzero(bends & (line >= 0)):
        by_line.setdefault(int(line[e]), []).append(int(e))
    for chain in by_line.values():
        pairs = list(zip(chain[:-1], chain[1:], strict=True))
        if len(chain) > 2:
            pairs.append((chain[-1], chain[0]))  # a closed line
        for a, b in pairs:
            i, j = edges[a]
            j2, k = edges[b]
            if j == j2 and i != k:
                out.append((a, b, i, j, k))
    return np.asarray(out, dtype=np.int64).reshape(-1, 5)


def without_hinges(rods: Rods, nodes: np.ndarray) -> Rods:
    """``rods`` without the hinges at ``nodes`` (there a rigid joint holds the lines'
    edges, ``catenet.model.joints``)."""
    keep = ~np.isin(rods.hinges[:, 1], nodes)
    return replace(
        rods,
        hinges=np.ascontiguousarray(rods.hinges[keep]),
        EI=np.ascontiguousarray(rods.EI[keep]),
        voronoi=np.ascontiguousarray(rods.voronoi[keep]),
        s0=np.ascontiguousarray(rods.s0[keep]),
    )


def build_rods(
    net: Net,
    EI: np.ndarray,
    line: np.ndarray,
    *,
    natural: np.ndarray | None = None,
    clamped: np.ndarray | None = None,
    clamp_key: str = "supports.clamped",
    springs: dict[int, float] | None = None,
    spring_key: str = "supports.rotational",
) -> Rods:
    """The rods of ``net``: EI (M,) per edge [N m^2] (0: no bending), ``line`` (M,) the
    line of every edge (-1: none), ``natural`` (M,) bool: the edge's rod is naturally
    curved as given (default straight), ``clamped`` node indices (each a rod end),
    ``springs`` node -> a rotational spring's stiffness [N m/rad] (each a rod end)."""
    EI = np.asarray(EI, dtype=np.float64)
    bends = EI > 0.0
    pairs = rod_hinges(net.edges, np.asarray(line), bends)
    a, b = pairs[:, 0], pairs[:, 1]
    hinges = np.ascontiguousarray(pairs[:, 2:])
    l0 = net.rest_length
    curved = np.zeros(net.n_edges, bool) if natural is None else np.asarray(natural, bool)
    s0 = np.zeros(len(hinges))
    if curved.any():
        x = net.nodes
        t1 = x[hinges[:, 1]] - x[hinges[:, 0]]
        t2 = x[hinges[:, 2]] - x[hinges[:, 1]]
        t1 /= np.linalg.norm(t1, axis=1)[:, None]
        t2 /= np.linalg.norm(t2, axis=1)[:, None]
        s0 = np.where(curved[a], np.linalg.norm(t2 - t1, axis=1), 0.0)
    clamps, tangent, c_ei, c_len = _clamps(net, EI, hinges, clamped, clamp_key)
    spring = None
    if springs:
        both = sorted(set(springs) & set(clamps[:, 0].tolist()))
        if both:
            raise ConfigError(
                f"{spring_key}: node {both[0]} is in supports.clamped too: a rod end is "
                "clamped (rigidly) or on a rotational spring, not both"
            )
        nodes = np.asarray(list(springs), dtype=np.int64)
        more = _clamps(net, EI, hinges, nodes, spring_key, "a rotational spring's node")
        clamps, tangent, c_ei, c_len = (
            np.ascontiguousarray(np.concatenate([a, b]))
            for a, b in zip((clamps, tangent, c_ei, c_len), more, strict=True)
        )
        spring = np.concatenate(
            [np.full(len(clamps) - len(nodes), np.nan), [springs[int(n)] for n in nodes]]
        )
    return Rods(
        hinges=hinges,
        EI=np.ascontiguousarray(0.5 * (EI[a] + EI[b])),
        voronoi=np.ascontiguousarray(0.5 * (l0[a] + l0[b])),
        s0=np.ascontiguousarray(s0),
        clamps=clamps,
        tangent=tangent,
        clamp_EI=c_ei,
        clamp_length=c_len,
        spring=spring,
    )


def _clamps(net: Net, EI, hinges, clamped, key: str, role: str = "a clamped node"):
    """The clamps' (node, other node) pairs, held tangents, EI and rest lengths; a
    ConfigError naming each clamped node (``role``) that is no rod end."""
    nodes = np.zeros(0, np.int64) if clamped is None else np.asarray(clamped, np.int64)
    pairs, tangent, edge = rod_ends(net, EI, hinges, nodes, key, role)
    return (
        pairs,
        tangent,
        np.ascontiguousarray(EI[edge]),
        np.ascontiguousarray(net.rest_length[edge]),
    )


def rod_ends(
    net: Net, EI: np.ndarray, hinges: np.ndarray, nodes: np.ndarray, key: str,
    role: str = "a clamped node",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Each rod end of ``nodes``: (K, 2) its node and the other node of its end edge, (K,
    3) the edge's given unit direction from the end, (K,) the edge; a ConfigError naming
    ``key`` for each node that is no rod end (``role`` says what it is meant to be)."""
    interior = set(hinges[:, 1].tolist())
    pairs, problems = [], []
    for c in np.asarray(nodes, np.int64).tolist():
        ends = [e for e in np.flatnonzero(EI > 0.0) if c in net.edges[e]]
        if c in interior or len(ends) != 1:
            why = (
                "an interior node of a rod"
                if c in interior
                else "on no edge with EI > 0"
                if not ends
                else f"the end of {len(ends)} rods (a joint)"
            )
            problems.append(
                f"{key}: node {c} is {why}: {role} must be the end of exactly one rod (an "
                "edge with EI > 0, the first or last of its line)"
            )
            continue
        e = int(ends[0])
        other = int(net.edges[e, 1] if net.edges[e, 0] == c else net.edges[e, 0])
        pairs.append((c, other, e))
    if problems:
        raise ConfigError(problems)
    arr = np.asarray(pairs, dtype=np.int64).reshape(-1, 3)
    t = net.nodes[arr[:, 1]] - net.nodes[arr[:, 0]]
    t = t / np.linalg.norm(t, axis=1)[:, None] if len(t) else t.reshape(0, 3)
    return (
        np.ascontiguousarray(arr[:, :2]),
        np.ascontiguousarray(t, dtype=np.float64),
        np.ascontiguousarray(arr[:, 2]),
    )


def curvature_measures(rods: Rods, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """|t2 - t1| of every hinge and |t - t0| of every clamp at x (N, 3)."""
    from catenet.kernels.bending import bend_measure

    s = np.zeros(len(rods.hinges))
    d = np.zeros(len(rods.clamps))
    bend_measure(np.ascontiguousarray(x), rods.hinges, rods.clamps, rods.tangent, s, d)
    return s, d


def bending_moment(rods: Rods, x: np.ndarray, n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Per node (N,), the bending moment |M| [N m] and the curvature |kappa| [1/m]: at a
    hinge EI |s - s0| / lbar and s / lbar (lbar its Voronoi length), at a clamp the
    mirrored end's 2 EI |t - t0| / l and 2 |t - t0| / l, at a rotational spring its
    moment 2 kc |t - t0| and that over the end edge's EI (|t - t0| there is also the
    spring's own turn); 0 where nothing bends (the largest where a node is a hinge of
    several rods)."""
    s, d = curvature_measures(rods, x)
    moment = np.zeros(n_nodes)
    kappa = np.zeros(n_nodes)
    j = rods.hinges[:, 1]
    np.maximum.at(moment, j, rods.EI * np.abs(s - rods.s0) / rods.voronoi)
    np.maximum.at(kappa, j, s / rods.voronoi)
    c = rods.clamps[:, 0]
    at_clamp = 2.0 * rods.kc * d
    np.maximum.at(moment, c, at_clamp)
    with np.errstate(divide="ignore", invalid="ignore"):
        by_moment = np.where(rods.clamp_EI > 0, at_clamp / rods.clamp_EI, 0.0)
    np.maximum.at(kappa, c, np.where(rods.rigid, 2.0 * d / rods.clamp_length, by_moment))
    return moment, kappa


def bending_edges(rods: Rods, edges: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """(M,) bool: the ``edges`` (M, 2) that bend: an edge of a hinge or a clamp's end edge,
    and those of the node ``pairs`` (P, 2) given (a rigid joint's members)."""
    m = len(edges)
    n = int(edges.max()) + 1 if m else 0
    key = np.sort(edges, axis=1) @ np.array([n, 1], dtype=np.int64)
    order = np.argsort(key)
    found = [rods.hinges[:, :2], rods.hinges[:, 1:], rods.clamps]
    if pairs is not None:
        found.append(pairs)
    ends = np.concatenate([np.asarray(p, dtype=np.int64).reshape(-1, 2) for p in found])
    out = np.zeros(m, dtype=bool)
    if not m or not len(ends):
        return out
    want = np.sort(ends, axis=1) @ np.array([n, 1], dtype=np.int64)
    at = np.minimum(np.searchsorted(key, want, sorter=order), m - 1)
    hit = key[order[at]] == want
    out[order[at[hit]]] = True
    return out


def cable_bending(
    rods: Rods, edges: np.ndarray, cable: np.ndarray, moment: np.ndarray, n: int, pairs=None
) -> tuple[np.ndarray, np.ndarray]:
    """Per cable of ``n`` (``cable`` (M,): each edge's, -1: none): whether any of its
    edges bends (``bending_edges``, ``pairs`` a rigid joint's members) and the largest
    bending moment ``moment`` (N,) over its edges' nodes."""
    cable = np.asarray(cable)
    on = cable >= 0
    top = np.zeros(n)
    for end in (0, 1):
        np.maximum.at(top, cable[on], moment[edges[on, end]])
    bends = bending_edges(rods, edges, pairs)
    return np.bincount(cable[on & bends], minlength=n) > 0, top
