"""Free rigid bodies of a case: an ``[[obstacle]]`` box, capsule, mesh or sphere with
``mass`` or ``density`` (a sphere: with ``density``, ``inertia`` or
``angular_velocity``; a sphere with ``mass`` alone is a ball, ``catenet.case.bodies``,
the exact torque-free case: a frictionless ball never spins up).

Each body is four nodes appended to the net (``catenet.terms.rigid``: an affine body
whose lumped masses m/4 carry its mass and second moment exactly), with its initial
``velocity`` and ``angular_velocity`` (world frame, about its centre of mass), the
orthogonality energy that keeps it rigid (``Rigidity``) and the barrier between its
shape and every free net node (``BodyContact``). Mass properties come from the shape at
uniform density (``mass_properties``) unless ``inertia`` (3 x 3 about the centre of
mass in the body axes: a box's own axes, a capsule's (x', y', axis), a sphere's and a
mesh's the world axes at t = 0; or 3 principal moments) is given.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from catenet.case.keys import show
from catenet.errors import ConfigError
from catenet.model.limits import carried, too_large

RESOLVED = 1e-8  # the share of a free body's size its coordinates' round-off may reach

if TYPE_CHECKING:  # the terms load where a body is built
    from catenet.terms.rigid import BodyFrame

#: The orthogonality energy's k over the body's load scale (force x size): the body
#: strains by about 1/RIGIDITY under a force of the scale.
RIGIDITY = 1e6
#: The largest solver.rho_inf with a free body: its rigidity is a stiff mode that the
#: newmark scheme must damp (at 0.99 a spinning box's momentum drifts by half, at 1 the
#: run blows up; 0.95 and below keep the second-order drift).
RHO_INF_MAX = 0.95


@dataclass(frozen=True)
class FreeBody:
    """A free body as the result file records it: its ``[[obstacle]]`` table, its four
    nodes (``frame``), mass [kg], inertia (3, 3) [kg m^2] in its body axes ``axes``
    (their world directions at t = 0, as columns) and its centre of mass at t = 0."""

    obstacle: int
    frame: BodyFrame
    mass: float
    inertia: np.ndarray
    axes: np.ndarray
    center: np.ndarray


def mass_properties(obs) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """(mass, centre of mass, inertia in the body axes, axes (columns)) of a free body
    table, uniform density unless ``mass``/``inertia`` say otherwise."""
    volume, com, inertia_unit, axes = obs.shape().mass_properties()  # inertia per unit mass
    mass = obs.mass if obs.mass is not None else obs.density * volume
    inertia = mass * inertia_unit if obs.inertia is None else np.array(obs.inertia, float)
    return float(mass), com, inertia, axes


def add_free_bodies(case, net, loads, velocity, size: float):
    """(net, loads, velocity, terms, bodies) with the case's free bodies appended (four
    nodes each). Raises ConfigError with the key path for a body that starts overlapping
    the net, that shares the scene with an obstacle on a prescribed motion, or has a bad
    inertia."""
    from catenet.case.bodies import pad_loads

    which = [k for k, o in enumerate(case.obstacles) if getattr(o, "free", False)]
    if not which:
        return net, loads, velocity, (), ()
    _check_alone(case, which)
    solver = case.solver
    if solver.method == "dynamic" and solver.integrator == "newmark":
        if solver.rho_inf > RHO_INF_MAX:
            raise ConfigError(
                f"solver.rho_inf = {solver.rho_inf!r}: must be <= {RHO_INF_MAX} with a free "
                f"body (obstacle[{which[0]}]): its rigidity is a stiff mode the newmark "
                "scheme must damp; the default 0.8 does"
            )
    n0 = net.n_nodes
    places, speeds, built = [], [], []
    for j, k in enumerate(which):
        obs = case.obstacles[k]
        body, P, V = _frame(obs, k, n0 + 4 * j, case)
        places.append(P)
        speeds.append(V)
        built.append(body)
    nb = 4 * len(which)
    masses = np.repeat([b.mass / 4 for b in built], 4)
    net = net.with_body_nodes(np.vstack(places), masses)
    v = np.zeros((n0, 3)) if velocity is None else velocity
    velocity = np.vstack([v, *speeds])
    loads = pad_loads(loads, nb)
    terms = []
    for body in built:
        terms += _terms(case, body, net, loads, size)
    return net, loads, velocity, tuple(terms), tuple(built)


def _check_alone(case, which) -> None:
    """ConfigError for a free body beside an obstacle on a prescribed motion (a box,
    capsule or mesh that moves: no contact term follows it). Several free bodies, fixed
    obstacles and balls are allowed: they touch each other (``catenet.case.touching``)."""
    k = which[0]
    for i, obs in enumerate(case.obstacles):
        if getattr(obs, "rigid_motion", False):
            raise ConfigError(
                f"obstacle[{i}] (kind {obs.kind!r}): an obstacle on a prescribed motion "
                f"beside a free body (obstacle[{k}]): a free body does not touch an "
                "obstacle on a prescribed motion and would pass through it; drop one of "
                "them, or give the other a fixed place"
            )


def _frame(obs, k: int, first: int, case):
    from catenet.terms.rigid import BodyFrame, inertia_problem

    path = f"obstacle[{k}]"
    mass, com, inertia, axes = mass_properties(obs)
    world = axes @ inertia @ axes.T
    why = inertia_problem(world)
    if why is not None:  # a given inertia is checked when parsed; a thin shape's may fail
        raise ConfigError(
            f"{path}: the inertia of its shape is no inertia tensor ({why}): give inertia"
        )
    frame = BodyFrame(first, mass, world, com)
    _check_resolved(path, obs, frame)
    v = None if obs.velocity is None else np.asarray(obs.velocity, float)
    w = getattr(obs, "angular_velocity", None)
    P, V = frame.place(v, None if w is None else np.asarray(w, float))
    moving = [n for n in ("velocity", "angular_velocity") if any(getattr(obs, n, None) or ())]
    if case.solver.method != "dynamic" and moving:
        key = moving[0]
        raise ConfigError(
            f"{path}.{key} = {list(getattr(obs, key))}: a free body's initial motion acts "
            "in dynamic runs only: set solver.method = 'dynamic', or drop it"
        )
    return FreeBody(k, frame, mass, inertia, axes, com), P, V


def _terms(case, body: FreeBody, net, loads, size: float) -> list:
    """The body's rigidity and its barrier with every free net node."""
    from catenet.scene.contact import DISTANCE_SHARE, check_clear
    from catenet.terms.contact import default_stiffness
    from catenet.terms.rigid import Rigidity
    from catenet.terms.rigid_contact import BodyContact

    k = body.obstacle
    obs = case.obstacles[k]
    path = f"obstacle[{k}]"
    frame = body.frame
    nodes = np.flatnonzero(~net.fixed[: net.n_net])
    g = 0.0 if loads.gravity is None else float(np.linalg.norm(loads.gravity))
    stiff = float(np.mean(net.EA / net.rest_length)) if net.n_edges else 1.0
    force = loads.external_force(net)[nodes]
    per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(nodes) else 0.0
    dhat = obs.distance if obs.distance is not None else DISTANCE_SHARE * size
    load = max(per_node, body.mass * g / 8.0)
    if load <= 0.0:
        load = stiff * dhat
    kappa = obs.stiffness if obs.stiffness is not None else default_stiffness(load, dhat)
    shape = obs.term(nodes, kappa, dhat)
    contact = BodyContact(shape, frame, n_nodes=net.n_nodes, label=f"{path} (kind {obs.kind!r})")
    check_clear(f"{path} (kind {obs.kind!r}, a free body)", "a body", shape, nodes, net, show)
    spin = 0.25 * frame.mass * float(np.sum(frame.points**2))  # tr J [kg m^2]
    reach = frame.reach  # about the body's size
    ea = float(np.max(net.EA)) if net.n_edges else stiff * size
    w0 = float(np.linalg.norm(getattr(obs, "angular_velocity", None) or (0.0, 0.0, 0.0)))
    v0 = float(np.linalg.norm(obs.velocity or (0.0, 0.0, 0.0)))
    scale = max(ea * reach, body.mass * g * reach, spin * w0**2, body.mass * v0**2)
    _check_carried(path, obs, RIGIDITY * scale, spin * w0**2, body.mass * v0**2)
    terms = [Rigidity(frame, RIGIDITY * scale, n_nodes=net.n_nodes), contact]
    terms += _planes(case, body, net, dhat, load)
    if getattr(obs, "friction", 0.0) > 0:  # Coulomb friction rides on the barrier
        from catenet.terms.friction import Friction
        from catenet.terms.rigid_contact import BodyFriction

        slip = obs.slip if obs.slip is not None else dhat
        terms.append(BodyFriction(Friction(shape, mu=obs.friction, slip=slip), contact))
    return terms


