"""Area loads: a pressure over the surface a net covers, lumped to its nodes by tributary
area.

The surface is made of the net's own cells. The edges among the covered nodes are drawn
in a plane (the plan; for a load normal to the surface whose drawing in plan crosses
itself or covers no area, a facade, the net's mean plane, fitted by least squares) and
their faces found as in any planar map: at every
node the edges are sorted by angle and each face is walked keeping it on the left. The
bounded faces are the cells (the quadrilaterals between crossing cables, with the nodes
that split their sides, or a mesh's triangles and polygons). The open cells at the
border of a cable net, between two cable ends that no edge joins, are closed first: on
the outer boundary, between each two consecutive cable ends (nodes of one edge), the
outline runs along the convex chain of the boundary nodes between them, so that the
outline passes through the outer nodes, supports included, and follows a concave border
where the net has one; a support on the boundary is such an end too (an L's inner
corner, where two cables end).

Each cell is split into triangles from its centroid (one per side); a triangle's share
goes half to each end of its side. On a square cell every corner takes a quarter, on a
triangle a third; the nodes that split a cable between two crossings take the share of
their pieces of side. The total is the pressure times the covered area exactly (to
round-off): on plan, the plan area inside the outline; normal to the surface, the force
of each triangle is the pressure times its vector area, in the given geometry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import components

DIRECTIONS = ("plan", "normal")

#: Relative tolerance (of the net's extent) for a point to count as off a line.
TOL = 1e-9


@dataclass(frozen=True)
class AreaLoad:
    """An area load lumped to nodes: ``force`` (N, 3) [N], the covered ``area`` [m^2]
    (plan area on plan, surface area normal to the surface), the ``normal`` of the
    plane it was drawn in (positive pressure pushes against it), that plane's ``basis``
    (2, 3) and the ``outline``: each part's border, its nodes in order (clockwise)."""

    force: np.ndarray
    area: float
    normal: np.ndarray
    basis: np.ndarray
    outline: tuple
    surface: bool = False  # its area is the surface's (normal to it), not the plan's


def area_load(
    nodes: np.ndarray,
    edges: np.ndarray,
    covered: np.ndarray,
    pressure: float,
    direction: str,
    anchors: np.ndarray | None = None,
) -> AreaLoad:
    """The nodal forces of ``pressure`` [Pa] over the cells of the edges between
    ``covered`` nodes (an (N,) mask), on plan (-z, per plan area) or normal to the
    surface; ``anchors`` (N,) the supports, through which the outline of the open border
    cells passes (a notch's corner where two cables end). ConfigError (without a key
    path: the caller adds it) when they cover no area or their drawing in the plane
    crosses itself."""
    if direction not in DIRECTIONS:
        raise ValueError(f"direction {direction!r}: must be one of {DIRECTIONS}")
    nodes = np.asarray(nodes, dtype=np.float64)
    edges = np.asarray(edges, dtype=np.int64)
    sub = edges[covered[edges[:, 0]] & covered[edges[:, 1]]]
    if not len(sub):
        raise ConfigError("covers no area: no edge joins two of its nodes")
    used = np.unique(sub)
    if len(used) < 3:  # one edge: its two nodes lie on a line
        raise ConfigError(_no_area(False))
    xyz = nodes[used]
    local = np.searchsorted(used, sub)
    ends = None if anchors is None else np.asarray(anchors, dtype=bool)[used]
    planes = ("plan",) if direction == "plan" else ("plan", "fitted")
    for k, plane in enumerate(planes):  # a normal load: drawn in plan where it can be
        try:
            normal, basis, faces, scale = _drawn(xyz, local, used, plane, direction, ends)
            break
        except ConfigError:
            if k + 1 == len(planes):
                raise
    force, area = _lump(xyz, faces, pressure, direction)
    if not area > (TOL * scale) ** 2:
        raise ConfigError(_no_area(False))
    out = np.zeros((len(nodes), 3))
    out[used] = force
    loops = tuple(used[_loop(faces, int(f))] for f in np.flatnonzero(faces.area <= 0.0))
    return AreaLoad(out, area, normal, basis, loops, direction == "normal")


