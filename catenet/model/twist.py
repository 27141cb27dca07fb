"""Twisted rods: the chains of edges whose twist is held at both ends, as arrays
(``catenet.kernels.twist``).

An edge with torsional stiffness GJ > 0 twists. Along a line (as for bending,
``catenet.model.rods``), the consecutive twisting edges form a chain; a chain's twist is
uniform between the constraints that hold it (an isotropic rod), so only chains held at
both ends carry twist: an open chain whose two ends are clamped (``supports.clamped``
holds the tangent and the twist) and a closed ring (its twist, the link of its two
edges, is conserved). A chain with a free or pinned end untwists at no cost.

A rigid joint (``catenet.model.joints``) holds the twist of the rods that meet there:
a chain ends at a joint node (a line passing through one is split there), and its
twist at that end is measured against the joint's director, D = cos(phi0) n +
sin(phi0) t x n, n the unit part of another member's direction (the joint's member most
normal to the chain's end edge, its ``partner``) normal to the end tangent t, phi0 such
that the rod is untwisted as given. Turning the partner about the rod's axis twists the
rod. The partner's direction is its first edge's, which leaves the joint's turn by the
bending of its half edge (as a rod's end edge leaves a clamp's direction): that half
edge's compliance about the rod's axis, sin^2 l / (2 EI) (sin: of the angle between
them), is in series with the rod's twist and is added to the segment's compliance, so
that the twist a joint carries is second order in the edge length, as a rotational
spring at a clamp is (``catenet.model.rods``), where one rod meets its partner at a right
angle. Where two rods' twists share a partner, each adds only its own share of that half
edge (the shared spring would couple their segments), and at oblique joints the partner's
bending across the plane also turns the reference: first order there.

Each clamp may turn its end about the rod's axis (``[[supports.twist]]``): by an angle
right-handed about the outward tangent (pointing out of the rod there), so that turning
either end by a positive angle twists the rod right-handed and the segment's imposed
twist is the sum of its two ends' angles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import Net

#: A joint's partner member must be at least this far from the rod's axis (the sine).
PARTNER = 0.1


@dataclass(frozen=True, eq=False)
class Twists:
    """The twisted segments of a net's rods.

    nodes : (P,) int64, every segment's nodes in order (a ring's once each)
    start : (S + 1,) int64, segment s's nodes are nodes[start[s]:start[s + 1]]
    edges : (E,) int64, every segment's edges in order; first : (S,) its first's row
    closed : (S,) bool, a ring
    head, tail : (S, 3) an open segment's clamped tangents at its ends, along the chain
    head_dir, tail_dir : (S, 3) the clamps' directors (normal to head, tail): tail_dir
        is head_dir carried along the given geometry, so that it is untwisted
    compliance : (S,) sum over its edges of l0 / GJ [1/(N m)], and at an end on a rigid
        joint its partner's half edge's (``joint_partner``)
    ends : (S, 2) int64, an open segment's first and last node (-1: a ring)
    partner : (S, 2) int64, at an end on a rigid joint, the other node of the joint's
        partner member (-1: a clamp, or a ring)
    phase : (S, 2) there, phi0: the director's angle from the partner's normal part
    """

    nodes: np.ndarray
    start: np.ndarray
    edges: np.ndarray
    first: np.ndarray
    closed: np.ndarray
    head: np.ndarray
    tail: np.ndarray
    head_dir: np.ndarray
    tail_dir: np.ndarray
    compliance: np.ndarray
    ends: np.ndarray
    partner: np.ndarray
    phase: np.ndarray

    def __len__(self) -> int:
        return len(self.closed)

    def segment_of(self, node: int) -> tuple[int, int]:
        """(segment, 0 or 1: its first or last node) of an open segment's end node, or
        (-1, -1) where it is none's."""
        hit = np.argwhere(self.ends == node)
        return (int(hit[0, 0]), int(hit[0, 1])) if len(hit) else (-1, -1)


def _chains(
    edges: np.ndarray, line: np.ndarray, twists: np.ndarray, cuts: frozenset = frozenset()
) -> list[tuple[list, bool]]:
    """The runs of consecutive twisting edges of each line (edge lists, closed), split at
    the nodes ``cuts`` (rigid joints: each side's twist ends there)."""
    by_line: dict[int, list[int]] = {}
    for e in np.flatnonzero(twists & (line >= 0)):
        by_line.setdefault(int(line[e]), []).append(int(e))
    out = []
    for chain in by_line.values():
        runs = [[chain[0]]]
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            if edges[a, 1] == edges[b, 0] and int(edges[b, 0]) not in cuts:
                runs[-1].append(b)
            else:
                runs.append([b])
        loop = len(chain) > 2 and edges[chain[-1], 1] == edges[chain[0], 0]
        closed = loop and len(runs) == 1 and int(edges[chain[0], 0]) not in cuts
        if loop and len(runs) > 1 and int(edges[chain[0], 0]) not in cuts:
            runs[0] = runs.pop() + runs[0]  # a ring cut at a joint: one run round it
        out += [(run, closed) for run in runs]
    return out