def _check_resolved(path: str, obs, frame) -> None:
    """ConfigError where the body lies so far from the origin that the round-off of its
    coordinates (|c| eps) is beyond RESOLVED of its size: its turns and its rigidity's
    forces would be noise, or overflow."""
    far = float(np.max(np.abs(frame.center)))
    if far * np.finfo(float).eps <= RESOLVED * frame.reach:
        return
    key = obs.shape().origin_key
    limit = RESOLVED * frame.reach / np.finfo(float).eps
    raise ConfigError(
        f"{path}.{key} = {show(list(getattr(obs, key)))}: a free body {far:.3g} m from the "
        f"origin is not resolved against its size ({frame.reach:.3g} m: its coordinates "
        f"carry round-off of {far * np.finfo(float).eps:.3g} m); a free body this size must "
        f"lie within {limit:.3g} m of the origin: place the origin near the scene"
    )


def _check_carried(path: str, obs, stiffness: float, turning: float, moving: float) -> None:
    """ConfigError where the body's rigidity stiffness (set by its largest energy: the
    net's stiffness, its weight, its spin, its speed) is beyond what the arithmetic
    carries: its energies and the squares of its forces would overflow in the first step."""
    if carried(stiffness):
        return
    if turning >= moving:
        key, value, what = "angular_velocity", obs.angular_velocity, "spin"
    else:
        key, value, what = "velocity", obs.velocity, "speed"
    raise ConfigError(
        f"{path}.{key} = {show(list(value))}: the body's kinetic energy of {what} "
        f"({max(turning, moving):.3g} J) makes its energies overflow; a free body's "
        f"energies must stay within {too_large()}"
    )


