"""Nodes and edges within reach of two obstacles on prescribed motions in one step (a
rope between two closing plates, a rope on a moving belt crossed by a blade).

``catenet.terms.moving.Moving.carry`` moves the nodes an obstacle may reach in a step
rigidly with it, and a node is carried by one obstacle at most (the first that claims
it). Where a second obstacle reaches the same node or edge in that step, that rigid
motion keeps the node's gap to the first obstacle only: the second may close on it
faster than the gap it has (two jaws), or sweep over it within the step (a blade
thinner than its travel crossing a rope carried by a slow belt). ``share`` watches
every such node and edge over the step: its points follow their carry (per node a
blend of the obstacles' rigid motions, weights W summing to 1) while each obstacle
follows its own motion, and the first contact of any of them with an obstacle other
than its carrier is found: where every motion involved translates, each point moves on
a straight line relative to the obstacle and the shape's own first contact along it
decides (exact for nodes, the edges' continuous collision detection); else conservative
advancement (every point moves relative to the obstacle by at most the sum of the two
largest sweeps over the step), which creeps where a node slides along the obstacle at a
small gap. Where there is a contact, the blends (1 - l) e_j + l e_k of the carrier j and
the obstacle k that reached it are tried in turn (l = 1/2 first: two jaws closing at the
same speed keep a pinched node in the middle), for the node or edge reached and, where
each blend bends an edge of it into k, for that edge's other node with it; the first
blend that no obstacle reaches over the step is kept, in the
step's start ``base`` and its predictor ``trial``. Where none does, ``Pinched``: the
step is too long for the room the obstacles leave (the time stepping halves it). Two
obstacles that close to less than the room the net's capsule needs (their gaps' sum at
the node below zero) make every step fail: the run stops at the last good state, the
message naming the obstacles, the node or edge and the time; so does a moving obstacle
that carries a node or edge, moved on by the step the run plans, into a fixed one
(``pinch_note``: a blade driving a cord against a post).

The guarantee is the moving obstacles': every step starts with every node and every
point of every edge outside every obstacle, and no obstacle passes over one within it.
"""

from __future__ import annotations

import numpy as np

from catenet.errors import ConvergenceError
from catenet.terms.collide import SWEEP_SAFETY
from catenet.terms.probe import Only

#: The blends tried for a node that an obstacle other than its carrier reaches, as the
#: share l of that obstacle's motion (0: the carrier's alone, the first tried).
BLENDS = (0.5, 1.0, 0.25, 0.75, 0.1, 0.9)
MAX_ADVANCES = 400  # conservative advancement's steps per obstacle and check


class Pinched(ConvergenceError):
    """No carry of the nodes keeps them out of every obstacle over the step (the time
    stepping tries a shorter one)."""


def share(movers, start, base, trial, trial0, moved, t0: float, t1: float) -> int:
    """Re-carries the nodes that an obstacle other than their carrier reaches from t0 to
    t1 (module docstring), in ``base`` and ``trial`` in place (``start`` and ``trial0``:
    both before any carrying; ``moved``: per node the index in ``movers`` of its carrier,
    -1: none). Returns how many nodes were re-carried; raises ``Pinched``."""
    roots = [getattr(m, "twin", None) or m for m in movers]
    groups = {id(r): g for g, r in reversed(list(enumerate(roots)))}
    group = np.array([groups[id(r)] for r in roots])
    if len(set(group.tolist())) < 2:
        return 0
    sweeps = np.array([m.sweep(t0, t1) for m in movers])
    weights = np.zeros((len(base), len(movers)))
    carried = np.flatnonzero(moved >= 0)
    weights[carried, group[moved[carried]]] = 1.0
    watch = _watched(movers, group, sweeps, start, weights, t0)
    if not watch:
        return 0
    changed: set[int] = set()
    # each round re-carries at least one node of a watched item: a rope along a paddle
    # has one per node and edge in front of it
    rounds = 4 * len(movers) + 2 * sum(len(items) for items in watch.values())
    for _ in range(rounds):
        hit = _first_hit(movers, group, sweeps, watch, start, weights, t0, t1)
        if hit is None:
            break
        k, nodes = hit
        nodes = [n for n in nodes if keep_carried(weights, n, group[k])]
        blended = _reblend(movers, group, sweeps, watch, start, weights, nodes, k, t0, t1)
        if blended is None:
            raise Pinched(_message(movers[k], movers, nodes, moved, start, t1))
        changed.update(blended)
    else:
        raise Pinched(_message(movers[hit[0]], movers, hit[1], moved, start, t1))
    if changed:
        idx = np.array(sorted(changed))
        base[idx] = _carried(movers, weights, start, idx, t0, t1)
        trial[idx] = _carried(movers, weights, trial0, idx, t0, t1)
    return len(changed)


