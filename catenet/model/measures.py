"""Derived measures of a state, in one place: strain, tension, reactions, deflection.

Everything a result, a result file, a figure or a sweep table reports about a state is
computed here from the positions and the net's material law, never re-derived elsewhere:
the strain is geometric (|e|/l0 - 1) whatever the law, the tension is the law's axial
force (``catenet.kernels.stretch.stretch_tension``).
"""

from __future__ import annotations

import math

import numpy as np

from catenet.model.net import Net


def strain(net: Net, x: np.ndarray) -> np.ndarray:
    """Engineering strain |e|/l0 - 1 of every edge at positions x (N, 3)."""
    e = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    return np.linalg.norm(e, axis=1) / net.rest_length - 1.0


#: A strain beyond this many times its law's range is no cable's: a state that holds one
#: (a unit slip, a length asked below its chord) is implausible
IMPLAUSIBLE = 10.0


def implausible_edge(net: Net, x: np.ndarray) -> int:
    """The edge strained furthest beyond IMPLAUSIBLE times its law's range at x, relative
    to that range; -1 where none is."""
    ratio = strain(net, x) / net.law.max_strain()
    worst = int(np.argmax(ratio)) if len(ratio) else -1
    return worst if worst >= 0 and ratio[worst] > IMPLAUSIBLE else -1


def tension(net: Net, x: np.ndarray, law=None) -> np.ndarray:
    """Axial force of every edge [N] under its law (0 when slack and tension-only)."""
    return edge_tension(x, net.edges, net.rest_length, net.EA, net.law if law is None else law)


def edge_tension(x, edges, rest_length, EA, law) -> np.ndarray:
    """Axial forces [N] of edges given as arrays (as a result file stores them)."""
    from catenet.kernels.stretch import stretch_tension

    out = np.empty(len(edges))
    stretch_tension(
        np.ascontiguousarray(x, dtype=np.float64),
        np.ascontiguousarray(edges, dtype=np.int64),
        np.ascontiguousarray(rest_length, dtype=np.float64),
        np.ascontiguousarray(EA, dtype=np.float64),
        law.kernel_kind,
        law.params,
        law.table,
        law.tension_only,
        out,
    )
    return out


def max_strain(net: Net, x: np.ndarray) -> float:
    """The largest edge strain, 0 when no edge is stretched."""
    return float(max(np.max(strain(net, x), initial=0.0), 0.0))


def slack_strain(net: Net, x: np.ndarray) -> float:
    """The largest compressive strain at x (0 when no edge is shorter than its rest length)."""
    return float(max(-np.min(strain(net, x)), 0.0))


def slack_edges(net: Net, x: np.ndarray) -> int:
    """How many tension-only edges are shorter than their rest length (slack; a strut,
    an edge that is not tension-only, in compression is not slack)."""
    return int(np.count_nonzero((strain(net, x) < 0.0) & net.law.tension_only))


def reaction(
    net: Net,
    internal_gradient: np.ndarray,
    force: np.ndarray,
    springs: np.ndarray | None = None,
) -> np.ndarray:
    """Force each support exerts on the net (N, 3) (0 at free nodes): it balances the
    internal forces (the gradient of the internal terms, ``springs``' included) and the
    applied loads there: all of it at a fixed node, its held part Q (grad - f) at a
    node on a roller (along the normal) or a slider (across the direction); plus the
    force ``springs`` (N, 3) of the elastic supports, -K (x - X) (None: none)."""
    r = np.zeros_like(internal_gradient)
    r[net.fixed] = internal_gradient[net.fixed] - force[net.fixed]
    if net.guides is not None:
        k = net.guides.nodes
        r[k] = net.guides.held_part(internal_gradient[k] - force[k])
    if springs is not None:
        r += springs
    return r


def support_force(system, x: np.ndarray) -> np.ndarray | None:
    """(N, 3) the force of the elastic supports (the ``holds`` terms) on the net, or
    None (none)."""
    held = [t for t in system.terms if t.holds]
    if not held:
        return None
    out = np.zeros_like(x)
    for term in held:
        term.held_force(x, out)
    return out


def contact_force(system, x: np.ndarray) -> np.ndarray:
    """Force (N, 3) that every internal term besides the structure's own (the edges'
    stretching, the rods' bending: ``structural``) and the supports' springs (``holds``)
    exerts on each node (obstacles, rigid bodies, friction): minus the sum of their
    gradients. Zero for a net held by its edges and supports alone."""
    force = np.zeros_like(x)
    for term in system.terms:
        if term is not system.stretch and not term.structural and not term.holds:
            term.gradient(x, force)
    return np.negative(force, out=force)


def deflection(nodes: np.ndarray, x: np.ndarray, probe: int):
    """z-displacement of the probe node from its reference position ``nodes[probe]``,
    positive downward (the paper's delta); ``x`` (N, 3) or a trajectory (T, N, 3)."""
    d = np.asarray(nodes)[probe, 2] - np.asarray(x)[..., probe, 2]
    return float(d) if np.ndim(d) == 0 else d


