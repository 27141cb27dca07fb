"""What the scene builder takes of a ball or a free body (``Mover``), of an obstacle the
bodies meet (``Fixed``), what it records of a ball (``Body``), and the loads padded for
the bodies' nodes (``pad_loads``): ``catenet.scene.bodies``, ``catenet.scene.rigid``,
``catenet.scene.touching``."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.model.net import Loads
from catenet.scene.contact import Contact

if TYPE_CHECKING:
    from catenet.scene.shapes import Shape
    from catenet.terms.base import Term


@dataclass(frozen=True)
class Mover:
    """A body the builder adds (module docstring): its obstacle ``index`` (its
    ``obstacle[k]`` in messages), ``shape``, ``contact`` (distance, stiffness, friction,
    slip), and its motion and mass: a free body (``free``) has ``mass`` or ``density``
    [kg, kg/m^3], an optional ``inertia`` (3, 3) [kg m^2] about its centre of mass in its
    body axes, an initial ``velocity`` and ``angular_velocity``; a ball has ``mass`` (None:
    on the path ``velocity`` [m/s] scaled by ``history``)."""

    index: int
    shape: Shape
    contact: Contact
    free: bool
    mass: float | None = None
    density: float | None = None
    inertia: np.ndarray | None = None
    velocity: tuple[float, ...] | None = None
    angular_velocity: tuple[float, ...] | None = None
    history: tuple[tuple[float, float], ...] | None = None
    placed: Any = None  # its shape's origin key as its case file gives it (messages)

    @property
    def path(self) -> str:
        return f"obstacle[{self.index}]"


@dataclass(frozen=True)
class Fixed:
    """An obstacle the bodies meet: its index, shape and contact (``Scene.obstacles``)."""

    index: int
    shape: Shape
    contact: Contact

    def term(self, nodes: Any, kappa: float, dhat: float, offset: float = 0.0) -> Term:
        """Its barrier on ``nodes`` (centres of balls of radius ``offset``)."""
        return placed_barrier(self.shape, self.contact, nodes, kappa, dhat, offset)


@dataclass(frozen=True)
class StruckBy:
    """A solid's own barrier with an obstacle or another solid (``term.struck_by``): the
    solid that strikes (``head``: its first node, whose momentum scale it is judged
    by), the other's nodes (``carry``: none for a fixed obstacle), the mass [kg] that
    strikes (the pair's reduced mass) and ``who`` (the pair in messages)."""

    head: int
    carry: tuple[int, ...]
    mass: float
    who: str


def impact_energy(owner: Mover | Fixed, mass: float, gravity: float, height: float) -> float:
    """An upper bound [J] of the energy a solid brings to an impact: its initial motion's
    (its spin about a radius of its size) and its weight's work over ``height`` (0 for a
    fixed obstacle or a solid without mass)."""
    if not isinstance(owner, Mover) or mass <= 0:
        return 0.0
    v = np.asarray(owner.velocity or (0.0, 0.0, 0.0), dtype=np.float64)
    w = np.asarray(owner.angular_velocity or (0.0, 0.0, 0.0), dtype=np.float64)
    points, _, radius = owner.shape.outline()
    reach = float(np.linalg.norm(points - points.mean(axis=0), axis=1).max()) + radius
    kinetic = 0.5 * mass * (float(v @ v) + float(w @ w) * reach * reach)
    return kinetic + mass * gravity * height


def placed_barrier(
    shape: Shape, contact: Contact, nodes: Any, kappa: float, dhat: float, offset: float = 0.0
) -> Term:
    """The barrier of ``shape`` on ``nodes`` (centres of balls of radius ``offset``: the
    shape grown by it), on the contact's prescribed motion if any."""
    from catenet.scene.contact import moving

    return moving(shape.barrier(nodes, kappa, dhat, offset), shape, contact, offset)


@dataclass(frozen=True)
class Body:
    """A moving sphere as the result file records it: its ``node`` (the centre), the
    obstacle it comes from, radius [m], mass [kg] and whether it follows a prescribed
    path."""

    node: int
    obstacle: int
    radius: float
    mass: float
    prescribed: bool


def pad_loads(loads: Loads, nb: int) -> Loads:
    """The loads with ``nb`` unloaded, unsupported nodes appended."""

    def pad(a: np.ndarray | None, width: int = 3) -> np.ndarray | None:
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
