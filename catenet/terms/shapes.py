"""More fixed obstacles as log-barrier terms (``catenet.terms.contact``): a box, a capsule
and a closed triangle mesh (a satellite, a rock). Kernels in ``catenet.kernels.shapes``
and ``catenet.kernels.mesh``; each kind's ``max_step`` is the exact first contact along
a step, so the no-penetration guarantee of the plane and the sphere holds for them too.
On a prescribed motion (translating, tumbling) they are wrapped by ``catenet.terms.moving``.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.mesh import build_grid, mesh_gap, mesh_gradient, mesh_hessian, mesh_max_step
from catenet.kernels.shapes import (
    BOX,
    CAPSULE,
    box_max_step,
    capsule_max_step,
    shape_gap,
    shape_gradient,
    shape_hessian,
)
from catenet.terms.base import register
from catenet.terms.contact import Obstacle

MAX_CELLS = 2_000_000  # the mesh's grid never has more cells


def rotation(axis, angle: float) -> np.ndarray:
    """The rotation matrix (3, 3) by ``angle`` [rad] about ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.max(np.abs(k))  # first to O(1): the norm of a tiny axis would underflow to 0
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * (K @ K)


class _Shape(Obstacle):
    """A box or capsule: the barrier through one set of kernels (``kind``, ``geom``
    packed as ``catenet.kernels.shapes`` says); each kind gives its ``max_step``."""

    convex = False
    kind: int
    geom: np.ndarray

    def gap(self, x):
        out = np.empty(len(self.nodes))
        shape_gap(self.kind, x, self.nodes, self.geom, out)
        return out

    def gradient(self, x, grad):
        return shape_gradient(self.kind, x, self.nodes, self.geom, self.kappa, self.dhat, grad)

    def hessian(self, x, values):
        args = (self.kind, x, self.nodes, self.geom, self.kappa, self.dhat, values)
        return shape_hessian(*args) > 0


@register("box")
class BoxBarrier(_Shape):
    """The outside of a box: ``center``, ``half`` sizes along its axes, which are the
    columns of ``axes`` (a rotation matrix; identity: aligned with x, y, z); with an
    ``offset`` r > 0, the outside of the box rounded by r (a ball's centre against it)."""

    def __init__(self, nodes, center, half, axes=None, *, kappa, dhat, offset: float = 0.0):
        super().__init__(nodes, kappa=kappa, dhat=dhat)
        if not (math.isfinite(offset) and offset >= 0):
            raise ValueError(f"box: offset = {offset!r}: must be >= 0")
        self.offset = float(offset)
        self.center = np.asarray(center, dtype=np.float64)
        self.half = np.asarray(half, dtype=np.float64)
        if not (self.half.shape == (3,) and np.all(self.half > 0)):
            raise ValueError(f"box: half sizes {self.half.tolist()}: must be three values > 0")
        R = np.eye(3) if axes is None else np.asarray(axes, dtype=np.float64)
        if R.shape != (3, 3) or not np.allclose(R.T @ R, np.eye(3), atol=1e-9):
            raise ValueError("box: axes must be a rotation matrix")
        self.axes = np.ascontiguousarray(R)
        self.kind = BOX
        self.geom = np.concatenate([self.center, self.axes.ravel(), self.half, [self.offset]])

    def first_hit(self, x, dx, grow, upto=math.inf):
        args = (self.nodes, self.center, self.axes, self.half, self.offset + grow, upto)
        return box_max_step(x, dx, *args)


@register("capsule")
class CapsuleBarrier(_Shape):
    """The outside of a capsule: the points within ``radius`` of the segment a-b."""

    def __init__(self, nodes, a, b, radius: float, *, kappa: float, dhat: float):
        super().__init__(nodes, kappa=kappa, dhat=dhat)
        self.a = np.asarray(a, dtype=np.float64)
        self.b = np.asarray(b, dtype=np.float64)
        if not (math.isfinite(radius) and radius > 0):
            raise ValueError(f"capsule: radius = {radius!r}: must be > 0")
        if not np.linalg.norm(self.b - self.a) > 0:
            raise ValueError("capsule: the two end points must differ")
        self.radius = float(radius)
        self.kind = CAPSULE
        self.geom = np.concatenate([self.a, self.b, [self.radius]])

    def first_hit(self, x, dx, grow, upto=math.inf):
        return capsule_max_step(x, dx, self.nodes, self.a, self.b, self.radius + grow)


