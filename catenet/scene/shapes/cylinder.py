"""A solid cylinder with flat ends: a pipe, a drum, a pile, a boom with cut ends.

Its barrier (``CylinderBarrier``, kernels in ``catenet.kernels.cylinder``) is exact: the
gap is a node's distance to the cylinder (side, end or rim), a ball's centre's to the
cylinder grown by the ball, and the first contact along a step is exact for the
cylinder and no later than the true one grown (so no node and no ball ever enters it).

As a free body it touches other solids and planes through its outline: the prisms of
OUTLINE sides circumscribed about its two end circles (their vertices at
r / cos(pi / OUTLINE), their edges tangent to the circles). The outline holds the
cylinder, so a free cylinder never enters a plane or another solid; it may rest up to
r (1 / cos(pi / OUTLINE) - 1) = 0.48 % of its radius away where a vertex of the outline
points at the plane or the solid. A node of the net and a ball meet its exact surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from catenet.kernels.cylinder import (
    cylinder_gap,
    cylinder_gradient,
    cylinder_hessian,
    cylinder_max_step,
)
from catenet.scene.shapes.base import (
    AboutSegment,
    MassProperties,
    Outline,
    axis_frame,
    lathe,
    positive,
)
from catenet.terms.base import register
from catenet.terms.contact import Obstacle

OUTLINE = 32  # sides of the prisms that stand for it as a free body


@register("cylinder")
class CylinderBarrier(Obstacle):
    """The log-barrier of the outside of the cylinder (centre ``center``, unit ``axis``,
    ``half_length``, ``radius``) on ``nodes``; ``offset`` r > 0: on the centres of balls
    of radius r (the cylinder grown by r)."""

    convex = False  # the curved side's hess d times b' < 0: indefinite near contact

    def __init__(
        self,
        nodes: ArrayLike,
        center: ArrayLike,
        axis: ArrayLike,
        half_length: float,
        radius: float,
        *,
        kappa: float,
        dhat: float,
        offset: float = 0.0,
    ) -> None:
        super().__init__(nodes, kappa=kappa, dhat=dhat)
        if not (math.isfinite(offset) and offset >= 0):
            raise ValueError(f"cylinder: offset = {offset!r}: must be >= 0")
        self.center = np.asarray(center, dtype=np.float64)
        self.axis = np.asarray(axis, dtype=np.float64)
        self.half_length = positive("cylinder: half length", half_length)
        self.radius = positive("cylinder: radius", radius)
        self.offset = float(offset)

    def _geometry(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        return self.center, self.axis, self.half_length, self.radius

    def gap(self, x: np.ndarray) -> np.ndarray:
        out = np.empty(len(self.nodes))
        cylinder_gap(x, self.nodes, *self._geometry(), self.offset, out)
        return out

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        args = (*self._geometry(), self.offset, self.kappa, self.dhat, grad)
        return float(cylinder_gradient(x, self.nodes, *args))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> bool:
        args = (*self._geometry(), self.offset, self.kappa, self.dhat, values)
        return bool(cylinder_hessian(x, self.nodes, *args) > 0)

    def first_hit(
        self, x: np.ndarray, dx: np.ndarray, grow: float, upto: float = math.inf
    ) -> float:
        return float(cylinder_max_step(x, dx, self.nodes, *self._geometry(), self.offset + grow))


@dataclass(frozen=True, eq=False)
class Cylinder(AboutSegment):
    """The solid cylinder of ``radius`` about the segment ``start``-``end``, flat at
    both ends."""

    kind: ClassVar[str] = "cylinder"

    @property
    def axis(self) -> np.ndarray:
        unit: np.ndarray = (self.end - self.start) / self.length
        return unit

    @property
    def reach(self) -> float:
        return math.hypot(0.5 * self.length, self.radius)

    def barrier(
        self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0
    ) -> CylinderBarrier:
        args = (self.origin, self.axis, 0.5 * self.length, self.radius)
        return CylinderBarrier(nodes, *args, kappa=kappa, dhat=dhat, offset=offset)

    def outline(self) -> Outline:
        """The circumscribed prisms of OUTLINE sides (module docstring): 2 OUTLINE points,
        the rims' edges and the generators between them."""
        x, y, e = axis_frame(self.start, self.end).T
        u = 2 * np.pi * (np.arange(OUTLINE) + 0.5) / OUTLINE
        ring = (np.cos(u)[:, None] * x + np.sin(u)[:, None] * y) * (
            self.radius / math.cos(math.pi / OUTLINE)
        )
        points = np.concatenate([self.start + ring, self.end + ring])
        k = np.arange(OUTLINE)
        rims = [np.stack([k, (k + 1) % OUTLINE], axis=1) + j * OUTLINE for j in (0, 1)]
        edges = np.concatenate([*rims, np.stack([k, k + OUTLINE], axis=1)])
        return Outline(points, edges, 0.0)

    def edge_outline(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What the net's edges meet (``solver.edge_contact``): points, lines and a radius
        per line. Longer than its diameter: its core capsule, the axis shortened by the
        radius R at both ends and grown by R (its round side exact over the middle: a rope
        wrapped round it slides on it as on a capsule), and the circumscribed prisms of
        its two end bands, each R long (their rims, the rings where the core reaches its
        full radius, the generators between them), which hold what the core's round ends
        leave of the cylinder. Else (a drum no longer than its diameter) the
        circumscribed prisms whole (``outline``)."""
        R = self.radius
        if self.length <= 2.0 * R:
            points, lines, _ = self.outline()
            return points, lines, np.zeros(len(lines))
        x, y, e = axis_frame(self.start, self.end).T
        u = 2 * np.pi * (np.arange(OUTLINE) + 0.5) / OUTLINE
        ring = (np.cos(u)[:, None] * x + np.sin(u)[:, None] * y) * (R / math.cos(math.pi / OUTLINE))
        core = np.array([self.start + R * e, self.end - R * e])
        levels = [self.start, core[0], core[1], self.end]
        points = np.concatenate([*(level + ring for level in levels), core])
        k = np.arange(OUTLINE)
        rims = [np.stack([k, (k + 1) % OUTLINE], axis=1) + j * OUTLINE for j in range(4)]
        sides = [np.stack([k, k + OUTLINE], axis=1) + j * OUTLINE for j in (0, 2)]
        axis = np.array([[4 * OUTLINE, 4 * OUTLINE + 1]])
        lines = np.concatenate([*rims, *sides, axis]).astype(np.int64)
        radii = np.zeros(len(lines))
        radii[-1] = R
        return points, lines, radii

    def mass_properties(self) -> MassProperties:
        """Axes (x', y', axis): inertia r^2/4 + L^2/12 across, r^2/2 about the axis."""
        r, L = self.radius, self.length
        side = r * r / 4 + L * L / 12
        inertia = np.diag([side, side, r * r / 2])
        frame = axis_frame(self.start, self.end)
        return MassProperties(math.pi * r * r * L, self.origin, inertia, frame)

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """36 meridians: a flat end, the side, the other flat end (quads)."""
        a, b, r = self.start, self.end, self.radius
        points = np.array([a, a, b, b])
        return lathe(points, np.array([0.0, r, r, 0.0]), b - a)


SHAPE = Cylinder
