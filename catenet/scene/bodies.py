"""The bodies a scene adds to its net (``Scene.with_ball``, ``Scene.with_body``), built
once and in one order, whatever the order they were added in (``assemble``):

- **balls** (a sphere with ``mass``: rigid and two-way coupled, frictionless, never
  spinning; or with ``velocity`` and no mass: on a prescribed path): one node each,
  appended after the net's nodes in the order of their obstacle index; their terms are
  the barrier with every free net node and, for a path, the spring that holds the ball
  there (``catenet.terms.body``), and the barrier against every other obstacle
  (``_collisions``: that obstacle's own term on the centre, grown by the radius);
- **free bodies** (a shape with ``mass`` or ``density``): four nodes each, after the
  balls' (``catenet.scene.rigid``);
- the pairs of solids: every free body against every later free body, every ball and
  every fixed obstacle but a plane (``catenet.scene.touching``).

Loads are padded with zeros for the new nodes, initial velocities with the bodies'. The
terms come after the scene's own (obstacles, ``with_terms``): balls', then free bodies',
then the pairs'. Every problem is a ConfigError naming the obstacle (``obstacle[k]``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError
from catenet.model.histories import History
from catenet.model.net import Loads, Net
from catenet.scene.contact import DISTANCE_SHARE, Shown
from catenet.scene.movers import Body, Fixed, Mover, pad_loads

if TYPE_CHECKING:
    from catenet.scene.rigid import FreeBody
    from catenet.terms.base import Term

#: The path spring's stiffness, per mean edge stiffness EA/l0: the ball lags its path
#: by force / k, 1e-6 of a length under the force that strains an edge by 1e-2.
GUIDE_SHARE = 1e4


@dataclass(frozen=True)
class Assembled:
    """The net, loads and velocities with the bodies' nodes, their terms, and the
    records of the balls (``Body``) and free bodies (``FreeBody``)."""

    net: Net
    loads: Loads
    velocity: np.ndarray | None
    terms: tuple[Term, ...]
    balls: tuple[Body, ...]
    rigid: tuple[FreeBody, ...]


def assemble(
    net: Net,
    loads: Loads,
    velocity: np.ndarray | None,
    movers: tuple[Mover, ...],
    fixed: tuple[Fixed, ...],
    size: float,
    shown: Shown,
    radius: float | None = None,
) -> Assembled:
    """The scene's balls, then free bodies, then their pairs (module docstring), added
    to ``net``; ``fixed``: the scene's obstacles, ``size`` its length scale; ``radius``:
    the edges' contact radius where the balls and bodies meet every edge as a capsule
    (``catenet.scene.segments``; None: the nodes only)."""
    from catenet.scene.rigid import add_free_bodies
    from catenet.scene.touching import touch_terms

    movers = tuple(sorted(movers, key=lambda m: m.index))
    balls = tuple(m for m in movers if not m.free)
    free = tuple(m for m in movers if m.free)
    scale = _Scale(net, loads)
    n0 = net.n_nodes
    net, loads, velocity, masses = _add_balls(net, loads, velocity, balls, shown)
    net, loads, velocity, rigid, rigid_terms = add_free_bodies(
        net, loads, velocity, free, fixed, size, shown, radius
    )
    centres = {m.index: n0 + j for j, m in enumerate(balls)}
    terms: list[Term] = []
    records = []
    for j, ball in enumerate(balls):
        made, record = _ball_terms(
            ball, centres[ball.index], masses[j], net, scale, size, shown, radius
        )
        for term in made:
            term.owner = ball.index
        terms += made
        records.append(record)
        others: list[Fixed | Mover] = [*fixed, *(m for m in balls if m.index > ball.index)]
        terms += _collisions(ball, record, net, scale, others, centres, size)
    terms += rigid_terms
    if rigid:
        terms += touch_terms(rigid, free, tuple(records), balls, fixed, net, loads, size)
    return Assembled(net, loads, velocity, tuple(terms), tuple(records), rigid)


def _add_balls(
    net: Net, loads: Loads, velocity: np.ndarray | None, balls: tuple[Mover, ...], shown: Shown
) -> tuple[Net, Loads, np.ndarray | None, list[float]]:
    """(net, loads, velocity, masses) with the balls' centres appended. Raises
    ConfigError for a ball that starts overlapping the net."""
    if not balls:
        return net, loads, velocity, []
    n0 = net.n_nodes
    centres: list[np.ndarray] = []
    masses: list[float] = []
    speeds: list[np.ndarray] = []
    for ball in balls:
        c = np.asarray(ball.shape.origin, dtype=np.float64)
        radius = ball.shape.reach
        gap = np.linalg.norm(net.nodes - c, axis=1) - radius
        inside = np.flatnonzero(~(gap > 0.0))
        if inside.size:
            i = int(inside[0])
            raise ConfigError(
                f"{ball.path} (kind 'sphere'): node {i} at {shown(net.nodes[i].tolist())} "
                f"starts inside or on it (gap {gap[i]:.3g} m), "
                f"{inside.size} node{'' if inside.size == 1 else 's'} in all: "
                "an obstacle must not overlap the initial net; move it or the net"
            )
        mass = float(np.sum(net.mass)) if ball.mass is None else float(ball.mass)
        hist = _history(ball)
        v0 = np.zeros(3) if ball.velocity is None else np.asarray(ball.velocity, dtype=float)
        if hist is not None:
            v0 = v0 * hist(0.0)
        centres.append(c)
        masses.append(mass)
        speeds.append(v0)
    grown = net.with_body_nodes(np.vstack(centres), masses)
    v = np.zeros((n0, 3)) if velocity is None else velocity
    return grown, pad_loads(loads, len(balls)), np.vstack([v, speeds]), masses


def _history(ball: Mover) -> History | None:
    path = f"{ball.path}.history"
    return History(ball.history, path=path) if ball.history else None


class _Scale:
    """What a ball's barriers read off the net before the bodies: its free nodes, the
    mean load per free node [N], the mean edge stiffness EA/l0 [N/m] and gravity [m/s^2]."""

    def __init__(self, net: Net, loads: Loads) -> None:
        self.free = np.flatnonzero(~net.fixed[: net.n_net])
        force = loads.external_force(net)[self.free]
        self.per_node = float(np.mean(np.linalg.norm(force, axis=1))) if len(self.free) else 0.0
        self.stiff = float(np.mean(net.EA / net.rest_length))
        self.g = 0.0 if loads.gravity is None else float(np.linalg.norm(loads.gravity))


def _dhat(mover: Mover | Fixed, size: float) -> float:
    """A body's activation distance: its ``distance``, else DISTANCE_SHARE of the scene."""
    d = mover.contact.distance
    return d if d is not None else DISTANCE_SHARE * size


