"""A surface that form finding's targets put nodes on: a triangle mesh read from a file
(meshio: .stl, .obj, .ply, .vtu, ...), taken as a height field z = f(x, y) over its plan,
linear on each triangle (an architect's roof surface), or, ``smooth``, the C1 height
field through its vertices (matplotlib's Clough-Tocher cubic on each triangle, the
slopes at the vertices estimated from the neighbouring triangles: continuous slopes, so
a node crossing from one triangle to the next sees no crease).

A node's offset from it is z - f(x, y), with the derivatives (-f_x, -f_y, 1); a node
outside the surface's plan has none (``offset`` gives NaN there).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np


class HeightField:
    """The triangle mesh (``vertices``, ``triangles``) as z = f(x, y): linear on each
    triangle, or ``smooth`` (C1)."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray, smooth: bool = False):
        from matplotlib.tri import CubicTriInterpolator, Triangulation

        self.vertices, self.triangles, self.smooth = vertices, triangles, smooth
        tri = Triangulation(vertices[:, 0], vertices[:, 1], triangles)
        self._finder = tri.get_trifinder()  # (RuntimeError where triangles overlap in plan)
        self._f: Any = None
        if smooth:
            self._f = CubicTriInterpolator(tri, vertices[:, 2], kind="geom")
        a, b, c = (vertices[triangles[:, k]] for k in range(3))
        # Each triangle's plane z = p0 x + p1 y + p2, and its barycentric map (the test of
        # whether a point is still in the triangle it was last found in).
        m = np.stack([np.column_stack([v[:, 0], v[:, 1], np.ones(len(v))]) for v in (a, b, c)], 1)
        rhs = np.column_stack([a[:, 2], b[:, 2], c[:, 2]])[:, :, None]
        self._plane = np.linalg.solve(m, rhs)[:, :, 0]
        self._bary = np.linalg.inv(m)  # (barycentric weights: (x, y, 1) @ inv)
        self._last: tuple = (None, None)  # (the points' bytes, their offset): one kept
        self._found = np.zeros(0, dtype=np.int64)  # the last points' triangles

    def _triangles(self, x: np.ndarray) -> np.ndarray:
        """The triangle under each point (-1: none): a point still strictly inside the
        one it was last found in keeps it (the only one under it: the same as the trifinder
        gives, whatever came before); the others are sought anew."""
        n = len(x)
        tri = np.full(n, -1, dtype=np.int64)
        last = self._found if len(self._found) == n else np.full(n, -1, dtype=np.int64)
        had = np.flatnonzero(last >= 0)
        if had.size:
            h = np.column_stack([x[had, 0], x[had, 1], np.ones(had.size)])
            w = np.einsum("ij,ijk->ik", h, self._bary[last[had]])
            inside = np.all(w > 1e-12, axis=1)  # (on an edge or a vertex: sought anew)
            tri[had[inside]] = last[had[inside]]
        seek = np.flatnonzero(tri < 0)
        if seek.size:
            tri[seek] = self._finder(x[seek, 0], x[seek, 1])
        self._found = tri
        return tri

    def offset(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(z - f(x, y), (f_x, f_y)) at the points x (n, 3); NaN outside the plan. The
        last points' answer is kept (a search asks for the same shape's several times)."""
        key = np.ascontiguousarray(x, dtype=np.float64).tobytes()
        if self._last[0] == key:
            return self._last[1][0].copy(), self._last[1][1].copy()
        tri = self._triangles(x)
        on = tri >= 0
        z = np.full(len(x), np.nan)
        grad = np.full((len(x), 2), np.nan)
        if self._f is None:
            p = self._plane[tri[on]]
            z[on] = p[:, 0] * x[on, 0] + p[:, 1] * x[on, 1] + p[:, 2]
            grad[on] = p[:, :2]
        elif on.any():
            keys = ("z", "dzdx", "dzdy")
            multikeys = getattr(self._f, "_interpolate_multikeys", None)
            if multikeys is not None:  # matplotlib's one evaluation of all three
                got = multikeys(x[on, 0], x[on, 1], tri_index=tri[on], return_keys=keys)
            else:  # (its public calls, should a version drop that one)
                got = (self._f(x[on, 0], x[on, 1]), *self._f.gradient(x[on, 0], x[on, 1]))
            z[on], grad[on, 0], grad[on, 1] = (np.ma.filled(g, np.nan) for g in got)
        out = (x[:, 2] - z, grad)
        self._last = (key, out)
        return out[0].copy(), out[1].copy()


def read_height_field(file: str, smooth: bool = False) -> HeightField:
    """The height field of a mesh file (``smooth``: C1); ValueError with the reason."""
    path = Path(file)
    if not path.is_file():
        raise ValueError(f"{'is a directory' if path.is_dir() else 'no such file'} ({path})")
    stat = path.stat()
    return _read(str(path), stat.st_mtime_ns, stat.st_size, smooth)


@functools.lru_cache(maxsize=4)
def _read(file: str, mtime: int, size: int, smooth: bool = False) -> HeightField:
    from catenet.scene.meshfiles import read_triangles

    v, t = read_triangles(file, "a surface")
    if v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
        raise ValueError(f"its points (shape {v.shape}) must be finite 3D points")
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    plan = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    extent = float(np.ptp(v[:, :2], axis=0).max())
    flat = np.flatnonzero(np.abs(plan) <= 1e-12 * extent**2)
    if flat.size:
        raise ValueError(
            f"triangle {int(flat[0])} is vertical (no area in plan; {flat.size} in all): a "
            "target surface is a height field z = f(x, y)"
        )
    try:
        return HeightField(v, t, smooth)
    except (ValueError, RuntimeError) as exc:
        raise ValueError(f"is not a height field over its plan ({exc})") from None


__all__ = ["HeightField", "read_height_field"]
