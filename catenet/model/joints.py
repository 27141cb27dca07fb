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
straight rod's hinge). The joint holds no twist (as a pinned end: a twisting rod's chain
ends there) and turning one member about another's axis is free where no member twists.
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


def joint_bending(joints: Joints, x: np.ndarray, moment: np.ndarray, kappa: np.ndarray) -> None:
    """Raises moment (N,) [N m] and kappa (N,) [1/m] at each joint's node to its members'
    largest, 2 k_i |t_i - R t_i0| and 2 |t_i - R t_i0| / l_i (each member's end held by a
    clamp turning with the joint: ``catenet.model.rods.bending_moment``'s clamps)."""
    from catenet.kernels.joints import joint_rotations

    x = np.ascontiguousarray(x, dtype=np.float64)
    rot = np.zeros((len(joints), 3, 3))
    joint_rotations(x, joints.node, joints.start, joints.other, joints.rest, joints.k, rot)
    for j in range(len(joints)):
        node = joints.node[j]
        for p in range(joints.start[j], joints.start[j + 1]):
            t = x[joints.other[p]] - x[node]
            t /= np.linalg.norm(t)
            d = float(np.linalg.norm(t - rot[j] @ joints.rest[p]))
            moment[node] = max(moment[node], 2.0 * joints.k[p] * d)
            kappa[node] = max(kappa[node], 2.0 * d / joints.length[p])


#: A rigid joint turned about one of its members' axes by more than this [rad] is warned:
#: a rod there would twist, and the joint holds no twist.
TURN_WARN = 1e-2


def turned_about_members(joints: Joints, x: np.ndarray) -> tuple[float, int, int] | None:
    """(angle [rad], joint node, member's other node) of the joint turned most about one
    of its members' axes at x (the joint's rotation R's axis-angle vector along the
    member's tangent): a turn the rod would resist by twisting, which the joint does not
    hold (module docstring); None without joints."""
    from catenet.kernels.joints import joint_rotations

    if not len(joints):
        return None
    x = np.ascontiguousarray(x, dtype=np.float64)
    rot = np.zeros((len(joints), 3, 3))
    joint_rotations(x, joints.node, joints.start, joints.other, joints.rest, joints.k, rot)
    best = (0.0, int(joints.node[0]), int(joints.other[0]))
    for j in range(len(joints)):
        r = rot[j]
        angle = float(np.arccos(np.clip(0.5 * (np.trace(r) - 1.0), -1.0, 1.0)))
        axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
        size = float(np.linalg.norm(axis))
        if size > 1e-12 * max(angle, 1e-300):
            axis /= size
        elif angle > 0.5 * np.pi:  # a half turn: the axis from R + I
            col = r + np.eye(3)
            axis = col[:, int(np.argmax(np.linalg.norm(col, axis=0)))]
            axis /= np.linalg.norm(axis)
        else:
            continue
        for p in range(joints.start[j], joints.start[j + 1]):
            t = x[joints.other[p]] - x[joints.node[j]]
            about = abs(angle * float(axis @ t) / float(np.linalg.norm(t)))
            if about > best[0]:
                best = (about, int(joints.node[j]), int(joints.other[p]))
    return best


def turn_warning(joints: Joints, x: np.ndarray, net: Net, cables=None) -> str | None:
    """The warning where a rigid joint ends turned about a member's axis by more than
    TURN_WARN (``turned_about_members``), else None; ``cables`` (a scene's: ``names``,
    ``edge``) names the member's cable."""
    found = turned_about_members(joints, x)
    if found is None or not found[0] > TURN_WARN:
        return None
    angle, node, other = found
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
        f"axis of {member}: a rigid joint holds the angles between its rods but "
        "no twist (each rod's end turns about its own axis freely there), so a frame "
        "loaded out of its plane turns there as a mechanism would; hold the frame against "
        "that turn (a support, a bracing cable) or read the result as a pinned frame's "
        "(docs/howto/rods.md#rigid-joints)"
    )
