"""Rigid frictionless obstacles as energy terms: a log-barrier on each free node's gap.

Guarantee: no node is ever inside an obstacle. The barrier is infinite at zero gap, every
start is checked to be outside (``gap``), and the Newton line search never tries a step
beyond the first contact along it (``max_step``, exact for planes and spheres), so every
accepted iterate, static or dynamic, at any step size, has every node outside. The price
is a gap below ``dhat`` (the activation distance) where nodes press on an obstacle: the
contact force -kappa b'(d) grows without bound as the gap closes.

``kappa`` [N/m] scales the barrier; by default it is chosen so that the barrier holds a
node's share of the load at half the activation distance (see ``default_stiffness``).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from catenet.kernels.contact import (
    plane_gradient,
    plane_hessian,
    plane_max_step,
    sphere_gradient,
    sphere_hessian,
    sphere_max_step,
)
from catenet.terms.base import Term, node_block_pattern, register

#: -b'(dhat / 2) / dhat: the barrier force at half the activation distance, per kappa dhat.
HALF_GAP_FORCE = 2.0 * 0.5 * math.log(2.0) + 0.5


def default_stiffness(force_per_node: float, dhat: float) -> float:
    """kappa [N/m] at which the barrier balances ``force_per_node`` at a gap of dhat/2."""
    return max(force_per_node, 1e-300) / (HALF_GAP_FORCE * dhat)


#: A solid's impact is taken by its barrier before the gap is this share of dhat: its
#: bounce then meets a barrier some 10 times stiffer than at dhat / 2 at its deepest, as
#: a ball dropped 1 m on a barrier of 1 mm and 1e7 N/m does (tests/solver/test_accuracy.py,
#: its period within 0.8 % at the default tolerance; a share of 1e-2 gave 1e3 times).
IMPACT_SHARE = 0.25


def impact_stiffness(energy: float, dhat: float) -> float:
    """kappa [N/m] at which the barrier's energy kappa b(d), b(d) = -(d - dhat)^2 ln(d /
    dhat), reaches ``energy`` [J] at the gap d = IMPACT_SHARE dhat: a solid that brings
    that much stops (and turns back) before then (0 for no energy, or none finite)."""
    s = IMPACT_SHARE
    kappa = max(energy, 0.0) / (dhat * dhat * (1.0 - s) ** 2 * math.log(1.0 / s))
    return kappa if math.isfinite(kappa) else 0.0  # (beyond floats: the other stiffness)


class Obstacle(Term):
    """A rigid obstacle acting on ``nodes`` (the free nodes) with barrier stiffness
    ``kappa`` [N/m] and activation distance ``dhat`` [m].

    ``stages``: wider barriers of the same obstacle, widest first, that a static solve
    goes through before this one (``narrowed`` copies; ``catenet.solver.static.equilibrium``):
    each stage's equilibrium, a gap below its dhat, starts the next."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)

    role = "internal"

    def __init__(self, nodes, *, kappa: float, dhat: float):
        if not (math.isfinite(kappa) and kappa > 0 and math.isfinite(dhat) and dhat > 0):
            raise ValueError(f"obstacle: kappa = {kappa!r}, dhat = {dhat!r}: must be > 0")
        self.nodes = np.ascontiguousarray(nodes, dtype=np.int64)
        self.kappa = float(kappa)
        self.dhat = float(dhat)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return node_block_pattern(self.nodes)

    def narrowed(self, kappa: float, dhat: float) -> Obstacle:
        """The same obstacle with another barrier, no wider than this one's (a mesh's
        grid, which lists the triangles within dhat, stays valid)."""
        if not (math.isfinite(kappa) and kappa > 0 and 0 < dhat <= self.dhat):
            raise ValueError(f"obstacle: kappa = {kappa!r}, dhat = {dhat!r}: not narrower")
        out = copy.copy(self)
        out.kappa, out.dhat, out.stages = float(kappa), float(dhat), ()
        return out

    def energy(self, x: np.ndarray) -> float:
        return self.gradient(x, np.zeros_like(x))

    def gap(self, x: np.ndarray) -> np.ndarray:
        """Signed distance of every one of ``nodes`` to the surface (> 0 outside)."""
        raise NotImplementedError

    def max_step(self, x: np.ndarray, dx: np.ndarray) -> float:
        """The largest t for which x + t dx keeps every node outside (inf: never hits)."""
        return self.first_hit(x, dx, 0.0)

    def first_hit(
        self, x: np.ndarray, dx: np.ndarray, grow: float, upto: float = math.inf
    ) -> float:
        """The first t >= 0 at which a node on x + t dx meets the surface grown by
        ``grow`` >= 0 (inf: never): the exact first contact; exact up to t = ``upto``
        at least (a shape may skip nodes that cannot arrive before it: a larger value
        may then be inf)."""
        raise NotImplementedError(f"{type(self).__name__} has no first-hit test")


@register("plane")
class PlaneBarrier(Obstacle):
    """The half-space n.(x - p) >= 0: a ground or a seabed (``point`` p, outward unit
    normal ``normal``)."""

    convex = True

    def __init__(self, nodes, point, normal, *, kappa: float, dhat: float):
        super().__init__(nodes, kappa=kappa, dhat=dhat)
        normal = np.asarray(normal, dtype=np.float64)
        length = float(np.linalg.norm(normal))
        if not length > 0:
            raise ValueError("plane: the normal must not be zero")
        self.point = np.asarray(point, dtype=np.float64)
        self.normal = normal / length

    def gap(self, x):
        return (x[self.nodes] - self.point) @ self.normal

    def gradient(self, x, grad):
        return plane_gradient(x, self.nodes, self.point, self.normal, self.kappa, self.dhat, grad)

    def hessian(self, x, values):
        args = (x, self.nodes, self.point, self.normal, self.kappa, self.dhat, values)
        return plane_hessian(*args) > 0

    def first_hit(self, x, dx, grow, upto=math.inf):
        point = self.point if grow == 0.0 else self.point + grow * self.normal  # (max_step:
        return plane_max_step(x, dx, self.nodes, point, self.normal)  # no array per call)


@register("sphere")
class SphereBarrier(Obstacle):
    """The outside of the sphere |x - c| >= R (a fixed obstacle, or the shape of a rigid
    body whose centre the scene moves)."""

    convex = False  # hess d = (I - n n^T)/rho times b' < 0: indefinite near contact

    def __init__(self, nodes, center, radius: float, *, kappa: float, dhat: float):
        super().__init__(nodes, kappa=kappa, dhat=dhat)
        if not (math.isfinite(radius) and radius > 0):
            raise ValueError(f"sphere: radius = {radius!r}: must be > 0")
        self.center = np.asarray(center, dtype=np.float64)
        self.radius = float(radius)

    def gap(self, x):
        return np.linalg.norm(x[self.nodes] - self.center, axis=1) - self.radius

    def gradient(self, x, grad):
        args = (x, self.nodes, self.center, self.radius, self.kappa, self.dhat, grad)
        return sphere_gradient(*args)

    def hessian(self, x, values):
        args = (x, self.nodes, self.center, self.radius, self.kappa, self.dhat, values)
        return sphere_hessian(*args) > 0

    def first_hit(self, x, dx, grow, upto=math.inf):
        return sphere_max_step(x, dx, self.nodes, self.center, self.radius + grow)
