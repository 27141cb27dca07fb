"""Supports that move as design variables of the force density method's target search
([[formfind.support]] with ``method = "linear"``).

A support's offset d along one axis c moves its nodes k (a node or a node set, as one)
to x_k + d e_c. The free nodes' equilibrium R = C_f^T Q (C_f x_f + C_s x_s) - P(x, q) = 0
(``catenet.formfind.adjoint``) then changes by dR/dd: -q_e e_c at the free end i of each
edge e that joins i to a moved node, and the self-weight's change -g (dm_e/dL) dL_e at
each free end of an edge whose length the offset changes (dL_e = n_e . (dx_b - dx_a),
``catenet.formfind.newton.weight_coefficients``). A target's residual changes by

    dr/dd = r_s - r_x A^-1 dR/dd,

r_s its partial derivative in the moved nodes' positions (a tension or a length of an
edge that ends there, a cable's length, the support's own reaction and its neighbours'):
one forward solve per offset with the shape's factors, the columns whole (the supports
are a few variables). The offsets are variables s = d / size (the net's size), as in
the elastic method (``catenet.formfind.variables``).

Where the force densities' Jacobian is an operator (a large search), ``Bordered`` adds
these columns to it: its damped step minimises |J_q p_q + J_s p_s + r|^2 + mu |p|^2 by
eliminating p_q, which for a given p_s is the force densities' own damped step for the
residual r + J_s p_s, linear in p_s: one such step for r and one per offset, then the
small system in p_s.
"""

from __future__ import annotations

import numpy as np

from catenet.errors import ConfigError


def support_moves(scene, moves: tuple, prefix: str) -> list:
    """(nodes, axis, name, (low, high)) of each support offset of [[formfind.support]]:
    its nodes must be fixed, each moved along an axis by one entry at most (ConfigError
    naming the key otherwise)."""
    from catenet.formfind.goals import _node_set

    out = []
    seen: dict[tuple[int, int], int] = {}  # (node, axis): the entry that moves it
    for k, m in enumerate(moves):
        path = f"{prefix}support[{k}].node"
        nodes = _node_set(path, m.node, scene)
        free = nodes[~scene.net.fixed[nodes]]
        if free.size:
            raise ConfigError(
                f"{path} = {m.node!r}: node {int(free[0])} is free: a support the search "
                "moves is a fixed node (free nodes move with the equilibrium)"
            )
        for c in m.axes:
            for i in nodes.tolist():
                if (i, c) in seen:
                    raise ConfigError(
                        f"{path} = {m.node!r}: node {i} moves along {'xyz'[c]} in "
                        f"{prefix}support[{seen[i, c]}] too: each support's offset along an "
                        "axis is one entry's"
                    )
                seen[i, c] = k
        for c in m.axes:
            axis = "xyz"[c]
            out.append((nodes, c, f"support {m.node!r} d{axis}", getattr(m, f"d{axis}")))
    return out


