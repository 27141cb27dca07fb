"""Barrier contact between the net's nodes and a free rigid body (``catenet.terms.rigid``).

The body's shape is a fixed obstacle term (box, capsule, sphere, mesh) built at the
body's pose at t = 0; a node x is seen there at X = c0 + A^T (x - c), with (c, A) the
body's pose, linear in its four nodes p (``Frame.state``). With g, H the shape's
gradient and Hessian at X and u = x - c:

    dE/dx = A g,   dE/dc = -A g,   dE/dA = u g^T,

and the Hessian in q = (x, c, a1, a2, a3) (a_m the columns of A) is L^T H L + S, with
L = [A^T, -A^T, e_1 u^T, e_2 u^T, e_3 u^T] the Jacobian of X and S the second
derivative of X weighted by g: g_m 1 between a_m and x, -g_m 1 between a_m and c. The
chain to the body's nodes is the constant kron(T, 1) of ``Frame.chain``. Per contact
node the values are its (x, x) block (9), (x, p) (36) and (p, x) (36), then the
body's (p, p) block (144) summed over the nodes.

``max_step``: along the step, a node's body-frame point follows the quadratic path
X(t) = X0 + t V + t^2 W (V = A^T du + dA^T u, W = dA^T du, du = dx - dc). The distance to
the shape is 1-Lipschitz, so moving by at most the remaining gap keeps the node
outside: each node advances t by the root of |V + 2 t W| s + |W| s^2 = d(t) - CA_SHARE d0
until its gap is within twice that share of its start (the first contact, from below)
or it gets beyond every step the line search tries (inf).
"""

from __future__ import annotations

import math

import numpy as np

from catenet.terms.base import Term, register
from catenet.terms.rigid import CA_ITER, CA_SHARE, Frame

T_FAR = 4.0**13  # beyond the longest step a line search tries (MAX_EXPANSIONS = 12)


