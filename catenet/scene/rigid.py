"""Free rigid bodies of a scene (``Scene.with_body``): a box, capsule, cylinder, mesh or
sphere with a mass or density.

Each body is four nodes appended to the net (``catenet.terms.rigid``: an affine body
whose lumped masses m/4 carry its mass and second moment exactly), with its initial
``velocity`` and ``angular_velocity`` (world frame, about its centre of mass), the
orthogonality energy that keeps it rigid (``Rigidity``), the barrier between its shape
and every free net node (``BodyContact``) and, on every plane obstacle, the barrier of
its outline's vertices (``BodyPlane``). Mass properties come from the shape at uniform
density (``mass_properties``) unless ``inertia`` (3 x 3 about the centre of mass in the
body axes: a box's own axes, a capsule's (x', y', axis), a sphere's and a mesh's the
world axes at t = 0) is given.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError
from catenet.model.limits import carried, too_large
from catenet.model.net import Loads, Net
from catenet.scene.contact import DISTANCE_SHARE, Shown

if TYPE_CHECKING:
    from catenet.scene.movers import Fixed, Mover
    from catenet.terms.base import Term
    from catenet.terms.rigid import BodyFrame
    from catenet.terms.segments import EdgeContact

RESOLVED = 1e-8  # the share of a free body's size its coordinates' round-off may reach

#: The largest solver.rho_inf with a free body: its rigidity is a stiff mode that the
#: newmark scheme must damp (at 0.99 a spinning box's momentum drifts by half, at 1 the
#: run blows up; 0.95 and below keep the second-order drift).
RHO_INF_MAX = 0.95

#: The orthogonality energy's k over the body's load scale (force x size): the body
#: strains by about 1/RIGIDITY under a force of the scale.
RIGIDITY = 1e6


@dataclass(frozen=True)
class FreeBody:
    """A free body as the result file records it: its obstacle index, its four nodes
    (``frame``), mass [kg], inertia (3, 3) [kg m^2] in its body axes ``axes`` (their
    world directions at t = 0, as columns) and its centre of mass at t = 0."""

    obstacle: int
    frame: BodyFrame
    mass: float
    inertia: np.ndarray
    axes: np.ndarray
    center: np.ndarray


def mass_properties(body: Mover) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """(mass, centre of mass, inertia in the body axes, axes (columns)) of a free body,
    uniform density unless its ``mass``/``inertia`` say otherwise."""
    volume, com, inertia_unit, axes = body.shape.mass_properties()  # inertia per unit mass
    if body.mass is not None:
        mass = body.mass
    elif body.density is not None:
        mass = body.density * volume
    else:
        raise ConfigError(f"{body.path}: a free body needs mass or density")
    inertia = mass * inertia_unit if body.inertia is None else np.array(body.inertia, float)
    return float(mass), com, inertia, axes


def add_free_bodies(
    net: Net,
    loads: Loads,
    velocity: np.ndarray | None,
    free: tuple[Mover, ...],
    fixed: tuple[Fixed, ...],
    size: float,
    shown: Shown,
    radius: float | None = None,
) -> tuple[Net, Loads, np.ndarray | None, tuple[FreeBody, ...], list[Term]]:
    """(net, loads, velocity, bodies, terms) with the free bodies appended (four nodes
    each); ``radius``: the edges' contact radius where they meet every edge as a capsule
    (None: the nodes only). Raises ConfigError for a body that starts overlapping the
    net or a plane, that shares the scene with an obstacle on a prescribed motion, or has
    a bad inertia."""
    from catenet.scene.movers import pad_loads

    if not free:
        return net, loads, velocity, (), []
    _check_alone(free, fixed)
    n0 = net.n_nodes
    places, speeds, built = [], [], []
    for j, body in enumerate(free):
        record, P, V = _frame(body, n0 + 4 * j, shown)
        places.append(P)
        speeds.append(V)
        built.append(record)
    masses = np.repeat([b.mass / 4 for b in built], 4)
    net = net.with_body_nodes(np.vstack(places), masses)
    v = np.zeros((n0, 3)) if velocity is None else velocity
    velocity = np.vstack([v, *speeds])
    loads = pad_loads(loads, 4 * len(free))
    terms: list[Term] = []
    for body, record in zip(free, built, strict=True):
        made = _terms(body, record, fixed, net, loads, size, shown, radius)
        for term in made:
            term.owner = body.index
        terms += made
    return net, loads, velocity, tuple(built), terms


def _check_alone(free: tuple[Mover, ...], fixed: tuple[Fixed, ...]) -> None:
    """ConfigError for a free body beside an obstacle on a prescribed motion (a box,
    capsule or mesh that moves: no contact term follows it). Several free bodies, fixed
    obstacles and balls are allowed: they touch each other (``catenet.scene.touching``)."""
    k = free[0].index
    for obs in fixed:
        if obs.contact.moving:
            raise ConfigError(
                f"obstacle[{obs.index}] (kind {obs.shape.kind!r}): an obstacle on a "
                f"prescribed motion beside a free body (obstacle[{k}]): a free body does not "
                "touch an obstacle on a prescribed motion and would pass through it; drop "
                "one of them, or give the other a fixed place"
            )


def _frame(body: Mover, first: int, shown: Shown) -> tuple[FreeBody, np.ndarray, np.ndarray]:
    """(its record, its four nodes' places and velocities) of a free body whose first
    node is ``first``."""
    from catenet.terms.rigid import BodyFrame, inertia_problem

    mass, com, inertia, axes = mass_properties(body)
    world = axes @ inertia @ axes.T
    why = inertia_problem(world)
    if why is not None:  # a given inertia is checked when parsed; a thin shape's may fail
        raise ConfigError(
            f"{body.path}: the inertia of its shape is no inertia tensor ({why}): give inertia"
        )
    frame = BodyFrame(first, mass, world, com)
    _check_resolved(body, frame, shown)
    v = None if body.velocity is None else np.asarray(body.velocity, float)
    w = body.angular_velocity
    P, V = frame.place(v, None if w is None else np.asarray(w, float))
    return FreeBody(body.index, frame, mass, inertia, axes, com), P, V


def _terms(
    body: Mover,
    record: FreeBody,
    fixed: tuple[Fixed, ...],
    net: Net,
    loads: Loads,
    size: float,
    shown: Shown,
    radius: float | None = None,
) -> list[Term]:
    """The body's rigidity, its barrier with every free net node (with ``radius``: the
    shape grown by it, and its barrier with every edge, ``catenet.scene.segments``), its
    planes' barriers and its friction."""
    from catenet.scene.contact import check_clear
    from catenet.scene.shapes import solid_width
    from catenet.terms.contact import default_stiffness
    from catenet.terms.rigid import Rigidity
    from catenet.terms.rigid_contact import BodyContact

    kind = body.shape.kind
    frame = record.frame
    nodes = np.flatnonzero(~net.fixed[: net.n_net])
    g = 0.0 if loads.gravity is None else float(np.linalg.norm(loads.gravity))
    stiff = float(np.mean(net.EA / net.rest_length)) if net.n_edges else 1.0
    force = loads.external_force(net)[nodes]
    per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(nodes) else 0.0
    contact = body.contact
    dhat = contact.distance if contact.distance is not None else DISTANCE_SHARE * size
    load = max(per_node, record.mass * g / 8.0)
    if load <= 0.0:
        load = stiff * dhat
    kappa = contact.stiffness if contact.stiffness is not None else default_stiffness(load, dhat)
    shape = body.shape.barrier(nodes, kappa, dhat, 0.0 if radius is None else radius)
    edge = float(np.min(net.rest_length)) if net.n_edges else 0.0
    touch = BodyContact(shape, frame, n_nodes=net.n_nodes, label=f"{body.path} (kind {kind!r})",
                        candidates=True, edge=edge)  # fmt: skip
    touch.key = f"{body.path}.distance"
    touch.width = solid_width(body.shape)  # how far it may move in a step near the net
    label = f"{body.path} (kind {kind!r}, a free body)"
    check_clear(label, "a body", shape, nodes, net, shown, 0.0 if radius is None else radius)
    spin = 0.25 * frame.mass * float(np.sum(frame.points**2))  # tr J [kg m^2]
    reach = frame.reach  # about the body's size
    ea = float(np.max(net.EA)) if net.n_edges else stiff * size
    w0 = float(np.linalg.norm(body.angular_velocity or (0.0, 0.0, 0.0)))
    v0 = float(np.linalg.norm(body.velocity or (0.0, 0.0, 0.0)))
    scale = max(ea * reach, record.mass * g * reach, spin * w0**2, record.mass * v0**2)
    _check_carried(body, RIGIDITY * scale, spin * w0**2, record.mass * v0**2, shown)
    terms: list[Term] = [Rigidity(frame, RIGIDITY * scale, n_nodes=net.n_nodes), touch]
    edges = None if radius is None else _edges(body, frame, net, radius, kappa, dhat, label, shown)
    if edges is not None:
        terms.append(edges)
    terms += _planes(body, record, fixed, net, dhat, (load, g, size), shown)
    if contact.friction > 0:  # Coulomb friction rides on the barrier
        from catenet.terms.friction import Friction
        from catenet.terms.rigid_contact import BodyFriction

        slip = contact.slip if contact.slip is not None else dhat
        terms.append(BodyFriction(Friction(shape, mu=contact.friction, slip=slip), touch))
        if edges is not None:  # and where its outline pushes the edges
            from catenet.terms.body_segments import BodyEdgeFriction

            terms.append(BodyEdgeFriction(edges, frame, mu=contact.friction, slip=slip))
    return terms


