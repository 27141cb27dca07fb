"""The rods' twist with its rotational inertia, for ``catenet modes``: the edges' twist
angles kept as degrees of freedom (``catenet.terms.twist`` eliminates them).

Along every chain of edges with GJ > 0 (a run of consecutive twisting edges of one line,
as ``catenet.model.twist`` finds them, whatever holds its ends), edge k carries a twist
angle theta_k of its material frame against its reference frame (carried by parallel
transport, in time as along the rod), with the rotational inertia J_k = rho J_p l0 [kg
m^2] (rho J_p, the mass polar moment per length: ``material.polar_inertia``). Each vertex
v between two edge slots a, b (two consecutive edges, or a clamp and its end edge: the
clamp's angle is held) carries the material twist tw_v = m_v(x) + theta_b - theta_a,
m_v the reference twist of the kernels (``catenet.kernels.twist``), with the compliance
c_v = (c_a + c_b) / 2 (c = l0 / GJ of each edge, 0 for a clamp): the energy is

    E(x, theta) = sum_v (tw_v - tw0_v)^2 / (2 c_v).

A free (or pinned) end has no vertex: its end edge's outer half carries no moment. The
c_v of a chain add up to C = sum l0 / GJ, so that minimising over theta (the moment
(tw_v - tw0_v) / c_v = M uniform along a chain held at both ends, 0 along one that is not)
gives back the eliminated energy (Theta - Theta_0 + Phi)^2 / (2 C) of the twist term.
Its Hessian at such a minimum, with g_v = dm_v / dx:

    H_xx = sum_v g_v g_v^T / c_v + M Hess Theta,
    H_x theta_k = g_v / c_v at the vertex whose slot b is k, -g_v / c_v where it is a,
    H_theta theta = sum_v (e_b - e_a)(e_b - e_a)^T / c_v,

and the eliminated Hessian is its Schur complement, g g^T / C + M Hess Theta (g = sum
g_v = grad Theta). ``Torsion.blocks`` gives the difference of H_xx from the twist term's
Hessian and the two other blocks; ``catenet.solver.modes`` adds them to the net's
stiffness and solves the modes of positions and twist angles together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.model.net import Net
from catenet.model.twist import Twists, _chains, _held_ends, joint_partner


@dataclass(frozen=True, eq=False)
class Torsion:
    """The twisting chains of a net's rods with their twist angles as DOFs.

    nodes, start, edges, first, closed : as ``catenet.model.twist.Twists`` (every chain
        with GJ > 0 and a rotational inertia, whatever holds its ends)
    held : (S, 2) bool, an open chain's head and tail clamped or on a rigid joint (their
        twist held)
    partner : (S, 2) int64, at an end on a rigid joint its partner's node
        (``catenet.model.twist``; -1: none)
    end_compliance : (S, 2) there, the partner's half edge's compliance
        (``catenet.model.twist.joint_partner``; 0 elsewhere)
    head, tail : (S, 3) the clamps' held tangents along the chain (0 where free)
    compliance : (E,) each chain edge row's l0 / GJ [1/(N m)]
    inertia : (E,) its rotational inertia rho J_p l0 [kg m^2]
    segment : (S,) the chain's segment in the twist term's ``Twists`` (-1: none, its
        twist is not held at both ends)
    missing : "" or why some twisting chains are left out (their rotational inertia is
        unknown: the case's key to give), for ``catenet modes`` to refuse
    """

    nodes: np.ndarray
    start: np.ndarray
    edges: np.ndarray
    first: np.ndarray
    closed: np.ndarray
    held: np.ndarray
    partner: np.ndarray
    end_compliance: np.ndarray
    head: np.ndarray
    tail: np.ndarray
    compliance: np.ndarray
    inertia: np.ndarray
    segment: np.ndarray
    missing: str = ""

    def __len__(self) -> int:
        return len(self.closed)

    @property
    def count(self) -> int:
        """The number of twist angles (one per chain edge)."""
        return int(self.edges.size)

    @property
    def spins(self) -> int:
        """The chains whose twist nothing holds (rings, and open chains with no clamped
        end): each turns about its own axis at no cost, a zero-frequency mode."""
        return int(np.count_nonzero(self.closed | ~self.held.any(axis=1)))

    def blocks(self, x: np.ndarray, twists: Twists | None) -> tuple:
        """At x, on the net's DOFs (3 N) and the twist angles (E): (dK_xx, K_x theta,
        K_theta theta) as SciPy COO matrices, dK_xx the un-eliminated H_xx less the twist
        term's Hessian (its Schur complement: g g^T / C of each segment it holds)."""
        import scipy.sparse as sp

        from catenet.kernels.twist import segment_gradient, vertex_gradients

        x = np.ascontiguousarray(x, dtype=np.float64)
        n = 3 * x.shape[0]
        comp, who, grad, rows = vertex_gradients(
            x, self.nodes, self.start, self.closed, self.head, self.tail, self.held,
            self.compliance, self.partner, self.end_compliance,
        )  # fmt: skip
        dofs = np.where(who[:, :, None] >= 0, 3 * who[:, :, None] + np.arange(3), -1)
        dofs, grad = dofs.reshape(len(comp), 9), grad.reshape(len(comp), 9)
        on = dofs >= 0
        pair = on[:, :, None] & on[:, None, :]
        outer = grad[:, :, None] * grad[:, None, :] / comp[:, None, None]
        r = np.broadcast_to(dofs[:, :, None], pair.shape)[pair]
        c = np.broadcast_to(dofs[:, None, :], pair.shape)[pair]
        parts = [(r, c, outer[pair])]
        held = np.flatnonzero(self.segment >= 0)
        if held.size and twists is None:
            raise ValueError("the twist term's segments are missing (a chain holds its twist)")
        for s in held:  # the twist term's g g^T / C, out
            assert twists is not None
            seg = int(self.segment[s])
            lo, hi = twists.start[seg], twists.start[seg + 1]
            args = (twists.nodes, lo, hi, twists.closed, twists.head, twists.tail, seg)
            g = segment_gradient(x, *args, twists.partner)
            local = np.concatenate(
                [twists.nodes[lo:hi], twists.partner[seg][twists.partner[seg] >= 0]]
            )
            d = (3 * local[:, None] + np.arange(3)).ravel()
            scale = -1.0 / float(twists.compliance[seg])
            parts.append((np.repeat(d, d.size), np.tile(d, d.size), scale * np.outer(g, g).ravel()))
        dk = sp.coo_matrix(
            (np.concatenate([p[2] for p in parts]),
             (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))),
            shape=(n, n),
        )  # fmt: skip
        sign = np.array([-1.0, 1.0])  # tw_v = m_v + theta_b - theta_a
        real = rows >= 0  # (V, 2)
        kxt_r = np.broadcast_to(dofs[:, None, :], (len(comp), 2, 9))
        kxt_c = np.broadcast_to(rows[:, :, None], kxt_r.shape)
        kxt_v = sign[None, :, None] * grad[:, None, :] / comp[:, None, None]
        keep = real[:, :, None] & on[:, None, :]
        kxt = sp.coo_matrix(
            (np.broadcast_to(kxt_v, kxt_r.shape)[keep], (kxt_r[keep], kxt_c[keep])),
            shape=(n, self.count),
        )
        sr = np.broadcast_to(rows[:, :, None], (len(comp), 2, 2))
        sc = np.broadcast_to(rows[:, None, :], sr.shape)
        sv = sign[None, :, None] * sign[None, None, :] / comp[:, None, None]
        both = real[:, :, None] & real[:, None, :]
        ktt = sp.coo_matrix(
            (np.broadcast_to(sv, sr.shape)[both], (sr[both], sc[both])),
            shape=(self.count, self.count),
        )
        return dk, kxt, ktt

    def edge_nodes(self, net: Net) -> np.ndarray:
        """(E,) each twist angle's node for messages: its edge's first node."""
        return np.asarray(net.edges[self.edges, 0], dtype=np.int64)


