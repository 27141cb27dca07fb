"""The fixed and prescribed-motion obstacles of a case (``[[obstacle]]`` tables, as the
resolved case gives them: ``Declared.to_dict`` or the TOML a result file stores) as
surfaces in world coordinates, at any time: what ``catenet plot`` draws
(``catenet.plot.obstacles``) and what a result file stores for ParaView
(``catenet.output.obstacles``).

A surface is its vertices at t = 0 and its faces, oriented outward (towards the free
side: counter-clockwise seen from there): quads for the plane, the sphere, the box and
the capsule (a quad at a pole repeats a vertex), triangles for a mesh;
``Surface.triangles`` splits the quads. Each shape draws itself
(``catenet.scene.shapes``, its ``surface_mesh``): a box its 8 corners and 6 faces, a
sphere 36 meridians and 18 parallels of quads, a capsule 36 meridians with 9 parallels on
each end ball, a mesh its file as the solver reads it. A plane is
infinite: its surface is the quad covering the given points (the net) 1.5 times in its
plane, or none when no points are given (``catenet plot`` cuts it to its views).

A box, capsule or mesh on a prescribed rigid motion (``velocity``, ``angular_velocity``,
``history``) has a ``Motion``: its pose at time t is the solver's own
(``catenet.terms.moving.Moving.pose``, from the same reference point and keys), so that
the surface drawn or stored at a frame is where the barrier had the obstacle. Moving
spheres (a ``mass`` or a path's ``velocity``) are nodes of the net, not surfaces here
(``catenet.output.bodies``, ``catenet.plot.bodies``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Motion", "Surface", "is_body", "is_free", "surface"]


def _vec(d: dict, key: str, default=None) -> np.ndarray | None:
    v = d.get(key, default)
    return None if v is None else np.asarray(v, dtype=np.float64).reshape(3)


def is_body(d: dict) -> bool:
    """A moving sphere: a node of the net (a rigid ball or a ball on a path)."""
    return (
        d.get("kind") == "sphere"
        and (d.get("mass") is not None or d.get("velocity") is not None)
        and not is_free(d)
    )


def is_free(d: dict) -> bool:
    """A free rigid body (``catenet.scene.rigid``): it moves as the solver finds, its
    pose is read from the state (``catenet.output.obstacles``), never a ``Motion``."""
    if d.get("density") is not None:
        return True
    if d.get("mass") is None:
        return False
    spins = any(d.get(k) is not None for k in ("inertia", "angular_velocity"))
    return d.get("kind") != "sphere" or spins


class Motion:
    """The prescribed rigid motion of an obstacle table ``d`` about its reference point
    ``origin`` (a box's centre, a capsule's axis midpoint, a mesh's ``offset``): the
    pose (c(t), R(t)) of ``catenet.terms.moving.Moving``, the term the solver steps."""

    def __init__(self, d: dict, origin):
        from catenet.terms.moving import Moving

        history = None
        if d.get("history") is not None:
            from catenet.model.histories import History

            history = History(d["history"], path="history")
        # Moving's pose needs no shape: a stand-in with what its constructor reads
        still = type("Still", (), {"nodes": np.zeros(0, np.int64), "kappa": 0.0, "dhat": 0.0})
        self.origin = np.asarray(origin, dtype=np.float64)
        self._term = Moving(
            still(), self.origin, _vec(d, "velocity"), _vec(d, "angular_velocity"), history,
            reach=1.0,
        )  # fmt: skip

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(c(t), R(t)): where the reference point is and how the body is turned."""
        return self._term.pose(float(t))

    def place(self, points, t: float, pose=None) -> np.ndarray:
        """Points (K, 3) of the body at its t = 0 pose where the motion has them at t
        (``pose``: ``pose(t)``, when known)."""
        c, R = self.pose(t) if pose is None else pose
        return c + (np.asarray(points) - self.origin) @ R.T


@dataclass(frozen=True)
class Surface:
    """Obstacle ``index`` of a case (its ``kind``) at t = 0: ``vertices`` (V, 3) and
    ``faces`` (F, 4) quads or (F, 3) triangles, outward; ``motion`` None when fixed. A
    plane also has ``point`` and unit ``normal`` (its vertices may be empty)."""

    index: int
    kind: str
    vertices: np.ndarray
    faces: np.ndarray
    motion: Motion | None = None
    point: np.ndarray | None = None
    normal: np.ndarray | None = None

    @property
    def moving(self) -> bool:
        return self.motion is not None

    @property
    def label(self) -> str:
        return f"obstacle[{self.index}]: {'moving ' if self.moving else ''}{self.kind}"

    def at(self, t: float) -> np.ndarray:
        """The vertices at time t (those at t = 0 for a fixed obstacle)."""
        return self.vertices if self.motion is None else self.motion.place(self.vertices, t)

    @property
    def triangles(self) -> np.ndarray:
        """The faces as triangles (T, 3), outward: quads split along their first
        diagonal, those with a repeated vertex (at a pole) left out."""
        return triangles(self.faces)


def triangles(faces) -> np.ndarray:
    """Quads (F, 4) or triangles (F, 3) as triangles (T, 3) without repeated vertices."""
    F = np.asarray(faces, dtype=np.int64)
    if F.shape[1] == 4:
        F = np.concatenate([F[:, [0, 1, 2]], F[:, [0, 2, 3]]])
    keep = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])
    return np.ascontiguousarray(F[keep])


def surface(d: dict, index: int, cover=None) -> Surface | None:
    """Obstacle ``index``, the table ``d`` of a resolved case, as a ``Surface`` (None for
    a moving sphere, which is a node of the net). ``cover``: the points (the net) a
    plane's quad covers (None: a plane without vertices). Raises KeyError, TypeError or
    ValueError for a table it cannot build (a mesh file gone: ValueError)."""
    from catenet.scene.shapes import shape_of
    from catenet.scene.shapes.plane import Plane

    if is_body(d):
        return None
    shape = shape_of(d)
    V, F = shape.surface_mesh(cover)
    if isinstance(shape, Plane):  # infinite: drawn over the cover, cut to a plot's views
        return Surface(index, shape.kind, V, F, point=shape.point, normal=shape.unit_normal)
    moving = d.get("velocity") is not None or d.get("angular_velocity") is not None
    moving = moving and not is_free(d) and shape.kind != "sphere"  # a moving sphere: a node
    return Surface(index, shape.kind, V, F, Motion(d, shape.origin) if moving else None)
