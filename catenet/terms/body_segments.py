"""Friction along the edge against a free body (``solver.edge_contact`` with a body's
``friction``): ``catenet.terms.segments.EdgeFriction`` seen in the body's frame, as
``catenet.terms.rigid_contact.BodyFriction`` sees the nodes' friction.

Each pair of a net edge and an outline feature of the body that pushes it holds, lagged
from the step's start, its normal force lambda, its normal n and the edge's material
point s, y = (1 - s) x_i + s x_j; the friction potential mu lambda f(|P (X - a)|) acts on
that point seen in the body frame, X = c0 + A^T (y - c), with the anchor a and normal n
in the body frame (they ride with the body): the friction opposes the slip of the edge's
material over the body's surface, and acts on the edge and on the body equal and
opposite. The chain to the nodes is BodyContact's for the point y (``frame_contact_
hessian``), then to the edge's two nodes by the weights (1 - s, s): the values have the
layout of the edge barrier's (``catenet.kernels.segments``) with the body's four nodes.
A pair that sticks keeps s and its anchor; one whose material point slid farther than
``slip`` takes the contact's point now, its anchor dragged to ``slip`` behind it.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.friction import friction_gradient, friction_hessian
from catenet.kernels.rigid import frame_contact_hessian
from catenet.terms.base import Term, register
from catenet.terms.segments import EdgeContact, pushes


@register("body_edge_friction")
class BodyEdgeFriction(Term):
    """Coulomb friction ``mu``, slip distance ``slip`` [m], where a free body's outline
    (``contact``: its ``EdgeContact``, riding on the body ``frame``) pushes the net's
    edges (module docstring)."""

    lagged = True
    role = "internal"
    convex = False

    def __init__(self, contact: EdgeContact, frame, *, mu: float, slip: float):
        if not (math.isfinite(mu) and mu >= 0 and math.isfinite(slip) and slip > 0):
            raise ValueError(f"body_edge_friction: mu = {mu!r}, slip = {slip!r}")
        self.contact = self.rides_on = contact
        self.frame = frame
        self.mu, self.slip = float(mu), float(slip)
        self.c0 = frame.center.copy()
        self._chain = np.ascontiguousarray(frame.chain())
        self.pairs = np.zeros((0, 2), dtype=np.int64)
        self.share = np.zeros(0)
        self.normal = np.zeros((0, 3))
        self.weight = np.zeros(0)
        self.anchor = np.zeros((0, 3))
        self._anchors: dict[tuple[int, int], np.ndarray] = {}

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self.contact.pattern()

    # ---- the material points in the body frame ----------------------------------------
    def _world(self, x) -> np.ndarray:
        e = self.contact.edges[self.pairs[:, 0]]
        s = self.share[:, None]
        return np.ascontiguousarray((1.0 - s) * x[e[:, 0]] + s * x[e[:, 1]])

    def _local(self, x):
        """(A, U, X): the body's A, the points' y - c (K, 3) and body-frame X (K, 3)."""
        c, A = self.frame.state(x)
        U = self._world(x) - c
        return A, U, np.ascontiguousarray(self.c0 + U @ A)

    def _lag(self, x, drag: bool) -> None:
        """The pushing pairs at x with their normal forces and body-frame normals; the
        known pairs' anchors and material points kept (with ``drag``, moved where the
        material point slid beyond ``slip``), a new pair's where it touches."""
        pairs, lam, normal, share = pushes(self.contact, x)
        keys = [(int(e), int(f)) for e, f in pairs.tolist()]
        _, A = self.frame.state(x)
        held = [self._anchors.get(k) for k in keys]
        was = np.array([h is not None for h in held], dtype=bool)
        self.pairs, self.weight = pairs, self.mu * lam
        n = normal @ A  # to the body frame (A^T n), then unit
        self.normal = np.ascontiguousarray(n / np.linalg.norm(n, axis=1)[:, None])
        self.share = share.copy()
        anchor = np.zeros((len(keys), 3))
        for i, h in enumerate(held):
            if h is not None:
                anchor[i], self.share[i] = h[:3], h[3]
        _, _, X = self._local(x)
        u = X - anchor
        u -= np.sum(u * self.normal, axis=1)[:, None] * self.normal
        slid = np.linalg.norm(u, axis=1)
        moved = was & (slid > self.slip) if drag else np.zeros(len(keys), dtype=bool)
        self.share = np.where(moved | ~was, share, self.share)
        _, _, X = self._local(x)
        anchor[~was] = X[~was]
        behind = self.slip / np.where(moved, slid, 1.0)
        anchor[moved] = X[moved] - behind[moved, None] * u[moved]
        self.anchor = np.ascontiguousarray(anchor)
        rows = np.concatenate([self.anchor, self.share[:, None]], axis=1)
        self._anchors = dict(zip(keys, rows, strict=True))

    def begin_step(self, x, time, start=None) -> None:
        self._lag(x, drag=True)

    def relag(self, x) -> float:
        before = dict(zip(map(tuple, self.pairs.tolist()), self.weight, strict=True))
        top = float(self.weight.max(initial=0.0))
        self._lag(x, drag=False)
        keys = [tuple(p) for p in self.pairs.tolist()]
        now = dict(zip(keys, self.weight, strict=True))
        change = max(
            (abs(now.get(k, 0.0) - before.get(k, 0.0)) for k in {*now, *before}), default=0.0
        )
        top = max(top, float(self.weight.max(initial=0.0)))
        return change / top if top > 0.0 else 0.0

    # ---- energy -----------------------------------------------------------------------
    def _shape(self, X):
        idx = np.arange(len(X), dtype=np.int64)
        g = np.zeros_like(X)
        energy = friction_gradient(X, idx, self.anchor, self.normal, self.weight, self.slip, g)
        return float(energy), g

    def gradient(self, x, grad) -> float:
        if not len(self.pairs):
            return 0.0
        A, U, X = self._local(x)
        energy, g = self._shape(X)
        fy = g @ A.T  # on the material point y
        e = self.contact.edges[self.pairs[:, 0]]
        s = self.share[:, None]
        np.add.at(grad, e[:, 0], (1.0 - s) * fy)
        np.add.at(grad, e[:, 1], s * fy)
        grad[self.frame.nodes] += -0.25 * fy.sum(axis=0) + self.frame.B @ (U.T @ g).T
        return energy

    def hessian(self, x, values) -> bool:
        values[:] = 0.0
        if not len(self.pairs):
            return False
        A, U, X = self._local(x)
        K = len(X)
        hv = np.zeros(9 * K)
        idx = np.arange(K, dtype=np.int64)
        friction_hessian(X, idx, self.anchor, self.normal, self.weight, self.slip, hv)
        _, g = self._shape(X)
        blocks = np.zeros((K, 81))
        body = np.zeros(144)
        active = np.flatnonzero(self.weight > 0.0)
        frame_contact_hessian(A, U, hv.reshape(K, 3, 3), g, self._chain, active, blocks, body)
        yy = blocks[:, :9].reshape(K, 3, 3)
        yp = blocks[:, 9:45].reshape(K, 3, 12)
        py = blocks[:, 45:].reshape(K, 12, 3)
        w = np.stack([1.0 - self.share, self.share], axis=1)  # (K, 2)
        S = 180  # per edge: 6 x 6, 6 x 12, 12 x 6 (EdgeContact's layout with four nodes)
        per = np.zeros((K, S))
        per[:, :36] = np.einsum("ka,kb,kij->kaibj", w, w, yy).reshape(K, 36)
        per[:, 36:108] = np.einsum("ka,kiq->kaiq", w, yp).reshape(K, 72)
        per[:, 108:] = np.einsum("kb,kqj->kqbj", w, py).reshape(K, 72)
        edges = len(self.contact.edges)
        np.add.at(values[: edges * S].reshape(edges, S), self.pairs[:, 0], per)
        values[edges * S :] += body
        return True
