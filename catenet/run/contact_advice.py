"""What a run's end state says of its frictionless contacts: a cable's tension cannot
change where only frictionless obstacles push on it, so a contact force along the cable
at a node is the discretisation's (``wrap_share``).

A node held on a solid's corner, or where the cable leaves a face at a kink, is pushed
along the surface's normal there, which is not square to the cable: the edges on either
side of the node carry different tensions in the discrete equilibrium. A cord of 25 mm
edges dragged round a box blade's 3 mm-rounded corners read 8.9 % above the hand tension
of its path, "converged"; 3 mm edges 3.9 %; a round blade of 10 mm within 0.8 %. The
runner warns above WRAP_SHARE, naming the node and how much. And a friction coefficient
no surface pair has (``unlikely_friction``) is warned before the run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from catenet.model.net import Net
from catenet.model.peaks import TAUT
from catenet.solver.events import contact_terms

if TYPE_CHECKING:
    from catenet.case.parse import Case

#: A frictionless contact force along the cable beyond this share of its tension is warned.
WRAP_SHARE = 0.02
#: A run's pushes that add up to this many times the largest node's are told as the run's.
RUN_OVER = 1.25


def wrap_share(net: Net, x: np.ndarray, tension: np.ndarray, contact: np.ndarray):
    """(share, node, force) of the node of a cable (two edges meet there) whose contact
    force ``contact`` (N, 3) has the largest component along the cable (the bisector of its
    two edges' directions at x) relative to the larger of their ``tension``; None where no
    node of two edges is pushed or no edge is taut."""
    edges = np.asarray(net.edges)
    if not len(edges):
        return None
    degree = np.bincount(edges.ravel(), minlength=net.n_nodes)
    pushed = np.flatnonzero((degree == 2) & (np.linalg.norm(contact, axis=1) > 0.0))
    if not pushed.size:
        return None
    ends = np.concatenate([edges[:, 0], edges[:, 1]])  # each node's incidences
    order = np.argsort(ends, kind="stable")
    first = np.searchsorted(ends[order], pushed)
    e1, e2 = order[first] % len(edges), order[first + 1] % len(edges)  # its two edges
    a = np.where(edges[e1, 1] == pushed, edges[e1, 0], edges[e1, 1])  # their far ends
    b = np.where(edges[e2, 0] == pushed, edges[e2, 1], edges[e2, 0])
    u1, u2 = x[pushed] - x[a], x[b] - x[pushed]
    n1, n2 = np.linalg.norm(u1, axis=1), np.linalg.norm(u2, axis=1)
    top = np.maximum(np.abs(tension[e1]), np.abs(tension[e2]))
    ea = np.asarray(net.EA, dtype=np.float64)
    top[top <= TAUT * np.maximum(ea[e1], ea[e2])] = 0.0  # round-off's tension: not judged
    with np.errstate(divide="ignore", invalid="ignore"):
        t = u1 / n1[:, None] + u2 / n2[:, None]
        t /= np.linalg.norm(t, axis=1)[:, None]
        along = np.abs(np.einsum("ij,ij->i", contact[pushed], t))
        share = along / top
    share[~np.isfinite(share)] = -1.0  # a zero edge, a straight reversal or no tension
    k = int(np.argmax(share))
    if not share[k] >= 0.0:
        return None
    return float(share[k]), int(pushed[k]), float(along[k])


def wrap_drift(net: Net, x: np.ndarray, tension: np.ndarray, contact: np.ndarray):
    """(share, first node, last node, drift) of the run of consecutive pushed cable nodes
    (``cable_runs``) along which the frictionless ``contact`` (N, 3) adds up, from the
    run's first node, to the largest push along the cable relative to its tension there:
    the tension the contact changes along the run, each node's push below WRAP_SHARE
    perhaps (a rope wrapped half round a polygon, a cylinder's circumscribed prisms as
    edge contact met it before its exact core, lost 25 % of its tension, about 1 % at
    each corner, unwarned); None where no run is pushed."""
    pushed = np.linalg.norm(contact, axis=1) > 0.0
    if not len(net.edges) or np.count_nonzero(pushed) < 2:
        return None
    edges = np.asarray(net.edges)
    ea = np.asarray(net.EA, dtype=np.float64)
    best = None
    runs, at = cable_runs(net, pushed)
    for run, (enter, leave) in runs:
        back = _other(edges, enter, run[0])  # the cable's node before the run
        total, tops = 0.0, 0.0
        for k, node in enumerate(run):
            ahead = run[k + 1] if k + 1 < len(run) else _other(edges, leave, node)
            t = x[ahead] - x[back]  # the cable's direction at the node, along the run
            size = float(np.linalg.norm(t))
            total += float(contact[node] @ t) / size if size > 0.0 else 0.0
            two = at[node]
            top = float(np.max(np.abs(tension[two])))
            tops = max(tops, top if top > TAUT * float(ea[two].max()) else 0.0)
            if tops > 0.0 and (best is None or abs(total) / tops > best[0]):
                best = (abs(total) / tops, run[0], node, abs(total))
            back = node
    return best


def cable_runs(
    net: Net, pushed: np.ndarray
) -> tuple[list[tuple[list[int], tuple[int, int]]], dict[int, list[int]]]:
    """The runs of consecutive cable nodes (two edges meet at each) that ``pushed`` (N,)
    marks, each its nodes in order along the cable (from its lower end node) and its
    (entering, leaving) edges; and the two edges at each node of the runs."""
    edges = np.asarray(net.edges)
    degree = np.bincount(edges.ravel(), minlength=net.n_nodes)
    inner = np.asarray(pushed, dtype=bool) & (degree == 2)
    nodes = np.flatnonzero(inner)
    ends = np.concatenate([edges[:, 0], edges[:, 1]])
    order = np.argsort(ends, kind="stable")
    first = np.searchsorted(ends[order], nodes)
    two = np.stack([order[first], order[first + 1]], axis=1) % len(edges)
    at = {int(n): [int(a), int(b)] for n, (a, b) in zip(nodes, two, strict=True)}
    seen = np.zeros(net.n_nodes, bool)
    out: list[tuple[list[int], tuple[int, int]]] = []
    for start in nodes.tolist():
        if seen[start]:
            continue
        seen[start] = True
        run: list[int] = [start]
        ends_of: list[int] = []
        for e in at[start]:  # walk both ways along the cable from the run's first node
            node, edge, side = start, e, []
            while True:
                other = _other(edges, edge, node)
                if not inner[other] or seen[other]:
                    break
                seen[other] = True
                side.append(other)
                node, edge = other, next(f for f in at[other] if f != edge)
            run = side[::-1] + run if not ends_of else run + side
            ends_of.append(edge)
        if run[0] > run[-1]:  # (told from its lower node)
            run, ends_of = run[::-1], ends_of[::-1]
        out.append((run, (ends_of[0], ends_of[1])))
    return out, at


def _other(edges: np.ndarray, edge: int, node: int) -> int:
    """The node at the other end of ``edge`` from ``node``."""
    return int(edges[edge, 1] if edges[edge, 0] == node else edges[edge, 0])


def wrap_warning(net: Net, terms, x, tension) -> str | None:
    """The warning where a frictionless scene's contact pushes along a cable at a node by
    more than WRAP_SHARE of its tension (module docstring), else None. Scenes with
    friction are not judged (friction pushes along the cable by design); the contact is
    the barriers' alone (obstacles, balls, bodies, strands: the water's drag along a
    sinking rope is no contact, and against a free rope's round-off tension it was
    warned). A tension below TAUT's strain is round-off's: a steel rod lying on the floor,
    its tension 7e-9 N, was warned of a push of 1.2e-7 N along it, "1630 %"."""
    barriers = contact_terms(terms)
    if not barriers or any("friction" in t.name for t in terms):
        return None
    x = np.asarray(x, dtype=np.float64)
    return wrap_message(net, x, np.asarray(tension), _pushes(barriers, x))


def _pushes(barriers, x: np.ndarray) -> np.ndarray:
    """(N, 3) the forces of the ``barriers`` on the nodes at x."""
    force = np.zeros_like(x)
    for term in barriers:
        term.gradient(x, force)
    return -force


def wrap_message(net: Net, x: np.ndarray, tension: np.ndarray, contact: np.ndarray):
    """``wrap_warning``'s message for the frictionless ``contact`` (N, 3) on the nodes: the
    run of nodes whose pushes add up beyond RUN_OVER times the largest node's, else that
    node, beyond WRAP_SHARE of the tension; None for neither."""
    found = wrap_share(net, x, tension, contact)
    run = wrap_drift(net, x, tension, contact)
    node_share = found[0] if found is not None else 0.0
    if run is not None and run[0] > max(WRAP_SHARE, RUN_OVER * node_share):  # (pushes
        share, node, last, along = run  # that add up along a run: the tension they change)
        return (
            f"nodes {node} to {last}: the frictionless contact along them pushes along the "
            f"cable with {100.0 * share:.3g} % of its tension in all ({along:.4g} N; at "
            f"most {100.0 * node_share:.3g} % at one node): the tension changes by as much "
            "where nothing should change it. The cable catches on the corners of the "
            "solid's outline (with solver.edge_contact, a cylinder's prisms of 32 sides "
            "within its radius of an end: wrap it nearer the middle, or use a capsule, or "
            "node contact with short edges) or its edges are too long to follow the shape; "
            "refine the cable where it wraps the obstacle (docs/howto/contact.md)"
        )
    if found is None or not found[0] > WRAP_SHARE:
        return None
    share, node, along = found
    return (
        f"node {node}: the frictionless contact there pushes along the cable with "
        f"{100.0 * share:.3g} % of its tension ({along:.4g} N): the edges are too long to "
        "follow the obstacle's shape (a corner, or where the cable leaves it), and the "
        "tensions on either side differ by about as much; refine the cable where it "
        "wraps the obstacle (docs/howto/contact.md)"
    )


#: A tension ratio across a frictional contact beyond exp(mu theta) by this share is warned,
CAPSTAN_SLACK = 0.05
#: ... where the contact forces along the run are at most this many times what the
#: cable's turn there presses on it (T theta at each node).
WRAPPED = 1.25


def capstan_excess(net: Net, x: np.ndarray, tension: np.ndarray, contact: np.ndarray, mu: float):
    """(ratio, bound, first node, last node) of the run of consecutive cable nodes (two
    edges meet at each) pushed by ``contact`` (N, 3) whose tensions on either side differ
    most beyond the capstan bound exp(mu theta), theta the cable's turn over the run's
    nodes (Coulomb friction cannot hold more on any surface: a sharp corner's (1 + mu s)
    / (1 - mu s), s the sine of half its turn, is less); only runs whose contact forces
    the cable's turn explains (within WRAPPED: a rope on a rough floor is pressed by its
    weight, and friction there holds what the weight allows); None where no run is
    judged."""
    edges = np.asarray(net.edges)
    push = np.linalg.norm(contact, axis=1)
    ea = np.asarray(net.EA, dtype=np.float64)
    best = None
    runs, at = cable_runs(net, push > 0.0)
    for run, ends in runs:
        t_in, t_out = (float(tension[e]) for e in ends)
        if min(t_in, t_out) <= TAUT * float(ea[list(ends)].max()):
            continue
        turns = [_turn(x, edges, at[n], n) for n in run]
        tops = [float(np.max(np.abs(tension[at[n]]))) for n in run]
        pulled = sum(t * top for t, top in zip(turns, tops, strict=True))
        if float(push[run].sum()) > WRAPPED * pulled:  # pressed by loads, not the turn
            continue
        ratio, bound = max(t_in, t_out) / min(t_in, t_out), float(np.exp(mu * sum(turns)))
        if best is None or ratio / bound > best[0] / best[1]:
            best = (ratio, bound, run[0], run[-1])
    return best


def _turn(x: np.ndarray, edges: np.ndarray, two: list[int], node: int) -> float:
    """The cable's turn [rad] at ``node`` between its ``two`` edges."""
    a, b = (_other(edges, e, node) for e in two)
    u, v = x[node] - x[a], x[b] - x[node]
    nu, nv = float(np.linalg.norm(u)), float(np.linalg.norm(v))
    if nu == 0.0 or nv == 0.0:
        return 0.0
    return float(np.arccos(np.clip(u @ v / (nu * nv), -1.0, 1.0)))


