"""The fixed and prescribed-motion obstacles of a case (``[[obstacle]]`` tables, as the
resolved case gives them: ``Declared.to_dict`` or the TOML a result file stores) as
surfaces in world coordinates, at any time: what ``catenet plot`` draws
(``catenet.plot.obstacles``) and what a result file stores for ParaView
(``catenet.output.obstacles``).

A surface is its vertices at t = 0 and its faces, oriented outward (towards the free
side: counter-clockwise seen from there): quads for the plane, the sphere, the box and
the capsule (a quad at a pole repeats a vertex), triangles for a mesh;
``Surface.triangles`` splits the quads. A box is its 8 corners and 6 faces, a sphere 36
meridians and 18 parallels of quads, a capsule 36 meridians with 9 parallels on each end
ball, a mesh its file as the solver reads it (``catenet.case.shapes``). A plane is
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

SEGMENTS = 36  # meridians of a sphere or capsule
SPHERE_RINGS = 18  # parallels of a sphere, pole to pole
CAP_RINGS = 9  # parallels of each of a capsule's end balls, pole to equator
PLANE_COVER = 1.5  # a plane's quad covers the net's extent in it this many times

#: A box's faces: corner 4 i + 2 j + k is at -/+ the half size along its axes for
#: i, j, k = 0/1 (x, y, z), each face counter-clockwise seen from outside.
BOX_FACES = np.array(
    [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]],
    dtype=np.int64,
)
_SIGNS = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)

__all__ = ["Motion", "Surface", "is_body", "is_free", "surface"]


def _vec(d: dict, key: str, default=None) -> np.ndarray | None:
    v = d.get(key, default)
    return None if v is None else np.asarray(v, dtype=np.float64).reshape(3)


def _req(d: dict, key: str, default=None) -> np.ndarray:
    """``_vec`` of a key the surface needs (KeyError where it is missing)."""
    v = _vec(d, key, default)
    if v is None:
        raise KeyError(key)
    return v


def is_body(d: dict) -> bool:
    """A moving sphere: a node of the net (a rigid ball or a ball on a path)."""
    return (
        d.get("kind") == "sphere"
        and (d.get("mass") is not None or d.get("velocity") is not None)
        and not is_free(d)
    )


def is_free(d: dict) -> bool:
    """A free rigid body (``catenet.case.rigid``): it moves as the solver finds, its
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


