"""The fixed and prescribed-motion obstacles of a result file in ``catenet plot``'s figure
(``catenet.plot.figure``), rebuilt from the resolved case the file stores (its root attribute
``case``, ``catenet.output.reader``): planes, fixed spheres, boxes, capsules and meshes,
light grey and translucent under the net, in the 3D view and the side view, a moving one
at its pose at the time of the plotted frame (``catenet.terms.moving``). A plane is the
patch of it inside the views' box; everything is culled to that box. Moving spheres are
``catenet.plot.bodies``'. A mesh of more than ``MAX_FACES`` triangles is drawn in 3D as
(at most ``MAX_EDGES`` of) its edges. A file without obstacles draws nothing; an obstacle
that cannot be rebuilt (a mesh file gone since the run) is skipped with a warning.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

log = logging.getLogger(__name__)

MAX_FACES = 3000  # above: a mesh is drawn in 3D by its edges
MAX_EDGES = 6000  # at most this many of them
FACE = {"facecolors": "0.6", "edgecolors": "0.6", "alpha": 0.25, "linewidth": 0.0, "zorder": 0.5}
SIDE: dict[str, Any] = {"facecolor": "0.8", "edgecolor": "0.6", "linewidth": 0.6, "alpha": 0.6}
#: finite obstacles widen the views by at most this share of the net's span on each side
REACH = 0.5


@dataclass
class Shape:
    """One obstacle in world coordinates: ``polys`` (a list of (K, 3) faces), or for a
    mesh ``vertices`` and ``triangles``; a plane has ``point`` and ``normal`` only."""

    kind: str
    label: str
    polys: list = field(default_factory=list)
    vertices: np.ndarray | None = None
    triangles: np.ndarray | None = None
    point: np.ndarray | None = None
    normal: np.ndarray | None = None

    def points(self) -> np.ndarray:
        if self.vertices is not None:
            return self.vertices
        return np.concatenate(self.polys) if self.polys else np.zeros((0, 3))


def plotted_time(res) -> float:
    """The time of the state ``res.x`` of a dynamic run (the last frame or /result's
    time); 0 for any other run (nothing moves in static runs) or when unknown."""
    if res.method != "dynamic":
        return 0.0
    if not res.from_trajectory and "time" in res.result_attrs:
        try:
            t = float(res.result_attrs["time"])
        except (TypeError, ValueError):
            t = math.nan
        if math.isfinite(t):
            return t
    return float(res.times[-1]) if len(res.times) else 0.0


def shapes(res, t: float | None = None) -> list[Shape]:
    """The obstacles of ``res``'s case at time ``t`` (default: the plotted state's), as
    ``catenet.output.surfaces`` builds them."""
    from catenet.output.surfaces import is_free, surface

    items = res.case.get("obstacle") if isinstance(res.case, dict) else None
    if not isinstance(items, list):
        return []
    t = plotted_time(res) if t is None else t
    out = []
    for k, d in enumerate(items):
        if not isinstance(d, dict):
            continue
        moving = d.get("velocity") is not None or d.get("angular_velocity") is not None
        label = f"obstacle[{k}]: {'moving ' if moving else ''}{d.get('kind')}"
        try:
            s = surface(d, k)
            if s is None:
                continue  # a moving ball: catenet.plot.bodies
            if is_free(d):  # a free body: where the result file has it at t
                s = _posed(res, s, k, t)
            if s.kind == "plane":
                out.append(Shape(s.kind, label, point=s.point, normal=s.normal))
            elif s.kind == "mesh":
                out.append(Shape(s.kind, label, vertices=s.at(t), triangles=s.faces))
            else:
                out.append(Shape(s.kind, label, list(s.at(t)[s.faces])))
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            log.warning("%s: %s not drawn: %s", res.path, label, exc)
    return out


def _posed(res, s, k: int, t: float):
    """The surface ``s`` of free body ``k`` at its stored pose nearest to time t (the
    frame's, or /result's at the end); as at t = 0 when the file has none."""
    import dataclasses

    from catenet.output.reader import open_result

    with open_result(res.path) as h5:
        g = h5.get(f"trajectory/obstacles/{k}")
        origin = h5.get(f"mesh/obstacles/{k}")
        if g is None or origin is None or "center" not in g or not len(g["center"]):
            return s
        times = np.asarray(h5["trajectory/time"][: len(g["center"])])
        j = int(np.argmin(np.abs(times - t)))
        c, R = np.asarray(g["center"][j]), np.asarray(g["rotation"][j])
        o = np.asarray(origin.attrs["origin"], dtype=np.float64)
    return dataclasses.replace(s, vertices=c + (s.vertices - o) @ R.T)


def plane_patch(point, normal, lo, hi) -> np.ndarray:
    """The polygon (K, 3) where the plane cuts the box [lo, hi] (K = 0: it does not)."""
    corners = _box_corners(lo, hi)
    s = (corners - point) @ normal
    pts = [corners[i] for i in range(8) if s[i] == 0.0]
    for i in range(8):
        for j in range(i + 1, 8):
            if bin(i ^ j).count("1") == 1 and s[i] * s[j] < 0.0:  # a box edge crossing it
                pts.append(corners[i] + s[i] / (s[i] - s[j]) * (corners[j] - corners[i]))
    if len(pts) < 3:
        return np.zeros((0, 3))
    P = np.array(pts)
    m = P.mean(axis=0)
    e1 = P[np.argmax(np.linalg.norm(P - m, axis=1))] - m
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    return P[np.argsort(np.arctan2((P - m) @ e2, (P - m) @ e1))]


def solid_side(point, normal, lo, hi) -> np.ndarray:
    """The corners of the part of the box [lo, hi] on the plane's solid side (behind
    ``normal``) and where the plane cuts the box: their hull is that part."""
    corners = _box_corners(lo, hi)
    inside = corners[(corners - point) @ normal <= 0.0]
    return np.concatenate([inside, plane_patch(point, normal, lo, hi)])


def _box_corners(lo, hi) -> np.ndarray:
    """The 8 corners of the box [lo, hi]."""
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )


def _corners_inside(faces: np.ndarray, lo, hi) -> np.ndarray:
    """The corners of the box [lo, hi] inside the convex body of these faces (P, K, 3)."""
    n = np.cross(faces, np.roll(faces, -1, axis=1)).sum(axis=1)  # Newell: degenerate edges add 0
    fc = faces.mean(axis=1)
    outward = np.einsum("ij,ij->i", fc - faces.reshape(-1, 3).mean(axis=0), n) >= 0
    n *= np.where(outward, 1.0, -1.0)[:, None]
    corners = _box_corners(lo, hi)
    side = np.einsum("pj,cpj->cp", n, corners[:, None] - fc[None])
    return corners[(side <= 0.0).all(axis=1)]


def _turn(a, b, c) -> float:
    return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _hull(p: np.ndarray) -> np.ndarray:
    """The convex hull (counter-clockwise) of 2D points (monotone chain)."""
    p = np.unique(p, axis=0)
    if len(p) < 3:
        return p

    def half(points):
        h: list = []
        for q in points:
            while len(h) >= 2 and _turn(h[-2], h[-1], q) <= 0:
                h.pop()
            h.append(q)
        return h[:-1]

    return np.array(half(p) + half(p[::-1]))


def _clip_poly(P: np.ndarray, lo, hi) -> np.ndarray:
    """The convex polygon P (K, 3) cut to the box [lo, hi] (Sutherland-Hodgman)."""
    for axis in range(3):
        for bound, sign in ((lo[axis], 1.0), (hi[axis], -1.0)):
            if not len(P):
                return P
            d = sign * (P[:, axis] - bound)  # >= 0: inside
            out = []
            for k in range(len(P)):
                a, b, da, db = P[k - 1], P[k], d[k - 1], d[k]
                if (da >= 0) != (db >= 0):
                    out.append(a + da / (da - db) * (b - a))
                if db >= 0:
                    out.append(b)
            P = np.array(out).reshape(-1, 3)
    return P


def _visible(polys: np.ndarray, lo, hi) -> np.ndarray:
    """Which polygons (P, K, 3) are not wholly beyond a face of the box [lo, hi]."""
    return ~np.any((polys < lo).all(axis=1) | (polys > hi).all(axis=1), axis=1)


def clipped(polys: np.ndarray, lo, hi) -> list:
    """The convex polygons (P, K, 3) cut to the box [lo, hi]: those wholly inside as they
    are, those wholly beyond a face dropped, the others cut."""
    polys = np.asarray(polys)
    if not len(polys):
        return []
    inside = ((polys >= lo) & (polys <= hi)).all(axis=(1, 2))
    out = list(polys[inside])
    for P in polys[~inside & _visible(polys, lo, hi)]:
        P = _clip_poly(P, lo, hi)
        if len(P) >= 3:
            out.append(P)
    return out


def clipped_segments(seg: np.ndarray, lo, hi) -> np.ndarray:
    """The segments (S, 2, 3) cut to the box [lo, hi] (Liang-Barsky); those outside dropped."""
    a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
    t0, t1 = np.zeros(len(seg)), np.ones(len(seg))
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis in range(3):
            for bound, sign in ((lo[axis], 1.0), (hi[axis], -1.0)):
                p, q = -sign * d[:, axis], sign * (a[:, axis] - bound)  # inside: p t <= q
                t = q / p
                t0 = np.where(p < 0, np.maximum(t0, t), t0)
                t1 = np.where(p > 0, np.minimum(t1, t), t1)
                t1 = np.where((p == 0) & (q < 0), -1.0, t1)
    keep = t0 < t1
    a, d, t0, t1 = a[keep], d[keep], t0[keep, None], t1[keep, None]
    return np.stack([a + t0 * d, a + t1 * d], axis=1)


def _union(polys: list, **style):
    """One patch filling the union of 2D polygons: each turned counter-clockwise, the
    nonzero rule fills where any lies, and neither overlaps darken nor does ``catenet
    plot``'s legend placement test every triangle of a large mesh."""
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path

    verts, codes = [], []
    for k in sorted({len(P) for P in polys}):  # triangles at once, then cut ones by size
        P = np.array([P for P in polys if len(P) == k])  # (n, k, 2)
        x, y = P[..., 0], P[..., 1]
        area = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
        P = np.where((area < 0)[:, None, None], P[:, ::-1], P)
        verts.append(np.concatenate([P, P[:, :1]], axis=1).reshape(-1, 2))
        one = [Path.MOVETO] + [Path.LINETO] * (k - 1) + [Path.CLOSEPOLY]
        codes.append(np.tile(np.array(one, dtype=Path.code_type), len(P)))
    path = Path(np.concatenate(verts), np.concatenate(codes))
    return PathPatch(path, **(style | {"edgecolor": "none"}))


