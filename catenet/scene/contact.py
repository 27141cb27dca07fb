"""The contact policy, once: how an obstacle's shape (``catenet.scene.shapes``) meets the
net, for a scene read from a case file and one built in Python alike.

- The activation distance dhat is ``distance``, else ``accuracy`` times the net's median
  edge length: a node resting on the obstacle has a gap below dhat (the barrier acts on
  no node farther away), so positions are exact to dhat.
- The stiffness kappa is ``stiffness``, else the value at which the barrier holds the
  mean load of a free node at dhat / 2 (without loads: the force that strains an average
  edge by dhat / l0): ``catenet.terms.contact.default_stiffness``.
- A fixed obstacle whose dhat is below the wide start (DISTANCE_SHARE of the scene's
  length scale) gets the wider barriers between them, STAGE_SHRINK times narrower each,
  as ``stages``: static solves go through them first, each from the last.
- Coulomb friction (``friction`` > 0) rides on the barrier with the slip distance
  ``slip``, else dhat, at least MIN_SLIP of dhat.
- On a prescribed motion (``velocity``, ``angular_velocity``, ``history``) the barrier
  moves rigidly about the shape's origin (``catenet.terms.moving.Moving``).
- No node of the net may start inside or on an obstacle (``check_clear``).

Every problem is a ConfigError naming the obstacle's key path (``obstacle[k].key``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, cast

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import Loads, Net

if TYPE_CHECKING:
    from catenet.scene.shapes import Shape
    from catenet.terms.base import Term
    from catenet.terms.moving import Moving
    from catenet.terms.segments import EdgeContact

DISTANCE_SHARE = 1e-3  # the static continuation's widest barrier, of the scene's length scale
STAGE_SHRINK = 10.0  # each continuation stage's barrier is this much narrower
ACCURACY = 1e-4  # the default largest gap of a resting node, per median edge length
MIN_SLIP = 1e-12  # the smallest friction slip distance, relative to the activation distance

#: A node nearer an obstacle than ON_ROUNDOFF round-offs of its coordinates, or than
#: ON_SHARE of the barrier's distance, starts on it: which side it is on is round-off
#: (a node at z = 5e-324 over the plane z = 0, the long fuzz run's seed 12), and its
#: barrier's force and stiffness (about kappa dhat^2 / d and kappa dhat^2 / d^2) are
#: beyond floating point.
ON_ROUNDOFF = 1e3
ON_SHARE = 1e-100


class Gaps(Protocol):
    """What ``check_clear`` reads of a barrier: its activation distance and gaps."""

    dhat: float

    def gap(self, x: np.ndarray) -> np.ndarray: ...


def shown_as_is(value: Any) -> str:
    """A value in a message (a case file's scene shows it as written: ``Shown``)."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    return "none" if value is None else repr(value)


Shown = Callable[[Any], str]


@dataclass(frozen=True)
class Contact:
    """How an obstacle meets the net (module docstring): its barrier's ``distance`` [m]
    (None: ``accuracy`` times the median edge length), ``stiffness`` [N/m] (None: from
    the loads), Coulomb ``friction`` and ``slip`` [m] (None: the distance), and a
    prescribed rigid motion (``velocity`` [m/s], ``angular_velocity`` [rad/s] about the
    shape's origin, ``history`` [[t, factor], ...]; dynamic runs)."""

    distance: float | None = None
    accuracy: float = ACCURACY
    stiffness: float | None = None
    friction: float = 0.0
    slip: float | None = None
    velocity: tuple[float, ...] | None = None
    angular_velocity: tuple[float, ...] | None = None
    history: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        """ConfigError for a value a case file's keys would refuse (a scene built in
        Python: ``Scene.with_obstacle``), naming the key."""
        problems = []
        for name, value in (("distance", self.distance), ("stiffness", self.stiffness),
                            ("slip", self.slip)):  # fmt: skip
            if value is not None and not (math.isfinite(value) and value > 0):
                problems.append(f"{name} = {value!r}: must be a finite number > 0 (or None)")
        if not (math.isfinite(self.accuracy) and 0 < self.accuracy < 1):
            problems.append(f"accuracy = {self.accuracy!r}: must be a number in (0, 1)")
        if not (math.isfinite(self.friction) and self.friction >= 0):
            problems.append(f"friction = {self.friction!r}: must be a finite number >= 0")
        for name, vector in (("velocity", self.velocity),
                             ("angular_velocity", self.angular_velocity)):  # fmt: skip
            if vector is not None and not (
                len(vector) == 3 and all(math.isfinite(c) for c in vector)
            ):
                problems.append(f"{name} = {list(vector)!r}: must be 3 finite numbers")
        if problems:
            raise ConfigError([f"obstacle: {p}" for p in problems])

    @property
    def moving(self) -> bool:
        return self.velocity is not None or self.angular_velocity is not None


@dataclass(frozen=True)
class Reach:
    """What the contact policy reads off the net: the free ``nodes`` obstacles act on,
    the mean load per free node [N], the median edge length [m] and the scene's length
    scale ``size`` [m]."""

    nodes: np.ndarray
    per_node: float
    edge: float
    size: float

    @classmethod
    def of(cls, net: Net, loads: Loads, size: float) -> Reach:
        nodes = np.flatnonzero(~net.fixed[: net.n_net])  # a body's centre is no contact node
        force = loads.external_force(net)[nodes]
        per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(nodes) else 0.0
        edge = float(np.median(net.rest_length[: net.n_edges])) if net.n_edges else size
        return cls(nodes, per_node, edge, float(size))


def moving(
    barrier: Term, shape: Shape, contact: Contact, offset: float = 0.0, label: str | None = None
) -> Term:
    """``barrier`` on the contact's prescribed motion about the shape's origin, if any;
    ``offset``: a ball's radius (the shape grown by it, ``catenet.terms.collide``), which
    guards no supports; ``label``: the obstacle in messages."""
    if not contact.moving:
        return barrier
    from catenet.model.histories import History
    from catenet.terms.moving import Moving

    history = History(contact.history, path="history") if contact.history else None
    reach = shape.reach + offset
    args = (shape.origin, contact.velocity, contact.angular_velocity, history)
    term = Moving(barrier, *args, reach=reach)
    term.guards_supports = offset == 0.0
    if label is not None:
        term.label = label
    return term


def obstacle_terms(
    path: str,
    shape: Shape,
    contact: Contact,
    reach: Reach,
    net: Net,
    shown: Shown = shown_as_is,
    radius: float | None = None,
) -> list[Term]:
    """The barrier of ``shape`` on the net's free nodes and, with friction, its Coulomb
    friction (module docstring); ``path``: the obstacle's key path in messages
    ("obstacle[k]"), ``shown`` how they show a value; ``radius``: the edges' contact
    radius where every edge is a capsule (``catenet.scene.segments``; None: the nodes
    alone meet it)."""
    dhat = contact.distance if contact.distance is not None else contact.accuracy * reach.edge
    load = reach.per_node
    if load <= 0.0:  # no loads: the force that strains an edge by dhat / l0
        load = float(np.mean(net.EA / net.rest_length)) * dhat

    def stiffness(distance: float) -> float:
        if contact.stiffness is not None:
            return contact.stiffness
        from catenet.terms.contact import default_stiffness

        return default_stiffness(load, distance)

    widths = []  # the continuation's wider barriers, widest first
    wide = DISTANCE_SHARE * reach.size
    if contact.distance is None and not contact.moving and wide > 10.0 * dhat:
        while wide > dhat * (1.0 + 1e-9):  # tenfold narrower each, the last within 10x
            widths.append(wide)
            wide /= STAGE_SHRINK
    kappa = stiffness(dhat)
    if not (math.isfinite(kappa) and kappa > 0):
        if contact.stiffness is not None:
            key, value = "stiffness", contact.stiffness
        elif contact.distance is not None:
            key, value = "distance", contact.distance
        else:
            key, value = "accuracy", contact.accuracy
        raise ConfigError(
            f"{path}.{key} = {shown(value)}: the barrier's stiffness would be {kappa:.3g} "
            "N/m: give a larger distance (or a finite stiffness)"
        )
    nodes = reach.nodes
    label = f"{path} (kind {shape.kind!r})"
    grow = 0.0 if radius is None else radius  # the nodes against the shape grown by it
    term: Term
    if widths:
        first = shape.barrier(nodes, stiffness(widths[0]), widths[0], grow)
        term = first.narrowed(kappa, dhat)
        term.stages = tuple(first.narrowed(stiffness(w), w) for w in widths)
    else:
        term = moving(shape.barrier(nodes, kappa, dhat, grow), shape, contact, label=label)
        term.stages = ()
    term.label, term.key = label, f"{path}.distance"  # (its stages keep neither)
    check_clear(label, "an obstacle", cast(Gaps, term), nodes, net, shown, grow)  # a barrier
    out = [term]
    edge = None
    rubs: EdgeContact | Moving | None = None  # the edges' barrier friction rides on
    if radius is not None:
        from catenet.scene.segments import (
            check_edges_clear,
            check_outline_clear,
            edge_barrier,
            held_edges,
        )

        check_edges_clear(label, shape, radius, dhat, net, shown)
        edge = edge_barrier(shape, net, radius, kappa, dhat)
        if edge is not None:
            check_outline_clear(label, edge, radius, net, shown)
            edge.stages = tuple(edge.narrowed(stiffness(w), w) for w in widths)
            edge.label, edge.key = label, term.key
            if contact.moving:  # on the obstacle's motion, as its nodes' barrier
                from catenet.terms.moving import Moving
                from catenet.terms.moving_edges import moving_edges

                fixed = held_edges(net)  # guarded: the obstacle must not run over them
                guard = edge_barrier(shape, net, radius, kappa, dhat, edges=fixed)
                moved = moving_edges(edge, cast(Moving, term), guard if len(fixed) else None)
                moved.stages, moved.key = (), term.key
                out.append(moved)
                rubs = moved
            else:
                out.append(edge)
                rubs = edge
    if contact.friction > 0:  # Coulomb friction rides on the barrier
        from catenet.terms.friction import Friction

        slip = contact.slip if contact.slip is not None else dhat
        if not slip >= MIN_SLIP * dhat:  # its stiffness mu lambda / slip would overflow
            raise ConfigError(
                f"{path}.slip = {shown(contact.slip)}: must be at least {MIN_SLIP:.0e} "
                f"times the barrier's activation distance ({dhat:.3g})"
            )
        out.append(Friction(term, mu=contact.friction, slip=slip))
        if rubs is not None:  # and where the edges touch
            from catenet.terms.segments import EdgeFriction

            out.append(EdgeFriction(rubs, mu=contact.friction, slip=slip))
    return out


def check_clear(
    label: str,
    what: str,
    shape: Gaps,
    nodes: np.ndarray,
    net: Net,
    shown: Shown = shown_as_is,
    grown: float = 0.0,
) -> None:
    """ConfigError where a node of ``nodes`` (those ``shape`` acts on, in its order) starts
    inside or on ``shape`` (``label``: the obstacle in messages, ``what``: "an obstacle",
    "a body"): its gap is not above ON_ROUNDOFF round-offs of its coordinates and
    ON_SHARE of the barrier's distance. ``grown``: the edges' contact radius the shape is
    grown by (a node outside the solid but within it is told so)."""
    gap = shape.gap(net.nodes)
    scale = np.abs(net.nodes[nodes]).max(axis=1) if len(nodes) else np.zeros(0)
    on = np.maximum(ON_ROUNDOFF * np.finfo(np.float64).eps * scale, ON_SHARE * shape.dhat)
    inside = np.flatnonzero(~(gap > on))
    if inside.size:
        i = int(nodes[inside[0]])
        where, fix = f"starts inside or on it (gap {gap[inside[0]]:.3g} m)", ""
        if grown > 0.0 and gap[inside[0]] + grown > 0.0:  # outside the solid itself
            where = (
                f"starts {gap[inside[0]] + grown:.3g} m off it, within the contact radius "
                f"{grown:.3g} m (material.contact_radius, else material.radius, with "
                "solver.edge_contact)"
            )
            fix = ", or give a smaller contact radius"
        raise ConfigError(
            f"{label}: node {i} at {shown(net.nodes[i].tolist())} {where}, {inside.size} "
            f"node{'' if inside.size == 1 else 's'} in all: {what} must not overlap the "
            f"initial net; move it or the net{fix}"
        )