def _drawn(xyz, local, used, plane: str, direction: str, ends):
    """(normal, basis, faces, scale) of the net drawn in ``plane`` ("plan" or "fitted",
    the nodes' least-squares plane), its open border cells closed; ConfigError where the
    drawing covers no area, puts two nodes on one point or crosses itself."""
    scale3 = float(np.linalg.norm(xyz.max(axis=0) - xyz.min(axis=0)))
    normal, basis = _plane(xyz, plane, scale3)
    q = (xyz - xyz.mean(axis=0)) @ basis.T
    scale = float(np.linalg.norm(np.ptp(q, axis=0)))  # the extent in the plane
    if not scale > 0:
        raise ConfigError(_no_area(direction == "plan"))
    upright = np.linalg.svd(xyz - xyz.mean(axis=0), compute_uv=False)[1] > TOL * scale3
    if np.linalg.svd(q - q.mean(axis=0), compute_uv=False)[-1] <= TOL * scale:
        raise ConfigError(_no_area(direction == "plan" and upright))
    _distinct(q, used, scale)
    return normal, basis, _closed_faces(q, local, scale, ends), scale


def _no_area(upright: bool) -> str:
    where = " in plan (a vertical net has no plan area)" if upright else ""
    return f"covers no area: its nodes lie on a line{where}"


