"""A closed triangle surface read from a file (a satellite, a rock):
``catenet.terms.shapes.MeshBarrier``, kernels in ``catenet.kernels.mesh``. The file is read
with meshio (``.stl``, ``.obj``, ``.ply``, ``.vtk``, ...) and must be a closed,
consistently oriented surface (``catenet.terms.shapes.closed_surface``)."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from catenet.model.limits import MAGNITUDE
from catenet.scene.meshfiles import read_triangles
from catenet.scene.shapes.base import MassProperties, Outline, vec

if TYPE_CHECKING:
    from catenet.terms.contact import Obstacle


@dataclass(frozen=True, eq=False)
class Mesh:
    """The outside of a closed triangle surface: ``vertices`` (V, 3) and outward
    ``triangles`` (T, 3); ``offset`` the point it turns about on a prescribed motion."""

    vertices: np.ndarray
    triangles: np.ndarray
    offset: np.ndarray

    kind: ClassVar[str] = "mesh"
    origin_key: ClassVar[str] = "offset"

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> Mesh:
        """From the surface in ``file``, its coordinates times ``scale`` plus ``offset``."""
        origin = vec(table, "offset", (0.0, 0.0, 0.0))
        V, T = read_surface(str(table["file"]))
        return cls(V * float(table.get("scale", 1.0)) + origin, T, origin)

    @property
    def origin(self) -> np.ndarray:
        return np.asarray(self.offset, dtype=np.float64)

    @property
    def placed(self) -> np.ndarray:
        return self.origin

    @property
    def reach(self) -> float:
        return float(np.linalg.norm(self.vertices - self.origin, axis=1).max())

    def barrier(self, nodes: ArrayLike, kappa: float, dhat: float, offset: float = 0.0) -> Obstacle:
        """The mesh's barrier; ``offset`` r: the mesh grown by r."""
        from catenet.terms.shapes import MeshBarrier as MeshTerm

        return MeshTerm(nodes, self.vertices, self.triangles, kappa=kappa, dhat=dhat, offset=offset)

    def outline(self) -> Outline:
        """Its vertices and the triangles' edges: exact."""
        T = self.triangles
        pairs = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
        points = np.asarray(self.vertices, dtype=np.float64)
        return Outline(points, np.unique(pairs, axis=0), 0.0)

    def mass_properties(self) -> MassProperties:
        """By signed tetrahedra from the origin; body axes the world's."""
        V, T = self.vertices, self.triangles
        a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
        vol = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
        volume = float(vol.sum())
        com = (vol[:, None] * (a + b + c) / 4.0).sum(axis=0) / volume
        s = a + b + c
        outer = np.einsum("ki,kj->kij", a, a) + np.einsum("ki,kj->kij", b, b)
        outer += np.einsum("ki,kj->kij", c, c) + np.einsum("ki,kj->kij", s, s)
        J = (vol[:, None, None] * outer).sum(axis=0) / 20.0 / volume - np.outer(com, com)
        return MassProperties(volume, com, np.trace(J) * np.eye(3) - J, np.eye(3))

    def surface_mesh(self, cover: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices, self.triangles


def read_surface(file: str) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of a closed surface file, outward oriented. Raises
    ValueError with the reason (missing, unreadable, no triangles, not closed)."""
    path = Path(file)
    if not path.is_file():
        raise ValueError(f"{'is a directory' if path.is_dir() else 'no such file'} ({path})")
    stat = path.stat()
    return _read_surface(str(path), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=8)
def _read_surface(file: str, mtime: int, size: int) -> tuple[np.ndarray, np.ndarray]:
    from catenet.terms.shapes import closed_surface

    points, triangles = read_triangles(file, "a mesh obstacle")
    if points.ndim != 2 or points.shape[1] != 3 or not np.all(np.abs(points) <= MAGNITUDE):
        raise ValueError(
            f"its points (shape {points.shape}) must be finite 3D points, within +-{MAGNITUDE:.0e}"
        )
    V, T = closed_surface(points, triangles)
    V.setflags(write=False)
    T.setflags(write=False)
    return V, T


SHAPE = Mesh
