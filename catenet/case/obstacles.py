"""Obstacles of a case (``[[obstacle]]``): rigid bodies the net cannot enter.

Each kind owns its keys (registered by name in ``OBSTACLES``) and names its shape
(``catenet.scene.shapes``) and how it meets the net (``catenet.scene.contact.Contact``);
``catenet.case.scene`` applies the contact policy to them (``catenet.scene.contact``), as
a scene built in Python does. Common keys: ``distance`` (the barrier's activation
distance dhat; default ``accuracy``, 1e-4, of the net's median edge length) and
``stiffness`` (kappa [N/m], default: the barrier holds the mean nodal load at half that
distance). ``friction`` (mu_f >= 0, default 0: frictionless) adds Coulomb friction beside
the barrier of a plane, a fixed sphere, or a box, capsule, cylinder or mesh, fixed or on
a prescribed motion (then relative to its surface; ``catenet.terms.friction``), with
``slip`` (the distance below which a node sticks, default the activation distance); a
moving sphere (a ball) is frictionless, a free body (``catenet.scene.rigid``) is not. A
new kind is its shape (``catenet.scene.shapes``) and its keys (``catenet.case.shapes``,
where ``SHAPED`` lists it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    choice,
    names,
    parse_table,
    real,
    vec3,
)
from catenet.case.rigid_keys import FreeKeys, density_key, inertia_key
from catenet.case.sections import history_key
from catenet.case.shapes import (
    SHAPED,
    STIFFNESS_DOC,
    MeshObstacle,
    Shaped,
    _accuracy,
    _distance,
)


@dataclass(frozen=True)
class PlaneObstacle(Shaped, Declared):
    """The half-space on the side of `normal`: a ground or seabed."""

    kind: str = choice("plane", ("plane",), doc="a half-space (ground, seabed)")
    point: tuple = vec3((0.0, 0.0, 0.0), unit="m", doc="plane: a point of the plane")
    normal: tuple = vec3((0.0, 0.0, 1.0), doc="plane: normal pointing to the free side")
    distance: float | None = _distance()
    accuracy: float = _accuracy()
    stiffness: float | None = real(None, gt=0, write="given", unit="N/m", doc=STIFFNESS_DOC)
    friction: float = real(0.0, ge=0, write="given", doc="Coulomb coefficient mu_f (0: none)")
    slip: float | None = real(
        None, gt=0, write="given", unit="m", doc="friction: sticking below this slip (distance)"
    )

    @property
    def free(self) -> bool:
        """A plane is never a free body (a sphere, box, capsule, cylinder or mesh may be)."""
        return False

    def check(self, ck: Checker, path: str) -> None:
        if not any(self.normal):
            ck.add(f"{path}.normal = {list(self.normal)}: must not be zero")


@dataclass(frozen=True, kw_only=True)
class SphereObstacle(Shaped, FreeKeys, Declared):
    """A ball: fixed, moving (`mass`; a path: `velocity`), or turning (`angular_velocity`)."""

    kind: str = choice("sphere", ("sphere",), doc="a ball")
    center: tuple = vec3(missing="[x, y, z] of the centre [m]", unit="m", doc="sphere: centre")
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="sphere: radius")
    distance: float | None = _distance()
    accuracy: float = _accuracy()
    stiffness: float | None = real(None, gt=0, write="given", unit="N/m", doc=STIFFNESS_DOC)
    friction: float = real(0.0, ge=0, write="given", doc="Coulomb coefficient mu_f (0: none)")
    slip: float | None = real(
        None, gt=0, write="given", unit="m", doc="friction: sticking below this slip (distance)"
    )
    mass: float | None = real(
        None, gt=0, write="given", unit="kg", doc="sphere: a rigid body of this mass (moves)"
    )
    velocity: tuple | None = vec3(
        None,
        write="given",
        shown="none",
        unit="m/s",
        doc="sphere: initial velocity of a body; without mass, the path's velocity",
    )
    history: tuple | None = history_key(
        "sphere on a path: its velocity is factor(t) times velocity (dynamic runs)"
    )
    density: float | None = density_key()
    inertia: tuple | None = inertia_key()
    angular_velocity: tuple | None = vec3(
        None,
        write="given",
        shown="none",
        unit="rad/s",
        doc="free body: initial angular velocity (world frame, about its centre of mass)",
    )

    @property
    def free(self) -> bool:
        """A free body with six degrees of freedom (``catenet.scene.rigid``)."""
        spins = self.inertia is not None or self.angular_velocity is not None
        return self.density is not None or (self.mass is not None and spins)

    @property
    def moves(self) -> bool:
        """A rigid ball or a ball on a prescribed path (a node of its own)."""
        return (self.mass is not None or self.velocity is not None) and not self.free

    def check(self, ck: Checker, path: str) -> None:
        if self.angular_velocity is not None and self.mass is None and self.density is None:
            ck.add(
                f"{path}.angular_velocity = {list(self.angular_velocity)}: a sphere turns "
                "as a free body: give mass or density with it"
            )
            return
        self._check_free(ck, path)
        if self.friction > 0 and self.moves:
            ck.add(
                f"{path}.friction = {self.friction!r}: a moving sphere (mass or velocity) "
                "is frictionless (it has no spin): friction = 0; friction acts on planes, "
                "fixed spheres, boxes, capsules and meshes, and on free bodies (a sphere "
                "with mass and angular_velocity, e.g. [0, 0, 0], turns)"
            )
        if self.history is not None and (self.velocity is None or self.mass is not None):
            ck.add(
                f"{path}.history: scales the velocity of a sphere on a prescribed path: "
                "give velocity and no mass"
            )


#: Obstacle kinds by name.
OBSTACLES: dict[str, type] = {"plane": PlaneObstacle, "sphere": SphereObstacle}
OBSTACLES.update(SHAPED)  # the kinds of case/shapes.py


def parse_obstacles(ck: Checker, value: Any, ctx: Context, base_dir=None) -> tuple | Any:
    """The ``[[obstacle]]`` array of tables (absent: none); files relative to ``base_dir``."""
    if value is None:
        return ()
    items = ck.array_of_tables(value, "obstacle")
    out = []
    for k, t in enumerate(items):
        path = f"obstacle[{k}]"
        kind = t.get("kind")
        if not isinstance(kind, str) or kind not in OBSTACLES:
            accepted = "one of " + ", ".join(map(repr, OBSTACLES))
            if "kind" in t:
                ck.bad(f"{path}.kind", kind, f"must be {accepted}")
            else:
                ck.add(f"{path}.kind: missing: {accepted}")
            out.append(BAD)
            continue
        cls = OBSTACLES[kind]
        ck.keys(t, path, names(cls), f" for kind {kind!r}")
        parsed = parse_table(ck, {k2: v for k2, v in t.items() if k2 in names(cls)}, cls, path, ctx)
        if parsed is not BAD:
            parsed.check(ck, path)
            if isinstance(parsed, MeshObstacle):  # a mesh reads its file
                parsed = parsed.resolve(ck, path, base_dir)
        out.append(parsed)
    return BAD if BAD in out else tuple(out)
