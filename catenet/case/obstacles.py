"""Obstacles of a case (``[[obstacle]]``): rigid bodies the net cannot enter.

Each kind owns its keys and builds its energy term (``catenet.terms.contact``), registered
by name in ``OBSTACLES``. Common keys: ``distance`` (the barrier's activation distance
dhat, default 1e-3 of the scene's length scale) and ``stiffness`` (kappa [N/m], default:
the barrier holds the mean nodal load at half that distance). ``friction`` (mu_f >= 0,
default 0: frictionless) adds Coulomb friction beside the barrier of a plane, a fixed
sphere, or a box, capsule or mesh, fixed or on a prescribed motion (then relative to its
surface; ``catenet.terms.friction``), with ``slip`` (the distance below which a node
sticks, default the activation distance); a moving sphere (a ball) is frictionless. A new
kind is one class here and one line in ``OBSTACLES``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    choice,
    names,
    parse_table,
    real,
    show,
    vec3,
)
from catenet.case.sections import history_key
from catenet.case.shapes import BoxObstacle, CapsuleObstacle, MeshObstacle
from catenet.errors import ConfigError

DISTANCE_SHARE = 1e-3  # default activation distance, of the scene's length scale


@dataclass(frozen=True)
class PlaneObstacle(Declared):
    """The half-space on the side of `normal`: a ground or seabed."""

    kind: str = choice("plane", ("plane",), doc="a half-space (ground, seabed)")
    point: tuple = vec3((0.0, 0.0, 0.0), unit="m", doc="plane: a point of the plane")
    normal: tuple = vec3((0.0, 0.0, 1.0), doc="plane: normal pointing to the free side")
    distance: float | None = real(
        None, gt=0, write="given", unit="m", doc="barrier activation distance (1e-3 L)"
    )
    stiffness: float | None = real(
        None, gt=0, write="given", unit="N/m", doc="barrier stiffness (from the loads)"
    )
    friction: float = real(0.0, ge=0, write="given", doc="Coulomb coefficient mu_f (0: none)")
    slip: float | None = real(
        None, gt=0, write="given", unit="m", doc="friction: sticking below this slip (distance)"
    )

    def check(self, ck: Checker, path: str) -> None:
        if not any(self.normal):
            ck.add(f"{path}.normal = {list(self.normal)}: must not be zero")

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.contact import Plane

        return Plane(nodes, self.point, self.normal, kappa=kappa, dhat=dhat)


@dataclass(frozen=True, kw_only=True)
class SphereObstacle(Declared):
    """A rigid ball: fixed, a rigid body (`mass`) or on a path (`velocity` and no `mass`)."""

    kind: str = choice("sphere", ("sphere",), doc="a ball")
    center: tuple = vec3(missing="[x, y, z] of the centre [m]", unit="m", doc="sphere: centre")
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="sphere: radius")
    distance: float | None = real(
        None, gt=0, write="given", unit="m", doc="barrier activation distance (1e-3 L)"
    )
    stiffness: float | None = real(
        None, gt=0, write="given", unit="N/m", doc="barrier stiffness (from the loads)"
    )
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

    @property
    def moves(self) -> bool:
        """A rigid body or a ball on a prescribed path (a node of its own)."""
        return self.mass is not None or self.velocity is not None

    def check(self, ck: Checker, path: str) -> None:
        if self.friction > 0 and self.moves:
            ck.add(
                f"{path}.friction = {self.friction!r}: a moving sphere (mass or velocity) "
                "is frictionless (it has no spin): friction = 0; friction acts on planes, "
                "fixed spheres, boxes, capsules and meshes"
            )
        if self.history is not None and (self.velocity is None or self.mass is not None):
            ck.add(
                f"{path}.history: scales the velocity of a sphere on a prescribed path: "
                "give velocity and no mass"
            )

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.contact import Sphere

        return Sphere(nodes, self.center, self.radius, kappa=kappa, dhat=dhat)


#: Obstacle kinds by name.
OBSTACLES: dict[str, type] = {"plane": PlaneObstacle, "sphere": SphereObstacle}
OBSTACLES.update(box=BoxObstacle, capsule=CapsuleObstacle, mesh=MeshObstacle)  # case/shapes.py


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
            if hasattr(parsed, "resolve"):  # a mesh reads its file
                parsed = parsed.resolve(ck, path, base_dir)
        out.append(parsed)
    return BAD if BAD in out else tuple(out)


def obstacle_terms(obstacles, net, loads, size: float) -> tuple:
    """The energy terms of a case's obstacles on the net's free nodes. Raises ConfigError
    (with the obstacle's key path) for an obstacle that a node of the net starts in."""
    if not obstacles:
        return ()
    nodes = np.flatnonzero(~net.fixed[: net.n_net])  # a moving body's centre is no contact node
    force = loads.external_force(net)[nodes]
    per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(nodes) else 0.0
    terms = []
    for k, obs in enumerate(obstacles):
        if getattr(obs, "moves", False):
            continue  # a node of its own: catenet.case.bodies
        dhat = obs.distance if obs.distance is not None else DISTANCE_SHARE * size
        if per_node <= 0.0:  # no loads: the force that strains an edge by dhat / l0
            per_node = float(np.mean(net.EA / net.rest_length)) * dhat
        kappa = obs.stiffness
        if kappa is None:
            from catenet.terms.contact import default_stiffness

            kappa = default_stiffness(per_node, dhat)
        term = obs.term(nodes, kappa, dhat)
        if hasattr(term, "carry"):  # on a prescribed motion: its name in messages
            term.label = f"obstacle[{k}] (kind {obs.kind!r})"
        gap = term.gap(net.nodes)
        inside = np.flatnonzero(~(gap > 0.0))
        if inside.size:
            i = int(nodes[inside[0]])
            raise ConfigError(
                f"obstacle[{k}] (kind {obs.kind!r}): node {i} at "
                f"{show(net.nodes[i].tolist())} starts inside or on it (gap "
                f"{gap[inside[0]]:.3g} m), {inside.size} nodes in all: an obstacle must not "
                "overlap the initial net; move it or the net"
            )
        if not math.isfinite(kappa):
            raise ConfigError(f"obstacle[{k}].stiffness: must be finite")
        terms.append(term)
        if getattr(obs, "friction", 0.0) > 0:  # Coulomb friction rides on the barrier
            from catenet.terms.friction import Friction

            slip = obs.slip if obs.slip is not None else dhat
            terms.append(Friction(term, mu=obs.friction, slip=slip))
    return tuple(terms)
