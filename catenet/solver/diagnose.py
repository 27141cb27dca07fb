"""Naming what makes a stiffness matrix singular or indefinite: the nodes of a mechanism
(an unstable equilibrium; the zero-frequency modes of ``catenet.solver.modes``).

A node's own 3x3 block of the edges' tangent stiffness, sum over its edges of
(EA/l0) w'' t t^T + (N/|e|)(I - t t^T), is its stiffness when its neighbours stay put.
Where that block has a negative eigenvalue the whole matrix is indefinite (its Rayleigh
quotient along that node's direction is negative): the node is pushed sideways by
compressed bilateral edges more than anything holds it (a joint in a chain of struts, a
straight compressed strut's interior). Such nodes are named in the messages of an
unstable equilibrium, with the edges (and cables) in compression that meet there.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from catenet.model.net import Net
    from catenet.solver.system import System
    from catenet.terms import Stretch
    from catenet.terms.rigid_contact import BodyContact

NEGATIVE = 1e-9  # a block eigenvalue below -NEGATIVE x the block's largest is negative


def has_twist(system: System) -> bool:
    """Whether the system has twisted rods (a ``Twist`` term)."""
    return any(t.name == "twist" for t in system.terms)


def bending_nodes(system: System, ends: bool = False) -> np.ndarray | None:
    """(N,) bool: the nodes where a rod's bending stiffness holds the net sideways (a
    hinge's interior node, the far node of a clamped end edge; ``ends``: a rod's end
    nodes too); None without rods."""
    if "catenet.terms.bending" not in sys.modules:
        return None  # none exists before its module loads: not loaded to look
    from catenet.terms.bending import Bending

    rods = [t.rods for t in system.terms if isinstance(t, Bending)]
    if not rods:
        return None
    held = np.zeros(system.net.n_nodes, bool)
    for r in rods:
        held[np.asarray(r.hinges[:, 1:2] if not ends else r.hinges, dtype=np.int64)] = True
        held[np.asarray(r.clamps[:, 1], dtype=np.int64)] = True
    return held


def unstable_nodes(stretch: Stretch, x: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Free nodes whose own block of the edges' tangent stiffness at x (N, 3) has a
    negative eigenvalue (``stretch``: the net's ``terms.Stretch``; ``free`` (N,) bool)."""
    net = stretch.net
    values = np.empty(36 * net.n_edges)
    stretch.hessian(x, values)
    h = values.reshape(-1, 6, 6)
    blocks = np.zeros((net.n_nodes, 3, 3))
    np.add.at(blocks, net.edges[:, 0], h[:, :3, :3])
    np.add.at(blocks, net.edges[:, 1], h[:, 3:, 3:])
    eig = np.linalg.eigvalsh(blocks)
    size = np.max(np.abs(eig), axis=1)
    return np.flatnonzero(free & (eig[:, 0] < -NEGATIVE * size))


