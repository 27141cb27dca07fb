"""Elastic supports (``[[supports.spring]]``): each holds its node toward the node's given
position X by a linear spring of stiffness K (3 x 3, symmetric positive semidefinite):

    U = 1/2 (x - X)^T K (x - X),   grad U = K (x - X),   Hessian K (the node's block).

Exact in all three, convex, node-local (it fits every workspace's pattern). Its force
-K (x - X) is a support's: it counts in the reactions (``holds``), not among the contact
forces (``catenet.model.measures``). NumPy alone: a few nodes, a 3 x 3 block each.
"""

from __future__ import annotations

import numpy as np

from catenet.model.net import Net
from catenet.terms.base import Term, node_block_pattern, register


@register("elastic_support")
class ElasticSupport(Term):
    """The springs of a net's elastic supports (``Net.springs``)."""

    name = "elastic_support"
    role = "internal"
    convex = True
    holds = True  # a support: its force is a reaction

    def __init__(self, net: Net):
        springs = net.springs
        if springs is None:
            raise ValueError("ElasticSupport: the net has no springs")
        self.n_nodes = net.n_nodes
        self.nodes = np.ascontiguousarray(springs.nodes, dtype=np.int64)
        self.k = np.ascontiguousarray(springs.stiffness, dtype=np.float64)
        self.anchor = np.ascontiguousarray(net.nodes[self.nodes], dtype=np.float64)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return node_block_pattern(self.nodes)

    def _force(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K (x - X), x - X) per spring."""
        u = x[self.nodes] - self.anchor
        return np.einsum("kij,kj->ki", self.k, u), u

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        f, u = self._force(x)
        np.add.at(grad, self.nodes, f)
        return 0.5 * float(np.sum(f * u))

    def energy(self, x: np.ndarray) -> float:
        f, u = self._force(x)
        return 0.5 * float(np.sum(f * u))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        values.reshape(-1, 3, 3)[:] = self.k

    def force(self, x: np.ndarray) -> np.ndarray:
        """(N, 3) the force the springs exert on the net, -K (x - X) [N]."""
        out = np.zeros((self.n_nodes, 3))
        f, _ = self._force(x)
        np.subtract.at(out, self.nodes, f)
        return out

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """|K| (|x| + |X|): the spring force's round-off level (units of eps)."""
        k = float(np.linalg.norm(self.k.reshape(len(self.nodes), -1), axis=1).max(initial=0.0))
        size = float(np.max(np.abs(x), initial=0.0)) + float(
            np.max(np.abs(self.anchor), initial=0.0)
        )
        return k * size, abs(energy)

    def stiffness(self) -> np.ndarray:
        out = np.zeros(self.n_nodes)
        np.add.at(out, self.nodes, np.trace(self.k, axis1=1, axis2=2) / 3.0)
        return out