def joint_partner(joints, node: int, other: int, x: np.ndarray) -> tuple[int, float] | None:
    """At the rigid joint ``node`` (``joints``: a ``catenet.model.joints.Joints``, None:
    none), the partner of the member towards ``other`` for its twist, whose direction's
    part normal to it is the twist's reference there: (the other node of the joint's
    member most normal to it, the compliance [1/(N m)] its end edge adds to the rod's
    twist there: sin^2 of their angle / (2 k), k = EI / l of its edge, the half edge's
    bending between the joint and that edge's direction, as at a clamp); None where no
    joint is there or every other member lies within asin(PARTNER) of its axis (the rod
    untwists there)."""
    if joints is None:
        return None
    hit = np.flatnonzero(joints.node == node)
    if not hit.size:
        return None
    lo, hi = int(joints.start[hit[0]]), int(joints.start[hit[0] + 1])
    t = (x[other] - x[node]) / np.linalg.norm(x[other] - x[node])
    best, sine, stiff = -1, PARTNER, 0.0
    for p in range(lo, hi):
        o = int(joints.other[p])
        if o == other:
            continue
        s = (x[o] - x[node]) / np.linalg.norm(x[o] - x[node])
        size = float(np.linalg.norm(np.cross(t, s)))
        if size > sine:
            best, sine, stiff = o, size, float(joints.k[p])
    return None if best < 0 else (best, sine * sine / (2.0 * stiff))


def _phase(x: np.ndarray, node: int, partner: int, t: np.ndarray, d: np.ndarray) -> float:
    """phi0: the angle about t from the partner's unit normal part n to the director d."""
    b = x[partner] - x[node]
    n = b - (b @ t) * t
    n = n / np.linalg.norm(n)
    return float(np.arctan2(np.cross(n, d) @ t, n @ d))


def _normal(t: np.ndarray) -> np.ndarray:
    """A unit vector normal to the unit t."""
    axis = np.eye(3)[int(np.argmin(np.abs(t)))]
    u = axis - (axis @ t) * t
    return u / np.linalg.norm(u)


def _carried(x: np.ndarray, chain: list[int], head: np.ndarray, d: np.ndarray) -> np.ndarray:
    """d (normal to head) carried by parallel transport along the chain's nodes to the
    last edge's tangent."""
    from catenet.kernels.twist import transport

    t_prev = head
    for a, b in zip(chain[:-1], chain[1:], strict=True):
        t = x[b] - x[a]
        t = t / np.linalg.norm(t)
        d = transport(t_prev, t, d)
        t_prev = t
    return d


def build_twists(
    net: Net,
    GJ: np.ndarray,
    line: np.ndarray,
    clamps: np.ndarray,
    tangent: np.ndarray,
    joints=None,
    springs: dict | None = None,
) -> Twists:
    """The twisted segments of ``net``: GJ (M,) per edge [N m^2] (0: no twist), ``line``
    (M,) every edge's line (-1: none), the rods' clamps (C, 2) (clamped node, the other
    node of its end edge) and their held tangents (C, 3) (from the clamped node into the
    rod), its rigid joints (a ``catenet.model.joints.Joints``; None: none) and the rod
    ends whose 6x6 spring holds their twist (``catenet.model.rodends.twist_ends``: held
    as by a clamp, its compliance added)."""
    GJ = np.asarray(GJ, dtype=np.float64)
    held, soft = _held_ends(clamps, tangent, springs)
    x, edges = net.nodes, net.edges
    cuts = frozenset() if joints is None else frozenset(joints.node.tolist())
    parts: list[tuple] = []
    for run, closed in _chains(edges, np.asarray(line), GJ > 0.0, cuts):
        chain = [int(edges[e, 0]) for e in run]
        if not closed:
            chain.append(int(edges[run[-1], 1]))
            a, b = chain[0], chain[-1]
            first = (x[chain[1]] - x[a]) / np.linalg.norm(x[chain[1]] - x[a])
            last = (x[b] - x[chain[-2]]) / np.linalg.norm(x[b] - x[chain[-2]])
            at: list = [None, None]  # a joint's partner at the head, the tail
            added = soft.get(a, 0.0) + soft.get(b, 0.0)  # a spring's twist in series
            if held.get(a, (-1,))[0] == chain[1]:
                head = held[a][1]
            elif (found := joint_partner(joints, a, chain[1], x)) is not None:
                head, at[0] = first, found
            else:
                continue  # a free or pinned end: the chain untwists
            if held.get(b, (-1,))[0] == chain[-2]:
                tail = -held[b][1]
            elif (found := joint_partner(joints, b, chain[-2], x)) is not None:
                tail, at[1] = last, found
            else:
                continue
            head_dir = _normal(head)
            tail_dir = _transported(chain, x, head_dir, head, tail)
            ends = (a, b)
            partner = tuple(-1 if p is None else p[0] for p in at)
            added += sum(0.0 if p is None else p[1] for p in at)
            phase = (
                0.0 if at[0] is None else _phase(x, a, partner[0], first, head_dir),
                0.0 if at[1] is None else _phase(x, b, partner[1], last, tail_dir),
            )
        else:
            t = x[chain[1]] - x[chain[0]]
            head = tail = np.zeros(3)
            head_dir = _normal(t / np.linalg.norm(t))
            tail_dir = np.zeros(3)
            ends, partner, phase, added = (-1, -1), (-1, -1), (0.0, 0.0), 0.0
        compliance = float(np.sum(net.rest_length[run] / GJ[run])) + added
        parts.append(
            (chain, run, closed, head, tail, head_dir, tail_dir, compliance, ends, partner, phase)
        )
    return _pack(parts)


