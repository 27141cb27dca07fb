"""Moving spheres of a case: ``[[obstacle]] kind = "sphere"`` with ``mass`` (a rigid ball,
two-way coupled) or with ``velocity`` and no mass (a ball on a prescribed path).

Each moving sphere becomes one node appended to the net (``Net.bodies``, after every net
node, in the order of the ``[[obstacle]]`` tables): its mass lumped there (gravity acts
on it through ``load.gravity``), its initial velocity in ``Scene.velocity``, and its
terms (``catenet.terms.body``): the barrier with every free net node, and for a path,
the spring that holds it there; and its barrier against every other obstacle, that
obstacle's own term on the centre, grown by the radius (``_collisions``,
``catenet.terms.collide``). Loads are padded with zeros for the new nodes.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import show
from catenet.errors import ConfigError
from catenet.model.histories import History
from catenet.model.net import Loads, Net
from catenet.terms import Term

log = logging.getLogger(__name__)

#: The path spring's stiffness, per mean edge stiffness EA/l0: the ball lags its path
#: by force / k, 1e-6 of a length under the force that strains an edge by 1e-2.
GUIDE_SHARE = 1e4


@dataclass(frozen=True)
class Body:
    """A moving sphere as the result file records it: its ``node`` (the centre), the
    ``[[obstacle]]`` table it comes from, radius [m], mass [kg] and whether it follows a
    prescribed path."""

    node: int
    obstacle: int
    radius: float
    mass: float
    prescribed: bool


def moving(obstacles) -> list[int]:
    """Indices of the ``[[obstacle]]`` tables that move (rigid balls and paths)."""
    return [k for k, o in enumerate(obstacles) if getattr(o, "moves", False)]


def add_bodies(case, net: Net, loads: Loads, velocity, size: float):
    """(net, loads, velocity, terms, bodies) with the case's moving spheres appended.
    Raises ConfigError with the key path for a ball that starts overlapping the net, or
    a path in a static run."""
    which = moving(case.obstacles)
    if not which:
        return net, loads, velocity, (), ()
    from catenet.scene.contact import DISTANCE_SHARE
    from catenet.terms.body import Ball, Guide, Path
    from catenet.terms.contact import default_stiffness

    n0 = net.n_nodes
    free = np.flatnonzero(~net.fixed)
    force = loads.external_force(net)[free]
    per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(free) else 0.0
    stiff = float(np.mean(net.EA / net.rest_length))
    g = 0.0 if loads.gravity is None else float(np.linalg.norm(loads.gravity))
    centres, masses, v_new, specs = [], [], [], []
    for k in which:
        obs = case.obstacles[k]
        path = f"obstacle[{k}]"
        c = np.asarray(obs.center, dtype=np.float64)
        gap = np.linalg.norm(net.nodes - c, axis=1) - obs.radius
        inside = np.flatnonzero(~(gap > 0.0))
        if inside.size:
            i = int(inside[0])
            raise ConfigError(
                f"{path} (kind 'sphere'): node {i} at {show(net.nodes[i].tolist())} starts "
                f"inside or on it (gap {gap[i]:.3g} m), {inside.size} nodes in all: an "
                "obstacle must not overlap the initial net; move it or the net"
            )
        prescribed = obs.mass is None
        if prescribed and case.solver.method != "dynamic":
            raise ConfigError(
                f"{path}.velocity = {list(obs.velocity)}: a sphere on a prescribed path "
                "moves in dynamic runs only: set solver.method = 'dynamic', or drop velocity"
            )
        mass = float(np.sum(net.mass)) if prescribed else float(obs.mass)
        hist = History(obs.history, path=f"{path}.history") if obs.history else None
        v0 = np.zeros(3) if obs.velocity is None else np.asarray(obs.velocity, dtype=float)
        if hist is not None:
            v0 = v0 * hist(0.0)
        centres.append(c)
        masses.append(mass)
        v_new.append(v0)
        specs.append((k, obs, prescribed, hist))
    nb = len(which)
    net = net.with_body_nodes(np.vstack(centres), masses)
    v = np.zeros((n0, 3)) if velocity is None else velocity
    velocity = np.vstack([v, v_new])
    loads = pad_loads(loads, nb)
    terms: list[Term] = []
    bodies = []
    for j, (k, obs, prescribed, hist) in enumerate(specs):
        node = n0 + j
        dhat = obs.distance if obs.distance is not None else DISTANCE_SHARE * size
        load = max(per_node, masses[j] * g / 8.0) if not prescribed else per_node
        if load <= 0.0:
            load = stiff * dhat
        kappa = obs.stiffness if obs.stiffness is not None else default_stiffness(load, dhat)
        if not (math.isfinite(kappa) and kappa > 0 and dhat > 0):
            key = "stiffness" if obs.stiffness is not None else "distance"
            raise ConfigError(
                f"obstacle[{k}].{key} = {show(getattr(obs, key))}: the barrier's stiffness "
                f"would be {kappa:.3g} N/m: give a larger distance (or a finite stiffness)"
            )
        terms.append(Ball(free, node, obs.radius, kappa=kappa, dhat=dhat, n_nodes=net.n_nodes))
        if prescribed:
            route = Path(obs.center, obs.velocity, hist)
            terms.append(Guide(node, route, GUIDE_SHARE * stiff, n_nodes=net.n_nodes))
        bodies.append(Body(node, k, float(obs.radius), masses[j], prescribed))
        weight = max(masses[j] * g, per_node, stiff * dhat)
        centre_of = {kk: n0 + jj for jj, kk in enumerate(which)}
        terms += _collisions(case.obstacles, k, node, net, weight, size, centre_of)
    return net, loads, velocity, tuple(terms), tuple(bodies)


def _collisions(obstacles, k: int, node: int, net: Net, weight: float, size: float, nodes):
    """The terms that stop the ball of ``obstacle[k]`` (centre ``node``) at the other
    obstacles, exact for its shape: a plane moved out by the radius, a fixed sphere grown
    by it, another moving sphere (of a later table) as a ball of the summed radii, a box,
    capsule or mesh (fixed or moving) grown by it (``catenet.terms.collide``). Raises
    ConfigError for a ball that starts inside or on one of them."""
    from catenet.scene.contact import DISTANCE_SHARE
    from catenet.terms.body import Ball
    from catenet.terms.contact import default_stiffness

    me = obstacles[k]
    out = []
    term: Any  # an obstacle's term (Ball, Plane, Sphere, a shape): each has gap(x)
    for i, other in enumerate(obstacles):
        if i == k or (getattr(other, "moves", False) and i < k):
            continue  # itself, or a pair built with the other ball
        if getattr(other, "free", False):
            continue  # a free body: its contact with the ball (catenet.case.touching)
        dhat = min(
            d if d is not None else DISTANCE_SHARE * size for d in (me.distance, other.distance)
        )
        kappa = default_stiffness(weight, dhat)
        if getattr(other, "moves", False):
            term = Ball(
                [nodes[i]], node, me.radius + other.radius, kappa=kappa, dhat=dhat,
                n_nodes=net.n_nodes,
            )  # fmt: skip
        else:  # the centre against the shape grown by the radius
            term = other.term([node], kappa, dhat, offset=me.radius)
        gap = float(term.gap(net.nodes)[0])
        if not gap > 0.0:
            raise ConfigError(
                f"obstacle[{k}] (kind 'sphere'): starts inside or touching obstacle[{i}] "
                f"(kind {other.kind!r}; gap {gap:.3g} m between their surfaces): move one of them"
            )
        out.append(term)
    return out


def pad_loads(loads: Loads, nb: int) -> Loads:
    """The loads with ``nb`` unloaded, unsupported nodes appended."""

    def pad(a, width=3):
        if a is None:
            return None
        return np.concatenate([a, np.zeros((nb, width) if a.ndim == 2 else nb)])

    return dataclasses.replace(
        loads,
        force=pad(loads.force),
        support_displacement=pad(loads.support_displacement),
        ramp_time=pad(loads.ramp_time),
        parts=tuple((pad(f), h) for f, h in loads.parts),
    )