def _planes(case, body: FreeBody, net, dhat: float, load: float) -> list:
    """The barrier of every plane obstacle on the body's vertices (``BodyPlane``: a
    box's corners, a mesh's vertices, a sphere's or a capsule's centre or axis ends grown
    by its radius), its distance and stiffness the plane's keys, else the body's own
    distance and a stiffness that holds the body's weight on four vertices."""
    from catenet.terms.body_plane import BodyPlane
    from catenet.terms.contact import default_stiffness

    obs = case.obstacles[body.obstacle]
    vertices, _, radius = obs.shape().outline()  # the shape lies within them grown by radius
    out = []
    for k, plane in enumerate(case.obstacles):
        if plane.kind != "plane":
            continue
        distance = plane.distance if plane.distance is not None else dhat
        kappa = plane.stiffness
        if kappa is None:
            kappa = default_stiffness(max(load, body.mass * 9.81 / 4.0), distance)
        label = f"obstacle[{body.obstacle}] (a free {obs.kind}) on obstacle[{k}] (plane)"
        term = BodyPlane(
            body.frame, vertices, plane.point, plane.normal, radius=radius, kappa=kappa,
            dhat=distance, n_nodes=net.n_nodes, label=label,
        )  # fmt: skip
        gap = term.gap(net.nodes)
        if not np.all(gap > 0.0):
            v = int(np.argmin(gap))
            raise ConfigError(
                f"obstacle[{body.obstacle}] (a free {obs.kind}): its point "
                f"{show(np.round(vertices[v], 12).tolist())} starts in or on obstacle[{k}] "
                f"(plane) (gap {gap[v]:.3g} m): move the body or the plane"
            )
        out.append(term)
    return out
