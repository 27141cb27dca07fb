"""A state of a coarse net carried over to a finer net of the same cables (``transfer``):
the displacements interpolated along each cable by arc length.

Both nets are cut into chains: the paths between joints (supports and nodes where other
than two edges meet: crossings, cable ends, branch points), whose inner nodes have two
edges each. A net built at a finer edge length from the same cables has the same joints at
the same places and, between every two of them, the same chain with more nodes. Each
fine node on a chain takes the displacement of the coarse chain at the same fraction of
its length (the reference lengths of the edges, linear between the coarse nodes); each
joint takes its coarse joint's. Nets that are not so related (other joints, a joint where
the other has none, two chains between the same joints, a chain closing on its joint, a
ring without joints) give None: a start that does not come from a coarse net.
"""

from __future__ import annotations

import numpy as np

from catenet.model.net import Net

JOINT_RTOL = 1e-8  # joints of the two nets coincide to this share of the net's extent


class Chains:
    """The chains of a net: ``joints`` (indices), and per inner node (degree 2, free) its
    chain (``chain``, -1 at joints), its end joints (``ends``, (C, 2), the first the
    lower index) and its distance along the chain from the first end (``along``) over the
    chain's length (``length``, (C,)); ``ok`` False where the net is not cut into chains
    this way (see the module docstring)."""

    def __init__(self, net: Net):
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components, dijkstra

        n = net.n_nodes
        i, j = net.edges[:, 0], net.edges[:, 1]
        degree = np.bincount(net.edges.ravel(), minlength=n)
        joint = net.fixed | (degree != 2)
        self.joints = np.flatnonzero(joint)
        self.chain = np.full(n, -1, dtype=np.int64)
        self.along = np.zeros(n)
        self.ok = True
        inner_edge = ~joint[i] & ~joint[j]
        inner = np.flatnonzero(~joint)
        graph = sp.coo_matrix(
            (np.ones(int(inner_edge.sum())), (i[inner_edge], j[inner_edge])), shape=(n, n)
        )
        _, labels = connected_components(graph, directed=False)
        # inner chains numbered 0..C-1, then the edges from joint to joint, one each
        _, self.chain[inner] = np.unique(labels[inner], return_inverse=True)
        chains = int(self.chain[inner].max()) + 1 if inner.size else 0
        direct = np.flatnonzero(joint[i] & joint[j])
        ends = np.full((chains + direct.size, 2), -1, dtype=np.int64)
        ends[chains:] = np.sort(net.edges[direct], axis=1)
        length = np.zeros(chains + direct.size)
        span = np.linalg.norm(net.nodes[j] - net.nodes[i], axis=1)
        length[chains:] = span[direct]
        # every other edge belongs to one inner chain: its length, and its joint ends
        rest = np.flatnonzero(~(joint[i] & joint[j]))
        owner = np.where(joint[i[rest]], self.chain[j[rest]], self.chain[i[rest]])
        length[:chains] = np.bincount(owner, weights=span[rest], minlength=chains)
        tie = rest[joint[i[rest]] | joint[j[rest]]]
        tie_joint = np.where(joint[i[tie]], i[tie], j[tie])
        tie_chain = np.where(joint[i[tie]], self.chain[j[tie]], self.chain[i[tie]])
        order = np.argsort(tie_chain, kind="stable")
        tie_joint, tie_chain = tie_joint[order], tie_chain[order]
        if not np.array_equal(tie_chain, np.repeat(np.arange(chains), 2)):
            self.ok = False  # a ring without joints
            self.ends, self.length = ends, length
            return
        ends[:chains] = np.sort(tie_joint.reshape(-1, 2), axis=1)
        self.ends, self.length = ends, length
        if np.any(ends[:, 0] == ends[:, 1]):
            self.ok = False  # a chain closing on its joint: no direction along it
        if inner.size and self.ok:
            weighted = sp.coo_matrix((span, (i, j)), shape=(n, n)).tocsr()
            dist, _, source = dijkstra(
                weighted,
                directed=False,
                indices=self.joints,
                min_only=True,
                return_predecessors=True,
            )
            c = self.chain[inner]
            from_first = source[inner] == ends[c, 0]
            self.along[inner] = np.where(from_first, dist[inner], length[c] - dist[inner])

    def fraction(self, nodes: np.ndarray) -> np.ndarray:
        """Where the inner ``nodes`` lie along their chains (0 at the first end, 1 at the
        other)."""
        c = self.chain[nodes]
        return np.clip(self.along[nodes] / self.length[c], 0.0, 1.0)


