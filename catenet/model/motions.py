"""Prescribed support motions: where the supports are at a time (``support_positions``,
the body of ``Loads.support_positions``), when a motion or load turns a corner
(``corners``), the periods of its sines (``periods``) and how fast it drives the
supports (``drive_speed``), and a vessel's rigid motion that carries several supports at
once (``Vessel``).

A vessel moves as a rigid body by six motions: surge, sway and heave (translations along
its x, y and z axes [m]) and roll, pitch and yaw (rotations about them [rad]), about a
reference point P (its centre of motion, in the given geometry). Its axes are the
world's turned by ``heading`` about z. A support at X in the given geometry is at

    X + T + (R - I) (X - P),   R = Rz(yaw) Ry(pitch) Rx(roll)

(T and R turned by the heading into the world frame): the ship convention's z-y-x
rotation, exact for large angles. The six motions are a table [[t, six motions], ...]
(linear between rows, the first row before it and the last after) plus a sum of sines
a sin(2 pi t / period + phase), all times a smooth start r(t) = (1 - cos(pi t / ramp)) / 2
over the ramp (1 after it): position and velocity start at zero.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from catenet.model.net import Loads, Net

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) [rad]: the ship convention's rotation matrix."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


class Vessel:
    """A vessel's six rigid motions about ``reference`` (3,) [m], its axes turned by
    ``heading`` [rad]: ``table`` (K, 7) rows (t, surge, sway, heave [m], roll, pitch,
    yaw [rad]) or None, ``sines`` (S, 13) rows (period [s], six amplitudes, six phases
    [rad]), ``ramp`` [s] the smooth start (0: none)."""

    __slots__ = ("reference", "heading", "table", "sines", "ramp")

    def __init__(
        self,
        reference: Any,
        heading: float = 0.0,
        table: Any = None,
        sines: Any = (),
        ramp: float = 0.0,
    ):
        self.reference = np.asarray(reference, dtype=np.float64).reshape(3)
        self.heading = float(heading)
        self.table = None if table is None else np.asarray(table, dtype=np.float64).reshape(-1, 7)
        self.sines = np.asarray(sines, dtype=np.float64).reshape(-1, 13)
        self.ramp = float(ramp)

    def motions(self, t: float) -> np.ndarray:
        """(6,) the six motions at time t, the smooth start included [m, rad]."""
        out = np.zeros(6)
        if self.table is not None:
            for k in range(6):
                out[k] = np.interp(t, self.table[:, 0], self.table[:, k + 1])
        for row in self.sines:
            out += row[1:7] * np.sin(2.0 * math.pi * t / row[0] + row[7:13])
        if self.ramp > 0.0:
            out *= 0.0 if t <= 0.0 else 0.5 * (1.0 - math.cos(math.pi * min(t / self.ramp, 1.0)))
        return out

    def displacement(self, points: np.ndarray, t: float) -> np.ndarray:
        """(K, 3) the displacement at time t of the supports given at ``points`` (K, 3)."""
        m = self.motions(t)
        turn = rotation(0.0, 0.0, self.heading)
        spin = turn @ rotation(*m[3:]) @ turn.T
        arm = np.asarray(points, dtype=np.float64) - self.reference
        return (turn @ m[:3])[None, :] + arm @ (spin - np.eye(3)).T

    @property
    def end(self) -> float:
        """The time from which it stands still (infinite with sines)."""
        if len(self.sines):
            return math.inf
        last = 0.0 if self.table is None else float(self.table[-1, 0])
        return max(last, self.ramp)

    def frozen(self, t: float = 0.0) -> Vessel:
        """The vessel held where it is at time t (a run to rest's supports)."""
        row = np.concatenate([[0.0], self.motions(t)])
        return Vessel(self.reference, self.heading, row[None, :], (), 0.0)

    def __repr__(self) -> str:
        return f"Vessel(reference={self.reference.tolist()}, ramp={self.ramp})"


def support_positions(loads: Loads, net: Net, time: float | None, factor: float) -> np.ndarray:
    """Positions of the fixed nodes (K, 3): at ``time`` along each ramp, history, sine
    or vessel (dynamic), or at ``factor`` of their displacement at t = 0 for a sine or
    a vessel and of the final one for the others (static, time None)."""
    x = net.nodes[net.fixed].copy()
    row = np.cumsum(net.fixed) - 1  # a fixed node's row of x
    for nodes, vessel in loads.vessels:
        at = 0.0 if time is None else time
        scale = factor if time is None else 1.0
        x[row[nodes]] += scale * vessel.displacement(net.nodes[nodes], at)
    if loads.support_displacement is None:
        return x
    d = loads.support_displacement[net.fixed]
    if time is None:  # a history in full, a sine motion at its t = 0 value
        at_0 = np.ones(net.n_nodes)
        for nodes, history in loads.support_history:
            at_0[nodes] = getattr(history, "static", 1.0)
        return x + (factor * at_0[net.fixed])[:, None] * d
    ramp = np.zeros(len(d)) if loads.ramp_time is None else loads.ramp_time[net.fixed]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(ramp > 0, np.clip(time / np.where(ramp > 0, ramp, 1.0), 0.0, 1.0), 1.0)
    if loads.support_history:
        full = np.ones(net.n_nodes)
        moved = np.zeros(net.n_nodes, bool)
        for nodes, history in loads.support_history:
            full[nodes] = history(time)
            moved[nodes] = True
        s = np.where(moved[net.fixed], full[net.fixed], s)
    return x + s[:, None] * d


def corners(loads: Loads) -> np.ndarray:
    """The times at which a prescribed motion or load turns a corner (sorted): each point
    of a history or of a vessel's motion table (linear between them) and the end of a
    support's linear ramp. Steps chosen by accuracy end on them (a pulse between two step
    ends was stepped over whole; catenet/solver/adaptive.py)."""
    times: list[float] = []
    histories = [h for _, h in (*loads.parts, *loads.support_history)]
    if loads.gravity is not None and loads.gravity_history is not None:
        histories.append(loads.gravity_history)
    for h in histories:
        times.extend(getattr(h, "times", ()))
    for _, vessel in loads.vessels:
        if vessel.table is not None:
            times.extend(vessel.table[:, 0])
    if loads.support_displacement is not None and loads.ramp_time is not None:
        times.extend(loads.ramp_time[loads.ramp_time > 0.0])
    return np.unique(np.asarray(times, dtype=np.float64))


def ramps(loads: Loads) -> np.ndarray:
    """The pieces of the loads' histories (a load's, gravity's) along which the factor
    changes, (R, 3): start and end times and the change's share of the history's largest
    |factor|. A step across such a piece takes its load at the piece's end (a ramp up
    from rest, taken in one step, gave the pulse's whole impulse for its rising half;
    catenet/solver/adaptive.py)."""
    histories = [h for _, h in loads.parts]
    if loads.gravity is not None and loads.gravity_history is not None:
        histories.append(loads.gravity_history)
    out = set()
    for h in histories:
        if not isinstance(getattr(h, "times", None), np.ndarray):
            continue  # (a sine: smooth)
        top = float(np.max(np.abs(h.factors)))
        change = np.abs(np.diff(h.factors))
        for k in np.flatnonzero(change > 0):
            out.add((float(h.times[k]), float(h.times[k + 1]), float(change[k]) / top))
    return np.asarray(sorted(out), dtype=np.float64).reshape(-1, 3)


def periods(loads: Loads) -> np.ndarray:
    """The periods [s] of the prescribed sines: a support's ``sine``, a vessel's sines."""
    out = [getattr(h, "period", None) for _, h in loads.support_history]
    for _, vessel in loads.vessels:
        out.extend(vessel.sines[:, 0])
    return np.asarray([p for p in out if p is not None], dtype=np.float64)


def drive_speed(loads: Loads, net: Net) -> float:
    """A bound [m/s] on how fast the prescribed motions move a support: a history's
    steepest piece or a sine's 2 pi a / T times the displacement it scales, a ramp's
    displacement over its time, a vessel's motions' rates (its rotations' times the
    farthest support's arm)."""
    speeds = [0.0]
    d = loads.support_displacement
    if d is not None:
        size = np.linalg.norm(d, axis=1)
        timed = np.zeros(net.n_nodes, dtype=bool)
        for nodes, h in loads.support_history:
            timed[nodes] = True
            if hasattr(h, "period"):
                rate = 2.0 * math.pi / h.period + (math.pi / h.ramp if h.ramp > 0 else 0.0)
            else:
                rate = float(np.max(np.abs(np.diff(h.factors) / np.diff(h.times)), initial=0.0))
            speeds.append(rate * float(np.max(size[nodes], initial=0.0)))
        if loads.ramp_time is not None:
            ramped = ~timed & (loads.ramp_time > 0.0)
            speeds.extend((size[ramped] / loads.ramp_time[ramped]).tolist())
    for nodes, vessel in loads.vessels:
        arm = float(np.max(np.linalg.norm(net.nodes[nodes] - vessel.reference, axis=1)))
        rates = np.zeros(6)
        if vessel.table is not None and len(vessel.table) > 1:
            slope = np.diff(vessel.table[:, 1:], axis=0) / np.diff(vessel.table[:, :1], axis=0)
            rates = np.max(np.abs(slope), axis=0)
        for row in vessel.sines:
            rates = rates + np.abs(row[1:7]) * 2.0 * math.pi / row[0]
        speeds.append(float(np.linalg.norm(rates[:3]) + np.linalg.norm(rates[3:]) * arm))
    return max(speeds)
