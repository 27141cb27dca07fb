"""Free bodies against each other, balls and fixed obstacles: a scene's pairs of solids
(``catenet.terms.touch``).

Every free body (``catenet.scene.rigid``) meets every later free body, every ball
(``catenet.scene.bodies``) and every fixed sphere, box, capsule, cylinder and mesh
through one ``BodyTouch`` term; planes hold it through ``catenet.terms.body_plane``. A
pair's activation distance is the smaller of the two ``distance``s (each defaulting as
for the net: DISTANCE_SHARE of the scene), its stiffness the larger given ``stiffness``,
else the default barrier stiffness (``default_stiffness``) for the largest of the loads
the pair may carry: a body's weight on four points and the force that stops the pair's
initial kinetic energy within half the activation distance, and, where the pair starts
apart (beyond that distance), at least the stiffness that takes what the pair brings
(their motion's and their fall across the scene's size or their gap, the larger)
before a quarter of the distance (``impact_stiffness``).
Coulomb friction where either gives it: the larger ``friction`` of the two, the smaller
``slip`` given (else the activation distance), on the points' sides
(``BodyTouchFriction``; edge on edge is frictionless). Bodies that start touching are
refused (a ConfigError naming both).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError
from catenet.scene.contact import DISTANCE_SHARE

if TYPE_CHECKING:
    from catenet.model.net import Loads, Net
    from catenet.scene.movers import Body, Fixed, Mover
    from catenet.scene.rigid import FreeBody
    from catenet.terms.base import Term
    from catenet.terms.touch import Solid


def _barrier(owner: Fixed | Mover) -> Callable[[Any, float, float, float], Term]:
    """shape(nodes, kappa, dhat, grow): the shape's barrier term at t = 0, grown."""
    from catenet.scene.movers import placed_barrier

    def build(nodes: Any, kappa: float, dhat: float, grow: float) -> Term:
        return placed_barrier(owner.shape, owner.contact, nodes, kappa, dhat, grow)

    return build


def body_solid(body: FreeBody, mover: Mover) -> Solid:
    """The Solid of a free body: its points ride on its four nodes."""
    from catenet.terms.touch import Solid

    kind = mover.shape.kind
    points, edges, radius = mover.shape.outline()
    frame = body.frame
    weights = 0.25 + (points - frame.center) @ frame.B.T
    label = f"obstacle[{body.obstacle}] (a free {kind})"
    return Solid(label, frame.nodes, points, weights, edges, radius, kind, frame, _barrier(mover))


def fixed_solid(obs: Fixed) -> Solid:
    """The Solid of a fixed sphere, box, capsule, cylinder or mesh (no nodes)."""
    from catenet.terms.touch import Solid

    kind = obs.shape.kind
    points, edges, radius = obs.shape.outline()
    weights = np.zeros((len(points), 0))
    label = f"obstacle[{obs.index}] ({kind})"
    return Solid(label, [], points, weights, edges, radius, kind, None, _barrier(obs))


def ball_solid(ball: Body, net: Net) -> Solid:
    """The Solid of a ball: its centre is its node."""
    from catenet.terms.touch import Solid

    label = f"obstacle[{ball.obstacle}] (a moving sphere)"
    centre = net.nodes[ball.node][None]
    return Solid(
        label, [ball.node], centre, np.ones((1, 1)), np.zeros((0, 2)), ball.radius, "sphere"
    )


def touch_terms(
    rigid: tuple[FreeBody, ...],
    free: tuple[Mover, ...],
    balls: tuple[Body, ...],
    ball_movers: tuple[Mover, ...],
    fixed: tuple[Fixed, ...],
    net: Net,
    loads: Loads,
    size: float,
) -> list[Term]:
    """The BodyTouch term of every pair of a free body with a later free body, a ball or
    a fixed obstacle but a plane (module docstring). Raises ConfigError for a pair that
    starts touching."""
    from catenet.scene.movers import StruckBy, impact_energy
    from catenet.scene.shapes.plane import Plane
    from catenet.terms.contact import default_stiffness, impact_stiffness
    from catenet.terms.touch import BodyTouch, BodyTouchFriction

    g = 0.0 if loads.gravity is None else float(np.linalg.norm(loads.gravity))
    solids: list[tuple[Mover | Fixed, Solid, float]] = [
        (m, body_solid(b, m), b.mass) for b, m in zip(rigid, free, strict=True)
    ]
    mine = len(solids)
    solids += [(m, ball_solid(b, net), b.mass) for b, m in zip(balls, ball_movers, strict=True)]
    solids += [(f, fixed_solid(f), 0.0) for f in fixed if not isinstance(f.shape, Plane)]
    terms: list[Term] = []
    for i in range(mine):
        oa, a, ma = solids[i]
        for ob, b, mb in solids[i + 1 :]:
            ca, cb = oa.contact, ob.contact
            dhat = min(
                d if d is not None else DISTANCE_SHARE * size for d in (ca.distance, cb.distance)
            )
            given = [s for s in (ca.stiffness, cb.stiffness) if s is not None]
            if given:
                kappa = max(given)
            else:
                load = max(ma, mb) * max(g, 9.81) / 4.0
                moving = impact_energy(oa, ma, 0.0, 0.0) + impact_energy(ob, mb, 0.0, 0.0)
                kappa = default_stiffness(max(load, 2.0 * moving / dhat), dhat)
            term = BodyTouch(a, b, kappa=kappa, dhat=dhat, n_nodes=net.n_nodes)
            gap = term.gap(net.nodes)
            if not gap > 0.0:
                raise ConfigError(
                    f"{a.label}: it meets {b.label} at the start (gap {gap:.3g} m): "
                    "two solids must not overlap at the start; move them apart"
                )
            if not given and gap >= dhat:  # what they bring across their gap
                apart = gap if math.isfinite(gap) else _apart(a, b, net.nodes)
                h = max(size, float(apart))
                fall = impact_energy(oa, ma, g, h) + impact_energy(ob, mb, g, h)
                if (stiffer := impact_stiffness(fall, dhat)) > kappa:
                    term = BodyTouch(a, b, kappa=stiffer, dhat=dhat, n_nodes=net.n_nodes)
            both = ma * mb / (ma + mb) if mb > 0 else ma  # bounces resolved (solver/strikes)
            term.struck_by = StruckBy(int(a.nodes[0]), tuple(b.nodes.tolist()), both, term.label)
            terms.append(term)
            mu = max(ca.friction, cb.friction)
            if mu > 0.0:
                slips = [v for v in (ca.slip, cb.slip) if v]
                slip = min(slips) if slips else dhat
                terms.append(BodyTouchFriction(term, mu=mu, slip=slip))
    return terms


def _apart(a: Solid, b: Solid, x: np.ndarray) -> float:
    """How far apart two solids are at x (N, 3) [m]: the distance of their points'
    centres (their gap where it is beyond the pair's reach)."""
    return float(np.linalg.norm(a.place(x).mean(axis=0) - b.place(x).mean(axis=0)))