def transfer(coarse: Net, x_coarse: np.ndarray, fine: Net) -> np.ndarray | None:
    """The fine net's positions (N, 3) whose displacements from its reference positions
    are the coarse net's at ``x_coarse``, interpolated along each chain by arc length
    (module docstring); None where the nets are not a coarse and a fine net of the same
    cables."""
    cc, fc = Chains(coarse), Chains(fine)
    if not (cc.ok and fc.ok) or cc.joints.size != fc.joints.size or cc.joints.size == 0:
        return None
    extent = float(np.max(np.ptp(fine.nodes, axis=0), initial=0.0))
    hit = _same_places(coarse.nodes[cc.joints], fine.nodes[fc.joints], JOINT_RTOL * extent)
    if hit is None:
        return None
    partner = cc.joints[hit]  # the coarse joint of every fine joint
    if not np.array_equal(coarse.fixed[partner], fine.fixed[fc.joints]):
        return None
    u_coarse = x_coarse - coarse.nodes
    u = np.zeros_like(fine.nodes)
    u[fc.joints] = u_coarse[partner]

    # the coarse chains' nodes in order along each: key = chain * 4 + fraction
    n_c = len(cc.length)
    pairs = {(int(a), int(b)): k for k, (a, b) in enumerate(cc.ends)}
    if len(pairs) != n_c:
        return None  # two chains between the same joints
    inner_c = np.flatnonzero(cc.chain >= 0)
    chain_of = np.concatenate([np.arange(n_c), np.arange(n_c), cc.chain[inner_c]])
    where = np.concatenate([np.zeros(n_c), np.ones(n_c), cc.fraction(inner_c)])
    node_of = np.concatenate([cc.ends[:, 0], cc.ends[:, 1], inner_c])
    order = np.argsort(chain_of * 4.0 + where, kind="stable")
    key_c, node_c = (chain_of * 4.0 + where)[order], node_of[order]

    inner_f = np.flatnonzero(fc.chain >= 0)
    if inner_f.size == 0:
        return fine.nodes + u
    fine_of_coarse = np.full(coarse.n_nodes, -1, dtype=np.int64)
    fine_of_coarse[partner] = fc.joints
    coarse_of_fine = np.full(fine.n_nodes, -1, dtype=np.int64)
    coarse_of_fine[fc.joints] = partner
    ends_f = coarse_of_fine[fc.ends]  # the coarse joints at each fine chain's ends
    flip = ends_f[:, 0] > ends_f[:, 1]
    low, high = np.minimum(ends_f[:, 0], ends_f[:, 1]), np.maximum(ends_f[:, 0], ends_f[:, 1])
    match = np.array([pairs.get((int(a), int(b)), -1) for a, b in zip(low, high, strict=True)])
    if match.size and np.any(match < 0):
        return None  # a fine chain between joints no coarse chain joins
    c_f = fc.chain[inner_f]
    s = fc.fraction(inner_f)
    s = np.where(flip[c_f], 1.0 - s, s)
    key = match[c_f] * 4.0 + s
    hi = np.clip(np.searchsorted(key_c, key, side="right"), 1, key_c.size - 1)
    lo = hi - 1
    width = key_c[hi] - key_c[lo]
    w = np.where(width > 0.0, (key - key_c[lo]) / np.where(width > 0.0, width, 1.0), 0.0)
    w = np.clip(w, 0.0, 1.0)[:, None]
    u[inner_f] = (1.0 - w) * u_coarse[node_c[lo]] + w * u_coarse[node_c[hi]]
    return fine.nodes + u


def _same_places(a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray | None:
    """For every point of ``b`` the index of the point of ``a`` at its place (to ``tol``),
    or None unless the two sets of distinct points are the same (a grid of ``tol``)."""
    if not (np.isfinite(tol) and tol > 0.0):
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        qa, qb = np.round(a / tol), np.round(b / tol)
    oa, ob = np.lexsort(qa.T[::-1]), np.lexsort(qb.T[::-1])
    sa = qa[oa]
    if not np.array_equal(sa, qb[ob]) or not np.all(np.isfinite(sa)):
        return None
    if len(sa) > 1 and np.any(np.all(sa[1:] == sa[:-1], axis=1)):
        return None  # two joints at one place
    hit = np.empty(len(b), dtype=np.int64)
    hit[ob] = oa
    return hit
