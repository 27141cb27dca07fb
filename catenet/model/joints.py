"""Rigid joints where rods meet (``supports.rigid_joints``): the rods' ends at a joint node
turn together, as if clamped to a joint that may turn as a whole.

Where two lines meet, rods are pinned to each other (``catenet.model.rods``). A rigid joint
holds the angles between its members instead: the edges with EI > 0 that meet at the
node (two or more lines' rods; a line passing through the node brings both its edges).
Each member i (its edge from the joint node j to its other node o_i, unit tangent t_i,
t_i0 as given) is held by a clamp that turns with the joint's rotation R:

    E = sum_i k_i |t_i - R t_i0|^2,    k_i = EI_i / l_i,

R the rotation that minimises it (the polar factor of B = sum_i k_i t_i t_i0^T: an
orthogonal Procrustes problem), so that E = 2 sum_i k_i - 2 tr(R^T B). Each member's
term is a clamp's (``catenet.kernels.bending``: the rod's end mirrored at the clamp), so
that two members in line are the hinge of a straight rod, EI / (l1 + l2) |t2 - t1|^2 to
second order, at any angle between them (a joint drawn at 90 degrees is as stiff as a
straight rod's hinge). The joint holds the twist of a rod that twists (GJ > 0) and ends
there (``catenet.model.twist``: its twist measured against a partner member's direction;
a line passing through is split at the joint); a rod that does not twist turns freely
about its own axis there, and turning one member about such a rod's axis costs nothing
where it bends no member (``turn_warning``).
``catenet.kernels.joints`` derives E and its exact derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import Net


@dataclass(frozen=True, eq=False)
class Joints:
    """The rigid joints of a net.

    node : (J,) int64, each joint's node
    start : (J + 1,) int64, joint j's members are rows start[j]:start[j + 1]
    other : (P,) int64, each member's other node (its edge from the joint node)
    rest : (P, 3) float64, each member's unit tangent as given (from the joint node out)
    k : (P,) float64, EI / l of each member's edge [N m]
    length : (P,) float64, each member's edge's rest length [m]
    """

    node: np.ndarray
    start: np.ndarray
    other: np.ndarray
    rest: np.ndarray
    k: np.ndarray
    length: np.ndarray

    def __len__(self) -> int:
        return len(self.node)


def build_joints(net: Net, EI: np.ndarray, line: np.ndarray, nodes: np.ndarray, key: str) -> Joints:
    """The rigid joints at ``nodes`` (indices, each once) of ``net``, whose edges bend
    where EI (M,) > 0 along their ``line`` (M,; -1: none); a ConfigError naming ``key``
    for a node where fewer than two lines' rods meet or whose members all lie on one
    straight line."""
    edges = net.edges[: net.n_edges]
    bends = (np.asarray(EI) > 0.0) & (np.asarray(line) >= 0)
    problems = []
    start, other, rest, k, length = [0], [], [], [], []
    for node in np.asarray(nodes, dtype=np.int64).tolist():
        at = np.flatnonzero(bends & ((edges[:, 0] == node) | (edges[:, 1] == node)))
        lines = {int(line[e]) for e in at}
        if len(lines) < 2:
            problems.append(
                f"{key}: node {node} joins {'no rod' if not at.size else 'the rod of one line'}"
                ": a rigid joint joins the rods (edges with EI > 0) of two lines or more "
                "(a line already bends continuously through its own nodes)"
            )
            continue
        ends = np.where(edges[at, 0] == node, edges[at, 1], edges[at, 0])
        t = net.nodes[ends] - net.nodes[node]
        t /= np.linalg.norm(t, axis=1)[:, None]
        if np.linalg.matrix_rank(t, tol=1e-6) < 2:
            problems.append(
                f"{key}: node {node}: its rods all lie on one straight line: there a rigid "
                "joint is a straight rod's hinge (draw them as one cable)"
            )
            continue
        other += ends.tolist()
        rest += t.tolist()
        k += (np.asarray(EI)[at] / net.rest_length[at]).tolist()
        length += net.rest_length[at].tolist()
        start.append(start[-1] + len(at))
    if problems:
        raise ConfigError(problems)
    return Joints(
        node=np.asarray(np.asarray(nodes, dtype=np.int64).tolist(), dtype=np.int64),
        start=np.asarray(start, dtype=np.int64),
        other=np.asarray(other, dtype=np.int64),
        rest=np.ascontiguousarray(np.asarray(rest, dtype=np.float64).reshape(-1, 3)),
        k=np.asarray(k, dtype=np.float64),
        length=np.asarray(length, dtype=np.float64),
    )


def joint_bending(
    joints: Joints,
    x: np.ndarray,
    moment: np.ndarray,
    kappa: np.ndarray,
    carried: np.ndarray | None = None,
) -> None:
    """Raises moment (N,) [N m] and kappa (N,) [1/m] at each joint's node to its members'
    largest: a member's end moment is r x f at its first edge (r from the joint node to
    its other node, f the force there of the joint's term, 2 k |t - R t0| for its clamp
    turning with the joint, plus ``carried`` (N, 3), the force there of the rods' twist:
    the torque a twisting rod passes into it as its partner, ``catenet.model.twist``),
    its part across the member; kappa 2 |t - R t0| / l (``catenet.model.rods``'s clamps)."""
    from catenet.kernels.joints import joint_gradient, joint_rotations

    x = np.ascontiguousarray(x, dtype=np.float64)
    rot = np.zeros((len(joints), 3, 3))
    joint_rotations(x, joints.node, joints.start, joints.other, joints.rest, joints.k, rot)
    force = np.zeros_like(x)
    joint_gradient(x, joints.node, joints.start, joints.other, joints.rest, joints.k, force)
    if carried is not None:
        force += carried
    for j in range(len(joints)):
        node = joints.node[j]
        for p in range(joints.start[j], joints.start[j + 1]):
            o = joints.other[p]
            r = x[o] - x[node]
            t = r / np.linalg.norm(r)
            m = np.cross(r, force[o])
            across = float(np.linalg.norm(m - (m @ t) * t))
            d = float(np.linalg.norm(t - rot[j] @ joints.rest[p]))
            moment[node] = max(moment[node], across)
            kappa[node] = max(kappa[node], 2.0 * d / joints.length[p])


#: A rigid joint whose turn has a component about one of its members' axes beyond this
#: share of the turn (a turn a rod there would resist by twisting, which the joint does not
#: hold) is warned; in-plane loads on a plane frame give shares of 1e-10 and below, loads
#: out of its plane shares near 1.
TURN_SHARE = 0.1
#: ... where that component also exceeds this [rad] (below it the turn's axis is round-off).
TURN_FLOOR = 1e-9


def would_twist(joints: Joints, hinges: np.ndarray, holding: set[int]) -> frozenset:
    """(joint node, member's other node) of every member whose rod, followed along its
    hinges (``hinges`` (H, 3): a ``Rods``'), ends at a node in ``holding`` (a rigid clamp
    or a rigid joint) or closes on itself: a rod whose twist the joint's turn about it
    would change. A rod with a free or pinned far end turns with the joint at no cost."""
    step: dict[tuple[int, int], int] = {}
    for i, j, k in np.asarray(hinges, dtype=np.int64).tolist():
        step[(i, j)] = k
        step[(k, j)] = i
    out = set()
    for jj in range(len(joints)):
        node = int(joints.node[jj])
        for other in joints.other[joints.start[jj] : joints.start[jj + 1]].tolist():
            prev, cur = node, int(other)
            for _ in range(len(step) + 1):
                if (prev, cur) not in step:
                    break
                prev, cur = cur, step[(prev, cur)]
            else:
                out.add((node, int(other)))  # a ring
                continue
            if cur in holding:
                out.add((node, int(other)))
    return frozenset(out)


def turned_about_members(
    joints: Joints, x: np.ndarray, held: frozenset = frozenset(), watch: frozenset | None = None
) -> tuple[float, float, int, int] | None:
    """(share, angle [rad], joint node, member's other node) of the joint whose turn at x
    (its rotation R's axis-angle vector) has the largest component about one of its
    members' axes, over the whole turn (share) and as an angle; components below
    TURN_FLOOR do not count, nor members whose twist the joint holds (``held``: pairs of
    joint node and member's other node; ``catenet.terms.twist.Twist.joint_members``), nor
    where ``watch`` is given members not in it (None: none, or no joints)."""
    from catenet.kernels.joints import joint_rotations

    if not len(joints):
        return None
    x = np.ascontiguousarray(x, dtype=np.float64)
    rot = np.zeros((len(joints), 3, 3))
    joint_rotations(x, joints.node, joints.start, joints.other, joints.rest, joints.k, rot)
    best = None
    for j in range(len(joints)):
        r = rot[j]
        angle = float(np.arccos(np.clip(0.5 * (np.trace(r) - 1.0), -1.0, 1.0)))
        axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
        size = float(np.linalg.norm(axis))
        if angle > 0.5 * np.pi and size < 1e-6:  # a half turn: the axis from R + I
            col = r + np.eye(3)
            axis = col[:, int(np.argmax(np.linalg.norm(col, axis=0)))]
            axis /= np.linalg.norm(axis)
        elif size > 0.0:
            axis /= size
        else:
            continue
        for p in range(joints.start[j], joints.start[j + 1]):
            pair = (int(joints.node[j]), int(joints.other[p]))
            if pair in held or (watch is not None and pair not in watch):
                continue  # a rod that twists, or one whose far end lets it turn
            t = x[joints.other[p]] - x[joints.node[j]]
            share = abs(float(axis @ t)) / float(np.linalg.norm(t))
            if angle * share > TURN_FLOOR and (best is None or share > best[0]):
                best = (share, angle * share, int(joints.node[j]), int(joints.other[p]))
    return best


def turn_warning(
    joints: Joints,
    x: np.ndarray,
    net: Net,
    cables=None,
    held: frozenset = frozenset(),
    watch: frozenset | None = None,
) -> str | None:
    """The warning where a rigid joint's turn is about the axis of a member that does not
    twist (``held``: those that do) but would (``watch``: ``would_twist``; None: any) by
    more than TURN_SHARE of it (``turned_about_members``), else None; ``cables`` (a
    scene's: ``names``, ``edge``) names the member's cable."""
    found = turned_about_members(joints, x, held, watch)
    if found is None or not found[0] > TURN_SHARE:
        return None
    share, angle, node, other = found
    member = f"its member toward node {other}"
    edges = net.edges[: net.n_edges]
    at = np.flatnonzero(
        ((edges[:, 0] == node) & (edges[:, 1] == other))
        | ((edges[:, 1] == node) & (edges[:, 0] == other))
    )
    if cables is not None and at.size and cables.edge[at[0]] >= 0:
        member += f" (cable {cables.names[int(cables.edge[at[0]])]!r})"
    return (
        f"the rigid joint at node {node} turned by {np.degrees(angle):.3g} deg about the "
        f"axis of {member}, {100.0 * share:.3g} % of its turn, and that rod does not "
        "twist: it turns freely about its axis there (a frame loaded out of its plane "
        "carries that load as if the rod had no torsional stiffness: less shared between "
        "its members, or turning as a mechanism); give the rod GJ > 0 and hold its twist "
        "at its other end too (a clamp or another rigid joint), or hold the frame against "
        "those turns (supports, bracing) (docs/howto/rods.md#rigid-joints)"
    )


def twisting_members(terms) -> tuple[frozenset, frozenset | None]:
    """For a rigid joint's warning: the members whose twist their joint holds (the twist
    term's), and those whose rods would twist (``catenet.model.joints.would_twist``: their
    far end a rigid clamp or another joint); None: no rods."""
    held = frozenset().union(*[t.joint_members() for t in terms if t.name == "twist"])
    rods = next((t.rods for t in terms if t.name == "bending"), None)
    if rods is None:
        return held, None
    holding = set(rods.clamps[rods.rigid, 0].tolist())
    joints = [t.joints for t in terms if t.name == "joints"]
    for j in joints:
        holding |= set(j.node.tolist())
    return held, frozenset().union(*[would_twist(j, rods.hinges, holding) for j in joints])