def closed_surface(points, triangles) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of a closed, consistently oriented triangle surface with
    outward normals: duplicate points merged, orientation flipped if the volume is
    negative. Raises ValueError saying what is wrong (degenerate triangles, an edge not
    shared by exactly two triangles, inconsistent orientation, no volume)."""
    P = np.asarray(points, dtype=np.float64)
    T = np.asarray(triangles, dtype=np.int64)
    if T.ndim != 2 or T.shape[1] != 3 or len(T) < 4:
        raise ValueError(f"has {len(T)} triangles: a closed surface needs at least 4")
    V, inverse = np.unique(P, axis=0, return_inverse=True)
    T = inverse.reshape(-1)[T]
    area = 0.5 * np.linalg.norm(np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]), axis=1)
    scale = float(np.ptp(V, axis=0).max())
    flat = np.flatnonzero(~(area > 1e-14 * scale * scale))
    if flat.size:
        raise ValueError(f"triangle {int(flat[0])} has no area ({flat.size} such triangles)")
    directed = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    edges, counts = np.unique(undirected, axis=0, return_counts=True)
    bad = np.flatnonzero(counts != 2)
    if bad.size:
        i, j = edges[bad[0]]
        raise ValueError(
            f"is not closed: {bad.size} edges are not shared by exactly two triangles "
            f"(e.g. the edge {V[i].tolist()} - {V[j].tolist()} belongs to {counts[bad[0]]})"
        )
    if len(np.unique(directed, axis=0)) != len(directed):
        raise ValueError("its triangles are not consistently oriented (neighbours disagree)")
    volume = float(np.einsum("ij,ij->", V[T[:, 0]], np.cross(V[T[:, 1]], V[T[:, 2]]))) / 6.0
    if not abs(volume) > 1e-12 * scale**3:
        raise ValueError("encloses no volume")
    if volume < 0:
        T = T[:, ::-1].copy()
    return V, np.ascontiguousarray(T)


def pseudo_normals(V, T) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit face normals (nt, 3), edge pseudo-normals per triangle and local edge
    (nt, 3, 3: the sum of the two faces' normals) and angle-weighted vertex
    pseudo-normals (nv, 3)."""
    A, B, C = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    fn = np.cross(B - A, C - A)
    fn /= np.linalg.norm(fn, axis=1)[:, None]
    vn = np.zeros_like(V)
    corners = (A, B, C)
    for k in range(3):
        u = corners[(k + 1) % 3] - corners[k]
        w = corners[(k + 2) % 3] - corners[k]
        cos = np.einsum("ij,ij->i", u, w) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        np.add.at(vn, T[:, k], np.arccos(np.clip(cos, -1, 1))[:, None] * fn)
    vn /= np.linalg.norm(vn, axis=1)[:, None]
    key = np.sort(np.stack([T, np.roll(T, -1, axis=1)], axis=2), axis=2)  # (nt, 3, 2)
    flat = key.reshape(-1, 2)
    _, edge_id = np.unique(flat, axis=0, return_inverse=True)
    edge_id = edge_id.reshape(-1)
    sums = np.zeros((edge_id.max() + 1, 3))
    np.add.at(sums, edge_id, np.repeat(fn, 3, axis=0))
    en = sums[edge_id]
    en /= np.linalg.norm(en, axis=1)[:, None]
    return fn, np.ascontiguousarray(en.reshape(-1, 3, 3)), vn


@register("mesh")
class MeshBarrier(Obstacle):
    """The outside of a closed triangle mesh (``vertices`` (nv, 3), ``triangles``
    (nt, 3)), e.g. a satellite; see ``closed_surface`` for what it must be. With an
    ``offset`` r > 0, the outside of the mesh grown by r (a ball's centre against it)."""

    convex = False

    def __init__(self, nodes, vertices, triangles, *, kappa, dhat, offset: float = 0.0):
        super().__init__(nodes, kappa=kappa, dhat=dhat)
        if not (math.isfinite(offset) and offset >= 0):
            raise ValueError(f"mesh: offset = {offset!r}: must be >= 0")
        self.offset = float(offset)
        V, T = closed_surface(vertices, triangles)
        self.vertices, self.triangles = V, T
        self.fn, self.en, self.vn = pseudo_normals(V, T)
        tri = V[T]  # (nt, 3, 3)
        self.tri_lo = np.ascontiguousarray(tri.min(axis=1))
        self.tri_hi = np.ascontiguousarray(tri.max(axis=1))
        extent = float(np.median((self.tri_hi - self.tri_lo).max(axis=1)))
        pad = 1.01 * (self.dhat + self.offset)  # every triangle within a gap of dhat
        lo = V.min(axis=0) - pad
        span = V.max(axis=0) + pad - lo
        h = max(extent, 2.0 * pad / 1.01, float(span.max()) / 256)
        while np.prod(np.ceil(span / h)) > MAX_CELLS:
            h *= 1.5
        self.lo, self.h = lo, h
        self.dims = np.maximum(np.ceil(span / h), 1).astype(np.int64)
        self.start, self.items = build_grid(V, T, lo, h, self.dims, pad)

    def _grid(self):
        return self.lo, self.h, self.dims, self.start, self.items

    def _surface(self):
        return self.vertices, self.triangles, self.fn, self.en, self.vn

    def gap(self, x):
        out = np.empty(len(self.nodes))
        mesh_gap(x, self.nodes, *self._surface(), self.tri_lo, self.tri_hi, self.offset, out)
        return out

    def gradient(self, x, grad):
        args = (*self._surface(), *self._grid(), self.kappa, self.dhat, self.offset, grad)
        return mesh_gradient(x, self.nodes, *args)

    def hessian(self, x, values):
        args = (*self._surface(), *self._grid(), self.kappa, self.dhat, self.offset, values)
        return mesh_hessian(x, self.nodes, *args) > 0

    def first_hit(self, x, dx, grow, upto=math.inf):
        args = (self.vertices, self.triangles, self.fn, self.offset + grow, *self._grid())
        return mesh_max_step(x, dx, self.nodes, *args)

    def surface(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, triangles) as used (outward orientation)."""
        return self.vertices, self.triangles
