"""Free bodies against each other, balls and fixed obstacles: the case's pairs of solids
(``catenet.terms.touch``).

Every free body (``catenet.case.rigid``) meets every later free body, every ball (a
sphere with ``mass`` alone, or on a path: ``catenet.case.bodies``) and every fixed
sphere, box, capsule and mesh through one ``BodyTouch`` term; planes hold it through
``catenet.terms.body_plane``. A pair's activation distance is the smaller of the two
tables' ``distance`` (each defaulting as for the net: DISTANCE_SHARE of the scene), its
stiffness the larger given ``stiffness``, else the default barrier stiffness
(``default_stiffness``) for the largest of the loads the pair may carry: a body's weight
on four points and the force that stops the pair's initial kinetic energy within half
the activation distance.
Coulomb friction where either table gives it: the larger ``friction`` of the two, the
smaller ``slip`` given (else the activation distance), on the points' sides
(``BodyTouchFriction``; edge on edge is frictionless). Bodies that start touching are
refused (exit 2) with both named.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError

if TYPE_CHECKING:
    from catenet.terms.base import Term


def _shape(obs):
    """shape(nodes, kappa, dhat, grow): the obstacle's barrier term at t = 0, grown."""

    def build(nodes, kappa, dhat, grow):
        return obs.term(nodes, kappa, dhat, offset=grow)

    return build


def body_solid(body, obs):
    """The Solid of a free body (``FreeBody``): its points ride on its four nodes."""
    from catenet.terms.touch import Solid

    points, edges, radius = obs.shape().outline()
    frame = body.frame
    weights = 0.25 + (points - frame.center) @ frame.B.T
    label = f"obstacle[{body.obstacle}] (a free {obs.kind})"
    return Solid(label, frame.nodes, points, weights, edges, radius, obs.kind, frame, _shape(obs))


def fixed_solid(k: int, obs):
    """The Solid of a fixed sphere, box, capsule or mesh (no nodes)."""
    from catenet.terms.touch import Solid

    points, edges, radius = obs.shape().outline()
    weights = np.zeros((len(points), 0))
    return Solid(
        f"obstacle[{k}] ({obs.kind})",
        [],
        points,
        weights,
        edges,
        radius,
        obs.kind,
        None,
        _shape(obs),
    )


def ball_solid(ball, net):
    """The Solid of a ball (``catenet.case.bodies.Body``): its centre is its node."""
    from catenet.terms.touch import Solid

    label = f"obstacle[{ball.obstacle}] (a moving sphere)"
    centre = net.nodes[ball.node][None]
    return Solid(
        label, [ball.node], centre, np.ones((1, 1)), np.zeros((0, 2)), ball.radius, "sphere"
    )


def touch_terms(case, rigid, balls, net, size: float) -> tuple:
    """The BodyTouch term of every pair of a free body with a later free body, a ball or
    a fixed non-plane obstacle (module docstring). Raises ConfigError for a pair that
    starts touching."""
    from catenet.scene.contact import DISTANCE_SHARE
    from catenet.terms.contact import default_stiffness
    from catenet.terms.touch import BodyTouch, BodyTouchFriction

    obstacles = case.obstacles
    gravity = case.load.gravity if getattr(case, "load", None) is not None else None
    g = float(np.linalg.norm(gravity)) if gravity is not None else 0.0
    taken = {b.obstacle for b in rigid} | {b.obstacle for b in balls}
    others = [(b.obstacle, body_solid(b, obstacles[b.obstacle]), b.mass) for b in rigid]
    mine = len(others)
    others += [(b.obstacle, ball_solid(b, net), b.mass) for b in balls]
    for k, obs in enumerate(obstacles):
        if k not in taken and obs.kind != "plane":
            others.append((k, fixed_solid(k, obs), 0.0))
    terms: list[Term] = []
    for i in range(mine):
        ka, a, ma = others[i]
        for kb, b, mb in others[i + 1 :]:
            oa, ob = obstacles[ka], obstacles[kb]
            dhat = min(
                d if d is not None else DISTANCE_SHARE * size for d in (oa.distance, ob.distance)
            )
            given = [s for s in (oa.stiffness, ob.stiffness) if s is not None]
            if given:
                kappa = max(given)
            else:
                load = max(ma, mb) * max(g, 9.81) / 4.0
                load = max(load, 2.0 * (_kinetic(oa, ma) + _kinetic(ob, mb)) / dhat)
                kappa = default_stiffness(load, dhat)
            term = BodyTouch(a, b, kappa=kappa, dhat=dhat, n_nodes=net.n_nodes)
            gap = term.gap(net.nodes)
            if not gap > 0.0:
                raise ConfigError(
                    f"{a.label}: it meets {b.label} at the start (gap {gap:.3g} m): "
                    "two solids must not overlap at the start; move them apart"
                )
            terms.append(term)
            mu = max(getattr(oa, "friction", 0.0), getattr(ob, "friction", 0.0))
            if mu > 0.0:
                slips = [v for v in (getattr(oa, "slip", None), getattr(ob, "slip", None)) if v]
                slip = min(slips) if slips else dhat
                terms.append(BodyTouchFriction(term, mu=mu, slip=slip))
    return tuple(terms)


def _kinetic(obs, mass: float) -> float:
    """The kinetic energy [J] of a table's initial motion, its spin about a radius of
    its size (an upper bound for the solid's)."""
    v = np.asarray(getattr(obs, "velocity", None) or (0.0, 0.0, 0.0), dtype=np.float64)
    w = np.asarray(getattr(obs, "angular_velocity", None) or (0.0, 0.0, 0.0), dtype=np.float64)
    points, _, radius = obs.shape().outline() if mass > 0 else (np.zeros((1, 3)), None, 0.0)
    reach = float(np.linalg.norm(points - points.mean(axis=0), axis=1).max()) + radius
    return 0.5 * mass * (float(v @ v) + float(w @ w) * reach * reach)
