"""Obstacles of a case (``[[obstacle]]``): rigid bodies the net cannot enter.

Each kind owns its keys and builds its energy term (``catenet.terms.contact``), registered
by name in ``OBSTACLES``. Common keys: ``distance`` (the barrier's activation distance
dhat; default ``accuracy``, 1e-4, of the net's median edge length: see
``obstacle_terms``) and ``stiffness`` (kappa [N/m], default:
the barrier holds the mean nodal load at half that distance). ``friction`` (mu_f >= 0,
default 0: frictionless) adds Coulomb friction beside the barrier of a plane, a fixed
sphere, or a box, capsule or mesh, fixed or on a prescribed motion (then relative to its
surface; ``catenet.terms.friction``), with ``slip`` (the distance below which a node
sticks, default the activation distance); a moving sphere (a ball) is frictionless, a
free body (``catenet.case.rigid``) is not. A new kind is its shape
(``catenet.scene.shapes``) and its keys (``catenet.case.shapes``, where ``SHAPED`` lists
it).
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
from catenet.case.rigid_keys import FreeKeys, density_key, inertia_key
from catenet.case.sections import history_key
from catenet.case.shapes import (
    SHAPED,
    Shaped,
    _accuracy,
    _distance,
)
from catenet.errors import ConfigError

DISTANCE_SHARE = 1e-3  # the static continuation's widest barrier, of the scene's length scale
STAGE_SHRINK = 10.0  # each continuation stage's barrier is this much narrower


@dataclass(frozen=True)
class PlaneObstacle(Shaped, Declared):
    """The half-space on the side of `normal`: a ground or seabed."""

    kind: str = choice("plane", ("plane",), doc="a half-space (ground, seabed)")
    point: tuple = vec3((0.0, 0.0, 0.0), unit="m", doc="plane: a point of the plane")
    normal: tuple = vec3((0.0, 0.0, 1.0), doc="plane: normal pointing to the free side")
    distance: float | None = _distance()
    accuracy: float = _accuracy()
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


@dataclass(frozen=True, kw_only=True)
class SphereObstacle(Shaped, FreeKeys, Declared):
    """A ball: fixed, moving (`mass`; a path: `velocity`), or turning (`angular_velocity`)."""

    kind: str = choice("sphere", ("sphere",), doc="a ball")
    center: tuple = vec3(missing="[x, y, z] of the centre [m]", unit="m", doc="sphere: centre")
    radius: float = real(gt=0, missing="the radius [m] (> 0)", unit="m", doc="sphere: radius")
    distance: float | None = _distance()
    accuracy: float = _accuracy()
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
        """A free body with six degrees of freedom (``catenet.case.rigid``)."""
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
            if hasattr(parsed, "resolve"):  # a mesh reads its file
                parsed = parsed.resolve(ck, path, base_dir)
        out.append(parsed)
    return BAD if BAD in out else tuple(out)


#: The smallest friction slip distance, relative to the barrier's activation distance.
MIN_SLIP = 1e-12


def obstacle_terms(obstacles, net, loads, size: float) -> tuple:
    """The energy terms of a case's obstacles on the net's free nodes. Raises ConfigError
    (with the obstacle's key path) for an obstacle that a node of the net starts in.

    The activation distance dhat is ``distance``, else ``accuracy`` times the net's median
    edge length: a node resting on the obstacle has a gap below dhat (the barrier acts
    on no node farther away), so positions are exact to dhat and no node off the
    obstacle by more than dhat feels it. A fixed obstacle whose dhat is below the wide
    start (DISTANCE_SHARE of the scene's length scale) gets the wider barriers between
    them, ten times narrower each, as ``stages``: static solves go through them first."""
    if not obstacles:
        return ()
    nodes = np.flatnonzero(~net.fixed[: net.n_net])  # a moving body's centre is no contact node
    force = loads.external_force(net)[nodes]
    per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(nodes) else 0.0
    edge = float(np.median(net.rest_length[: net.n_edges])) if net.n_edges else size
    terms = []
    for k, obs in enumerate(obstacles):
        if getattr(obs, "moves", False) or getattr(obs, "free", False):
            continue  # nodes of its own: catenet.case.bodies, catenet.case.rigid
        dhat = obs.distance if obs.distance is not None else obs.accuracy * edge
        load = per_node
        if load <= 0.0:  # no loads: the force that strains an edge by dhat / l0
            load = float(np.mean(net.EA / net.rest_length)) * dhat

        def stiffness(distance: float, obs=obs, load=load) -> float:
            if obs.stiffness is not None:
                return obs.stiffness
            from catenet.terms.contact import default_stiffness

            return default_stiffness(load, distance)

        widths = []  # the continuation's wider barriers, widest first
        wide = DISTANCE_SHARE * size
        if obs.distance is None and not getattr(obs, "rigid_motion", False) and wide > 10.0 * dhat:
            while wide > dhat * (1.0 + 1e-9):  # tenfold narrower each, the last within 10x
                widths.append(wide)
                wide /= STAGE_SHRINK
        kappa = stiffness(dhat)
        if not (math.isfinite(kappa) and kappa > 0):
            key = next(
                (n for n in ("stiffness", "distance") if getattr(obs, n, None) is not None),
                "accuracy",
            )
            raise ConfigError(
                f"obstacle[{k}].{key} = {show(getattr(obs, key, None))}: the barrier's stiffness "
                f"would be {kappa:.3g} N/m: give a larger distance (or a finite stiffness)"
            )
        first = obs.term(nodes, stiffness(widths[0]), widths[0]) if widths else None
        term = obs.term(nodes, kappa, dhat) if first is None else first.narrowed(kappa, dhat)
        if first is not None:  # (widths: the wider stages, none without)
            term.stages = tuple(first.narrowed(stiffness(w), w) for w in widths)
        else:
            term.stages = ()
        if term.moving:  # on a prescribed motion: its name in messages
            term.label = f"obstacle[{k}] (kind {obs.kind!r})"
        check_clear(f"obstacle[{k}] (kind {obs.kind!r})", "an obstacle", term, nodes, net)
        terms.append(term)
        if getattr(obs, "friction", 0.0) > 0:  # Coulomb friction rides on the barrier
            from catenet.terms.friction import Friction

            slip = obs.slip if obs.slip is not None else dhat
            if not slip >= MIN_SLIP * dhat:  # its stiffness mu lambda / slip would overflow
                raise ConfigError(
                    f"obstacle[{k}].slip = {show(obs.slip)}: must be at least "
                    f"{MIN_SLIP:.0e} times the barrier's activation distance ({dhat:.3g})"
                )
            terms.append(Friction(term, mu=obs.friction, slip=slip))
    return tuple(terms)


#: A node nearer an obstacle than ON_ROUNDOFF round-offs of its coordinates, or than
#: ON_SHARE of the barrier's distance, starts on it: which side it is on is round-off
#: (a node at z = 5e-324 over the plane z = 0, the long fuzz run's seed 12), and its
#: barrier's force and stiffness (about kappa dhat^2 / d and kappa dhat^2 / d^2) are
#: beyond floating point.
ON_ROUNDOFF = 1e3
ON_SHARE = 1e-100


def check_clear(label: str, what: str, shape, nodes: np.ndarray, net) -> None:
    """ConfigError where a node of ``nodes`` (those ``shape`` acts on, in its order) starts
    inside or on ``shape`` (``label``: the obstacle in messages, ``what``: "an obstacle",
    "a body"): its gap is not above ON_ROUNDOFF round-offs of its coordinates and
    ON_SHARE of the barrier's distance."""
    gap = shape.gap(net.nodes)
    scale = np.abs(net.nodes[nodes]).max(axis=1) if len(nodes) else np.zeros(0)
    on = np.maximum(ON_ROUNDOFF * np.finfo(np.float64).eps * scale, ON_SHARE * shape.dhat)
    inside = np.flatnonzero(~(gap > on))
    if inside.size:
        i = int(nodes[inside[0]])
        raise ConfigError(
            f"{label}: node {i} at {show(net.nodes[i].tolist())} starts inside or on it "
            f"(gap {gap[inside[0]]:.3g} m), {inside.size} nodes in all: {what} must not "
            "overlap the initial net; move it or the net"
        )
