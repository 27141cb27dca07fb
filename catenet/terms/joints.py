"""Rigid joints of rods: E = sum over joints of sum_i EI_i / l_i |t_i - R t_i0|^2, R the
joint's rotation that minimises it (``catenet.model.joints`` says what a joint holds,
``catenet.kernels.joints`` derives E and its exact derivatives).

Guarantee: the energy and its gradient are exact for every state whose members have
nonzero length; the Hessian is exact wherever the joint's rotation is unique (its members
not all on one line, the joint not turned half a turn against them), checked against
finite differences. E is 0 for the joint as drawn and for any rigid motion of it; the
term is not convex.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from catenet.kernels.joints import joint_energy, joint_gradient, joint_hessian
from catenet.model.joints import Joints
from catenet.terms.base import Term, register
from catenet.terms.bending import dense_blocks


@register("joints")
class RigidJoints(Term):
    """The rods' rigid joints (module docstring)."""

    role = "internal"
    convex = False
    structural = True

    def __init__(self, joints: Joints, n_nodes: int):
        self.joints = joints
        self.n_nodes = int(n_nodes)

    def _args(self):
        j = self.joints
        return j.node, j.start, j.other, j.rest, j.k

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._pattern

    @cached_property
    def _pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """Every joint's dense block over its node and its members' others, row-major."""
        j = self.joints
        return dense_blocks(
            np.concatenate([[j.node[k]], j.other[j.start[k] : j.start[k + 1]]])
            for k in range(len(j))
        )

    def energy(self, x: np.ndarray) -> float:
        return float(joint_energy(np.ascontiguousarray(x, dtype=np.float64), *self._args()))

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        x = np.ascontiguousarray(x, dtype=np.float64)
        return float(joint_gradient(x, *self._args(), grad))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        joint_hessian(np.ascontiguousarray(x, dtype=np.float64), *self._args(), values)

    @cached_property
    def _scale(self) -> np.ndarray:
        """Per node, the scale of its Hessian diagonal [N/m]: k / l^2 of each member at
        its two nodes."""
        j = self.joints
        unit = j.k / j.length**2
        out = np.zeros(self.n_nodes)
        np.add.at(out, j.other, unit)
        np.add.at(out, np.repeat(j.node, np.diff(j.start)), unit)
        return out

    def stiffness(self) -> np.ndarray:
        return self._scale

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """As a rod's bending (``catenet.terms.bending``): a coordinate error eps |x| moves
        a node's force by its stiffness times it; a tangent error eps changes a member's
        energy by 2 sqrt(k E) eps (levels in units of eps)."""
        size = float(np.max(np.abs(x)))
        total_k = float(np.sum(self.joints.k))
        level = float(np.linalg.norm(self._scale)) * size
        return level, abs(energy) + 2.0 * float(np.sqrt(total_k * abs(energy)))

    def node_roundoff(self, x: np.ndarray, energy: float) -> np.ndarray:
        return self._scale * float(np.max(np.abs(x)))