def _plane(xyz: np.ndarray, direction: str, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The normal and the in-plane basis (2, 3) of the plane the net is drawn in: the
    plan, or the least-squares plane of the nodes (the plan when they lie in one
    horizontal plane), its normal pointing up (a vertical plane: towards +x, else +y)."""
    flat = np.ptp(xyz[:, 2]) <= TOL * scale
    if direction == "plan" or flat:
        return np.array([0.0, 0.0, 1.0]), np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    _, _, vt = np.linalg.svd(xyz - xyz.mean(axis=0), full_matrices=False)
    n = vt[2]
    for axis in (2, 0, 1):
        if abs(n[axis]) > 1e-6:
            n = n if n[axis] > 0 else -n
            break
    e1 = vt[0] - (vt[0] @ n) * n
    e1 /= np.linalg.norm(e1)
    return n, np.array([e1, np.cross(n, e1)])


def _distinct(q: np.ndarray, used: np.ndarray, scale: float) -> None:
    """ConfigError when two nodes fall on one point of the plane."""
    key = np.round(q / (TOL * 100 * scale)).astype(np.int64)
    _, first, inv, counts = np.unique(
        key, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    if (counts > 1).any():
        inv = inv.ravel()
        k = int(np.flatnonzero((counts[inv] > 1) & (first[inv] != np.arange(len(q))))[0])
        other = int(first[inv[k]])
        raise ConfigError(
            f"nodes {int(used[other])} and {int(used[k])} lie at one point of the plane the "
            "net is drawn in (one above the other): an area load needs a net in one layer"
        )


# --------------------------------------------------------------------------- faces


@dataclass(frozen=True)
class _Faces:
    """Half-edges (origin, destination: local node indices), their face and each face's
    signed area in the plane (> 0: a cell; <= 0: the outside of a part of the net)."""

    origin: np.ndarray
    dest: np.ndarray
    face: np.ndarray
    area: np.ndarray
    next: np.ndarray


def _faces(q: np.ndarray, edges: np.ndarray) -> _Faces:
    """The faces of the plane graph: half-edge 2e runs along edge e, 2e + 1 back; the
    half-edge after (u -> v) leaves v clockwise next to (v -> u), so that every cell is
    walked counterclockwise."""
    origin = edges.reshape(-1)
    dest = edges[:, ::-1].reshape(-1)
    d = q[dest] - q[origin]
    angle = np.arctan2(d[:, 1], d[:, 0])
    order = np.lexsort((angle, origin))
    pos = np.empty_like(order)
    pos[order] = np.arange(len(order))
    start = np.searchsorted(origin[order], np.arange(len(q)))
    count = np.bincount(origin, minlength=len(q))
    twin = np.arange(len(origin)) ^ 1
    p = pos[twin]
    o = origin[twin]
    prev = np.where(p > start[o], p - 1, start[o] + count[o] - 1)
    nxt = order[prev]
    lab = np.arange(len(nxt))
    jump = nxt.copy()
    for _ in range(int(np.ceil(np.log2(max(len(nxt), 2)))) + 1):
        lab = np.minimum(lab, lab[jump])
        jump = jump[jump]
    _, face = np.unique(lab, return_inverse=True)
    face = face.ravel()
    cross = q[origin, 0] * q[dest, 1] - q[origin, 1] * q[dest, 0]
    area = 0.5 * np.bincount(face, weights=cross)
    return _Faces(origin, dest, face, area, nxt)


def _closed_faces(q: np.ndarray, edges: np.ndarray, scale: float, ends=None) -> _Faces:
    """The faces after closing the open cells at the border (``ends``: the supports, the
    outline's corners), checked to be a plane drawing (Euler's formula; one outside per
    part). Edges in several parts (parallel cables without cross ties) or without a
    cell: the Delaunay triangles of the nodes."""
    tol = (TOL * scale) ** 2
    parts = int(components(len(q), edges).max()) + 1
    faces = _faces(q, edges)
    if parts > 1 or not (faces.area > tol).any():
        return _delaunay(q)
    extra = []
    have = {tuple(sorted(e)) for e in edges.tolist()}
    for f in np.flatnonzero(faces.area <= tol):
        for a, b in _outline(q, faces, int(f), scale, ends):
            if (min(a, b), max(a, b)) not in have:
                have.add((min(a, b), max(a, b)))
                extra.append((a, b))
    if extra:
        edges = np.concatenate([edges, np.asarray(extra, dtype=np.int64)])
        faces = _faces(q, edges)
    outside = int(np.count_nonzero(faces.area <= tol))
    expected = len(edges) - len(q) + 2
    if int(faces.area.size) != expected or outside != 1:
        raise ConfigError(
            "its edges cross in the plane the net is drawn in (a net folded over itself, "
            "or two layers): an area load needs a net in one layer; give nodes = a node "
            "set of one layer"
        )
    return faces


def _delaunay(q: np.ndarray) -> _Faces:
    """The Delaunay triangles of the nodes, each a cell walked counterclockwise."""
    from scipy.spatial import Delaunay, QhullError

    try:
        tri = Delaunay(q).simplices.astype(np.int64)
    except (QhullError, ValueError):
        raise ConfigError("covers no area: its nodes lie on a line") from None
    a, b, c = q[tri[:, 0]], q[tri[:, 1]], q[tri[:, 2]]
    signed = 0.5 * (
        (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    )
    tri[signed < 0] = tri[signed < 0][:, ::-1]
    origin = tri.reshape(-1)
    dest = tri[:, [1, 2, 0]].reshape(-1)
    face = np.repeat(np.arange(len(tri)), 3)
    nxt = (np.arange(len(origin)) // 3) * 3 + (np.arange(len(origin)) + 1) % 3
    return _Faces(origin, dest, face, np.abs(signed), nxt)


def _loop(faces: _Faces, f: int) -> np.ndarray:
    """The nodes of face ``f`` in the order it is walked (local indices)."""
    return faces.origin[np.asarray(_walk(faces, f), dtype=np.int64)]


def _walk(faces: _Faces, f: int) -> list[int]:
    """The half-edges of face ``f`` in order."""
    h0 = int(np.flatnonzero(faces.face == f)[0])
    out = [h0]
    h = int(faces.next[h0])
    while h != h0:
        out.append(h)
        h = int(faces.next[h])
    return out


def _outline(
    q: np.ndarray, faces: _Faces, f: int, scale: float, ends=None
) -> list[tuple[int, int]]:
    """The edges that close the open cells along the outside ``f`` of a part: between
    each two consecutive ends along its boundary, the convex chain of the boundary nodes
    that lie outward of the chord between them. The ends: the nodes of one edge (a
    cable ending at the border), and where there are such, the supports (``ends``) on
    the boundary too, so that a notch's corner, where two cables end, stays a corner."""
    walk = _walk(faces, f)
    nodes = [int(faces.origin[h]) for h in walk]
    size = len(nodes)
    tips = sorted((k + 1) % size for k, h in enumerate(walk) if faces.next[h] == (h ^ 1))
    if len(tips) < 2:
        return []
    if ends is not None:
        tips = sorted(set(tips) | {k for k, i in enumerate(nodes) if ends[i]})
    out = []
    for t, k0 in enumerate(tips):
        k1 = tips[(t + 1) % len(tips)]
        k1 += size if k1 <= k0 else 0
        chain = _chain(q, [nodes[k % size] for k in range(k0, k1 + 1)], scale)
        out += list(zip(chain[:-1], chain[1:], strict=True))
    return out


def _chain(q: np.ndarray, stretch: list[int], scale: float) -> list[int]:
    """From the first node of ``stretch`` to its last, along the convex hull of the
    nodes that lie outward of the chord between them (the outside of the net is on the
    left of a boundary walked clockwise)."""
    a, b = stretch[0], stretch[-1]
    if a == b:
        return [a]
    chord = q[b] - q[a]
    length = float(np.hypot(*chord))
    inner = np.unique(np.asarray(stretch[1:-1], dtype=np.int64))
    ids = inner
    if ids.size:
        rel = q[ids] - q[a]
        left = (chord[0] * rel[:, 1] - chord[1] * rel[:, 0]) / length
        ids = ids[left > TOL * scale]
    if not ids.size:
        return _through(q, [a, b], inner, scale)
    pts = np.concatenate([[a, b], ids])
    hull = _hull(q, pts)  # counterclockwise; a -> b is one of its sides
    k = hull.index(b)
    ring = hull[k:] + hull[:k]  # b, ..., a counterclockwise
    return _through(q, ring[::-1], inner, scale)


def _through(q: np.ndarray, chain: list[int], nodes: np.ndarray, scale: float) -> list[int]:
    """``chain`` through those of ``nodes`` that lie on its sides (a border straight
    along a line of nodes: the outline follows its edges, never one edge over them)."""
    out = [chain[0]]
    for u, v in zip(chain[:-1], chain[1:], strict=True):
        side = q[v] - q[u]
        length = float(np.hypot(*side))
        rel = q[nodes] - q[u]
        t = (rel @ side) / length**2
        off = np.abs(side[0] * rel[:, 1] - side[1] * rel[:, 0]) / length
        on = (off <= TOL * scale) & (t > TOL) & (t < 1.0 - TOL)
        out += nodes[on][np.argsort(t[on])].tolist() + [v]
    return out


def _hull(q: np.ndarray, pts: np.ndarray) -> list[int]:
    """Andrew's monotone chain: the convex hull of ``pts`` counterclockwise."""
    order = pts[np.lexsort((q[pts, 1], q[pts, 0]))].tolist()

    def half(seq):
        out: list[int] = []
        for p in seq:
            while len(out) >= 2:
                o, a = q[out[-2]], q[out[-1]]
                if (a[0] - o[0]) * (q[p][1] - o[1]) - (a[1] - o[1]) * (q[p][0] - o[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    lower, upper = half(order), half(order[::-1])
    return lower[:-1] + upper[:-1]


# --------------------------------------------------------------------------- lumping


def _lump(xyz, faces: _Faces, pressure, direction):
    """Each cell's triangles from its centroid, half of each to each end of its side:
    forces (n, 3) and the covered area."""
    cell = faces.area[faces.face] > 0
    count = np.bincount(faces.face, minlength=faces.area.size).astype(np.float64)
    centre = (
        np.column_stack(
            [
                np.bincount(faces.face, weights=xyz[faces.origin, c], minlength=faces.area.size)
                for c in range(3)
            ]
        )
        / np.maximum(count, 1.0)[:, None]
    )
    g = centre[faces.face[cell]]
    u = xyz[faces.origin[cell]] - g
    v = xyz[faces.dest[cell]] - g
    vec = 0.5 * np.cross(u, v)
    force = np.zeros_like(xyz)
    if direction == "plan":
        share = np.zeros_like(vec)
        share[:, 2] = -pressure * vec[:, 2]
        area = float(np.sum(vec[:, 2]))
    else:
        share = -pressure * vec
        per_face = np.zeros((faces.area.size, 3))
        np.add.at(per_face, faces.face[cell], vec)
        area = float(np.sum(np.linalg.norm(per_face, axis=1)))
    np.add.at(force, faces.origin[cell], 0.5 * share)
    np.add.at(force, faces.dest[cell], 0.5 * share)
    return force, area


def with_chains(covered: np.ndarray, given: int, edges: np.ndarray) -> np.ndarray:
    """``covered`` (N,) with the nodes that split a cable (indices >= ``given``) added
    where every given node their chain ends at is covered."""
    n = len(covered)
    made = np.arange(n) >= given
    if not made.any():
        return covered
    inner = edges[made[edges[:, 0]] & made[edges[:, 1]]]
    lab = components(n, inner)
    ends = edges[made[edges[:, 0]] != made[edges[:, 1]]]
    chain = np.where(made[ends[:, 0]], ends[:, 0], ends[:, 1])
    end = np.where(made[ends[:, 0]], ends[:, 1], ends[:, 0])
    touched = np.zeros(n, bool)
    open_ = np.zeros(n, bool)
    touched[lab[chain]] = True
    open_[lab[chain[~covered[end]]]] = True
    out = covered.copy()
    out[made] |= touched[lab[made]] & ~open_[lab[made]]
    return out


def beyond_outline(nodes: np.ndarray, edges: np.ndarray, covered: np.ndarray, load: AreaLoad):
    """The covered nodes that no edge among the covered ones joins and that lie outside
    the outline ``load`` covers, in the plane it was drawn in (an (K,) int array), and
    the area [m^2] between them and the outline: for each, the triangle it makes with
    the outline's nearest side, what joining it there would add (on the surface for a
    load normal to it, as its ``area``; on the plane for one on plan: a 30 degree roof's
    corners were summed on plan against its loaded surface). Pressure there loads no
    node (a grid's corner where no cable ends). (empty, 0.0) where there are none."""
    nodes = np.asarray(nodes, dtype=np.float64)
    edges = np.asarray(edges, dtype=np.int64)
    sub = edges[covered[edges[:, 0]] & covered[edges[:, 1]]]
    joined = np.zeros(len(nodes), dtype=bool)
    joined[sub.ravel()] = True
    lonely = np.flatnonzero(covered & ~joined)
    loops = [loop for loop in load.outline if len(loop) >= 3]
    if not len(lonely) or not loops:
        return lonely[:0], 0.0
    plane = nodes @ load.basis.T
    out, area = [], 0.0
    for i in lonely.tolist():
        p = plane[i]
        if any(_inside(plane[loop], p) for loop in loops):
            continue
        dist, k, loop = min(((*_side(plane[loop], p), loop) for loop in loops),
                            key=lambda t: t[0])  # fmt: skip
        a, b = (nodes[loop[k]], nodes[loop[(k + 1) % len(loop)]]) if load.surface else (
            plane[loop[k]], plane[loop[(k + 1) % len(loop)]])  # fmt: skip
        u, w = b - a, (nodes[i] if load.surface else p) - a
        twice = np.cross(u, w) if load.surface else u[0] * w[1] - u[1] * w[0]
        out.append(i)
        area += 0.5 * float(np.linalg.norm(twice))
    return np.asarray(out, dtype=np.int64), float(area)


def _inside(polygon: np.ndarray, p: np.ndarray) -> bool:
    """Whether the point p lies inside the closed ``polygon`` (K, 2) (even-odd rule)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    crosses = (a[:, 1] > p[1]) != (b[:, 1] > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (p[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(crosses & (x > p[0])) % 2)


def _side(polygon: np.ndarray, p: np.ndarray) -> tuple[float, int]:
    """(distance, index) of the nearest side of the closed ``polygon`` (K, 2) to p: the
    side from its vertex index to the next."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    d = b - a
    t = np.clip(
        np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0
    )
    dist = np.linalg.norm(a + t[:, None] * d - p, axis=1)
    k = int(np.argmin(dist))
    return float(dist[k]), k