class Obstacles:
    """The obstacles of a result ``res`` in the figure (none: draws nothing)."""

    def __init__(self, res):
        self.shapes = shapes(res)

    def extent(self, lo, hi) -> list[np.ndarray]:
        """Points the views' limits must include: each finite obstacle's box, within the
        net's box [lo, hi] grown by REACH of its span (a huge seabed does not shrink it)."""
        span = float(np.max(hi - lo)) or 1.0
        a, b = lo - REACH * span, hi + REACH * span
        out = []
        for s in self.shapes:
            p = s.points()
            if len(p):
                out.append(np.clip(np.array([p.min(axis=0), p.max(axis=0)]), a, b))
        return out

    def draw3d(self, ax, lo, hi) -> None:
        """The obstacles under the net (drawn first: mplot3d's depth order of whole
        collections would put a box in front of the net that wraps it)."""
        from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

        lo, hi = np.asarray(lo), np.asarray(hi)
        if self.shapes:
            ax.computed_zorder = False
        for s in self.shapes:
            if s.kind == "plane":
                P = plane_patch(s.point, s.normal, lo, hi)
                if len(P):
                    ax.add_collection3d(Poly3DCollection([P], gid=s.label, **FACE))
            elif s.vertices is not None:
                tri = s.vertices[s.triangles]
                if not _visible(tri, lo, hi).any():
                    continue
                if _visible(tri, lo, hi).sum() <= MAX_FACES:
                    tri = clipped(tri, lo, hi)
                    ax.add_collection3d(Poly3DCollection(tri, gid=s.label, shade=True, **FACE))
                else:
                    edges = np.unique(
                        np.sort(s.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0
                    )
                    seg = clipped_segments(s.vertices[edges], lo, hi)
                    seg = seg[:: max(1, math.ceil(len(seg) / MAX_EDGES))]
                    ax.add_collection3d(
                        Line3DCollection(
                            seg, colors="0.5", linewidths=0.3, alpha=0.5, zorder=0.5, gid=s.label
                        )
                    )
            else:
                polys = clipped(s.polys, lo, hi)
                if polys:
                    ax.add_collection3d(Poly3DCollection(polys, gid=s.label, shade=True, **FACE))

    def draw2d(self, ax, h: int, lo, hi) -> None:
        """The obstacles seen along the other horizontal axis (labelled in the legend)."""
        from matplotlib.patches import Polygon

        lo, hi = np.asarray(lo), np.asarray(hi)
        axes = [h, 2]
        for s in self.shapes:
            if s.kind == "plane":  # its solid side within the box
                P = solid_side(s.point, s.normal, lo, hi)
                if len(P):
                    ax.add_patch(
                        Polygon(_hull(P[:, axes]), zorder=1, label=s.label, gid=s.label, **SIDE)
                    )
            elif s.vertices is not None:
                tri = [P[:, axes] for P in clipped(s.vertices[s.triangles], lo, hi)]
                if tri:  # add_artist: add_patch's data limits walk every segment
                    ax.add_artist(_union(tri, zorder=1, label=s.label, gid=s.label, **SIDE))
                    ax.update_datalim(np.concatenate(tri))
            else:
                polys = clipped(s.polys, lo, hi)  # a convex body: the hull of its outline
                if polys:  # with the box's corners inside it (a body bigger than the view)
                    pts = np.concatenate([*polys, _corners_inside(np.array(s.polys), lo, hi)])
                    hull = _hull(pts[:, axes])
                    ax.add_patch(Polygon(hull, zorder=1, label=s.label, gid=s.label, **SIDE))
