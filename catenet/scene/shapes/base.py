"""The ``Shape`` protocol: what every obstacle shape gives the layers above it.

- ``barrier(nodes, kappa, dhat, offset)``: its log-barrier term on nodes
  (``catenet.terms.contact.Obstacle``), grown by ``offset`` (a ball's radius: the
  Minkowski sum of the shape and the ball). The term's ``max_step`` is the exact first
  contact along a step and ``first_hit(x, dx, grow, upto)`` the same with the shape grown
  (exact up to t = upto at least).
- ``outline()``: the points, edges and radius that stand for its surface where it
  touches another solid or a plane as a free body (``catenet.terms.touch``,
  ``catenet.terms.body_plane``); the shape lies within the outline grown by the radius.
  ``edge_outline()`` (optional): what the net's edges meet with ``solver.edge_contact``
  where that differs, with a radius per line (``catenet.scene.segments.edge_outline``;
  a cylinder's exact core capsule and its end bands' prisms).
- ``mass_properties()``: volume, centre of mass, inertia per unit mass in its body axes,
  and those axes (columns), at uniform density.
- ``surface_mesh(cover)``: outward vertices and faces (quads or triangles) for drawing
  and ParaView; ``cover`` the points an infinite shape's drawing covers.
- ``origin`` (the reference point of a prescribed motion, the table key ``origin_key``
  gives it), ``reach`` (the radius about it that holds the shape).

A shape is built from its ``[[obstacle]]`` table (``from_table``: the resolved case's
keys, the same that a result file stores), or in Python by its constructor.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple, Protocol, Self

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from catenet.terms.contact import Obstacle

SEGMENTS = 36  # meridians of a drawn sphere, capsule or cylinder


class Outline(NamedTuple):
    """Points (V, 3), edges (E, 2) between them and the radius they are grown by."""

    points: np.ndarray
    edges: np.ndarray
    radius: float


class MassProperties(NamedTuple):
    """Volume [m^3], centre of mass (3,), inertia per unit mass (3, 3) [m^2] in the body
    axes, and the body axes' world directions (3, 3) as columns."""

    volume: float
    center: np.ndarray
    inertia: np.ndarray
    axes: np.ndarray


class Shape(Protocol):
    """An obstacle's geometry at t = 0, in world coordinates (module docstring)."""

    kind: ClassVar[str]
    origin_key: ClassVar[str]

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> Shape: ...

    @property
    def origin(self) -> np.ndarray: ...

    @property
    def placed(self) -> np.ndarray:
        """The value of its ``origin_key`` (where its table places it; messages)."""
        ...

    @property
    def reach(self) -> float: ...

    def barrier(
        self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0
    ) -> Obstacle: ...

    def outline(self) -> Outline: ...

    def mass_properties(self) -> MassProperties: ...

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]: ...


def vec(table: Mapping[str, Any], key: str, default: ArrayLike | None = None) -> np.ndarray:
    """Table key ``key`` as a float vector (3,); KeyError where it is missing."""
    value = table.get(key, default)
    if value is None:
        raise KeyError(key)
    return np.asarray(value, dtype=np.float64).reshape(3)


def lathe(
    axis_points: np.ndarray, radii: np.ndarray, axis: ArrayLike, n: int = SEGMENTS
) -> tuple[np.ndarray, np.ndarray]:
    """The surface swept by a profile about an axis: ``axis_points`` (m + 1, 3) on the
    axis with ``radii`` (m + 1,), 0 at both ends (the poles), ``axis`` from the first to
    the last; quads between consecutive parallels of n vertices (a quad at a pole
    repeats a vertex), counter-clockwise about the axis seen from outside."""
    e = np.asarray(axis, dtype=np.float64)
    e = e / np.linalg.norm(e)
    p, q = across(e)
    u = 2 * np.pi * np.arange(n) / n
    ring = np.cos(u)[:, None] * p + np.sin(u)[:, None] * q  # (n, 3)
    m = len(radii) - 1
    inner = axis_points[1:m, None, :] + radii[1:m, None, None] * ring[None]  # (m - 1, n, 3)
    V = np.concatenate([axis_points[:1], inner.reshape(-1, 3), axis_points[m:]])

    def index(i: np.ndarray, c: np.ndarray) -> np.ndarray:
        c = c % n
        return np.where(i == 0, 0, np.where(i == m, 1 + (m - 1) * n, 1 + (i - 1) * n + c))

    i, c = (g.ravel() for g in np.meshgrid(np.arange(m), np.arange(n), indexing="ij"))
    faces = np.stack([index(i, c), index(i, c + 1), index(i + 1, c + 1), index(i + 1, c)], axis=1)
    return V, faces


def across(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors p, q with (p, q, e) right-handed and orthonormal (e a unit vector)."""
    p = np.cross(e, [1.0, 0.0, 0.0] if abs(e[0]) < 0.9 else [0.0, 1.0, 0.0])
    p /= np.linalg.norm(p)
    return p, np.cross(e, p)


def axis_frame(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Body axes (columns x', y', z') of a shape with its axis along a-b: z' = (b - a) / |b - a|."""
    z = (b - a) / float(np.linalg.norm(b - a))
    helper = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def no_body(kind: str) -> ValueError:
    return ValueError(f"a {kind} is not a body: it has no outline and no mass")


def positive(name: str, value: float) -> float:
    """``value`` as a float; ValueError naming it unless finite and > 0."""
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} = {value!r}: must be > 0")
    return float(value)


@dataclass(frozen=True, eq=False)
class AboutSegment:
    """The fields and checks a shape about the segment ``start``-``end`` of a ``radius``
    shares (a capsule, a cylinder): its table's keys, its length and its origin (the
    midpoint, which a prescribed motion turns about)."""

    start: np.ndarray
    end: np.ndarray
    radius: float

    kind: ClassVar[str] = ""
    origin_key: ClassVar[str] = "start"

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", np.asarray(self.start, dtype=np.float64))
        object.__setattr__(self, "end", np.asarray(self.end, dtype=np.float64))
        object.__setattr__(self, "radius", positive(f"{self.kind}: radius", self.radius))
        if not np.linalg.norm(self.end - self.start) > 0:
            raise ValueError(f"{self.kind}: the two end points must differ")

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> Self:
        return cls(vec(table, "start"), vec(table, "end"), float(table["radius"]))

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    @property
    def placed(self) -> np.ndarray:
        return self.start

    @property
    def origin(self) -> np.ndarray:
        """The midpoint of its axis."""
        mid: np.ndarray = 0.5 * (self.start + self.end)
        return mid


def solid_width(shape: Shape) -> float:
    """The smallest extent of a shape across its principal directions [m]: its
    outline's points' extent there plus its radius on both sides."""
    points, _, radius = shape.outline()
    centred = points - points.mean(axis=0)
    if len(points) < 2:
        return 2.0 * float(radius)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    spans = [float(np.ptp(centred @ axis)) for axis in axes]
    spans += [0.0] * (3 - len(spans))  # a flat or straight outline: none across the rest
    return min(spans) + 2.0 * float(radius)
