"""A scene: what the solver solves, built from a case file (``catenet.case.build``) or in
Python, with one builder that owns the contact policy (``catenet.scene.contact``):

    scene = Scene.of(net, loads).with_obstacle(Box(...), friction=0.3)
    scene = scene.with_body(Box(...), mass=12.0, velocity=(0, 0, -3))
    result = catenet.solve(scene, method="dynamic", dt=1e-3, t_end=1.0)

A scene is frozen: each ``with_`` returns a new one. The same scene from a case file and
from the builder is the same computation: the case's obstacles, balls and free bodies go
through the same ``with_contact`` and ``with_movers`` (``catenet.case.scene``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConfigError
from catenet.model.net import Loads, Net
from catenet.scene.bodies import assemble
from catenet.scene.contact import ACCURACY, Contact, Reach, Shown, obstacle_terms, shown_as_is
from catenet.scene.movers import Body, Fixed, Mover
from catenet.scene.rigid import FreeBody

if TYPE_CHECKING:
    from catenet.scene.shapes import Shape
    from catenet.terms.base import Term


def extent(net: Net) -> float:
    """The diagonal of the net's bounding box [m]: a scene's length scale by default."""
    return float(np.linalg.norm(net.nodes.max(axis=0) - net.nodes.min(axis=0)))


@dataclass(frozen=True, eq=False)
class Scene:
    """A net, its loads and the energy terms the scene adds to the stretching of its
    edges (obstacles, friction, bodies' contacts; ``catenet.terms``), with:

    - ``probe``: the node whose z-deflection is "delta" (``probe_auto``: none was named,
      the summary reports the free node that moves most), ``size``: the length scale L
      of delta/L and of the contact policy's widest barrier;
    - ``velocity`` (N, 3): initial velocities (None: at rest);
    - ``bodies``: balls (``catenet.scene.bodies.Body``), whose centres are among the
      net's last nodes; ``rigid``: free bodies, four nodes each after them
      (``catenet.scene.rigid.FreeBody``); ``movers``: both as the builder took them
      (``with_ball``, ``with_body``), ``own``: the scene without them (None: none);
    - ``cables``: the cable of every edge (``catenet.case.kinds.cables.CableIndex``, None:
      no cables); ``sets``, ``at_nodes``, ``names``: node sets, the node of each point
      load along a cable, named nodes;
    - ``cases``: the load cases and combinations (``LoadCase``);
    - ``obstacles``: (index, shape, Contact) of each obstacle the builder added (the
      index: its ``obstacle[k]`` in messages and in a case file); ``shown``: how
      messages show a value (a case file's scene: as written);
    - ``design``: each edge's breaking load and the partial factors of its utilisation
      (``catenet.model.design.Design``; None: no utilisation, all NaN);
    - ``case``: the case file's case it was built from (None: built in Python);
      ``coarsen(factor)``: the same scene with every edge ``factor`` times longer, or
      None (a nested start, ``catenet.solver.nested``; None: it cannot be coarsened);
    - ``edge_radius``: the contact radius [m] of every edge where obstacles, balls and
      free bodies meet the whole edge, a capsule (``catenet.scene.segments``; None: the
      nodes alone); obstacles and bodies added later take it;
    - ``torsion``: the rods' twist angles as DOFs with their rotational inertia, for the
      modes (``catenet.model.torsion.Torsion``; None: no rod twists, the twist
      eliminated).
    """

    net: Net
    loads: Loads = field(default_factory=Loads)
    terms: tuple[Term, ...] = ()
    probe: int = 0
    size: float = 1.0
    velocity: np.ndarray | None = None
    bodies: tuple[Body, ...] = ()
    rigid: tuple[FreeBody, ...] = ()
    cables: Any = None
    sets: Mapping[str, Any] = field(default_factory=dict)
    at_nodes: Mapping[int, int] = field(default_factory=dict)
    names: Mapping[str, int] = field(default_factory=dict)
    probe_auto: bool = False
    cases: tuple[Any, ...] = ()
    obstacles: tuple[tuple[int, Shape, Contact], ...] = ()
    case: Any = None
    design: Any = None
    coarsen: Callable[[float], Scene | None] | None = None
    movers: tuple[Mover, ...] = ()
    own: Own | None = None
    shown: Shown = shown_as_is
    edge_radius: float | None = None
    torsion: Any = None

    @classmethod
    def of(
        cls,
        net: Net,
        loads: Loads | None = None,
        *,
        probe: int | None = None,
        size: float | None = None,
        velocity: ArrayLike | None = None,
        edge_radius: float | None = None,
    ) -> Scene:
        """A scene of ``net`` under ``loads`` (None: none); ``probe`` (None: the free
        node that moves most), ``size`` (None: the net's bounding-box diagonal),
        ``velocity`` (N, 3) initial velocities (None: at rest), ``edge_radius`` [m]:
        every edge a capsule of that radius for obstacles, balls and bodies (None: they
        meet the nodes only)."""
        if edge_radius is not None and not (math.isfinite(edge_radius) and edge_radius >= 0):
            raise ConfigError(f"edge_radius = {edge_radius!r}: must be a finite number >= 0")
        v = None if velocity is None else np.asarray(velocity, dtype=np.float64)
        if v is not None and v.shape != net.nodes.shape:
            raise ValueError(f"velocity: shape {v.shape}, the net's nodes are {net.nodes.shape}")
        return cls(
            net,
            Loads() if loads is None else loads,
            probe=0 if probe is None else int(probe),
            size=extent(net) if size is None else float(size),
            velocity=v,
            probe_auto=probe is None,
            edge_radius=None if edge_radius is None else float(edge_radius),
        )

    def with_terms(self, *terms: Term) -> Scene:
        """This scene with more energy terms (before its bodies' terms)."""
        own = self._own()
        own = dataclasses.replace(own, terms=(*own.terms, *terms))
        return self._with(own, self.movers, self.obstacles, assembled=self._body_terms())

    def with_obstacle(
        self,
        shape: Shape,
        *,
        distance: float | None = None,
        accuracy: float = ACCURACY,
        stiffness: float | None = None,
        friction: float = 0.0,
        slip: float | None = None,
        velocity: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
        history: Sequence[Sequence[float]] | None = None,
    ) -> Scene:
        """This scene with an obstacle of ``shape`` (``catenet.scene.shapes``: Plane,
        Sphere, Box, Capsule, Cylinder, Mesh) acting on every free node of the net, by
        the contact policy (``catenet.scene.contact``: the keys of an ``[[obstacle]]``
        table, the same defaults). Raises ConfigError where a node starts inside it."""
        contact = Contact(
            distance=distance,
            accuracy=accuracy,
            stiffness=stiffness,
            friction=friction,
            slip=slip,
            velocity=None if velocity is None else tuple(map(float, velocity)),
            angular_velocity=None
            if angular_velocity is None
            else tuple(map(float, angular_velocity)),
            history=_history(history),
        )
        return self.with_contact(shape, contact)

    def with_contact(
        self, shape: Shape, contact: Contact, index: int | None = None, shown: Shown | None = None
    ) -> Scene:
        """``with_obstacle`` with the policy's keys as a Contact; ``index``: the
        obstacle's number in messages (``obstacle[k]``; None: the next), ``shown``: how
        they show a value (a case file's: as written)."""
        k = self._next() if index is None else int(index)
        own = self._own()
        reach = Reach.of(own.net, own.loads, self.size)
        terms = obstacle_terms(
            f"obstacle[{k}]", shape, contact, reach, own.net, shown or self.shown,
            self.edge_radius,
        )  # fmt: skip
        for term in terms:
            term.owner = k  # the obstacle whose force on the net it is (histories)
        own = dataclasses.replace(own, terms=(*own.terms, *terms))
        return self._with(own, self.movers, (*self.obstacles, (k, shape, contact)))

    def with_ball(
        self,
        sphere: Shape,
        *,
        mass: float | None = None,
        velocity: Sequence[float] | None = None,
        history: Sequence[Sequence[float]] | None = None,
        distance: float | None = None,
        stiffness: float | None = None,
    ) -> Scene:
        """This scene with a ball (a Sphere): rigid, of ``mass`` [kg], two-way coupled
        with the net, frictionless and never spinning (its initial ``velocity`` [m/s]);
        or, without mass, on the prescribed path ``velocity`` scaled by ``history``
        ([[t, factor], ...]; dynamic runs). One node of the net, after its own
        (``catenet.scene.bodies``). Raises ConfigError where it starts overlapping the net
        or another obstacle."""
        from catenet.scene.shapes.sphere import Sphere

        if not isinstance(sphere, Sphere):
            raise ConfigError(f"ball: must be a Sphere, not {type(sphere).__name__}")
        if mass is None and velocity is None:
            raise ConfigError("ball: give mass (a rigid ball) or velocity (a prescribed path)")
        if mass is not None and history is not None:
            raise ConfigError("ball: history scales a prescribed path: give it without mass")
        mover = Mover(
            self._next(),
            sphere,
            Contact(distance=distance, stiffness=stiffness),
            free=False,
            mass=_positive("ball: mass", mass),
            velocity=_vector("ball: velocity", velocity),
            history=_history(history),
        )
        return self.with_movers(mover)

    def with_body(
        self,
        shape: Shape,
        *,
        mass: float | None = None,
        density: float | None = None,
        inertia: ArrayLike | None = None,
        velocity: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
        distance: float | None = None,
        stiffness: float | None = None,
        friction: float = 0.0,
        slip: float | None = None,
    ) -> Scene:
        """This scene with a free rigid body of ``shape`` (Sphere, Box, Capsule, Cylinder,
        Mesh) and ``mass`` [kg] or ``density`` [kg/m^3]: ``inertia`` (3 x 3 about its centre
        of mass in its body axes, or 3 principal moments; None: from the shape at uniform
        density), initial ``velocity`` [m/s] and ``angular_velocity`` [rad/s] (world frame,
        about its centre of mass). It meets the net, the planes, the other free bodies, the
        balls and the fixed obstacles (``catenet.scene.rigid``, ``catenet.scene.touching``),
        with Coulomb ``friction`` against the net and the solids. Four nodes of the net.
        Raises ConfigError where it starts overlapping anything."""
        if shape.kind == "plane":
            raise ConfigError("body: a plane cannot be a free body (it has no mass)")
        if (mass is None) == (density is None):
            raise ConfigError("body: give mass or density (one of them)")
        mover = Mover(
            self._next(),
            shape,
            Contact(distance=distance, stiffness=stiffness, friction=friction, slip=slip),
            free=True,
            mass=_positive("body: mass", mass),
            density=_positive("body: density", density),
            inertia=_inertia(inertia),
            velocity=_vector("body: velocity", velocity),
            angular_velocity=_vector("body: angular_velocity", angular_velocity),
        )
        return self.with_movers(mover)

    def with_movers(self, *movers: Mover) -> Scene:
        """This scene with balls and free bodies (``Mover``; ``with_ball``, ``with_body``),
        all built anew with those it had, in one order (``catenet.scene.bodies``)."""
        return self._with(self._own(), (*self.movers, *movers), self.obstacles)

    def _next(self) -> int:
        """The index of the next obstacle, ball or body."""
        return len(self.obstacles) + len(self.movers)

    def _own(self) -> Own:
        if self.own is not None:
            return self.own
        return Own(self.net, self.loads, self.velocity, self.terms)

    def _body_terms(self) -> tuple[Term, ...]:
        return self.terms[len(self._own().terms) :]

    def _with(
        self,
        own: Own,
        movers: tuple[Mover, ...],
        obstacles: tuple[tuple[int, Shape, Contact], ...],
        assembled: tuple[Term, ...] | None = None,
    ) -> Scene:
        """The scene of ``own`` with ``movers`` and ``obstacles``; ``assembled``: the
        bodies' terms where they stand (None: built anew)."""
        if not movers:
            return dataclasses.replace(
                self, net=own.net, loads=own.loads, velocity=own.velocity, terms=own.terms,
                bodies=(), rigid=(), own=None, movers=(), obstacles=obstacles,
            )  # fmt: skip
        if assembled is not None:
            terms = (*own.terms, *assembled)
            return dataclasses.replace(
                self, terms=terms, own=own, movers=movers, obstacles=obstacles
            )
        fixed = tuple(Fixed(k, shape, contact) for k, shape, contact in obstacles)
        args = (own.net, own.loads, own.velocity, movers, fixed, self.size, self.shown)
        built = assemble(*args, radius=self.edge_radius)
        return dataclasses.replace(
            self, net=built.net, loads=built.loads, velocity=built.velocity,
            terms=(*own.terms, *built.terms), bodies=built.balls, rigid=built.rigid,
            own=own, movers=movers, obstacles=obstacles,
        )  # fmt: skip

    def coarser(self, factor: float) -> Scene | None:
        """The same scene with every edge length times ``factor`` and fewer nodes, or
        None (``coarsen``)."""
        return None if self.coarsen is None else self.coarsen(factor)


@dataclass(frozen=True, eq=False)
class Own:
    """A scene without its balls and free bodies: its net, loads, initial velocities
    and its own terms (obstacles', ``with_terms``')."""

    net: Net
    loads: Loads
    velocity: np.ndarray | None
    terms: tuple[Term, ...]


def _positive(what: str, value: float | None) -> float | None:
    """``value`` as a float, None as None; ConfigError unless finite and > 0."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ConfigError(f"{what} = {value!r}: must be a number")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ConfigError(f"{what} = {value!r}: must be a finite number > 0")
    return v


def _vector(what: str, value: Sequence[float] | None) -> tuple[float, ...] | None:
    """``value`` as 3 floats, None as None; ConfigError unless 3 finite numbers."""
    if value is None:
        return None
    v = tuple(float(c) for c in value)
    if len(v) != 3 or not all(math.isfinite(c) for c in v):
        raise ConfigError(f"{what} = {list(value)!r}: must be 3 finite numbers")
    return v


def _history(value: Sequence[Sequence[float]] | None) -> tuple[tuple[float, float], ...] | None:
    return None if value is None else tuple((float(t), float(f)) for t, f in value)


def _inertia(value: ArrayLike | None) -> np.ndarray | None:
    """A free body's inertia (3, 3) from 3 x 3 or 3 principal moments; ConfigError unless
    an inertia tensor."""
    if value is None:
        return None
    from catenet.terms.rigid import inertia_problem

    try:
        tensor = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(
            f"body: inertia = {value!r}: must be 3 x 3 or 3 principal moments"
        ) from None
    if not np.all(np.isfinite(tensor)):
        raise ConfigError(f"body: inertia = {value!r}: must be finite numbers")
    if tensor.shape == (3,):
        tensor = np.diag(tensor)
    why = "must be 3 x 3 or 3 principal moments" if tensor.shape != (3, 3) else None
    why = why or inertia_problem(tensor)
    if why is not None:
        raise ConfigError(f"body: inertia = {np.asarray(value).tolist()!r}: {why}")
    return tensor
