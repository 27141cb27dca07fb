"""Coulomb friction on a rigid obstacle: a lagged dissipative potential per step.

The friction term rides on an obstacle's barrier term (``catenet.terms.contact``). At the
start of every static load step and dynamic time step (``begin_step``, at the last
accepted state) it stores, for every node the obstacle acts on, the normal force lambda
the barrier exerts there, the unit normal, and the node's anchor: where it sticks. Within
the step the potential is D(x) = sum mu_f lambda f(|P (x - a)|) (``catenet.kernels.
friction``), f a C2 smoothing of |u| that is quadratic below the slip distance eps.

Guarantees, for each node in contact:

- the friction force never exceeds mu_f times the (lagged) normal force, and it opposes
  the tangential displacement from the anchor;
- static sticking: a node whose tangential load stays below mu_f lambda stays within eps
  of its anchor for the whole run, over any number of steps (the anchor moves only when
  a node slid farther than eps, and then to eps behind it: sticking nodes do not creep,
  as they would if the displacement were measured from each step's start);
- a sliding node feels the full kinetic force mu_f lambda against its motion;
- D is convex in x within a step (lambda, n and a are fixed), so Newton's matrix stays
  positive semidefinite and Cholesky is allowed.

In a dynamic step the lag is the usual one of incremental-potential contact: lambda is
the normal force at the step's start, and a node that touches down during a step feels
friction from the next step on. A static load step has no time: it is re-solved with
lambda and n taken at its equilibrium (``relag``; ``catenet.solver.static``) until they agree,
so a static result does not depend on the lag (nor, much, on the number of load steps).

On an obstacle on a prescribed rigid motion (``catenet.terms.moving``: a conveyor, a
tumbling box) friction acts against motion relative to the obstacle's surface: lambda, the
normals and the anchors are taken at the step's start with the obstacle at its pose
then, and the anchors and normals ride with the obstacle to its pose at the step's end,
where the step is solved. A node sticking to a moving obstacle is carried along with it;
a sliding one feels mu_f lambda against its slip over the surface. The normals are a
plane's normal and a sphere's radial direction, else the direction of the barrier's
gradient, the gradient of its gap (the only normals that matter are those where the
barrier acts).
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.friction import (
    friction_gradient,
    friction_hessian,
    normal_forces,
    update_anchors,
)
from catenet.terms.base import Term, node_block_pattern, register
from catenet.terms.contact import PlaneBarrier, SphereBarrier


def contact_normals(obstacle, x: np.ndarray) -> np.ndarray:
    """Unit outward normals (K, 3) of ``obstacle`` at its nodes' positions in x: the
    plane's normal, the sphere's radial direction, else the direction of the barrier's
    force (minus its gradient: the gap's gradient) where the barrier acts and +z
    elsewhere, where no normal force needs one."""
    if isinstance(obstacle, PlaneBarrier):
        return np.ascontiguousarray(np.broadcast_to(obstacle.normal, (len(obstacle.nodes), 3)))
    if isinstance(obstacle, SphereBarrier):
        r = x[obstacle.nodes] - obstacle.center
        return np.ascontiguousarray(r / np.linalg.norm(r, axis=1)[:, None])
    grad = np.zeros_like(x)
    obstacle.gradient(x, grad)
    g = -grad[obstacle.nodes]
    size = np.linalg.norm(g, axis=1)
    out = np.zeros_like(g)
    out[:, 2] = 1.0
    acts = size > 0.0
    out[acts] = g[acts] / size[acts, None]
    return out


@register("friction")
class Friction(Term):
    """Coulomb friction with coefficient ``mu`` (>= 0) and slip distance ``slip`` [m] on
    the nodes of ``obstacle`` (a barrier term with nodes, kappa, dhat and gap)."""

    lagged = True

    role = "internal"
    convex = True

    def __init__(self, obstacle, *, mu: float, slip: float):
        if not (math.isfinite(mu) and mu >= 0):
            raise ValueError(f"friction: mu = {mu!r}: must be finite and >= 0")
        if not (math.isfinite(slip) and slip > 0):
            raise ValueError(f"friction: slip = {slip!r}: must be finite and > 0")
        self.obstacle = self.rides_on = obstacle
        self.nodes = obstacle.nodes
        self.mu = float(mu)
        self.slip = float(slip)
        k = len(self.nodes)
        self.normal_force = np.zeros(k)  # lambda at the step's start [N]
        self.weight = np.zeros(k)  # mu lambda
        self.normal = np.zeros((k, 3))
        self.normal[:, 2] = 1.0
        self.anchor = np.zeros((k, 3))
        self.dragged = 0  # anchors dragged at the last step's start (nodes that slid)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return node_block_pattern(self.nodes)

    def begin_step(self, x: np.ndarray, time: float | None, start: float | None = None) -> None:
        """The lagged normal forces, normals and anchors at the accepted state x (time
        ``start``); on a moving obstacle, carried with it to its pose at ``time``."""
        obs = self.obstacle
        moves = time is not None and start is not None and obs.moving
        if moves:
            obs.set_pose(start)  # the pose of the accepted state
        was = self.weight > 0.0
        normal_forces(np.ascontiguousarray(obs.gap(x)), obs.kappa, obs.dhat, self.normal_force)
        np.multiply(self.mu, self.normal_force, out=self.weight)
        self.normal[:] = contact_normals(obs, x)
        self.dragged = update_anchors(
            x, self.nodes, self.normal, self.weight, was, self.anchor, self.slip
        )
        if moves:  # the obstacle's rigid motion over the step
            c0, R0 = obs.pose(start)
            c1, R1 = obs.pose(time)
            turn = R1 @ R0.T
            self.anchor[:] = c1 + (self.anchor - c0) @ turn.T
            self.normal[:] = self.normal @ turn.T
            obs.set_pose(time)  # where the step is solved

    def relag(self, x: np.ndarray) -> float:
        """Normal forces and normals taken at x instead of the step's start (anchors
        kept): a static load step re-solved until they agree with its equilibrium.
        Returns the largest change of a normal force over the largest one."""
        obs = self.obstacle
        old = self.normal_force.copy()
        normal_forces(np.ascontiguousarray(obs.gap(x)), obs.kappa, obs.dhat, self.normal_force)
        np.multiply(self.mu, self.normal_force, out=self.weight)
        self.normal[:] = contact_normals(obs, x)
        top = max(float(np.max(self.normal_force, initial=0.0)), float(np.max(old, initial=0.0)))
        return float(np.max(np.abs(self.normal_force - old), initial=0.0)) / top if top > 0 else 0.0

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        return friction_gradient(
            x, self.nodes, self.anchor, self.normal, self.weight, self.slip, grad
        )

    def hessian(self, x: np.ndarray, values: np.ndarray) -> bool:
        args = (x, self.nodes, self.anchor, self.normal, self.weight, self.slip, values)
        return friction_hessian(*args) > 0

    def forces(self, x: np.ndarray) -> np.ndarray:
        """The friction force (N, 3) on every node at x (minus the gradient)."""
        grad = np.zeros_like(x)
        self.gradient(x, grad)
        return -grad

    def sticking(self, x: np.ndarray) -> np.ndarray:
        """Per node of the obstacle: in contact and within the slip distance of its
        anchor at x."""
        r = x[self.nodes] - self.anchor
        u = r - np.sum(r * self.normal, axis=1)[:, None] * self.normal
        return (self.weight > 0.0) & (np.linalg.norm(u, axis=1) <= self.slip)
