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
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from catenet.case.keys import Checker, Declared, choice, real, sizes3, text, vec3
from catenet.case.rigid_keys import FreeKeys, density_key, inertia_key, mass_key
from catenet.case.sections import history_key
from catenet.errors import ConfigError
from catenet.scene.contact import Contact
from catenet.scene.shapes.mesh import read_surface

if TYPE_CHECKING:
    from catenet.scene.shapes import Shape


#: obstacle[k].stiffness's description (every kind's)
STIFFNESS_DOC = (
    "barrier stiffness (default: from the loads; a ball or free body against the ground, "
    "an obstacle or another solid: also the energy it can bring, docs/guide/bodies.md)"
)


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
    return real(None, gt=0, write="given", unit="N/m", doc=STIFFNESS_DOC)


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
        doc="moves at this velocity (a free body: its initial one)",
    )


def _spin(about: str):
    return vec3(
        None,
        write="given",
        shown="none",
        unit="rad/s",
        doc=f"turns at this angular velocity (a vector) about {about} "
        "(a free body: its initial one, about its centre of mass)",
    )


def _history():
    return history_key("on a prescribed motion: velocities times factor(t) (dynamic runs)")


class Shaped:
    """An ``[[obstacle]]`` table's shape (``catenet.scene.shapes``), how it meets the net
    (``catenet.scene.contact.Contact``) and its barrier."""

    @property
    def rigid_motion(self) -> bool:
        """On a prescribed motion (a box, capsule, cylinder or mesh may be: ``_Motion``)."""
        return False

    @property
    def moves(self) -> bool:
        """A ball (a sphere with mass, or on a prescribed path: ``SphereObstacle``)."""
        return False

    def shape(self) -> Shape:
        from catenet.scene.shapes import shape_of

        return shape_of(vars(self))  # a dataclass's fields: the table's keys

    def given(self, key: str) -> Any:
        """The value of the table's key ``key``, as parsed (a message shows it as written)."""
        return vars(self)[key]

    def contact(self) -> Contact:
        table = vars(self)
        motion = ("velocity", "angular_velocity", "history") if self.rigid_motion else ()
        keys = ("distance", "accuracy", "stiffness", "friction", "slip", *motion)
        return Contact(**{k: table[k] for k in keys})


class _Motion(Shaped, FreeKeys):
    """A prescribed rigid motion (``velocity``, ``angular_velocity``, ``history``) of a
    box, capsule, cylinder or mesh (``catenet.terms.moving``): dynamic runs only; with ``mass`` or
    ``density`` a free body instead (``catenet.scene.rigid``)."""

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


@dataclass(frozen=True, kw_only=True)
class BoxObstacle(_Motion, Declared):
    """A rigid box (debris, a block), optionally rotated; fixed, or moving and tumbling."""

    kind: str = choice("box", ("box",), doc="a box")
    center: tuple = vec3(missing="[x, y, z] of the centre [m]", unit="m", doc="box: centre")
    half_size: tuple = sizes3(
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
        if not any(self.axis):
            ck.add(f"{path}.axis = {list(self.axis)}: must not be zero")
        self._check_motion(ck, path)


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


@dataclass(frozen=True, kw_only=True)
class CylinderObstacle(_Motion, Declared):
    """A solid cylinder with flat ends (a pipe, a drum, a pile) about `start`-`end`; may move."""

    kind: str = choice("cylinder", ("cylinder",), doc="a cylinder with flat ends")
    start: tuple = vec3(
        missing="[x, y, z] of the centre of one end [m]", unit="m", doc="cylinder: axis start"
    )
    end: tuple = vec3(
        missing="[x, y, z] of the centre of the other end [m]", unit="m", doc="cylinder: axis end"
    )
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="cylinder: radius")
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


#: The kinds of this module by name (``catenet.case.obstacles.OBSTACLES`` takes them).
SHAPED: dict[str, type] = {
    "box": BoxObstacle,
    "capsule": CapsuleObstacle,
    "cylinder": CylinderObstacle,
    "mesh": MeshObstacle,
}


def check_motion(case) -> None:
    """Raises ConfigError (key path) for a box, capsule or mesh on a prescribed motion
    in a run that is not dynamic."""
    if case.solver.method == "dynamic":
        return
    for k, obs in enumerate(case.obstacles):
        if obs.rigid_motion:
            key, value = (
                ("velocity", obs.velocity)
                if obs.velocity is not None
                else ("angular_velocity", obs.angular_velocity)
            )
            raise ConfigError(
                f"obstacle[{k}].{key} = {list(value)}: a {obs.kind} on a prescribed motion "
                "moves in dynamic runs only: set solver.method = 'dynamic', or drop "
                "velocity and angular_velocity"
            )