def _lathe(axis_points, radii, axis, n: int = SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """The surface swept by a profile about an axis: ``axis_points`` (m + 1, 3) on the
    axis with ``radii`` (m + 1,), 0 at both ends (the poles), ``axis`` from the first to
    the last; quads between consecutive parallels of n vertices."""
    e = np.asarray(axis, dtype=np.float64)
    e = e / np.linalg.norm(e)
    p = np.cross(e, [1.0, 0.0, 0.0] if abs(e[0]) < 0.9 else [0.0, 1.0, 0.0])
    p /= np.linalg.norm(p)
    q = np.cross(e, p)
    u = 2 * np.pi * np.arange(n) / n
    ring = np.cos(u)[:, None] * p + np.sin(u)[:, None] * q  # (n, 3)
    m = len(radii) - 1
    inner = axis_points[1:m, None, :] + radii[1:m, None, None] * ring[None]  # (m - 1, n, 3)
    V = np.concatenate([axis_points[:1], inner.reshape(-1, 3), axis_points[m:]])

    def index(i, c):
        c = c % n
        return np.where(i == 0, 0, np.where(i == m, 1 + (m - 1) * n, 1 + (i - 1) * n + c))

    i, c = (g.ravel() for g in np.meshgrid(np.arange(m), np.arange(n), indexing="ij"))
    # from pole to pole along e, counter-clockwise about e seen from outside
    faces = np.stack([index(i, c), index(i, c + 1), index(i + 1, c + 1), index(i + 1, c)], axis=1)
    return V, faces


def sphere(center, radius: float, rings: int = SPHERE_RINGS) -> tuple[np.ndarray, np.ndarray]:
    """A sphere of quads (vertices, faces)."""
    c, e = np.asarray(center, dtype=np.float64), np.array([0.0, 0.0, 1.0])
    phi = np.linspace(0.0, np.pi, rings + 1)
    return _lathe(c - radius * np.cos(phi)[:, None] * e, radius * np.sin(phi), e)


def capsule(a, b, radius: float, rings: int = CAP_RINGS) -> tuple[np.ndarray, np.ndarray]:
    """A capsule (the points within ``radius`` of a-b) of quads (vertices, faces)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    e = (b - a) / np.linalg.norm(b - a)
    phi = np.linspace(0.0, 0.5 * np.pi, rings + 1)
    z = -radius * np.cos(phi)
    points = np.concatenate([a + z[:, None] * e, b - z[::-1, None] * e])
    radii = radius * np.concatenate([np.sin(phi), np.sin(phi)[::-1]])
    return _lathe(points, radii, e)


def box(center, half, axes) -> tuple[np.ndarray, np.ndarray]:
    """A box's 8 corners (index 4 i + 2 j + k, see BOX_FACES) and its 6 faces."""
    corners = np.asarray(center, float) + (_SIGNS * np.asarray(half, float)) @ np.asarray(axes).T
    return corners, BOX_FACES.copy()


def plane_quad(point, normal, cover) -> np.ndarray:
    """The corners (4, 3) of the rectangle in the plane covering the projections of the
    points ``cover`` (K, 3) PLANE_COVER times about their middle (a square of the
    largest span where they span a line or a point; of side 1 m where they are one
    point), counter-clockwise seen from the free side."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    p = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    p /= np.linalg.norm(p)
    q = np.cross(n, p)  # p, q, n right-handed
    P = np.asarray(cover, dtype=np.float64).reshape(-1, 3) - point
    uv = np.stack([P @ p, P @ q], axis=1)
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    span = hi - lo
    side = np.maximum(span, 0.25 * span.max()) if span.max() > 0 else np.ones(2)
    mid, half = 0.5 * (lo + hi), 0.5 * PLANE_COVER * side
    corners = mid + half * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    return np.asarray(point, float) + corners[:, :1] * p + corners[:, 1:] * q


def surface(d: dict, index: int, cover=None) -> Surface | None:
    """Obstacle ``index``, the table ``d`` of a resolved case, as a ``Surface`` (None for
    a moving sphere, which is a node of the net). ``cover``: the points (the net) a
    plane's quad covers (None: a plane without vertices). Raises KeyError, TypeError or
    ValueError for a table it cannot build (a mesh file gone: ValueError)."""
    from catenet.terms.shapes import rotation

    kind = d.get("kind")
    motion = None
    moving = d.get("velocity") is not None or d.get("angular_velocity") is not None
    moving = moving and not is_free(d)
    if kind == "plane":
        point = _req(d, "point", (0.0, 0.0, 0.0))
        normal = _req(d, "normal", (0.0, 0.0, 1.0))
        normal = normal / np.linalg.norm(normal)
        if cover is None:
            V, F = np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int64)
        else:
            V, F = plane_quad(point, normal, cover), np.array([[0, 1, 2, 3]], dtype=np.int64)
        return Surface(index, kind, V, F, point=point, normal=normal)
    if kind == "sphere":
        if is_body(d):
            return None
        V, F = sphere(_req(d, "center"), float(d["radius"]))
        return Surface(index, kind, V, F)
    if kind == "box":
        center = _req(d, "center")
        axes = rotation(_req(d, "axis", (0.0, 0.0, 1.0)), float(d.get("angle", 0.0)))
        V, F = box(center, _req(d, "half_size"), axes)
        origin = center
    elif kind == "capsule":
        a, b = _req(d, "start"), _req(d, "end")
        V, F = capsule(a, b, float(d["radius"]))
        origin = 0.5 * (a + b)
    elif kind == "mesh":
        from catenet.case.shapes import read_surface

        origin = _req(d, "offset", (0.0, 0.0, 0.0))
        V, F = read_surface(str(d["file"]))
        V = V * float(d.get("scale", 1.0)) + origin
    else:
        raise ValueError(f"unknown obstacle kind {kind!r}")
    if moving:
        motion = Motion(d, origin)
    return Surface(index, kind, V, F, motion)
