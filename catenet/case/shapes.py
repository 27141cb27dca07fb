"""``[[obstacle]]`` kinds box, capsule and mesh (registered in ``case.obstacles``): their
keys, checks and terms (``catenet.terms.shapes``). A mesh file is read with meshio
(``.stl``, ``.obj``, ``.ply``, ``.vtk``, ...), its path relative to the case file, and
must be a closed surface: it is read and checked when the case is parsed.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.case.keys import Checker, Declared, choice, real, text, vec3


def _distance():
    return real(None, gt=0, write="given", unit="m", doc="barrier activation distance (1e-3 L)")


def _stiffness():
    return real(None, gt=0, write="given", unit="N/m", doc="barrier stiffness (from the loads)")


@dataclass(frozen=True, kw_only=True)
class BoxObstacle(Declared):
    """A fixed rigid box (a piece of debris, a block), optionally rotated."""

    kind: str = choice("box", ("box",), doc="a box")
    center: tuple = vec3(missing="[x, y, z] of the centre [m]", unit="m", doc="box: centre")
    half_size: tuple = vec3(
        missing="[hx, hy, hz]: half the box's size along its axes [m] (> 0)",
        unit="m",
        doc="box: half sizes along its own axes (> 0)",
    )
    axis: tuple = vec3((0.0, 0.0, 1.0), doc="box: axis its orientation is turned about")
    angle: float = real(0.0, unit="rad", doc="box: turn about `axis` (0: edges along x, y, z)")
    distance: float | None = _distance()
    stiffness: float | None = _stiffness()

    def check(self, ck: Checker, path: str) -> None:
        if not all(h > 0 for h in self.half_size):
            ck.add(f"{path}.half_size = {list(self.half_size)}: must be 3 numbers > 0")
        if not any(self.axis):
            ck.add(f"{path}.axis = {list(self.axis)}: must not be zero")

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.shapes import Box, rotation

        R = rotation(self.axis, self.angle)
        return Box(nodes, self.center, self.half_size, R, kappa=kappa, dhat=dhat)


@dataclass(frozen=True, kw_only=True)
class CapsuleObstacle(Declared):
    """A fixed rigid capsule (a boom, a pipe): all within `radius` of `start`-`end`."""

    kind: str = choice("capsule", ("capsule",), doc="a capsule")
    start: tuple = vec3(
        missing="[x, y, z] of one end of the axis [m]", unit="m", doc="capsule: axis start"
    )
    end: tuple = vec3(missing="[x, y, z] of the other end [m]", unit="m", doc="capsule: axis end")
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="capsule: radius")
    distance: float | None = _distance()
    stiffness: float | None = _stiffness()

    def check(self, ck: Checker, path: str) -> None:
        if self.start == self.end:
            ck.add(f"{path}.end = {list(self.end)}: must differ from {path}.start")

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.shapes import Capsule

        return Capsule(nodes, self.start, self.end, self.radius, kappa=kappa, dhat=dhat)


@dataclass(frozen=True, kw_only=True)
class MeshObstacle(Declared):
    """A fixed rigid body given by a closed triangle surface (a satellite, a rock)."""

    kind: str = choice("mesh", ("mesh",), doc="a closed triangle mesh from a file")
    file: str = text(
        nonempty=True,
        missing="the mesh file (.stl, .obj, ... read by meshio), relative to the case file",
        doc="mesh: a closed triangle surface (.stl, .obj, ...; relative to the case file)",
    )
    scale: float = real(1.0, gt=0, doc="mesh: factor on its coordinates")
    offset: tuple = vec3((0.0, 0.0, 0.0), unit="m", doc="mesh: added to its (scaled) coordinates")
    distance: float | None = _distance()
    stiffness: float | None = _stiffness()

    def check(self, ck: Checker, path: str) -> None:
        pass

    def resolve(self, ck: Checker, path: str, base_dir: Path | None) -> MeshObstacle:
        """This obstacle with ``file`` made absolute, once the file reads as a closed
        surface (a problem is recorded in ``ck`` under ``<path>.file``)."""
        file = Path(self.file)
        full = file if file.is_absolute() else (base_dir or Path.cwd()) / file
        full = full.resolve()
        try:
            read_surface(str(full))
        except ValueError as exc:
            ck.add(f"{path}.file = {self.file!r}: {exc}")
            return self
        return dataclasses.replace(self, file=str(full))

    def surface(self) -> tuple[np.ndarray, np.ndarray]:
        V, T = read_surface(self.file)
        return V * self.scale + np.asarray(self.offset), T

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.shapes import Mesh

        V, T = self.surface()
        return Mesh(nodes, V, T, kappa=kappa, dhat=dhat)


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

    try:
        import meshio
    except ImportError:
        raise ValueError(
            "reading a mesh obstacle needs the Python package meshio (pip install meshio)"
        ) from None
    try:
        with np.errstate(over="ignore"):  # meshio's binary-STL size test on ASCII files
            mesh = meshio.read(file)
    except Exception as exc:  # meshio raises many kinds for a file it cannot read
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"meshio cannot read it: {reason}") from None
    tris = [np.asarray(c.data, dtype=np.int64) for c in mesh.cells if c.type == "triangle"]
    if not tris:
        found = ", ".join(sorted({c.type for c in mesh.cells})) or "no cells"
        raise ValueError(f"holds no triangles (it has {found}): a mesh obstacle is a surface")
    points = np.asarray(mesh.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or not np.all(np.isfinite(points)):
        raise ValueError(f"its points (shape {points.shape}) must be finite 3D points")
    V, T = closed_surface(points, np.concatenate(tris))
    V.setflags(write=False)
    T.setflags(write=False)
    return V, T