def _ball_terms(
    ball: Mover,
    node: int,
    mass: float,
    net: Net,
    scale: _Scale,
    size: float,
    shown: Shown,
    r: float | None = None,
) -> tuple[list[Term], Body]:
    """([its barrier with the net's free nodes, with ``r`` its barrier with every edge
    (a capsule of radius r), its path spring], its Body record)."""
    from catenet.terms.body import Ball, Guide, Path
    from catenet.terms.contact import default_stiffness

    prescribed = ball.mass is None
    contact = ball.contact
    dhat = _dhat(ball, size)
    load = max(scale.per_node, mass * scale.g / 8.0) if not prescribed else scale.per_node
    if load <= 0.0:
        load = scale.stiff * dhat
    kappa = contact.stiffness if contact.stiffness is not None else default_stiffness(load, dhat)
    if not (math.isfinite(kappa) and kappa > 0 and dhat > 0):
        key, value = (
            ("stiffness", contact.stiffness)
            if contact.stiffness is not None
            else ("distance", contact.distance)
        )
        raise ConfigError(
            f"{ball.path}.{key} = {shown(value)}: the barrier's stiffness would be "
            f"{kappa:.3g} N/m: give a larger distance (or a finite stiffness)"
        )
    radius = ball.shape.reach
    grow = 0.0 if r is None else r
    sphere = Ball(scale.free, node, radius + grow, kappa=kappa, dhat=dhat, n_nodes=net.n_nodes)
    sphere.label, sphere.key = f"{ball.path} (kind 'sphere')", f"{ball.path}.distance"
    terms: list[Term] = [sphere]
    if r is not None:
        terms.append(_ball_edges(ball, node, net, r, kappa, dhat, shown))
    if prescribed:
        route = Path(ball.shape.origin, ball.velocity, _history(ball))
        terms.append(Guide(node, route, GUIDE_SHARE * scale.stiff, n_nodes=net.n_nodes))
    return terms, Body(node, ball.index, float(radius), mass, prescribed)


