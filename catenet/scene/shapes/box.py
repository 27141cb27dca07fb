"""A box, optionally turned (``catenet.terms.shapes.BoxBarrier``; kernels in
``catenet.kernels.shapes``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from catenet.scene.shapes.base import MassProperties, Outline, vec

#: The corners of a unit box, corner 4 i + 2 j + k at -/+ the half size along its axes
#: for i, j, k = 0/1; its 12 edges; its 6 faces, counter-clockwise seen from outside.
SIGNS = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=np.float64)
EDGES = np.array(
    [(a, b) for a in range(8) for b in range(a + 1, 8) if np.sum(SIGNS[a] != SIGNS[b]) == 1]
)
FACES = np.array(
    [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]],
    dtype=np.int64,
)


if TYPE_CHECKING:
    from catenet.terms.contact import Obstacle


@dataclass(frozen=True, eq=False)
class Box:
    """The outside of a box: ``center``, ``half_size`` along its axes, which are the
    columns of ``axes`` (a rotation matrix; default the identity)."""

    center: np.ndarray
    half_size: np.ndarray
    axes: np.ndarray = field(default_factory=lambda: np.eye(3))  # aligned with x, y, z

    kind: ClassVar[str] = "box"
    origin_key: ClassVar[str] = "center"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", np.asarray(self.center, dtype=np.float64))
        object.__setattr__(self, "half_size", np.asarray(self.half_size, dtype=np.float64))
        object.__setattr__(self, "axes", np.asarray(self.axes, dtype=np.float64))
        if not (self.half_size.shape == (3,) and np.all(self.half_size > 0)):
            raise ValueError(f"box: half sizes {self.half_size.tolist()}: must be three values > 0")

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> Box:
        """From ``center``, ``half_size`` and the turn ``angle`` [rad] about ``axis``."""
        from catenet.terms.shapes import rotation

        axes = rotation(vec(table, "axis", (0.0, 0.0, 1.0)), float(table.get("angle", 0.0)))
        return cls(vec(table, "center"), vec(table, "half_size"), axes)

    @property
    def origin(self) -> np.ndarray:
        return self.center

    @property
    def placed(self) -> np.ndarray:
        return self.center

    @property
    def reach(self) -> float:
        return float(np.linalg.norm(self.half_size))

    def barrier(self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0) -> Obstacle:
        """The box's barrier; ``offset`` r: the box rounded by r."""
        from catenet.terms.shapes import BoxBarrier as BoxTerm

        args = (self.center, self.half_size, self.axes)
        return BoxTerm(nodes, *args, kappa=kappa, dhat=dhat, offset=offset)

    def corners(self) -> np.ndarray:
        corners: np.ndarray = self.center + (SIGNS * self.half_size) @ self.axes.T
        return corners

    def outline(self) -> Outline:
        """Its 8 corners and 12 edges: exact."""
        return Outline(self.corners(), EDGES.copy(), 0.0)

    def mass_properties(self) -> MassProperties:
        h = self.half_size
        moments = np.array([h[1] ** 2 + h[2] ** 2, h[0] ** 2 + h[2] ** 2, h[0] ** 2 + h[1] ** 2])
        return MassProperties(8 * h.prod(), self.center.copy(), np.diag(moments) / 3, self.axes)

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        return self.corners(), FACES.copy()


SHAPE = Box