def loose_nodes(net: Net, tension: np.ndarray) -> np.ndarray:
    """Free nodes all of whose edges are slack (tension-only, zero tension)."""
    if not net.law.any_tension_only:
        return np.zeros(0, dtype=np.int64)
    taut = (tension > 0) | ~net.law.tension_only
    held = np.zeros(net.n_nodes, bool)
    held[net.n_nodes - net.bodies :] = True  # a moving body's centre has no edges
    held[net.edges[taut, 0]] = True
    held[net.edges[taut, 1]] = True
    return np.flatnonzero(~held & ~net.fixed)


def cable_stats(net: Net, x: np.ndarray, tension: np.ndarray, edge_cable: np.ndarray, n: int):
    """Per cable (``edge_cable`` (M,): each edge's cable index in 0..n-1, -1: none): the
    largest tension [N] and the slack fraction, the share of the cable's unstressed length
    in tension-only edges shorter than their rest length (a strut in compression is not
    slack)."""
    on = edge_cable >= 0
    c = edge_cable[on]
    top = np.full(n, -np.inf)
    np.maximum.at(top, c, np.asarray(tension)[on])
    top[~np.isfinite(top)] = 0.0
    l0 = net.rest_length[on]
    loose = (strain(net, x) < 0.0) & net.law.tension_only
    slack = np.bincount(c, weights=l0 * loose[on], minlength=n)
    total = np.bincount(c, weights=l0, minlength=n)
    return top, slack / np.where(total > 0, total, 1.0)


#: A node's position along the chord's plan within [0, 1] to this: its vertical meets it.
PLAN_TOL = 1e-9
#: The steepest chord [degrees from the horizontal] whose vertical sag is measured: a
#: node's vertical distance from a chord at angle a is its normal one over cos(a), and a
#: post 2.5 m high bent 2.5 mm read 370 mm "above" its chord, whatever its load.
STEEPEST = 80.0


def sag(net: Net, x: np.ndarray, edges: np.ndarray | None = None) -> dict | None:
    """The sag of a cable at x: the edges ``edges`` (indices; default every edge) must
    form one chain between two end nodes. ``normal``: the largest distance of its nodes
    from the chord between its ends (the sag normal to the chord); ``vertical``: the
    largest drop of a node below the chord, measured vertically at the node's position
    along the chord's plan, ``rise`` the largest height of one above it (a cable lifted
    over its chord); both nan where the vertical through a node meets the chord's plan
    outside its ends (a vertical chord; a rope hung 0.1 mm off the vertical that sways
    5.6 mm read 557 m of vertical sag) or where the chord is steeper than STEEPEST (a
    column, a post: their vertical distances are their normal ones blown up); ``node``
    where the normal sag is, ``ends`` the chord's end nodes. None where the edges are not
    one chain."""
    e = net.edges if edges is None else net.edges[np.asarray(edges, dtype=np.int64)]
    if len(e) == 0:
        return None
    nodes, degree = np.unique(e, return_counts=True)
    ends = nodes[degree == 1]
    if ends.size != 2 or np.any(degree > 2) or len(nodes) != len(e) + 1:
        return None
    a, b = x[ends[0]], x[ends[1]]
    chord = b - a
    length = float(np.linalg.norm(chord))
    if length == 0.0:
        return None
    p = x[nodes] - a
    along = p @ chord / length
    normal = np.linalg.norm(p - np.outer(along, chord / length), axis=1)
    k = int(np.argmax(normal))
    plan = chord[:2]
    vertical = rise = math.nan
    steep = float(np.linalg.norm(plan)) <= math.cos(math.radians(STEEPEST)) * length
    s = None if steep else (p[:, :2] @ plan) / float(plan @ plan)
    if s is not None and np.all((s >= -PLAN_TOL) & (s <= 1.0 + PLAN_TOL)):
        drop = s * chord[2] - p[:, 2]
        floor = 1e-12 * length  # the ends' round-off: neither below nor above
        vertical, rise = (
            v if v > floor else 0.0 for v in (float(np.max(drop)), float(np.max(-drop)))
        )
    return {
        "normal": float(normal[k]),
        "vertical": vertical,
        "rise": rise,
        "node": int(nodes[k]),
        "ends": (int(ends[0]), int(ends[1])),
    }


def line_mass(net: Net, rest_length: np.ndarray) -> np.ndarray:
    """Per node (N,), rho l0 / 2 of its edges at the rest lengths given [kg]: ``Net.mass``
    without the point masses, for rest lengths that change (form finding's self-weight,
    at every load update; by bincount, not through a new Net)."""
    half = 0.5 * net.line_density * rest_length
    ends = net.edges
    return np.bincount(ends[:, 0], half, net.n_nodes) + np.bincount(ends[:, 1], half, net.n_nodes)
