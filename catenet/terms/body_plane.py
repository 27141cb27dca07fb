"""Barrier contact between a free rigid body (``catenet.terms.rigid``) and a plane: the
ground under a box, the seabed under a buoy.

A point of the body at X (its place at t = 0) is at p = c + A (X - c0) (the affine
body's map), linear in the body's four nodes p_k: p = sum_k w_k p_k with
w_k = 1/4 + B_k . (X - c0) (``BodyFrame.B``; sum w_k = 1). Against a plane n . (y - q) >= 0
a convex polytope, and any closed triangle mesh, is nearest at one of its vertices, so
the body's gap is the least of its vertices' gaps d_v = n . (p_v - q) - r (r: a sphere's
or a capsule's radius about its centre or axis ends; 0 for a box's corners and a mesh's
vertices), each linear in the nodes. Each vertex stores kappa b(d_v), the log-barrier of
``catenet.kernels.contact``:

    gradient on node k:  kappa b'(d_v) w_vk n,
    Hessian (k, l):      kappa b''(d_v) w_vk w_vl n n^T,

positive semidefinite (b'' > 0, d linear): a convex term. ``max_step``: each gap moves
linearly along a step, d_v(t) = d_v + t n . dp_v; the first t at which one reaches
zero caps it (exact). The body's vertices never reach the plane; there is no friction.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.contact import barrier
from catenet.terms.base import Term, register
from catenet.terms.rigid import BodyFrame


@register("body_plane")
class BodyPlane(Term):
    """The barrier of the plane n . (y - ``point``) >= 0 on the ``vertices`` (V, 3)
    (places at t = 0) of the body ``frame``, grown by ``radius``; ``kappa`` [N/m],
    ``dhat`` [m]; ``label`` names the pair in messages."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    role = "internal"
    convex = True

    def __init__(
        self, frame: BodyFrame, vertices, point, normal, *, radius: float = 0.0, kappa: float,
        dhat: float, n_nodes: int, label: str = "a free body and a plane",
    ):  # fmt: skip
        self.frame = frame
        n = np.asarray(normal, dtype=np.float64)
        self.normal = n / np.linalg.norm(n)
        self.point = np.asarray(point, dtype=np.float64)
        X = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
        self.w = 0.25 + (X - frame.center) @ frame.B.T  # (V, 4): p_v = w_v . P
        self.radius, self.kappa, self.dhat = float(radius), float(kappa), float(dhat)
        self.n_nodes, self.label = int(n_nodes), label

    def gap(self, x: np.ndarray) -> np.ndarray:
        """(V,) the vertices' gaps to the plane [m]."""
        P = np.asarray(x)[self.frame.nodes]
        return (self.w @ P - self.point) @ self.normal - self.radius

    def pattern(self):
        d = self.frame.dofs()
        return np.repeat(d, 12), np.tile(d, 12)

    def _barrier(self, x):
        out = np.array([barrier(float(d), self.dhat) for d in self.gap(x)]).reshape(-1, 3)
        return self.kappa * out  # (V, 3): kappa (b, b', b'')

    def energy(self, x):
        return float(self._barrier(x)[:, 0].sum())

    def gradient(self, x, grad):
        b = self._barrier(x)
        grad[self.frame.nodes] += np.outer(self.w.T @ b[:, 1], self.normal)
        return float(b[:, 0].sum())

    def hessian(self, x, values):
        b = self._barrier(x)
        if not np.any(b[:, 2]):
            values[:] = 0.0
            return False
        ww = np.einsum("v,vk,vl->kl", b[:, 2], self.w, self.w)  # (4, 4)
        values[:] = np.kron(ww, np.outer(self.normal, self.normal)).ravel()
        return True

    def roundoff(self, x, energy):
        """A gap carries an error of eps |p| sum|w|; the force kappa b'(d) turns it into
        force through b'': the levels without eps, as the solver takes them."""
        b = self._barrier(x)
        spread = float(np.abs(np.asarray(x)[self.frame.nodes]).max())
        spread *= float(np.abs(self.w).sum(axis=1).max())
        level = float(np.abs(b[:, 2]).max(initial=0.0)) * spread + float(np.abs(b[:, 1]).sum())
        return level, abs(energy) + float(np.abs(b[:, 1]).sum()) * spread

    def stiffness(self):
        s = np.zeros(self.n_nodes)
        s[self.frame.nodes] = self.kappa
        return s

    def max_step(self, x, dx):
        d = self.gap(x)
        rate = (self.w @ np.asarray(dx)[self.frame.nodes]) @ self.normal
        closing = rate < 0.0
        if not closing.any():
            return math.inf
        return float(np.min(d[closing] / -rate[closing]))
