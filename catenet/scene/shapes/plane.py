"""A half-space: a ground, a seabed (``catenet.terms.contact.PlaneBarrier``). Infinite: never a
body; its drawing is the quad that covers the given points (the net) PLANE_COVER times."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from catenet.scene.shapes.base import MassProperties, Outline, across, no_body, vec

PLANE_COVER = 1.5  # the drawn quad covers the net's extent in the plane this many times


if TYPE_CHECKING:
    from catenet.terms.contact import Obstacle


@dataclass(frozen=True, eq=False)
class Plane:
    """The half-space n.(x - p) >= 0 (``point`` p, ``normal`` n towards the free side)."""

    point: np.ndarray
    normal: np.ndarray

    kind: ClassVar[str] = "plane"
    origin_key: ClassVar[str] = "point"

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, dtype=np.float64)
        if not np.linalg.norm(n) > 0:
            raise ValueError("plane: the normal must not be zero")
        object.__setattr__(self, "point", np.asarray(self.point, dtype=np.float64))
        object.__setattr__(self, "normal", n)  # as given: the term makes it a unit vector

    @property
    def unit_normal(self) -> np.ndarray:
        unit: np.ndarray = self.normal / np.linalg.norm(self.normal)
        return unit

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> Plane:
        return cls(vec(table, "point", (0.0, 0.0, 0.0)), vec(table, "normal", (0.0, 0.0, 1.0)))

    @property
    def origin(self) -> np.ndarray:
        return self.point

    @property
    def placed(self) -> np.ndarray:
        return self.point

    @property
    def reach(self) -> float:
        return float("inf")

    def barrier(self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0) -> Obstacle:
        from catenet.terms.contact import PlaneBarrier as PlaneTerm

        if offset == 0.0:
            return PlaneTerm(nodes, self.point, self.normal, kappa=kappa, dhat=dhat)
        n = self.unit_normal  # a ball's centre: the plane moved out by its radius
        return PlaneTerm(nodes, self.point + offset * n, n, kappa=kappa, dhat=dhat)

    def outline(self) -> Outline:
        raise no_body(self.kind)

    def mass_properties(self) -> MassProperties:
        raise no_body(self.kind)

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The quad covering the projections of the points ``cover`` (K, 3) PLANE_COVER
        times about their middle (a square of the largest span where they span a line
        or a point; of side 1 m where they are one point), counter-clockwise seen from
        the free side; no vertices without ``cover``."""
        if cover is None:
            return np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int64)
        n = self.unit_normal
        n = n / np.linalg.norm(n)
        p, q = across(n)  # p, q, n right-handed
        P = np.asarray(cover, dtype=np.float64).reshape(-1, 3) - self.point
        uv = np.stack([P @ p, P @ q], axis=1)
        lo, hi = uv.min(axis=0), uv.max(axis=0)
        span = hi - lo
        side = np.maximum(span, 0.25 * span.max()) if span.max() > 0 else np.ones(2)
        mid, half = 0.5 * (lo + hi), 0.5 * PLANE_COVER * side
        corners = mid + half * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
        V = self.point + corners[:, :1] * p + corners[:, 1:] * q
        return V, np.array([[0, 1, 2, 3]], dtype=np.int64)


SHAPE = Plane