def _items(mover):
    """(per item its nodes (K, m), the item's gaps at body-frame points): a node
    barrier's nodes, an edge barrier's edges."""
    edges = getattr(mover.shape, "edges", None)
    if edges is not None and getattr(mover, "horizon", False):
        return np.asarray(edges), mover.shape.gap
    return np.asarray(mover.nodes)[:, None], mover.shape.gap


def _watched(movers, group, sweeps, start, weights, t0: float) -> dict[int, np.ndarray]:
    """Per mover k, the items (indices) within its reach over the step that have a node
    carried by another obstacle's motion."""
    out = {}
    for k, mover in enumerate(movers):
        nodes, gap = _items(mover)
        others = np.delete(sweeps, np.flatnonzero(group == group[k]))
        if not others.size or not len(nodes):
            continue
        other = weights[nodes].sum(axis=-1) - weights[nodes][..., group[k]]  # (K, m)
        mixed = (other > 0.0).any(axis=1)
        if not mixed.any():
            continue
        c0, R0 = mover.pose(t0)
        g = gap(mover._body(start, c0, R0))
        reach = SWEEP_SAFETY * (sweeps[k] + others.max()) + mover.dhat
        items = np.flatnonzero(mixed & (g < reach))
        if items.size:
            out[k] = items
    return out


def _carried(movers, weights, points, idx, t0: float, t1: float, s: float = 1.0):
    """The points ``idx`` of ``points`` moved by their blends of the obstacles' rigid
    motions over the fraction s of the step."""
    p = points[idx]
    out = p.copy()
    for g in np.flatnonzero(weights[idx].any(axis=0)):
        out += weights[idx, g][:, None] * (_rigid(movers[g], p, t0, t1, s) - p)
    return out


def _rigid(mover, p, t0: float, t1: float, s: float):
    """Points p moved rigidly with ``mover`` over the fraction s of the step."""
    f0, f1 = mover.path.distance(t0), mover.path.distance(t1)
    c0, R0 = mover._pose(f0)
    c, R = mover._pose(f0 + s * (f1 - f0))
    return c + (p - c0) @ (R @ R0.T).T


def _first_hit(movers, group, sweeps, watch, start, weights, t0, t1):
    """(k, the nodes of the first of k's watched items it reaches) for the first mover k
    that reaches one over the step, else None: by the exact first contact where every
    motion involved translates (``_straight_hit``), else by conservative advancement."""
    for k, every in watch.items():
        mover = movers[k]
        nodes, gap = _items(mover)
        # an item whose nodes all ride on k's own motion keeps its gap to k: not watched
        items = every[~(weights[nodes[every], group[k]] >= 1.0).all(axis=1)]
        if not items.size:
            continue
        idx = np.unique(nodes[items])
        floor = 1e-9 * max(mover.reach, mover.dhat)
        if _translating(movers, weights, idx, k):
            hit = _straight_hit(mover, movers, weights, start, nodes, items, idx, t0, t1, floor)
            if hit is not None:
                return k, hit
            continue
        rate = sweeps[k] + np.delete(sweeps, np.flatnonzero(group == group[k])).max()
        f0, f1 = mover.path.distance(t0), mover.path.distance(t1)
        x = start.copy()
        s = 0.0
        for _ in range(MAX_ADVANCES):
            x[idx] = _carried(movers, weights, start, idx, t0, t1, s)
            c, R = mover._pose(f0 + s * (f1 - f0))
            g = gap(mover._body(x, c, R))[items]
            j = int(np.argmin(g))
            if not g[j] > floor:
                return k, [int(n) for n in nodes[items[j]]]
            if s >= 1.0 or rate == 0.0:
                break
            s = min(1.0, s + float(g[j]) / rate)
        else:
            return k, [int(n) for n in nodes[items[int(np.argmin(g))]]]
    return None


