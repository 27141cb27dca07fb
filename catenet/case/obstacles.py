"""Obstacles of a case (``[[obstacle]]``): rigid frictionless bodies the net cannot enter.

Each kind owns its keys and builds its energy term (``catenet.terms.contact``), registered
by name in ``OBSTACLES``. Common keys: ``distance`` (the barrier's activation distance
dhat, default 1e-3 of the scene's length scale) and ``stiffness`` (kappa [N/m], default:
the barrier holds the mean nodal load at half that distance). A new kind is one class
here and one line in ``OBSTACLES``.
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

    def check(self, ck: Checker, path: str) -> None:
        if not any(self.normal):
            ck.add(f"{path}.normal = {list(self.normal)}: must not be zero")

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.contact import Plane

        return Plane(nodes, self.point, self.normal, kappa=kappa, dhat=dhat)


@dataclass(frozen=True, kw_only=True)
class SphereObstacle(Declared):
    """A fixed rigid ball."""

    kind: str = choice("sphere", ("sphere",), doc="a ball")
    center: tuple = vec3(missing="[x, y, z] of the centre [m]", unit="m", doc="sphere: centre")
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="sphere: radius")
    distance: float | None = real(
        None, gt=0, write="given", unit="m", doc="barrier activation distance (1e-3 L)"
    )
    stiffness: float | None = real(
        None, gt=0, write="given", unit="N/m", doc="barrier stiffness (from the loads)"
    )

    def check(self, ck: Checker, path: str) -> None:
        pass

    def term(self, nodes, kappa: float, dhat: float):
        from catenet.terms.contact import Sphere

        return Sphere(nodes, self.center, self.radius, kappa=kappa, dhat=dhat)


#: Obstacle kinds by name.
OBSTACLES: dict[str, type] = {"plane": PlaneObstacle, "sphere": SphereObstacle}


def parse_obstacles(ck: Checker, value: Any, ctx: Context) -> tuple | Any:
    """The ``[[obstacle]]`` array of tables (absent: none)."""
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
        out.append(parsed)
    return BAD if BAD in out else tuple(out)


def obstacle_terms(obstacles, net, loads, size: float) -> tuple:
    """The energy terms of a case's obstacles on the net's free nodes. Raises ConfigError
    (with the obstacle's key path) for an obstacle that a node of the net starts in."""
    if not obstacles:
        return ()
    nodes = np.flatnonzero(~net.fixed)
    force = loads.external_force(net)[nodes]
    per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(nodes) else 0.0
    terms = []
    for k, obs in enumerate(obstacles):
        dhat = obs.distance if obs.distance is not None else DISTANCE_SHARE * size
        if per_node <= 0.0:  # no loads: the force that strains an edge by dhat / l0
            per_node = float(np.mean(net.EA / net.rest_length)) * dhat
        kappa = obs.stiffness
        if kappa is None:
            from catenet.terms.contact import default_stiffness

            kappa = default_stiffness(per_node, dhat)
        term = obs.term(nodes, kappa, dhat)
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
    return tuple(terms)