@register("body_contact")
class BodyContact(Term):
    """The barrier of ``shape`` (a fixed obstacle term on the net's contact nodes, built
    at the body's pose at t = 0) riding on the body ``frame``."""

    bounds_step = True
    role = "internal"
    convex = False

    def __init__(self, shape, frame: Frame, *, n_nodes: int, label: str = "a free body"):
        self.shape, self.frame = shape, frame
        self.nodes = shape.nodes
        self.kappa, self.dhat = shape.kappa, shape.dhat
        self.n_nodes = int(n_nodes)
        self.label = label
        self.c0 = frame.center.copy()
        self._buf = np.zeros((n_nodes, 3))
        self._g = np.zeros((n_nodes, 3))
        chain = frame.chain()
        T = np.zeros((15, 15))
        T[:3, :3] = np.eye(3)
        T[3:, 3:] = chain
        self._T = T

    # ---- evaluation -------------------------------------------------------------------
    def _local(self, x):
        c, A = self.frame.state(x)
        U = np.asarray(x)[self.nodes] - c
        self._buf[self.nodes] = self.c0 + U @ A
        return c, A, U

    def gap(self, x):
        self._local(x)
        return self.shape.gap(self._buf)

    def _shape_gradient(self):
        g = self._g
        energy = self.shape.gradient(self._buf, g)
        out = g[self.nodes].copy()
        g[self.nodes] = 0.0
        return energy, out

    def energy(self, x):
        self._local(x)
        return self.shape.energy(self._buf)

    def gradient(self, x, grad):
        _, A, U = self._local(x)
        energy, g = self._shape_gradient()
        fx = g @ A.T
        grad[self.nodes] += fx
        gA = U.T @ g
        grad[self.frame.nodes] += -0.25 * fx.sum(axis=0) + self.frame.B @ gA.T
        return energy

    def pattern(self):
        dn = 3 * self.nodes[:, None] + np.arange(3)  # (K, 3)
        db = self.frame.dofs()  # (12,)
        K = len(self.nodes)
        ii_r = np.repeat(dn, 3, axis=1)
        ii_c = np.tile(dn, (1, 3))
        ip_r = np.repeat(dn, 12, axis=1)
        ip_c = np.tile(db, (K, 3))
        pi_r = np.tile(np.repeat(db, 3), (K, 1))
        pi_c = np.tile(dn, (1, 12))
        rows = np.concatenate([ii_r, ip_r, pi_r], axis=1).ravel()
        cols = np.concatenate([ii_c, ip_c, pi_c], axis=1).ravel()
        return np.concatenate([rows, np.repeat(db, 12)]), np.concatenate([cols, np.tile(db, 12)])

    def hessian(self, x, values):
        _, A, U = self._local(x)
        K = len(self.nodes)
        hv = np.zeros(9 * K)
        self.shape.hessian(self._buf, hv)
        H = hv.reshape(K, 3, 3)
        _, g = self._shape_gradient()
        values[:] = 0.0
        act = np.flatnonzero(np.any(H.reshape(K, 9) != 0.0, axis=1) | np.any(g != 0.0, axis=1))
        if act.size == 0:
            return False
        Ka = act.size
        u, Ha, ga = U[act], H[act], g[act]
        L = np.zeros((Ka, 3, 15))
        L[:, :, 0:3] = A.T
        L[:, :, 3:6] = -A.T
        for m in range(3):
            L[:, m, 6 + 3 * m : 9 + 3 * m] = u
        Kq = np.einsum("kai,kab,kbj->kij", L, Ha, L)
        eye = np.eye(3)
        for m in range(3):
            s = ga[:, m, None, None] * eye  # (Ka, 3, 3)
            a = slice(6 + 3 * m, 9 + 3 * m)
            Kq[:, a, 0:3] += s
            Kq[:, 0:3, a] += s
            Kq[:, a, 3:6] -= s
            Kq[:, 3:6, a] -= s
        Kp = np.einsum("ia,kij,jb->kab", self._T, Kq, self._T)
        blocks = values[: 81 * K].reshape(K, 81)
        blocks[act, 0:9] = Kp[:, :3, :3].reshape(Ka, 9)
        blocks[act, 9:45] = Kp[:, :3, 3:].reshape(Ka, 36)
        blocks[act, 45:81] = Kp[:, 3:, :3].reshape(Ka, 36)
        values[81 * K :] = Kp[:, 3:, 3:].sum(axis=0).ravel()
        return True

    def stiffness(self):
        s = np.zeros(self.n_nodes)
        s[self.frame.nodes] = self.kappa
        return s

    # ---- the step cap -----------------------------------------------------------------
    def max_step(self, x, dx):
        c, A, U = self._local(x)
        X0 = self._buf[self.nodes].copy()
        dc, dA = self.frame.state(dx)
        dU = np.asarray(dx)[self.nodes] - dc
        V = dU @ A + U @ dA
        W = dU @ dA
        speed = np.linalg.norm(V, axis=1) + np.linalg.norm(W, axis=1)
        d0 = self.shape.gap(self._buf)
        moving = np.flatnonzero(speed > 0.0)
        if moving.size == 0:
            return math.inf
        return self._advance(moving, X0, V, W, d0)

    def _advance(self, idx, X0, V, W, d0) -> float:
        """Conservative advancement of the nodes ``idx`` (see the module docstring)."""
        t = np.zeros(idx.size)
        target = CA_SHARE * d0[idx]
        d = d0[idx].copy()
        live = np.ones(idx.size, dtype=bool)
        found = np.full(idx.size, math.inf)
        keep = self.shape.nodes
        try:
            for _ in range(CA_ITER):
                k = np.flatnonzero(live)
                if k.size == 0:
                    break
                a = np.linalg.norm(V[idx[k]] + 2.0 * t[k, None] * W[idx[k]], axis=1)
                b = np.linalg.norm(W[idx[k]], axis=1)
                room = np.maximum(d[k] - target[k], 0.0)
                step = 2.0 * room / (a + np.sqrt(a * a + 4.0 * b * room) + 1e-300)
                t[k] += step
                far = t[k] > T_FAR
                live[k[far]] = False
                k = k[~far]
                tk = t[k, None]
                pts = X0[idx[k]] + tk * V[idx[k]] + tk * tk * W[idx[k]]
                self.shape.nodes = self.nodes[idx[k]]
                self._buf[self.shape.nodes] = pts
                d[k] = self.shape.gap(self._buf)
                hit = d[k] <= 2.0 * target[k]
                found[k[hit]] = t[k[hit]]
                live[k[hit]] = False
            found[live] = t[live]  # still approaching: capped where it got
        finally:
            self.shape.nodes = keep
        return float(found.min())
