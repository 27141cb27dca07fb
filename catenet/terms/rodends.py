"""Rod ends on coupled 6 x 6 elastic supports (``catenet.model.rodends``): per support,
the end node c, the other node o of its end edge and the given direction t0,

    U = 1/2 q^T S q,   q = (u, w),   u = x_c - X_c,
    w = (t0 x t) / cos(theta / 2),   t = d / |d|,  d = x_o - x_c,  cos theta = t0 . t,

w the end edge's turn: along the turn's axis, of length |t - t0| = 2 sin(theta / 2)
(theta to O(theta^3), so the support's moment is S's at small turns; for a rigid S the
energy is the clamp's EI / l |t - t0|^2 exactly). With s(c) = sqrt(2 / (1 + c)) and
a = t0 x t, w = s a; dw/dt = s [t0]x + s' a t0^T, s' = -s / (2 (1 + c)),
s'' = 3 s / (4 (1 + c)^2); dt/dd = (1 - t t^T) / |d|. The gradient and the Hessian are
exact (the second derivatives of w through t and of t through d), checked by finite
differences in the tests; smooth for every turn below 180 degrees (at 180 the turn's
axis is undefined). Not convex (the turn is nonlinear in d). NumPy alone: a few supports,
a 6 x 6 block each, on an edge of the net (it fits every workspace's pattern).

Its force is a support's (``holds``): the reactions count the wrench, the force -(S q)_u
at c and the moment d x f_o about c, f_o = -dU/dx_o (``held_force``, ``moments``), not
the couple's two forces at c and o.
"""

from __future__ import annotations

import numpy as np

from catenet.model.rodends import RodEnds, end_state, outer
from catenet.terms.base import Term, register


@register("rod_end_support")
class RodEndSupport(Term):
    """The 6 x 6 supports of a net's rod ends (module docstring)."""

    name = "rod_end_support"
    role = "internal"
    convex = False
    holds = True

    def __init__(self, ends: RodEnds, nodes: np.ndarray, n_nodes: int):
        """``nodes`` (N', 3) the net's given positions (the anchors and the end edges)."""
        self.n_nodes = int(n_nodes)
        self.c = np.ascontiguousarray(ends.nodes, dtype=np.int64)
        self.o = np.ascontiguousarray(ends.other, dtype=np.int64)
        self.t0 = np.ascontiguousarray(ends.tangent, dtype=np.float64)
        self.S = np.ascontiguousarray(ends.series, dtype=np.float64)
        self.anchor = np.ascontiguousarray(nodes[self.c], dtype=np.float64)
        length = np.linalg.norm(nodes[self.o] - nodes[self.c], axis=1)
        # per support its scale [N/m]: translation, coupling over l, turn over l^2
        self._scale = np.stack(
            [
                np.abs(self.S[:, :3, :3]).max(axis=(1, 2)),
                np.abs(self.S[:, :3, 3:]).max(axis=(1, 2)) / length,
                np.abs(self.S[:, 3:, 3:]).max(axis=(1, 2)) / length**2,
            ]
        )

    def _state(self, x: np.ndarray) -> dict:
        """The turn's quantities per support at x (``catenet.model.rodends.end_state``)."""
        return end_state(self.c, self.o, self.t0, self.S, self.anchor, x)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        nodes = np.stack([self.c, self.o], axis=1)
        local = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(nodes), 6)
        return np.repeat(local, 6, axis=1).ravel(), np.tile(local, (1, 6)).ravel()

    def _parts(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, dict]:
        """The energy, the gradient at c and at o (K, 3) each, the state."""
        st = self._state(x)
        energy = 0.5 * float(np.sum(st["q"] * st["sq"]))
        g_o = np.einsum("kji,kj->ki", st["W"], st["sq"][:, 3:])
        g_c = st["sq"][:, :3] - g_o
        return energy, g_c, g_o, st

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        energy, g_c, g_o, _ = self._parts(x)
        np.add.at(grad, self.c, g_c)
        np.add.at(grad, self.o, g_o)
        return energy

    def energy(self, x: np.ndarray) -> float:
        return self._parts(x)[0]

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        st = self._state(x)
        big_w, m, t, r = st["W"], st["sq"][:, 3:], st["t"], st["r"]
        s_uu, s_uw, s_ww = self.S[:, :3, :3], self.S[:, :3, 3:], self.S[:, 3:, 3:]
        # sum_i m_i d2 w_i / dt2 = s'' (m . a) t0 t0^T + s' (t0 v^T + v t0^T), v = m x t0
        c1 = st["c"] + 1.0
        s2 = 3.0 * st["s"] / (4.0 * c1**2)
        v = np.cross(m, self.t0)
        mw = np.einsum("ki,ki->k", m, st["a"])
        h_t = (s2 * mw)[:, None, None] * outer(self.t0, self.t0) + st["ds"][:, None, None] * (
            outer(self.t0, v) + outer(v, self.t0)
        )
        proj = st["proj"]
        # sum_k g_k d2 t_k / dd2, g = (dw/dt)^T m
        g = np.einsum("kji,kj->ki", st["dwdt"], m)
        gt = np.einsum("ki,ki->k", g, t)
        eye = np.eye(3)[None]
        h_d = (
            -(outer(t, g) + outer(g, t)) - gt[:, None, None] * eye
            + 3.0 * gt[:, None, None] * outer(t, t)
        ) / (r**2)[:, None, None]  # fmt: skip
        dd = np.swapaxes(big_w, 1, 2) @ s_ww @ big_w + proj @ h_t @ proj + h_d
        ud = s_uw @ big_w
        # (x_c, x_o) -> (u, d) = (x_c, x_o - x_c)
        out = values.reshape(-1, 6, 6)
        du = np.swapaxes(ud, 1, 2)
        out[:, :3, :3] = s_uu - ud - du + dd
        out[:, :3, 3:] = ud - dd
        out[:, 3:, :3] = du - dd
        out[:, 3:, 3:] = dd

    def held_force(self, x: np.ndarray, out: np.ndarray) -> None:
        """Adds the wrench's force -(S q)_u at each support's node to ``out`` (N, 3)."""
        st = self._state(x)
        np.subtract.at(out, self.c, st["sq"][:, :3])

    def moments(self, x: np.ndarray) -> np.ndarray:
        """(K, 3) the moment [N m] each support exerts on its rod about the end node: the
        couple d x f_o of its force f_o = -dU/dx_o on the edge's other node
        (``catenet.model.rodends.end_moments``)."""
        _, _, g_o, st = self._parts(x)
        return np.cross(st["d"], -g_o)

    def stiffness(self) -> np.ndarray:
        """Per node, the scale of its diagonal [N/m]: the translation's and the turn's
        (over the end edge's length squared) at c, the turn's at o."""
        out = np.zeros(self.n_nodes)
        np.add.at(out, self.c, self._scale.sum(axis=0))
        np.add.at(out, self.o, self._scale[1:].sum(axis=0))
        return out

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """The support's scale [N/m] times (|x| + |X|): its force's round-off level
        (units of eps)."""
        k = float(self._scale.max(initial=0.0))
        size = float(np.max(np.abs(x), initial=0.0)) + float(
            np.max(np.abs(self.anchor), initial=0.0)
        )
        return k * size, abs(energy)