def _edges(
    body: Mover,
    frame: BodyFrame,
    net: Net,
    r: float,
    kappa: float,
    dhat: float,
    label: str,
    shown: Shown,
) -> EdgeContact:
    """The barrier of the net's edges, capsules of radius r, and the body's outline,
    its points riding on the four nodes (``catenet.scene.touching.body_solid``'s
    weights); ConfigError where an edge starts within r of the body."""
    from catenet.scene.segments import check_edges_clear, edge_barrier, edge_outline

    check_edges_clear(label, body.shape, r, dhat, net, shown)
    points = edge_outline(body.shape)[0]
    weights = 0.25 + (points - frame.center) @ frame.B.T
    term = edge_barrier(body.shape, net, r, kappa, dhat, weights, frame.nodes)
    assert term is not None  # a free body is no plane
    return term


def _check_resolved(body: Mover, frame: BodyFrame, shown: Shown) -> None:
    """ConfigError where the body lies so far from the origin that the round-off of its
    coordinates (|c| eps) is beyond RESOLVED of its size: its turns and its rigidity's
    forces would be noise, or overflow."""
    far = float(np.max(np.abs(frame.center)))
    if far * np.finfo(float).eps <= RESOLVED * frame.reach:
        return
    key = body.shape.origin_key
    limit = RESOLVED * frame.reach / np.finfo(float).eps
    raise ConfigError(
        f"{body.path}.{key} = {shown(_placed(body))}: a free body {far:.3g} m "
        f"from the origin is not resolved against its size ({frame.reach:.3g} m: its "
        f"coordinates carry round-off of {far * np.finfo(float).eps:.3g} m); a free body "
        f"this size must lie within {limit:.3g} m of the origin: place the origin near "
        "the scene"
    )