def _ball_edges(
    ball: Mover, node: int, net: Net, r: float, kappa: float, dhat: float, shown: Shown
) -> Term:
    """The barrier of the net's edges, capsules of radius r, and the ball's centre (its
    node); ConfigError where an edge starts within r of the ball."""
    from catenet.scene.segments import check_edges_clear, edge_barrier

    label = f"{ball.path} (kind 'sphere')"
    check_edges_clear(label, ball.shape, r, dhat, net, shown)
    term = edge_barrier(ball.shape, net, r, kappa, dhat, np.ones((1, 1)), [node])
    assert term is not None  # a sphere has an outline
    return term


def _collisions(
    ball: Mover,
    record: Body,
    net: Net,
    scale: _Scale,
    others: list[Fixed | Mover],
    centres: dict[int, int],
    size: float,
) -> list[Term]:
    """The terms that stop ``ball`` (centre ``node``) at the other obstacles, exact for
    its shape: a plane moved out by the radius, a fixed sphere grown by it, another ball
    (of a later index) as a ball of the summed radii, a box, capsule or mesh (fixed or
    moving) grown by it (``catenet.terms.collide``); their stiffness the larger
    ``stiffness`` the two give, else one that holds the ball's weight and, where they
    start apart (beyond the barrier's distance), takes the energy
    the two bring: their motion's and their fall across the scene's size or their gap,
    the larger (``impact_stiffness``).
    Raises ConfigError for a ball that starts inside or on one of them."""
    from catenet.scene.movers import StruckBy, impact_energy
    from catenet.terms.body import Ball
    from catenet.terms.contact import default_stiffness, impact_stiffness

    node, radius = record.node, record.radius
    weight = max(record.mass * scale.g, scale.per_node, scale.stiff * _dhat(ball, size))
    out: list[Term] = []
    for other in sorted(others, key=lambda o: o.index):
        i = other.index
        dhat = min(_dhat(ball, size), _dhat(other, size))

        def barrier(
            kappa: float, other: Fixed | Mover = other, i: int = i, dhat: float = dhat
        ) -> Any:  # each has gap(x)
            if isinstance(other, Mover):
                return Ball(
                    [centres[i]], node, radius + other.shape.reach, kappa=kappa, dhat=dhat,
                    n_nodes=net.n_nodes,
                )  # fmt: skip
            return other.term([node], kappa, dhat, offset=radius)  # the shape grown by r

        given = [k for k in (ball.contact.stiffness, other.contact.stiffness) if k]
        kappa = max(given) if given else default_stiffness(weight, dhat)  # (as for bodies)
        gap = float(barrier(kappa).gap(net.nodes)[0])
        if not gap > 0.0:
            raise ConfigError(
                f"{ball.path} (kind 'sphere'): starts inside or touching obstacle[{i}] "
                f"(kind {other.shape.kind!r}; gap {gap:.3g} m between their surfaces): "
                "move one of them"
            )
        mass = getattr(other, "mass", None) or 0.0  # (a fixed obstacle has none)
        pair = ((ball, record.mass), (other, mass))
        fall = sum(impact_energy(o, m, scale.g, max(size, gap)) for o, m in pair)
        if gap >= dhat and not given:  # (one placed within the barrier rests on it)
            kappa = max(kappa, impact_stiffness(fall, dhat))
        term = barrier(kappa)
        head, carry = (centres[i], (node,)) if isinstance(other, Mover) else (node, ())
        both = record.mass * mass / (record.mass + mass) if mass > 0 else record.mass
        who = f"{ball.path} (kind 'sphere') and obstacle[{other.index}] (kind {other.shape.kind!r})"
        term.struck_by = StruckBy(head, carry, both, who)
        out.append(term)
    return out