class Anchors:
    """The supports' offsets: ``moves`` (nodes, axis, name, (low, high)) of
    ``support_moves``, after the ``first`` variables of s."""

    def __init__(self, net, moves: list, first: int, size: float):
        self.net, self.moves, self.first, self.size = net, moves, first, size
        self.n = len(moves)

    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low, high, start) of their variables: the start at no offset, or the bound
        nearest to it where 0 is out of the range."""
        lo = np.array([a for *_, (a, _) in self.moves], dtype=np.float64) / self.size
        hi = np.array([b for *_, (_, b) in self.moves], dtype=np.float64) / self.size
        return lo, hi, np.clip(0.0, lo, hi)

    def positions(self, s: np.ndarray) -> np.ndarray | None:
        """The nodes (N, 3) at s (None without offsets: the net's own)."""
        if not self.n:
            return None
        x = self.net.nodes.copy()
        for j, (nodes, c, _, _) in enumerate(self.moves):
            x[nodes, c] += self.size * s[self.first + j]
        return x

    def offsets(self, s: np.ndarray) -> np.ndarray:
        """The offsets [m] at s."""
        return self.size * s[self.first : self.first + self.n]

    def columns(self, search, adj, x: np.ndarray, q: np.ndarray, a: np.ndarray, d_x):
        """dr/ds of the offsets (R, n), whole: ``search`` the target search (its goals
        and shape), ``adj`` the linearised equilibrium at (q, x), ``d_x`` dr/dx_f."""
        from catenet.formfind import reactions
        from catenet.formfind.newton import weight_coefficients

        shape, goals, net = search.shape, search.goals, self.net
        every = np.arange(net.n_nodes)
        d_all, _ = goals.partials(x, q, a, every, net)
        if goals.reacts.any():
            rx, _ = reactions.partials(goals, a, shape, x, q, every, own=True)
            d_all = d_all + rx
        d_all = d_all.tocsc()
        index = shape.pattern.index
        ea, eb = net.edges[:, 0], net.edges[:, 1]
        u = x[eb] - x[ea]
        length = np.linalg.norm(u, axis=1)
        wa = weight_coefficients(shape, q, length)[0] if shape.weighs else None
        g = np.asarray(shape.gravity if shape.weighs else np.zeros(3), dtype=np.float64)
        rhs = np.zeros((adj.n3, self.n))
        direct = np.zeros((goals.rows, self.n))
        for j, (nodes, c, _, _) in enumerate(self.moves):
            moved = np.zeros(net.n_nodes, dtype=bool)
            moved[nodes] = True
            direct[:, j] = self.size * np.asarray(d_all[:, 3 * nodes + c].sum(axis=1)).ravel()
            for end, other in ((ea, eb), (eb, ea)):  # C_f^T Q C_s: -q_e at the free end
                sel = (index[end] >= 0) & moved[other]
                np.add.at(rhs[:, j], 3 * index[end[sel]] + c, -self.size * q[sel])
            if wa is None:
                continue
            dl = self.size * u[:, c] / length * (moved[eb].astype(float) - moved[ea])
            for end in (ea, eb):  # the weight at a free end: -g a_e dL_e
                sel = (index[end] >= 0) & (dl != 0.0)
                for cc in range(3):
                    np.add.at(rhs[:, j], 3 * index[end[sel]] + cc, -g[cc] * wa[sel] * dl[sel])
        return direct - np.asarray(d_x @ adj.solve(rhs))


class Bordered:
    """J = [J_q, J_s]: the force densities' operator ``inner`` (a SparseJacobian)
    beside the offsets' columns ``cols`` (R, n) (module docstring)."""

    def __init__(self, inner, cols: np.ndarray):
        self.inner, self.cols = inner, cols
        self.nq = inner.shape[1]
        self.shape = (inner.shape[0], self.nq + cols.shape[1])

    def matvec(self, v: np.ndarray) -> np.ndarray:
        v = np.ravel(v)
        return self.inner.matvec(v[: self.nq]) + self.cols @ v[self.nq :]

    def rmatvec(self, z: np.ndarray) -> np.ndarray:
        z = np.ravel(z)
        return np.concatenate([self.inner.rmatvec(z), self.cols.T @ z])

    def damped(self, r: np.ndarray, mu: float, keep: np.ndarray, eta=None) -> np.ndarray:
        """The p of min |J p + r|^2 + mu |p|^2, p = 0 where not ``keep``."""
        nq = self.nq
        kq, ks = keep[:nq], keep[nq:]
        c = self.cols[:, ks]
        p = np.zeros(self.shape[1])
        base = self.inner.damped(r, mu, kq, eta)  # p_q where p_s = 0
        if not c.shape[1]:
            p[:nq] = base
            return p
        resp = np.column_stack([self.inner.damped(c[:, k], mu, kq, eta) for k in range(c.shape[1])])
        e0 = self.inner.matvec(base) + r  # the residual J p + r = e0 + E p_s
        e = np.column_stack([self.inner.matvec(resp[:, k]) + c[:, k] for k in range(c.shape[1])])
        h = e.T @ e + mu * (resp.T @ resp)
        h[np.diag_indices_from(h)] += mu
        p_s = -np.linalg.solve(h, e.T @ e0 + mu * (resp.T @ base))
        p[:nq] = base + resp @ p_s
        p[nq:][ks] = p_s
        return p


__all__ = ["Anchors", "Bordered", "support_moves"]
