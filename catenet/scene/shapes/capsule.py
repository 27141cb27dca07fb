"""A capsule: the points within a radius of a segment (``catenet.terms.shapes.CapsuleBarrier``;
kernels in ``catenet.kernels.shapes``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from catenet.scene.shapes.base import (
    AboutSegment,
    MassProperties,
    Outline,
    axis_frame,
    lathe,
)

RINGS = 9  # parallels of each drawn end ball, pole to equator


if TYPE_CHECKING:
    from catenet.terms.contact import Obstacle


@dataclass(frozen=True, eq=False)
class Capsule(AboutSegment):
    """The outside of the points within ``radius`` of the segment ``start``-``end``."""

    kind: ClassVar[str] = "capsule"

    @property
    def reach(self) -> float:
        return 0.5 * float(np.linalg.norm(self.end - self.start)) + self.radius

    def barrier(self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0) -> Obstacle:
        """The capsule's barrier; ``offset`` r: the capsule of radius + r (exact)."""
        from catenet.terms.shapes import CapsuleBarrier as CapsuleTerm

        radius = self.radius + offset
        return CapsuleTerm(nodes, self.start, self.end, radius, kappa=kappa, dhat=dhat)

    def outline(self) -> Outline:
        """Its axis grown by its radius: exact."""
        ends = np.array([self.start, self.end], dtype=np.float64)
        return Outline(ends, np.array([[0, 1]], dtype=np.int64), self.radius)

    def mass_properties(self) -> MassProperties:
        """A cylinder and two half balls; axes (x', y', axis)."""
        a, b, r = self.start, self.end, self.radius
        length = float(np.linalg.norm(b - a))
        v_cyl, v_sph = math.pi * r * r * length, 4 / 3 * math.pi * r**3
        volume = v_cyl + v_sph
        mc, ms = v_cyl / volume, v_sph / volume  # per unit mass
        axial = mc * r * r / 2 + ms * 0.4 * r * r
        arm = length / 2 + 3 * r / 8  # each half ball's centre from the middle
        side = mc * (r * r / 4 + length**2 / 12) + ms * (83 / 320 * r * r + arm**2)
        inertia = np.diag([side, side, axial])
        return MassProperties(volume, 0.5 * (a + b), inertia, axis_frame(a, b))

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """36 meridians, RINGS parallels on each end ball."""
        a, b, radius = self.start, self.end, self.radius
        e = (b - a) / np.linalg.norm(b - a)
        phi = np.linspace(0.0, 0.5 * np.pi, RINGS + 1)
        z = -radius * np.cos(phi)
        points = np.concatenate([a + z[:, None] * e, b - z[::-1, None] * e])
        radii = radius * np.concatenate([np.sin(phi), np.sin(phi)[::-1]])
        return lathe(points, radii, e)


SHAPE = Capsule