def _held_ends(clamps, tangent, springs) -> tuple[dict, dict[int, float]]:
    """Node -> (the end edge's other node, its held direction) of every end that holds
    its rod's twist (the clamps, the 6x6 springs of ``springs``), and node -> the
    compliance a spring adds."""
    held = {int(c): (int(o), tangent[k]) for k, (c, o) in enumerate(clamps)}
    soft: dict[int, float] = {}
    for node, (other, t, compliance) in (springs or {}).items():
        held[node] = (other, t)
        soft[node] = compliance
    return held, soft


def _transported(chain: list[int], x: np.ndarray, d: np.ndarray, head, tail) -> np.ndarray:
    """The head's director carried along the chain and on to the tail's tangent."""
    from catenet.kernels.twist import transport

    last = x[chain[-1]] - x[chain[-2]]
    last = last / np.linalg.norm(last)
    return transport(last, tail, _carried(x, chain, head, d))


def _pack(parts: list[tuple]) -> Twists:
    start = np.cumsum([0] + [len(p[0]) for p in parts]).astype(np.int64)
    first = np.cumsum([0] + [len(p[1]) for p in parts])[:-1].astype(np.int64)

    def rows(k: int) -> np.ndarray:
        rows = np.array([p[k] for p in parts], dtype=np.float64)
        return np.ascontiguousarray(rows.reshape(-1, 3))

    return Twists(
        nodes=np.asarray([n for p in parts for n in p[0]], dtype=np.int64),
        start=start,
        edges=np.asarray([e for p in parts for e in p[1]], dtype=np.int64),
        first=first,
        closed=np.asarray([p[2] for p in parts], dtype=np.bool_),
        head=rows(3),
        tail=rows(4),
        head_dir=rows(5),
        tail_dir=rows(6),
        compliance=np.asarray([p[7] for p in parts], dtype=np.float64),
        ends=np.asarray([p[8] for p in parts], dtype=np.int64).reshape(-1, 2),
        partner=np.asarray([p[9] for p in parts], dtype=np.int64).reshape(-1, 2),
        phase=np.asarray([p[10] for p in parts], dtype=np.float64).reshape(-1, 2),
    )


def twisting_moment(twists: Twists, moment: np.ndarray, n_edges: int) -> np.ndarray:
    """Per edge (M,), the signed twisting moment [N m] of its segment (> 0: a
    right-handed twist), 0 where no rod twists."""
    out = np.zeros(n_edges)
    for s in range(len(twists)):
        lo = twists.first[s]
        hi = lo + (twists.start[s + 1] - twists.start[s]) - (0 if twists.closed[s] else 1)
        out[twists.edges[lo:hi]] = moment[s]
    return out


def check_twist_ends(twists: Twists, nodes: np.ndarray, key: str, clamped: set[int]) -> None:
    """A ConfigError naming each node of ``key`` that is no end of a twisted segment."""
    problems = []
    for node in np.asarray(nodes, dtype=np.int64).tolist():
        if node not in clamped:
            why = "is not clamped: a twist turns a clamped rod end (add it to supports.clamped)"
        elif twists.segment_of(node)[0] < 0:
            why = (
                "is a clamped end of a rod that does not twist: give its material GJ > 0, "
                "and clamp the rod's other end too (a rod with a free or pinned end "
                "untwists)"
            )
        else:
            continue
        problems.append(f"{key}: node {node} {why}")
    if problems:
        raise ConfigError(problems)