def _translating(movers, weights, idx, k: int) -> bool:
    """Whether obstacle k and every motion that carries the nodes ``idx`` translate
    without turning (then each node moves on a straight line relative to k)."""
    groups = np.flatnonzero(weights[idx].any(axis=0))
    return not any(np.any(movers[g].omega) for g in (k, *groups.tolist()))


def _straight_hit(mover, movers, weights, start, nodes, items, idx, t0, t1, floor):
    """The nodes of the first of ``items`` that ``mover`` reaches over the step, else
    None, where every motion translates: relative to the obstacle each node then moves
    on a straight line, and the shape's own first contact along it (``max_step``: exact
    for a node, the edges' conservative continuous collision detection) is taken from
    where the last one stopped until an item is within ``floor`` of contact. A node
    sliding along the obstacle at a constant small gap (a rope pushed along a belt by a
    blade) is so seen never to reach it, where conservative advancement creeps on by
    that gap over the motion's largest speed."""
    f0, f1 = mover.path.distance(t0), mover.path.distance(t1)
    c0, R0 = mover._pose(f0)
    moved = np.zeros((len(idx), 3))
    for g in np.flatnonzero(weights[idx].any(axis=0)):
        other = movers[g]
        shift = other.velocity * (other.path.distance(t1) - other.path.distance(t0))
        moved += weights[idx, g][:, None] * shift
    x = mover._body(start, c0, R0)
    dx = np.zeros_like(x)
    dx[idx] = (moved - mover.velocity * (f1 - f0)) @ R0
    probe = Only(mover.shape, nodes[items])
    s = 0.0
    for _ in range(MAX_RESTARTS):
        t = probe.max_step(x + s * dx, (1.0 - s) * dx)
        s = 1.0 if not t < 1.0 else s + t * (1.0 - s)
        if not probe.gap(x + s * dx).min() > floor:
            break  # reached, at the step's end too (jaws that close on the rope just then)
        if s >= 1.0:
            return None
    return [int(n) for n in nodes[items[int(np.argmin(probe.gap(x + s * dx)))]]]


MAX_RESTARTS = 20  # continuous collision detection restarted from its last time


def _reblend(movers, group, sweeps, watch, start, weights, nodes, k, t0, t1):
    """Gives ``nodes`` the first blend of their carrier's motion and k's (BLENDS) that
    no obstacle reaches over the step and returns the nodes so re-blended; None (weights
    as they were) where none does.
    Where every blend fails because k then reaches an item that shares a node with
    ``nodes`` (a rope in front of a blade: the node at its corner riding with it bends
    the edge to the next node, which moves more slowly), that item's carried nodes join
    ``nodes`` and the blends are tried again for them all."""
    nodes = list(nodes)
    for _ in range(MAX_GROWTH):
        if not nodes:
            return None
        idx = np.array(nodes)
        keep = weights[idx].copy()
        carrier = np.argmax(keep, axis=1)
        joined: set[int] = set()
        for share_k in BLENDS:
            weights[idx] = 0.0
            weights[idx, carrier] = 1.0 - share_k
            weights[idx, group[k]] += share_k
            hit = _first_hit(movers, group, sweeps, watch, start, weights, t0, t1)
            if hit is None or not set(hit[1]) & set(nodes):
                return nodes
            if group[hit[0]] == group[k]:
                joined.update(n for n in hit[1] if keep_carried(weights, n, group[k]))
        weights[idx] = keep
        more = sorted(joined - set(nodes))
        if not more:
            return None
        nodes += more
    return None


MAX_GROWTH = 8  # times the nodes re-carried together grow by the items they bend


def keep_carried(weights, n: int, g: int) -> bool:
    """Whether node n is carried and not wholly by the motion of group g."""
    return bool(weights[n].any()) and weights[n, g] < 1.0