def _placed(body: Mover) -> Any:
    """Where the body's shape is placed (its origin key's value), as its case file gives
    it where it came from one."""
    return body.shape.placed.tolist() if body.placed is None else list(body.placed)


def _check_carried(
    body: Mover, stiffness: float, turning: float, moving: float, shown: Shown
) -> None:
    """ConfigError where the body's rigidity stiffness (set by its largest energy: the
    net's stiffness, its weight, its spin, its speed) is beyond what the arithmetic
    carries: its energies and the squares of its forces would overflow in the first step."""
    if carried(stiffness):
        return
    if turning >= moving:
        key, value, what = "angular_velocity", body.angular_velocity, "spin"
    else:
        key, value, what = "velocity", body.velocity, "speed"
    raise ConfigError(
        f"{body.path}.{key} = {shown(list(value or ()))}: the body's kinetic energy of "
        f"{what} ({max(turning, moving):.3g} J) makes its energies overflow; a free body's "
        f"energies must stay within {too_large()}"
    )


def _planes(
    body: Mover,
    record: FreeBody,
    fixed: tuple[Fixed, ...],
    net: Net,
    dhat: float,
    scales: tuple[float, float, float],
    shown: Shown,
) -> list[Term]:
    """The barrier of every plane obstacle on the body's vertices (``BodyPlane``: a
    box's corners, a mesh's vertices, a sphere's or a capsule's centre or axis ends grown
    by its radius), its distance and stiffness the plane's keys, else the body's own
    distance and a stiffness that holds the body's weight on four vertices (or the load
    of ``scales``: load [N], |g|, the scene's size) and, where the body starts beyond
    that distance, takes the energy it brings: its motion's and its fall across the
    scene's size or its gap, the larger (``impact_stiffness``)."""
    from catenet.scene.movers import StruckBy, impact_energy
    from catenet.scene.shapes.plane import Plane
    from catenet.terms.body_plane import BodyPlane
    from catenet.terms.contact import default_stiffness, impact_stiffness

    load, g, size = scales

    kind = body.shape.kind
    vertices, _, radius = body.shape.outline()  # the shape lies within them grown by radius
    out: list[Term] = []
    for plane in fixed:
        if not isinstance(plane.shape, Plane):
            continue
        k = plane.index
        distance = plane.contact.distance if plane.contact.distance is not None else dhat
        given = plane.contact.stiffness
        kappa = given or default_stiffness(max(load, record.mass * 9.81 / 4.0), distance)
        label = f"{body.path} (a free {kind}) on obstacle[{k}] (plane)"

        def barrier(
            kappa: float, plane: Any = plane, distance: float = distance, label: str = label
        ) -> BodyPlane:
            return BodyPlane(
                record.frame, vertices, plane.shape.point, plane.shape.normal, radius=radius,
                kappa=kappa, dhat=distance, n_nodes=net.n_nodes, label=label,
            )  # fmt: skip

        gap = barrier(kappa).gap(net.nodes)
        if not np.all(gap > 0.0):
            v = int(np.argmin(gap))
            raise ConfigError(
                f"{body.path} (a free {kind}): its point "
                f"{shown(np.round(vertices[v], 12).tolist())} starts in or on obstacle[{k}] "
                f"(plane) (gap {gap[v]:.3g} m): move the body or the plane"
            )
        if given is None and float(np.min(gap)) >= distance:  # (within: it rests there)
            fall = impact_energy(body, record.mass, g, max(size, float(np.min(gap))))
            kappa = max(kappa, impact_stiffness(fall, distance))
        term = barrier(kappa)
        head = int(record.frame.nodes[0])  # its bounces resolved (catenet/solver/strikes.py)
        term.struck_by = StruckBy(head, (), record.mass, label)
        out.append(term)
    return out