def compressed_edges(stretch: Stretch, x: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Bilateral edges in compression at x that meet one of ``nodes``."""
    net = stretch.net
    at = np.isin(net.edges, nodes).any(axis=1)
    return np.flatnonzero(at & (stretch.tension(x) < 0.0))


def describe_unstable(
    stretch: Stretch,
    x: np.ndarray,
    free: np.ndarray,
    cable_names: Sequence[str] | None = None,
    cable_of_edge: np.ndarray | None = None,
    *,
    twisted: bool = False,
    bent: np.ndarray | None = None,
    factor: float | None = None,
) -> str:
    """One sentence naming the nodes (and cables) of an unstable equilibrium and the fix
    (``twisted``: the system has twisted rods, which buckle beyond their critical twist).
    ``bent`` (N,) bool: the nodes a rod's bending stiffness holds (``bending_nodes``):
    where every node named has it, the structure is no mechanism but loaded beyond a
    buckling load, at the load factor ``factor`` where that is known."""
    nodes = unstable_nodes(stretch, x, free)
    if nodes.size == 0:  # a global instability: name the compressed edges' free nodes
        compressed = np.flatnonzero(stretch.tension(x) < 0.0)
        nodes = np.unique(stretch.net.edges[compressed])
        nodes = nodes[free[nodes]]
    edges = compressed_edges(stretch, x, nodes)
    shown = ", ".join(map(str, nodes[:10])) + (
        f" and {nodes.size - 10} more" if nodes.size > 10 else ""
    )
    where = f"nodes {shown}" if nodes.size else "the net"
    cables = ""
    if cable_names is not None and cable_of_edge is not None and edges.size:
        names = sorted({str(cable_names[c]) for c in cable_of_edge[edges] if c >= 0})
        if names:
            cables = f" (cables {', '.join(names)})"
    twist = (
        "; or a rod twisted beyond its critical twist (8.99 EI / GJ for a straight rod "
        "between clamps held apart, less under compression): turn its ends less"
        if twisted
        else ""
    )
    if bent is not None and nodes.size and bool(np.all(bent[nodes])):
        return _buckled(where, cables, factor) + twist
    return (
        f"a mechanism: the stiffness is negative at {where}, where compressed bilateral "
        f"edges{cables} push the net sideways more than anything holds it (a chain of "
        "pinned struts, a straight compressed strut): fix or brace those nodes (a support, "
        "an edge to a support, guys with prestress), make the strut one edge, or give it "
        "bending stiffness (material.EI: a rod; a rod beyond its Euler load buckles)" + twist
    )


def _buckled(where: str, cables: str, factor: float | None) -> str:
    """The message of an unstable equilibrium whose compressed edges all have bending
    stiffness: no mechanism, a buckling load exceeded (at load ``factor``, if known)."""
    at = "" if factor is None else f" (at load factor {factor:.6g})"
    return (
        f"the loads exceed a buckling (limit) load of the structure as modelled{at}: the "
        f"stiffness is negative at {where}, where compressed rods{cables} bend sideways "
        "although they have bending stiffness (material.EI): their compression is beyond "
        "what it holds (an Euler load); lower the loads or the compression (prestress), "
        "or stiffen or brace the rods there (a larger EI, a brace or guy at those nodes)"
    )


def describe_unstable_bodies(system: System, x: np.ndarray) -> str:
    """One sentence naming the free rigid bodies of an unstable equilibrium that no
    compressed bilateral edge explains (else ""): a body at rest on the net whose rigid
    motion has negative stiffness, and the fix."""
    stretch = system.stretch
    if np.any(stretch.tension(x) < 0.0):
        return ""  # compressed bilateral edges: ``describe_unstable`` names them
    labels = [t.label for t in _body_contacts(system)]
    if not labels:
        return ""
    names = ", ".join(labels)
    return (
        f"the free {'body' if len(labels) == 1 else 'bodies'} {names} would slide, roll or "
        "tip from where the solve balanced it: the net's nodes under a flat face hold a "
        "frictionless body up but not sideways, so a small tilt turns their push into a "
        "sideways force nothing resists; give the body friction (its friction key), or "
        "let it come to rest in a dynamic run with damping (solver.method = 'dynamic'), "
        "whose rest state catenet modes takes"
    )


def _held_by_terms(system: System) -> np.ndarray:
    """(N,) nodes that a term besides the edges' stretching holds (a spring, contact)."""
    held = np.zeros(system.net.n_nodes, bool)
    for term in system.terms:
        pattern = term.pattern() if term.edge_net is None else None
        if pattern is not None:
            held[np.asarray(pattern[0]) // 3] = True
    return held


def unpinned_parts(net: Net) -> np.ndarray:
    """(N,) bool: the nodes of the net's connected parts (by every edge) that no fixed
    node and no spring holds: rollers and sliders at most, which leave the part's
    translations and turns in their planes or along their lines free (a ring floating on
    a table)."""
    pinned = net.fixed.copy()
    if net.springs is not None:
        pinned[net.springs.held_nodes] = True
    return _unanchored(net.components(), pinned)


def _unanchored(label: np.ndarray, anchors: np.ndarray) -> np.ndarray:
    """(N,) bool: the nodes of the parts (``label`` per node) that hold no anchor."""
    anchored = np.zeros(label.max() + 1, bool)
    anchored[label[anchors]] = True
    out: np.ndarray = ~anchored[label]
    return out


def floating_parts(net: Net, tension: np.ndarray, x: np.ndarray, held: np.ndarray) -> np.ndarray:
    """(N,) bool: free nodes in a part of the net that only slack edges join to its
    supports (a rigid-body motion costs nothing). Taut: an edge in tension, at exactly
    zero strain (its axial stiffness counts) or bilateral; ``held`` nodes (another term
    holds them) count as supports."""
    from catenet.model.net import components

    length = np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1)
    taut = (tension > 0) | (length >= net.rest_length) | ~net.law.tension_only
    label = components(net.n_nodes, net.edges[taut])
    floating: np.ndarray = _unanchored(label, net.supported | held) & ~net.fixed
    return floating


def describe_zero_modes(
    system: System,
    x: np.ndarray,
    nodes: np.ndarray,
    count: int,
    cable_names: Sequence[str] | None = None,
    cable_of_edge: np.ndarray | None = None,
) -> str:
    """One sentence on the zero-frequency modes of a net at x: how many, and the nodes
    that move in them by what holds them (slack edges only, a part joined to the supports
    by slack edges only, else a mechanism of the taut edges)."""
    from catenet.model.measures import loose_nodes

    net = system.net
    tension = system.tension(x)
    held = _held_by_terms(system)
    loose = np.zeros(net.n_nodes, bool)
    loose[loose_nodes(net, tension)] = True
    loose &= ~held
    body = np.arange(net.n_nodes) >= net.n_net  # the centres of rigid balls
    floating = floating_parts(net, tension, x, held) & ~loose & ~body
    nodes = np.asarray(nodes, dtype=np.int64)
    free_bodies = _free_bodies(system)  # (label, nodes) of each free rigid body
    rigid = np.zeros(net.n_nodes, bool)
    named = []
    for label, own in free_bodies:
        rigid[own] = True
        if np.isin(own, nodes).any():
            named.append(label)
    nodes = nodes[~rigid[nodes]]
    whole = unpinned_parts(net) & ~loose & ~floating & ~body
    groups = [
        (nodes[body[nodes]], "are the centres of rigid bodies that touch nothing"),
        (nodes[loose[nodes]], "hang on slack edges only"),
        (nodes[floating[nodes]], "form a part that only slack edges join to the supports"),
        (
            nodes[whole[nodes]],
            "form a part that no fixed node or spring holds: it moves as a whole (the "
            "translations and turns its rollers or sliders leave free), a rigid-body "
            "motion",
        ),
        (
            nodes[~loose[nodes] & ~floating[nodes] & ~body[nodes] & ~whole[nodes]],
            "are a mechanism of the taut edges (untensioned straight edges or a chain "
            "that turns freely"
            + (
                ", or rods turning at a rigid joint about the axis of a rod that does not twist)"
                if any(t.name == "joints" for t in system.terms)
                else ")"
            ),
        ),
    ]
    parts = []
    for group, why in groups:
        if group.size:
            on = _cables(net, group, cable_names, cable_of_edge)
            parts.append(f"nodes {_shown(group)}{on} {why}")
    plural = "s" if count != 1 else ""
    head = f"{count} zero-frequency mode{plural} (left out): "
    if named:  # a frictionless free body slides or turns on the net's nodes at no cost
        which = ", ".join(named)
        bodies = (
            f"the free bod{'y' if len(named) == 1 else 'ies'} {which} slide or turn where "
            "they rest at no cost (frictionless contact: the net's nodes or the ground "
            "slip along a face, or every push passes through the body's axis): a rigid "
            "motion, not a vibration; friction holds it"
        )
        if not parts:
            return head + bodies
        head += bodies + "; "
    where = "; ".join(parts) if parts else "the net"
    if len(parts) == 1 and nodes[whole[nodes]].size == len(nodes):  # rigid motion alone
        return f"{head}{where}: a fixed node or a spring stops it, where it should not move"
    return f"{head}{where}: give them tension (prestress, a load) or a support"


def _free_bodies(system: System) -> list[tuple[str, np.ndarray]]:
    """(label, nodes) of each free rigid body: its contact term's label and frame."""
    return [(t.label, t.frame.nodes) for t in _body_contacts(system)]


def _body_contacts(system: System) -> list[BodyContact]:
    """The contact term (``BodyContact``, not its friction) of each free rigid body."""
    if "catenet.terms.rigid_contact" not in sys.modules:
        return []  # none exists before its module loads: not loaded to look
    from catenet.terms.rigid_contact import BodyContact

    return [t for t in system.terms if type(t) is BodyContact]


def _shown(items: ArrayLike) -> str:
    nodes = np.asarray(items)
    head = ", ".join(map(str, nodes[:10]))
    return head + (f" and {nodes.size - 10} more" if nodes.size > 10 else "")


MODE_SHARE = 0.3  # a mode names the nodes it moves by this share of its most


def mode_nodes(mode: np.ndarray) -> np.ndarray:
    """The nodes a ``mode`` (N, 3) moves by MODE_SHARE of its largest move or more, the
    farthest first (none for a zero mode)."""
    amp = np.linalg.norm(mode, axis=1)
    top = float(amp.max(initial=0.0))
    if not top > 0.0:
        return np.zeros(0, np.int64)
    nodes = np.flatnonzero(amp >= MODE_SHARE * top)
    return nodes[np.argsort(-amp[nodes])]


NEUTRAL_SAYS = {
    "rest": "which the loads do not drive: where the structure rests along it is not "
    "determined (round-off chooses it)",
    "failed": "along which Newton found no equilibrium further on",
    "driven": "which the loads drive, and along which Newton found no equilibrium "
    "further on: a mechanism under these loads, unless bilateral edges given straight "
    "must sag into their shape",
}
DRIVES = 1e-3  # a load whose share along a mode without stiffness is above this drives it


def describe_neutral(
    mode: np.ndarray, loose: np.ndarray, where: str = "rest", whole: np.ndarray | None = None
) -> str:
    """What a neutral state's ``mode`` without stiffness (N, 3) moves: the nodes, and
    what to do; "" where it moves only ``loose`` nodes (hanging on slack edges only:
    their own warning says it). ``where`` (``NEUTRAL_SAYS``): an end state ("rest"), or
    the last equilibrium of a path that Newton could not take further ("failed"), whose
    mode the loads drive ("driven"). ``whole``: the nodes of parts that no fixed node or
    spring holds (``unpinned_parts``); a mode within them is such a part's rigid motion."""
    nodes = mode_nodes(mode)
    if not np.setdiff1d(nodes, loose).size:
        return ""
    what = NEUTRAL_SAYS[where]
    if whole is not None and whole[nodes].all():
        return (
            f"its stiffness has a mode without resistance (nodes {_shown(nodes)} move most "
            f"in it), {what}: a part that no fixed node or spring holds moves in it as a "
            "whole (the translations and turns its rollers or sliders leave free, a "
            "rigid-body motion); fix a node of it, or hold it with a spring or a roller "
            "across that motion"
        )
    return (
        f"its stiffness has a mode without resistance (nodes {_shown(nodes)} move most in "
        f"it), {what}: a part that turns freely (a frame on pinned "
        "feet, a joint about a rod that does not twist) or that has no stiffness across it "
        "(straight unstressed edges); hold those nodes (a support, bracing, a clamp, a "
        "roller), prestress them, or give the rods that turn there GJ"
    )


def _cables(
    net: Net,
    nodes: np.ndarray,
    cable_names: Sequence[str] | None,
    cable_of_edge: np.ndarray | None,
) -> str:
    if cable_names is None or cable_of_edge is None:
        return ""
    at = np.isin(net.edges, nodes).any(axis=1)
    names = sorted({str(cable_names[c]) for c in cable_of_edge[at] if c >= 0})
    return f" (cables {', '.join(names)})" if names else ""


def joint_turn(terms: Any, far: np.ndarray | None) -> str:
    """Where the state a collapse moved toward (``far``) turned a rigid joint about the
    axis of a rod that does not twist there: which joint, how far, about which member;
    else ""."""
    from catenet.model.joints import TURN_SHARE, turned_about_members, twisting_members

    if far is None:
        return ""
    held, watch = twisting_members(terms)
    for term in terms:
        if term.name != "joints":
            continue
        found = turned_about_members(term.joints, far, held, watch)
        if found is not None and found[0] > TURN_SHARE:
            _, angle, node, other = found
            return (
                f"; the rigid joint at node {node} turned by {math.degrees(angle):.3g} deg "
                f"about the axis of its member toward node {other}, a rod that does not "
                "twist there"
            )
    return ""
