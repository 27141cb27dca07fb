"""What a run's summary says of its free rigid bodies (``catenet.scene.rigid``) and balls
(``catenet.scene.bodies``): the time each first came within its barrier's reach of the
net (the first contact), and its final speed and (a free body's) spin, from the states
the runner sees."""

from __future__ import annotations

import math

import numpy as np


class BodyWatch:
    """Follows the free bodies of a scene through a run's steps (``see``), then says
    what the summary reports (``stats``)."""

    def __init__(self, scene):
        rigid = scene.rigid
        contacts = {}
        if rigid:  # (the contact kernels load only for a scene with free bodies)
            from catenet.terms.rigid_contact import BodyContact

            contacts = {
                id(t.frame): [t]
                for t in scene.terms
                if isinstance(t, BodyContact) and t.bounds_step
            }  # the barriers (not the friction riding on them)
            for b in rigid if scene.edge_radius is not None else ():  # and the edges'
                contacts.setdefault(id(b.frame), []).extend(_edges(scene, b.frame.nodes))
        self.bodies = [(b, contacts.get(id(b.frame), [])) for b in rigid]
        self.balls = [(b, _ball_contacts(scene, b.node)) for b in scene.bodies]
        self.kinds = {
            b.obstacle: scene.case.obstacles[b.obstacle].kind
            for b, _ in [*self.bodies, *self.balls]
        }
        self.first = {b.obstacle: None for b, _ in [*self.bodies, *self.balls]}

    def __bool__(self) -> bool:
        return bool(self.bodies or self.balls)

    def see(self, t: float, x) -> None:
        """A state x (N, 3) at time t."""
        for body, contacts in [*self.bodies, *self.balls]:
            if self.first[body.obstacle] is not None:
                continue
            for contact in contacts:
                gap = contact.gap(x)  # empty where the net has no free node
                if gap.size and float(gap.min()) < contact.dhat:
                    self.first[body.obstacle] = float(t)
                    break

    def stats(self, x, v) -> dict:
        """Per body (its obstacle index): kind, first contact time (None: none), final
        speed [m/s], spin [deg/s] and its axis (world frame)."""
        out = {}
        for body, _ in self.bodies:
            vel, spin = (np.zeros(3), np.zeros(3)) if v is None else body.frame.motion(x, v)
            w = float(np.linalg.norm(spin))
            out[body.obstacle] = {
                "kind": self.kinds[body.obstacle],
                "first_contact": self.first[body.obstacle],
                "speed": float(np.linalg.norm(vel)),
                "spin": math.degrees(w),
                "axis": (spin / w).tolist() if w > 0 else [0.0, 0.0, 0.0],
            }
        for ball, _ in self.balls:  # a point: its speed, no spin
            speed = 0.0 if v is None else float(np.linalg.norm(v[ball.node]))
            out[ball.obstacle] = {
                "kind": self.kinds[ball.obstacle],
                "first_contact": self.first[ball.obstacle],
                "speed": speed,
                "ball": True,
            }
        return out


def _ball_contacts(scene, node: int) -> list:
    """The barriers of the ball centred at ``node`` (its ``Ball`` term, and its edge
    barrier where every edge is a capsule)."""
    from catenet.terms.body import Ball

    own = [t for t in scene.terms if isinstance(t, Ball) and t.center == node]
    return own + (_edges(scene, np.array([node])) if scene.edge_radius is not None else [])


def _edges(scene, nodes) -> list:
    """The edge barriers (``catenet.terms.segments.EdgeContact``) riding on ``nodes``."""
    from catenet.terms.segments import EdgeContact

    return [
        t for t in scene.terms if isinstance(t, EdgeContact) and np.array_equal(t.bnodes, nodes)
    ]
