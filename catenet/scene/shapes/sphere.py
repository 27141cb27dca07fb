"""A ball (``catenet.terms.contact.SphereBarrier``): fixed, or the shape of a free body."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from catenet.scene.shapes.base import MassProperties, Outline, lathe, positive, vec

RINGS = 18  # parallels of a drawn sphere, pole to pole


if TYPE_CHECKING:
    from catenet.terms.contact import Obstacle


@dataclass(frozen=True, eq=False)
class Sphere:
    """The outside of the ball |x - center| >= radius."""

    center: np.ndarray
    radius: float

    kind: ClassVar[str] = "sphere"
    origin_key: ClassVar[str] = "center"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", np.asarray(self.center, dtype=np.float64))
        object.__setattr__(self, "radius", positive("sphere: radius", self.radius))

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> Sphere:
        return cls(vec(table, "center"), float(table["radius"]))

    @property
    def origin(self) -> np.ndarray:
        return self.center

    @property
    def placed(self) -> np.ndarray:
        return self.center

    @property
    def reach(self) -> float:
        return self.radius

    def barrier(self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0) -> Obstacle:
        from catenet.terms.contact import SphereBarrier as SphereTerm

        return SphereTerm(nodes, self.center, self.radius + offset, kappa=kappa, dhat=dhat)

    def outline(self) -> Outline:
        """Its centre grown by its radius: exact."""
        return Outline(self.center[None], np.zeros((0, 2), np.int64), self.radius)

    def mass_properties(self) -> MassProperties:
        r = self.radius
        ball = 0.4 * r * r * np.eye(3)
        return MassProperties(4 / 3 * math.pi * r**3, self.center.copy(), ball, np.eye(3))

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """RINGS parallels of quads, pole to pole along z."""
        e = np.array([0.0, 0.0, 1.0])
        phi = np.linspace(0.0, np.pi, RINGS + 1)
        return lathe(
            self.center - self.radius * np.cos(phi)[:, None] * e, self.radius * np.sin(phi), e
        )


SHAPE = Sphere
