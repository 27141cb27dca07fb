"""The dynamic step's inertia and damping as an energy term (the paper's Eqs. 10-13)."""

from __future__ import annotations

import numpy as np

from catenet.kernels.inertia import inertia_gradient, inertia_roundoff
from catenet.terms.base import Term, register


@register("inertia")
class Inertia(Term):
    """E = 1/2 sum_d w_d (x_d - a_d)^2 over the free DOFs d.

    A step of implicit Euler from (q_k, v_k) with step h and damping mu has
    w = M (1/h^2 + mu/h) and a = (M/h^2 (q_k + h v_k) + mu M/h q_k) / w: then the gradient
    of stretching + loads + this term is Eq. 10a and its Hessian Eq. 13. ``set_step``
    gives each step its w and a; the pattern (the diagonal) never changes.
    """

    role = "step"

    def __init__(self, free_dofs: np.ndarray):
        self.dofs = np.ascontiguousarray(free_dofs, dtype=np.int64)
        self.w = np.zeros(len(self.dofs))
        self.a = np.zeros(len(self.dofs))

    def set_step(self, w: np.ndarray, a: np.ndarray) -> None:
        self.w, self.a = w, a

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self.dofs, self.dofs

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        return inertia_gradient(x.reshape(-1), self.dofs, self.w, self.a, grad.reshape(-1))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        values[:] = self.w

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        return inertia_roundoff(x.reshape(-1), self.dofs, self.w, self.a)

    def node_roundoff(self, x: np.ndarray, energy: float) -> np.ndarray:
        """Per node, the largest w (|x| + |a|) of its DOFs: w (x - a) of two close large
        numbers (units of eps)."""
        out = np.zeros(x.shape[0])
        level = self.w * (np.abs(x.reshape(-1)[self.dofs]) + np.abs(self.a))
        np.maximum.at(out, self.dofs // 3, level)
        return out
