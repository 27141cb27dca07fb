"""``[[obstacle]]`` kinds box, capsule and mesh (registered in ``case.obstacles``): their
keys, checks and terms (``catenet.terms.shapes``). A mesh file is read with meshio
(``.stl``, ``.obj``, ``.ply``, ``.vtk``, ...), its path relative to the case file, and
must be a closed surface: it is read and checked when the case is parsed. Each may move
on a prescribed rigid motion in dynamic runs (``velocity``, ``angular_velocity`` about its
centre, its axis' midpoint or the mesh's ``offset``, ``history``): ``catenet.terms.moving``.
Each takes Coulomb friction (``friction``, ``slip``) as the plane and the sphere do,
relative to its moving surface when it moves (``catenet.terms.friction``).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from catenet.case.keys import MAGNITUDE, Checker, Declared, choice, real, text, vec3
from catenet.case.meshfiles import read_mesh_file
from catenet.case.rigid_keys import FreeKeys, density_key, inertia_key, mass_key
from catenet.case.sections import history_key
from catenet.errors import ConfigError


def _distance():
    return real(
        None,
        gt=0,
        write="given",
        unit="m",
        doc="barrier activation distance (default: accuracy x the median edge length)",
    )


def _accuracy():
    return real(
        1e-4,
        gt=0,
        lt=1,
        write="given",
        doc="largest gap of a node resting on it, per median edge length (without distance)",
    )


def _stiffness():
    return real(None, gt=0, write="given", unit="N/m", doc="barrier stiffness (from the loads)")


def _friction():
    return real(0.0, ge=0, write="given", doc="Coulomb coefficient mu_f (0: none)")


def _slip():
    return real(
        None, gt=0, write="given", unit="m", doc="friction: sticking below this slip (distance)"
    )


def _velocity():
    return vec3(
        None,
        write="given",
        shown="none",
        unit="m/s",
        doc="box/capsule/mesh: moves at this velocity (a free body: its initial one)",
    )


def _spin(about: str):
    return vec3(
        None,
        write="given",
        shown="none",
        unit="rad/s",
        doc=f"box/capsule/mesh: turns at this angular velocity (a vector) about {about} "
        "(a free body: its initial one, about its centre of mass)",
    )


def _history():
    return history_key("moving box/capsule/mesh: velocities times factor(t) (dynamic runs)")


class _Motion(FreeKeys):
    """A prescribed rigid motion (``velocity``, ``angular_velocity``, ``history``) of a
    box, capsule or mesh (``catenet.terms.moving``): dynamic runs only; with ``mass`` or
    ``density`` a free body instead (``catenet.case.rigid``)."""

    velocity: Any  # the keys of the obstacle kinds that mix it in
    angular_velocity: Any
    history: Any

    @property
    def rigid_motion(self) -> bool:
        moves = self.velocity is not None or self.angular_velocity is not None
        return moves and not self.free

    def _check_motion(self, ck: Checker, path: str) -> None:
        self._check_free(ck, path)
        if self.history is not None and not self.rigid_motion and not self.free:
            ck.add(
                f"{path}.history: scales a prescribed motion: give velocity or "
                "angular_velocity with it"
            )

    def _moving(self, shape, origin, reach: float, offset: float = 0.0):
        """``shape`` on the prescribed motion, if any; ``offset``: a ball's radius (the
        shape grown by it, ``catenet.terms.collide``), which guards no supports."""
        if not self.rigid_motion:
            return shape
        from catenet.model.histories import History
        from catenet.terms.moving import Moving

        hist = History(self.history, path="history") if self.history else None
        term = Moving(
            shape, origin, self.velocity, self.angular_velocity, hist, reach=reach + offset
        )
        term.guards_supports = offset == 0.0
        return term


@dataclass(frozen=True, kw_only=True)
class BoxObstacle(_Motion, Declared):
    """A rigid box (debris, a block), optionally rotated; fixed, or moving and tumbling."""

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
    accuracy: float = _accuracy()
    stiffness: float | None = _stiffness()
    friction: float = _friction()
    slip: float | None = _slip()
    velocity: tuple | None = _velocity()
    angular_velocity: tuple | None = _spin("its centre")
    history: tuple | None = _history()
    mass: float | None = mass_key()
    density: float | None = density_key()
    inertia: tuple | None = inertia_key()

    def check(self, ck: Checker, path: str) -> None:
        if not all(h > 0 for h in self.half_size):
            ck.add(f"{path}.half_size = {list(self.half_size)}: must be 3 numbers > 0")
        if not any(self.axis):
            ck.add(f"{path}.axis = {list(self.axis)}: must not be zero")
        self._check_motion(ck, path)

    def term(self, nodes, kappa: float, dhat: float, offset: float = 0.0):
        """The barrier on ``nodes``; ``offset`` r: on the centres of balls of radius r
        (the box rounded by r)."""
        from catenet.terms.shapes import Box, rotation

        R = rotation(self.axis, self.angle)
        box = Box(nodes, self.center, self.half_size, R, kappa=kappa, dhat=dhat, offset=offset)
        return self._moving(box, self.center, float(np.linalg.norm(self.half_size)), offset)


@dataclass(frozen=True, kw_only=True)
class CapsuleObstacle(_Motion, Declared):
    """A rigid capsule (a boom, a pipe): all within `radius` of `start`-`end`; may move."""

    kind: str = choice("capsule", ("capsule",), doc="a capsule")
    start: tuple = vec3(
        missing="[x, y, z] of one end of the axis [m]", unit="m", doc="capsule: axis start"
    )
    end: tuple = vec3(missing="[x, y, z] of the other end [m]", unit="m", doc="capsule: axis end")
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="capsule: radius")
    distance: float | None = _distance()
    accuracy: float = _accuracy()
    stiffness: float | None = _stiffness()
    friction: float = _friction()
    slip: float | None = _slip()
    velocity: tuple | None = _velocity()
    angular_velocity: tuple | None = _spin("the midpoint of start-end")
    history: tuple | None = _history()
    mass: float | None = mass_key()
    density: float | None = density_key()
    inertia: tuple | None = inertia_key()

    def check(self, ck: Checker, path: str) -> None:
        if self.start == self.end:
            ck.add(f"{path}.end = {list(self.end)}: must differ from {path}.start")
        self._check_motion(ck, path)

    def term(self, nodes, kappa: float, dhat: float, offset: float = 0.0):
        """The barrier on ``nodes``; ``offset`` r: on the centres of balls of radius r
        (the capsule of radius + r, exact)."""
        from catenet.terms.shapes import Capsule

        radius = self.radius + offset
        capsule = Capsule(nodes, self.start, self.end, radius, kappa=kappa, dhat=dhat)
        a, b = np.asarray(self.start), np.asarray(self.end)
        reach = 0.5 * float(np.linalg.norm(b - a)) + self.radius
        return self._moving(capsule, 0.5 * (a + b), reach, offset)


@dataclass(frozen=True, kw_only=True)
class MeshObstacle(_Motion, Declared):
    """A rigid body given by a closed triangle surface (a satellite, a rock); may move."""

    kind: str = choice("mesh", ("mesh",), doc="a closed triangle mesh from a file")
    file: str = text(
        nonempty=True,
        missing="the mesh file (.stl, .obj, ... read by meshio), relative to the case file",
        doc="mesh: a closed triangle surface (.stl, .obj, ...; relative to the case file)",
    )
    scale: float = real(1.0, gt=0, doc="mesh: factor on its coordinates")
    offset: tuple = vec3((0.0, 0.0, 0.0), unit="m", doc="mesh: added to its (scaled) coordinates")
    distance: float | None = _distance()
    accuracy: float = _accuracy()
    stiffness: float | None = _stiffness()
    friction: float = _friction()
    slip: float | None = _slip()
    velocity: tuple | None = _velocity()
    angular_velocity: tuple | None = _spin("the point `offset`")
    history: tuple | None = _history()
    mass: float | None = mass_key()
    density: float | None = density_key()
    inertia: tuple | None = inertia_key()

    def check(self, ck: Checker, path: str) -> None:
        self._check_motion(ck, path)

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

    def term(self, nodes, kappa: float, dhat: float, offset: float = 0.0):
        """The barrier on ``nodes``; ``offset`` r: on the centres of balls of radius r
        (the mesh grown by r)."""
        from catenet.terms.shapes import Mesh

        V, T = self.surface()
        mesh = Mesh(nodes, V, T, kappa=kappa, dhat=dhat, offset=offset)
        origin = np.asarray(self.offset, dtype=np.float64)
        reach = float(np.linalg.norm(V - origin, axis=1).max())
        return self._moving(mesh, origin, reach, offset)


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
        mesh = read_mesh_file(file)
    except ImportError:
        raise ValueError(
            "reading a mesh obstacle needs the Python package meshio (pip install meshio)"
        ) from None
    except ValueError as exc:
        raise ValueError(f"meshio cannot read it: {exc}") from None
    tris = [np.asarray(c.data, dtype=np.int64) for c in mesh.cells if c.type == "triangle"]
    if not tris:
        found = ", ".join(sorted({c.type for c in mesh.cells})) or "no cells"
        raise ValueError(f"holds no triangles (it has {found}): a mesh obstacle is a surface")
    points = np.asarray(mesh.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or not np.all(np.abs(points) <= MAGNITUDE):
        raise ValueError(
            f"its points (shape {points.shape}) must be finite 3D points, within +-{MAGNITUDE:.0e}"
        )
    V, T = closed_surface(points, np.concatenate(tris))
    V.setflags(write=False)
    T.setflags(write=False)
    return V, T


def check_motion(case) -> None:
    """Raises ConfigError (key path) for a box, capsule or mesh on a prescribed motion
    in a run that is not dynamic."""
    if case.solver.method == "dynamic":
        return
    for k, obs in enumerate(case.obstacles):
        if getattr(obs, "rigid_motion", False):
            key = "velocity" if obs.velocity is not None else "angular_velocity"
            value = getattr(obs, key)
            raise ConfigError(
                f"obstacle[{k}].{key} = {list(value)}: a {obs.kind} on a prescribed motion "
                "moves in dynamic runs only: set solver.method = 'dynamic', or drop "
                "velocity and angular_velocity"
            )
