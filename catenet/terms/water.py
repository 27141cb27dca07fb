"""Water on a net: buoyancy (``Buoyancy``) and the Morison forces of the flow around
each edge (``WaterForce``: drag, added mass, the water's own acceleration).

``Buoyancy`` is conservative: the weight of the displaced water of the wetted part of
every edge, rho_w g A l0 times the share below the still level, that share smoothed
over the cable's hydrodynamic diameter (``catenet.kernels.water``): convex, exact
gradient and Hessian, bounded whatever the edge's slope.

``WaterForce`` acts at each node through half of each of its edges (a lumped line, as
MoorDyn's; at a support, the drag and the flow's force enter its reaction, as the half
edges' weight does, the added mass not): with u the node's velocity relative to the
water, t the edge's tangent and l its stretched length,

    drag        -1/2 rho_w d (cd_n |u_n| u_n + pi cd_t |u_t| u_t) l / 2
    added mass  -rho_w A (l0 / 2) (ca_n a_n + ca_t a_t)      (a: the node's acceleration)
    flow        +rho_w A (l0 / 2) ((1 + ca_n) a_w,n + ca_t a_w,t)   (a_w: the water's)

each times the wetted share of the node (the smoothed share of ``Buoyancy`` at its
depth). Drag is not a potential force; within one time step it is one: the scheme's
velocity is affine in the step's positions, v = k (x - c) (implicit Euler: k = 1/h,
c = x_n), so with t, l, the water's velocity and acceleration and the wetted shares
taken at the step's start (lagged, as friction's normal forces are), the step's drag is
the gradient of the convex potential (c_n |P u|^3 + c_t |t.u|^3) / (3 k), whose Hessian
is exact (``catenet.kernels.water``), and the added mass that of
1/2 k_a (x - c_a)^T M_a (x - c_a), the scheme's acceleration k_a (x - c_a): Newton
converges quadratically, the matrix stays positive semidefinite. The lag costs O(h) on
the tangents and the flow seen, the order of implicit Euler itself.

A static step (no velocity) sees the drag of the current on the cable at rest, with the
tangents of the step's start; it is re-solved with the tangents of its equilibrium until
they agree (``relag``, as friction's). Waves act in dynamic runs only. Both terms are
loads: a static run's load steps scale them with the load factor (``scaled``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from catenet.kernels.water import (
    added_gradient,
    buoyancy_gradient,
    buoyancy_hessian,
    drag_gradient,
    drag_hessian,
)
from catenet.model.water import Hydro, Water, added_mass_blocks
from catenet.terms.base import Term, node_block_pattern, register

#: A wave whose amplitude is at least this share of the largest's sets the steps chosen
#: by accuracy (``WaterForce.periods``): of a JONSWAP sea (gamma 3.3, 200 components from
#: 0.5 to 3 times its peak frequency), those up to 2.5 times it
WAVE_SHARE = 0.1

if TYPE_CHECKING:
    from catenet.model.net import Net


def wetted_share(depth: np.ndarray, half: np.ndarray) -> np.ndarray:
    """The share of a node's cable below the still level at ``depth`` below it: 0 above
    -half, 1 below +half, linear across (Psi' of ``catenet.kernels.water``)."""
    return np.clip((depth + half) / (2.0 * half), 0.0, 1.0)


@register("buoyancy")
class Buoyancy(Term):
    """The displaced water's weight on the wetted part of every edge (module docstring)."""

    loadlike = True  # a load: a static run's load factor scales it
    weighs = True  # the displaced water's weight: it follows gravity's history

    def __init__(self, net: Net, water: Water, hydro: Hydro):
        self.edges = np.ascontiguousarray(net.edges, dtype=np.int64)
        self.weight = np.ascontiguousarray(water.density * water.g * hydro.area * net.rest_length)
        self.half = np.ascontiguousarray(0.5 * hydro.diameter, dtype=np.float64)
        self.surface = float(water.surface)
        self.factor = 1.0
        self._scaled = self.weight
        # E counts from the reference positions (a constant: forces unchanged), so that
        # the energy balance compares energies of the motion's size, not of the depth
        scratch = np.zeros_like(net.nodes)
        self._nodes = net.nodes
        self._zero = float(
            buoyancy_gradient(net.nodes, self.edges, self.weight, self.half, self.surface, scratch)
        )
        self._zero_scaled = self._zero

    def set_factor(self, factor: float) -> None:
        self.factor = float(factor)
        self._scaled = self.weight * self.factor
        scratch = np.zeros((len(self._nodes), 3))
        self._zero_scaled = float(
            buoyancy_gradient(
                self._nodes, self.edges, self._scaled, self.half, self.surface, scratch
            )
        )  # (the same sum as the energy's: E is 0 at the reference at every factor)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        zi, zj = 3 * self.edges[:, 0] + 2, 3 * self.edges[:, 1] + 2
        rows = np.stack([zi, zi, zj, zj], axis=1).ravel()
        cols = np.stack([zi, zj, zi, zj], axis=1).ravel()
        return rows, cols

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        e = buoyancy_gradient(x, self.edges, self._scaled, self.half, self.surface, grad)
        return float(e) - self._zero_scaled

    def unit_energy(self, x: np.ndarray) -> float:
        """The energy at x per unit factor: what a change of the factor at x adds (the
        energy balance books it as work)."""
        scratch = np.zeros_like(x)
        e = buoyancy_gradient(x, self.edges, self.weight, self.half, self.surface, scratch)
        return float(e) - self._zero

    def hessian(self, x: np.ndarray, values: np.ndarray) -> bool:
        buoyancy_hessian(x, self.edges, self._scaled, self.half, self.surface, values)
        return True

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        level = float(np.linalg.norm(self._scaled))
        z = np.abs(x[self.edges, 2]).sum(axis=1)
        return level, float(np.sum(self._scaled * (abs(self.surface) + 0.5 * z)))


@register("water")
class WaterForce(Term):
    """Drag, added mass and the flow's inertia at every node (module docstring)."""

    lagged = True  # static steps: re-solved with the tangents of their equilibrium
    medium = True  # has begin_run, set_motion, kinetic, losses (catenet.terms.base)
    loadlike = True

    def __init__(self, net: Net, water: Water, hydro: Hydro):
        self.net, self.water = net, water
        free = ~net.fixed
        m = net.n_edges
        ends = np.concatenate([net.edges[:, 0], net.edges[:, 1]])
        edge = np.concatenate([np.arange(m), np.arange(m)])
        # every half edge, a support's too: its drag and the flow's force there go to the
        # support's reaction, as its weight does (the current on a line between two
        # supports summed 2.5 % short of q L at 40 edges); its added mass does not (a
        # support carries no inertia of its own in the reactions)
        self.nodes = np.ascontiguousarray(ends, dtype=np.int64)
        self.edge = edge
        self.carried = free[ends].astype(np.float64)  # 1: the half edge's node is free
        self.held = np.flatnonzero(net.fixed)
        rho, d = water.density, hydro.diameter[self.edge]
        self.cn0 = 0.5 * rho * hydro.cd_n[self.edge] * d  # per stretched length
        self.ct0 = 0.5 * rho * hydro.cd_t[self.edge] * math.pi * d
        volume = hydro.area[self.edge] * 0.5 * net.rest_length[self.edge]  # per half edge
        self.ca_n, self.ca_t = hydro.ca_n[self.edge], hydro.ca_t[self.edge]
        self.mass0 = rho * volume  # the displaced water's mass of each half edge
        self.half = 0.5 * d
        self.free_nodes = np.flatnonzero(free)
        self.slot = np.arange(net.n_nodes, dtype=np.int64)  # every node's block (a
        # support's too: the drag's derivative there; the solver keeps the free rows)
        n = net.n_nodes
        self.factor = 1.0
        self.kv = self.ka = 0.0  # 0: a static step (the cable at rest)
        self.centre = np.zeros((n, 3))
        self.centre_a = np.zeros((n, 3))
        self._lag(net.nodes, None)
        self._drag = self.still.copy()  # the drag at the last step's end (``losses``)
        self._booked = self.added  # the blocks of the last step booked (``relagged``)

    # --- the lagged state ------------------------------------------------------------
    def _lag(self, x: np.ndarray, t: float | None) -> None:
        """Tangents, lengths, wetted shares, the flow at the nodes at time t (None: the
        current alone), the added-mass blocks, the flow's inertia force and the current's
        drag on the cable at rest, all at the positions x."""
        e = self.net.edges[self.edge]
        ev = x[e[:, 1]] - x[e[:, 0]]
        length = np.linalg.norm(ev, axis=1)
        self.tang = np.ascontiguousarray(ev / np.where(length > 0, length, 1.0)[:, None])
        wet = wetted_share(self.water.surface - x[self.nodes, 2], self.half)
        self.cn = np.ascontiguousarray(self.cn0 * 0.5 * length * wet)
        self.ct = np.ascontiguousarray(self.ct0 * 0.5 * length * wet)
        self.flow, acc = self.water.flow(x, t)
        n = self.net.n_nodes
        mass = self.mass0 * wet
        moved = mass * self.carried
        normal, axial = moved * self.ca_n, moved * self.ca_t
        self.added = added_mass_blocks(n, self.nodes, self.tang, normal, axial)
        a = acc[self.nodes]
        along = np.sum(a * self.tang, axis=1)
        lateral = a - along[:, None] * self.tang
        push = mass[:, None] * ((1.0 + self.ca_n)[:, None] * lateral)
        push += (mass * self.ca_t * along)[:, None] * self.tang
        self.inflow = np.zeros((n, 3))
        np.add.at(self.inflow, self.nodes, push)
        self._pushed = bool(np.any(self.inflow[self.held]))
        drag = np.zeros((n, 3))
        drag_gradient(x, self.nodes, self.tang, self.cn, self.ct, self.flow, x, 0.0, drag)
        self.still = -drag  # the current's drag on the cable at rest

    def set_factor(self, factor: float) -> None:
        self.factor = float(factor)

    def begin_step(self, x: np.ndarray, time: float | None, start: float | None = None) -> None:
        """A static step (``time`` None): the current on the cable at rest; a time step:
        the flow at its end, the tangents at its start (``set_motion`` then gives the
        scheme's velocity)."""
        if time is None:
            self.kv = self.ka = 0.0
            self._lag(x, None)
            self.inflow[:] = 0.0
        else:
            self._lag(x, time)

    def begin_run(self, x: np.ndarray, t: float) -> None:
        """A dynamic run's start state at rest at time t (before its first step)."""
        self.kv = self.ka = 0.0
        self.factor = 1.0
        self._lag(x, t)
        self._drag = self.still.copy()  # the drag at the start (the cable at rest)
        self._booked = self.added

    def set_motion(self, kv: float, centre: np.ndarray, ka: float, centre_a: np.ndarray) -> None:
        """The scheme's velocity kv (x - centre) and acceleration ka (x - centre_a) of
        this step's positions x (N, 3)."""
        self.kv, self.ka = float(kv), float(ka)
        self.centre[:] = centre
        self.centre_a[:] = centre_a

    def relag(self, x: np.ndarray) -> float:
        old = self.still.copy()
        self._lag(x, None)
        self.inflow[:] = 0.0
        scale = float(np.linalg.norm(self.still))
        return 0.0 if scale == 0.0 else float(np.linalg.norm(self.still - old)) / scale

    # --- the term --------------------------------------------------------------------
    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return node_block_pattern(self.slot)

    def _static_force(self) -> np.ndarray:
        return (self.still + self.inflow) * self.factor

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        if self.kv == 0.0:
            f = self._static_force()
            grad -= f
            return -float(np.sum(f * x))
        energy = float(
            drag_gradient(
                x, self.nodes, self.tang, self.cn, self.ct, self.flow, self.centre, self.kv, grad
            )
        )
        if self._pushed:  # the flow's force at the supports (waves)
            held = self.inflow[self.held]
            grad[self.held] -= held
            energy -= float(np.sum(held * x[self.held]))
        return energy + float(
            added_gradient(
                x, self.free_nodes, self.added, self.centre_a, self.ka, self.inflow, grad
            )
        )

    def hessian(self, x: np.ndarray, values: np.ndarray) -> bool:
        values[:] = 0.0
        if self.kv == 0.0:
            return False
        drag_hessian(
            x,
            self.nodes,
            self.tang,
            self.cn,
            self.ct,
            self.flow,
            self.centre,
            self.kv,
            self.slot,
            values,
        )
        values += self.ka * self.added.reshape(-1)
        return True

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """The forces' scale (the current's and flow's forces, the drag at the step's
        velocities, the added mass's ka M (|x| + |c_a|)) and the energy's."""
        level = self.factor * float(np.linalg.norm(self.still)) + float(np.linalg.norm(self.inflow))
        if self.kv == 0.0:
            return level, abs(energy)
        at = self.nodes
        speed = self.kv * np.abs(x[at] - self.centre[at]).sum(axis=1)
        speed += np.abs(self.flow[at]).sum(axis=1)
        drag = (self.cn + self.ct) * speed * speed
        mass = np.trace(self.added, axis1=1, axis2=2)
        size = np.abs(x).sum(axis=1) + np.abs(self.centre_a).sum(axis=1)
        level += float(np.linalg.norm(drag)) + self.ka * float(np.linalg.norm(mass * size))
        return level, abs(energy) + self.ka * float(np.sum(mass * size * size))

    # --- the energy balance (catenet.solver.energy) ----------------------------------
    def mass_blocks(self) -> np.ndarray:
        """(N, 3, 3) the added mass at each node (the step's, or the start's) [kg]."""
        return self.added

    def kinetic(self, v: np.ndarray) -> float:
        """1/2 v^T M_a v: the kinetic energy of the water the net carries along."""
        return 0.5 * float(np.einsum("ni,nij,nj->", v, self.added, v))

    def periods(self) -> tuple[float, ...]:
        """The periods of the waves whose amplitude is at least WAVE_SHARE of the
        largest's (a sea's tail, too small to drive the line, left out)."""
        waves = self.water.waves
        largest = max((w.amplitude for w in waves), default=0.0)
        return tuple(2.0 * math.pi / w.omega for w in waves if w.amplitude >= WAVE_SHARE * largest)

    def relagged(self, v: np.ndarray, commit: bool = True) -> float:
        """1/2 v^T (M_a - M_a') v, M_a' the blocks of the last step booked: the water's
        added mass turns with the tangents from step to step, which changes the kinetic
        energy it carries at the same velocities. The ledger books that as the water's
        work; left in its balance, each step showed it as energy the integrator removed,
        however short the step (a rope pulled through water failed at tolerance 3e-4)."""
        jump = 0.5 * float(np.einsum("ni,nij,nj->", v, self.added - self._booked, v))
        if commit:
            self._booked = self.added
        return jump

    def losses(
        self,
        x_old: np.ndarray,
        x_new: np.ndarray,
        h: float,
        mean: bool = False,
        commit: bool = True,
    ) -> tuple[float, float]:
        """(dissipated, work) of the step from x_old to x_new of length h: the drag's
        work against the motion relative to the water, -F.(dx - h U) (>= 0 for implicit
        Euler), and the water's work on the net, F.(h U) of the drag and the flow's
        inertia force's F_w.dx; at a support's node all of F.dx is the water's work (the
        support's reaction carries the force there, and the ledger books its work: the
        two cancel, as before the drag there entered the reactions). ``mean``: F the
        mean of the step's two ends (the second-order schemes' rule, as the ledger takes
        their damping); ``commit``: the step is accepted (its end's force starts the
        next step's mean)."""
        g = np.zeros_like(x_new)
        if self.kv == 0.0:
            force = self.still * self.factor
        else:
            drag_gradient(
                x_new, self.nodes, self.tang, self.cn, self.ct, self.flow, self.centre, self.kv, g
            )
            force = -g
        used = 0.5 * (force + self._drag) if mean else force
        if commit:
            self._drag = force
        dx = x_new - x_old
        carried = h * self.flow
        held = self.held  # at a support's node, all of F.dx is the water's work there
        moved = used.copy()  # (its reaction pays it: no loss of the net's motion)
        moved[held] = 0.0
        dissipated = -float(np.sum(moved * (dx - carried)))
        work = float(np.sum(moved * carried)) + float(np.sum(self.inflow * dx))
        return dissipated, work + float(np.sum(used[held] * dx[held]))
