"""Applied loads as a linear potential -f.x: nodal forces, pressure and gravity."""

from __future__ import annotations

import numpy as np

from catenet.kernels.sparse import dot, norm
from catenet.terms.base import Term, register


@register("force")
class ExternalForce(Term):
    """E = -f.x for constant nodal forces f (N, 3) [N] (point loads, the paper's
    pressure, gravity on the lumped masses), already scaled by the load factor. No
    Hessian: a scene without loads has no such term and computes nothing for it."""

    role = "external"

    def __init__(self, force: np.ndarray):
        self.force = np.ascontiguousarray(force, dtype=np.float64)
        self.flat = self.force.reshape(-1)
        self.norm = float(norm(self.flat))

    def energy(self, x: np.ndarray) -> float:
        return -float(dot(self.flat, x.reshape(-1)))

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        grad -= self.force
        return self.energy(x)

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        return self.norm, abs(energy)