def build_torsion(
    net: Net,
    GJ: np.ndarray,
    polar: np.ndarray,
    line: np.ndarray,
    clamps: np.ndarray,
    tangent: np.ndarray,
    twists: Twists | None,
    joints=None,
    springs: dict | None = None,
) -> Torsion | None:
    """The twisting chains of ``net`` with twist angles as DOFs (None: none): GJ (M,) per
    edge [N m^2], ``polar`` (M,) the mass polar moment per length rho J_p [kg m] (a chain
    with an edge of 0 keeps its twist eliminated), ``line`` (M,), the rigid clamps (C, 2)
    and their held tangents (C, 3), the rigid joints and the rod ends on 6x6 springs
    that hold their twist (``catenet.model.twist.build_twists``'s),
    and the twist term's segments (None: no chain is held at both ends)."""
    GJ = np.asarray(GJ, dtype=np.float64)
    polar = np.asarray(polar, dtype=np.float64)
    held, soft = _held_ends(clamps, tangent, springs)
    seg_of = {}
    if twists is not None:
        seg_of = {int(twists.edges[twists.first[s]]): s for s in range(len(twists))}
    edges, x = net.edges, net.nodes
    cuts = frozenset() if joints is None else frozenset(joints.node.tolist())
    parts = []
    for run, closed in _chains(edges, np.asarray(line), GJ > 0.0, cuts):
        if not np.all(polar[run] > 0.0):
            continue
        chain = [int(edges[e, 0]) for e in run]
        head = tail = np.zeros(3)
        ends = [False, False]
        partner = [-1, -1]
        end_c = [0.0, 0.0]
        if not closed:
            chain.append(int(edges[run[-1], 1]))
            for end, (node, near, sign) in enumerate(
                ((chain[0], chain[1], 1.0), (chain[-1], chain[-2], -1.0))
            ):
                if held.get(node, (-1,))[0] == near:
                    ends[end], end_c[end] = True, soft.get(node, 0.0)
                    along = sign * np.asarray(held[node][1], dtype=np.float64)
                elif (found := joint_partner(joints, node, near, x)) is not None:
                    ends[end], partner[end], end_c[end] = True, found[0], found[1]
                    along = sign * (x[near] - x[node]) / np.linalg.norm(x[near] - x[node])
                else:
                    continue
                if end == 0:
                    head = along
                else:
                    tail = along
        comp = net.rest_length[run] / GJ[run]
        inertia = polar[run] * net.rest_length[run]
        segment = seg_of.get(run[0], -1)
        parts.append((chain, run, closed, ends, head, tail, comp, inertia, segment, partner, end_c))
    if not parts:
        return None
    return Torsion(
        nodes=np.asarray([n for p in parts for n in p[0]], dtype=np.int64),
        start=np.cumsum([0] + [len(p[0]) for p in parts]).astype(np.int64),
        edges=np.asarray([e for p in parts for e in p[1]], dtype=np.int64),
        first=np.cumsum([0] + [len(p[1]) for p in parts])[:-1].astype(np.int64),
        closed=np.asarray([p[2] for p in parts], dtype=np.bool_),
        held=np.asarray([p[3] for p in parts], dtype=np.bool_).reshape(-1, 2),
        partner=np.asarray([p[9] for p in parts], dtype=np.int64).reshape(-1, 2),
        end_compliance=np.asarray([p[10] for p in parts], dtype=np.float64).reshape(-1, 2),
        head=np.ascontiguousarray(np.array([p[4] for p in parts]).reshape(-1, 3)),
        tail=np.ascontiguousarray(np.array([p[5] for p in parts]).reshape(-1, 3)),
        compliance=np.concatenate([p[6] for p in parts]).astype(np.float64),
        inertia=np.concatenate([p[7] for p in parts]).astype(np.float64),
        segment=np.asarray([p[8] for p in parts], dtype=np.int64),
    )


def no_torsion() -> Torsion:
    """A Torsion of no chain."""
    empty = np.zeros(0, dtype=np.int64)
    return Torsion(
        nodes=empty, start=np.zeros(1, dtype=np.int64), edges=empty, first=empty,
        closed=np.zeros(0, dtype=np.bool_), held=np.zeros((0, 2), dtype=np.bool_),
        partner=np.zeros((0, 2), dtype=np.int64), end_compliance=np.zeros((0, 2)),
        head=np.zeros((0, 3)), tail=np.zeros((0, 3)), compliance=np.zeros(0),
        inertia=np.zeros(0), segment=empty,
    )  # fmt: skip