def _message(mover, movers, nodes, moved, start, t1: float) -> str:
    """What a step no carry keeps clear says: the obstacles, the node or edge, the time."""
    carriers = {int(moved[n]) for n in nodes if moved[n] >= 0}
    other = ", ".join(sorted({movers[c].label for c in carriers} - {mover.label}))
    if not len(nodes):
        return f"{mover.label} and another moving obstacle close on the net by t = {t1:.6g} s"
    what = f"edge {nodes[0]}-{nodes[1]}" if len(nodes) == 2 else f"node {nodes[0]}"
    where = ", ".join(f"{v:.6g}" for v in start[nodes[0]])
    return (
        f"{mover.label} and {other or 'another moving obstacle'} close on the {what} "
        f"(at [{where}]) by t = {t1:.6g} s: no motion keeps it out of both; where they "
        "leave less room than twice the contact radius (or, without edge contact, no "
        "room) the net cannot pass; change their motions"
    )


def pinch_note(terms, x, t: float, until: float | None = None) -> str:
    """Where two obstacles, one at least on a prescribed motion (or a ball), hold a node or
    edge of state x at time t with less than PINCH_ROOM of their activation distance
    between them (the sum of its two gaps), or where a moving obstacle carrying it
    rigidly on to its pose at ``until`` leaves it no room against a fixed one: what a
    run that stops there says of it ("" when none does). A blade driven against a fixed
    post pinches the rope between them as two jaws do."""
    holders = _holders(terms, x, t, fixed=True)
    worst = None
    for a, (ka, na, ga, da, root_a, still_a) in enumerate(holders):
        for kb, nb, gb, db, root_b, still_b in holders[a + 1 :]:
            if root_a is root_b or na.shape[1] != nb.shape[1]:
                continue
            both = _common(na, ga, nb, gb, PINCH_ROOM * max(da, db))
            if both is None and until is not None:  # a mover carrying it onto a fixed one
                if still_b is not None and hasattr(root_a, "rigid"):
                    both = _closing(root_a, (na, ga, da), (nb, gb), still_b, x, t, until)
                elif still_a is not None and hasattr(root_b, "rigid"):
                    both = _closing(root_b, (nb, gb, db), (na, ga), still_a, x, t, until)
            if both is not None and (worst is None or both[0] < worst[0]):
                worst = (*both, ka, kb)
    if worst is None:
        return ""
    room, nodes, la, lb = worst
    what = f"edge {nodes[0]}-{nodes[1]}" if len(nodes) == 2 else f"node {nodes[0]}"
    return (
        f"; {la} and {lb} pinch the {what} at t = {t:.6g} s, leaving it "
        f"{max(room, 0.0):.3g} m of room beyond its contact radius: a moving obstacle "
        "must not close on the net against another to less than twice its contact radius "
        "(without edge contact: on a node); change their motions"
    )


def _closing(mover, held, other, still, x, t: float, until: float):
    """(room, nodes) of the item with the least room now among those ``mover`` carries
    (``held``: its items, gaps and dhat; within its sweep to ``until`` of it) that,
    moved on with it to its pose at ``until``, enter the fixed obstacle ``still``
    (``other``: its items and gaps), else None."""
    (na, ga, dhat), (nb, gb) = held, other
    both = _pairs(na, nb)
    if both is None:
        return None
    ia, ib = both
    carried = ga[ia] < SWEEP_SAFETY * mover.sweep(t, until) + dhat
    if not carried.any():
        return None
    ia, ib = ia[carried], ib[carried]
    closed = np.flatnonzero(still.gap(mover.rigid(x, t, until))[ib] < 0.0)
    if not closed.size:
        return None
    room = ga[ia[closed]] + gb[ib[closed]]
    k = int(np.argmin(room))
    return float(room[k]), [int(n) for n in na[ia[closed[k]]]]


def _fixed_items(term) -> np.ndarray:
    """A fixed obstacle's barrier's items: its edges (K, 2) or its nodes (K, 1)."""
    edges = getattr(term, "edges", None)
    return np.asarray(edges) if edges is not None else np.asarray(term.nodes)[:, None]


PINCH_ROOM = 1e-3  # a node or edge is pinched below this share of dhat of room