def capstan_warning(net: Net, terms, x, tension) -> str | None:
    """The warning where friction holds a cable's tensions on either side of a run of
    contact further apart than Coulomb's law allows, exp(mu theta) beyond CAPSTAN_SLACK
    (the largest ``mu`` of the scene's frictions); else None. A rope hauled over a box's
    sharp edges with friction 0.3 ended at rest holding three times the most friction can
    hold (100 exp(0.3 pi) N on a 100 N load), with node contact 26 times, in silence: at
    a sharp corner the contact's forces and their lagged friction overshoot."""
    mus = [float(t.mu) for t in terms if "friction" in t.name and hasattr(t, "mu")]
    barriers = contact_terms(terms)
    if not mus or not barriers or not net.n_edges:
        return None
    x = np.asarray(x, dtype=np.float64)
    found = capstan_excess(net, x, np.asarray(tension), _pushes(barriers, x), max(mus))
    if found is None or not found[0] > found[1] * (1.0 + CAPSTAN_SLACK):
        return None
    ratio, bound, first, last = found
    return (
        f"nodes {first} to {last}: the tensions on either side of the frictional contact "
        f"along them differ by a factor {ratio:.3g}, beyond Coulomb's capstan bound "
        f"exp(mu theta) = {bound:.3g} for mu = {max(mus):.3g} and the cable's turn there: "
        "the contact holds more than its normal forces allow. Over a solid's sharp edges "
        "the discrete rope meets a corner at a node or (solver.edge_contact) at a point of "
        "an edge, whose forces and lagged friction overshoot there where its edges are "
        "longer than its contact radius; refine the rope below that radius where it turns "
        "(it then follows the grown solid's rounded edge), or round the corner (a capsule "
        "along it), and check the tensions (docs/howto/contact.md)"
    )


#: Coulomb coefficients above this are no surface pair's (rope on steel 0.1-0.3, rubber
#: on concrete up to about 1): a typo or a percentage, most likely.
FRICTION_HIGH = 2.0


def unlikely_friction(case: Case) -> list[str]:
    """A message per obstacle whose ``friction`` exceeds FRICTION_HIGH (``friction = 50``
    for 0.5 was taken as given: the contact sticks until the pull is 50 times its normal
    force)."""
    return [
        f"obstacle[{k}].friction = {obs.friction!r}: Coulomb coefficients of real surfaces "
        f"lie below about {FRICTION_HIGH:g} (a rope on steel 0.1-0.3, rubber on concrete "
        f"up to about 1); with {obs.friction!r} the contact sticks until the pull along it "
        f"is {obs.friction!r} times its normal force. A percentage or a typo? (0.5 is "
        "written friction = 0.5)"
        for k, obs in enumerate(case.obstacles)
        if getattr(obs, "friction", 0.0) > FRICTION_HIGH
    ]