def _holders(terms, x, t: float, fixed: bool = False) -> list:
    """(label, items (K, m) of nodes, their gaps at x and t, dhat, the motion's root, the
    term where it is fixed) of every obstacle on a prescribed motion and every ball;
    ``fixed``: and every fixed obstacle's barrier of nodes or of edges (its root None)."""
    from catenet.terms.body import Ball

    out = []
    for term in terms:
        if term.moving:  # a ``catenet.terms.moving.Moving``
            items, gap = _items(term)
            c, R = term.pose(t)
            root = getattr(term, "twin", None) or term
            out.append((term.label, items, gap(term._body(x, c, R)), term.dhat, root, None))
        elif isinstance(term, Ball):
            out.append((term.label, term.nodes[:, None], term.gap(x), term.dhat, term, None))
        elif fixed and term.key and term.barrier and not hasattr(term, "frame"):  # fixed
            out.append((term.label, _fixed_items(term), term.gap(x), term.dhat, None, term))
    return out


def _pairs(na, nb):
    """(ia, ib): the items of na and nb (K, m) of the same nodes, as index arrays into
    each; None where they share none."""
    index = {tuple(row): i for i, row in enumerate(nb.tolist())}
    pairs = [(i, index[tuple(row)]) for i, row in enumerate(na.tolist()) if tuple(row) in index]
    if not pairs:
        return None
    ia, ib = np.array(pairs).T
    return ia, ib


def _common(na, ga, nb, gb, floor: float):
    """(room, nodes) of the item of the same nodes that both hold tightest (items na, nb
    and their gaps ga, gb), where the sum of its two gaps is below ``floor``, else None."""
    both = _pairs(na, nb)
    if both is None:
        return None
    ia, ib = both
    room = ga[ia] + gb[ib]
    k = int(np.argmin(room))
    if not room[k] < floor:
        return None
    return float(room[k]), [int(n) for n in na[ia[k]]]


def squeeze_note(terms, x, t: float, tension: float) -> str:
    """Where two obstacles on prescribed motions (or one and a ball) both hold a node or
    edge of state x within their barriers' reach (each gap below its ``distance``) and
    press on it from both sides with more than SQUEEZE of the net's largest ``tension``:
    the warning a run that ends so earns ("" when none does). Both barriers then push on
    it, a squeeze that no gap of that size gives in the world: the contact forces there,
    and the tensions where the squeeze bends the net, are the barriers', not the
    structure's."""
    from catenet.terms.body import Ball

    holders = _holders(terms, x, t)
    forces = []
    for term in terms:  # in _holders' order: each one's force on the net's nodes
        if term.moving or isinstance(term, Ball):
            grad = np.zeros_like(x)
            term.gradient(x, grad)
            forces.append(np.linalg.norm(grad, axis=1))
    worst = None
    for a, (ka, na, ga, da, root_a, _) in enumerate(holders):
        for b, (kb, nb, gb, db, root_b, _) in enumerate(holders[a + 1 :], start=a + 1):
            if root_a is root_b or na.shape[1] != nb.shape[1]:
                continue
            both = _pairs(na, nb)
            if both is None:
                continue
            ia, ib = both
            held = (ga[ia] < da) & (gb[ib] < db)
            if not held.any():
                continue
            squeeze = np.minimum(forces[a], forces[b])  # per node, what the two cancel
            per_item = np.where(held, squeeze[na[ia]].max(axis=1), 0.0)
            j = int(np.argmax(per_item))
            if worst is None or per_item[j] > worst[0]:
                worst = (float(per_item[j]), [int(n) for n in na[ia[j]]], ka, kb, da + db)
    if worst is None or not worst[0] > SQUEEZE * tension:
        return ""
    force, nodes, la, lb, reach = worst
    what = f"edge {nodes[0]}-{nodes[1]}" if len(nodes) == 2 else f"node {nodes[0]}"
    return (
        f"{la} and {lb} both hold the net within their barriers' distance at t = {t:.6g} s "
        f"and press the {what} from both sides with {force:.4g} N ({force / tension:.3g} "
        "times the net's largest tension): that squeeze is the barriers' (their distances "
        f"sum to {reach:.3g} m), not the structure's, and so are the contact forces there "
        "and the tensions where it bends the net; leave the net more room than the two "
        "distances, or give the obstacles a smaller distance"
    )


SQUEEZE = 0.5  # a squeeze above this share of the net's largest tension warns
