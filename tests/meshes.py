"""Closed triangle meshes the tests share: a unit cube (vertices and outward triangles), an
icosphere, and writing a mesh to a file with meshio (a case's mesh obstacle reads it)."""

from __future__ import annotations

import math

import numpy as np

CUBE_V = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=float,
)


CUBE_T = np.array(
    [
        [0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
        [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7],
    ]
)  # fmt: skip


def icosphere(levels: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere of 20 * 4**levels triangles (a closed, convex, curved mesh)."""
    p = (1 + 5**0.5) / 2
    V = [[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0], [0, -1, p], [0, 1, p]]
    V += [[0, -1, -p], [0, 1, -p], [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]]
    T = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4]]
    T += [[11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8]]
    T += [[3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(levels):
        mid: dict = {}

        def m(i, j, mid=mid):
            key = (min(i, j), max(i, j))
            if key not in mid:
                v = V[i] + V[j]
                V.append(v / np.linalg.norm(v))
                mid[key] = len(V) - 1
            return mid[key]

        T = [
            t
            for a, b, c in T
            for t in ([a, m(a, b), m(c, a)], [b, m(b, c), m(a, b)], [c, m(c, a), m(b, c)],
                      [m(a, b), m(b, c), m(c, a)])
        ]  # fmt: skip
    return np.array(V), np.array(T)


def write_stl(path, V, T):
    import meshio

    meshio.write_points_cells(path, V, [("triangle", T)])
    return path


def hypar_roof(half: float = 6.0, rise: float = 1.5, cells: int = 3, edge_length=None) -> dict:
    """A graph case of a hypar roof z = rise (x^2 - y^2) / half^2 on the square plan
    [-half, half]^2: cables along x ("x0", ...) and y ("y0", ...) through the crossings
    of a (2 cells + 1)^2 grid, an "edge" cable round the pinned boundary (not split), a
    node set "border" of its nodes. Its plan area is (2 half)^2."""
    ks = range(-cells, cells + 1)
    h = half / cells
    idx, nodes = {}, []
    for j in ks:
        for i in ks:
            x, y = i * h, j * h
            idx[(i, j)] = len(nodes)
            nodes.append([x, y, rise * (x * x - y * y) / half**2])
    border = [idx[(i, j)] for (i, j) in idx if abs(i) == cells or abs(j) == cells]
    inner = list(ks)[1:-1]
    ring = (
        [idx[(i, -cells)] for i in ks]
        + [idx[(cells, j)] for j in list(ks)[1:]]
        + [idx[(i, cells)] for i in list(ks)[::-1][1:]]
        + [idx[(-cells, j)] for j in list(ks)[::-1][1:]]
    )
    cables = [{"name": f"x{j}", "nodes": [idx[(i, j)] for i in ks]} for j in inner]
    cables += [{"name": f"y{i}", "nodes": [idx[(i, j)] for j in ks]} for i in inner]
    cables.append({"name": "edge", "nodes": ring, "edge_length": 2 * half})
    geometry = {"kind": "graph", "nodes": nodes, "fixed": sorted(border), "cable": cables}
    geometry["sets"] = {"border": sorted(border)}
    if edge_length is not None:
        geometry["edge_length"] = edge_length
    return {"geometry": geometry, "material": {"EA": 1e7, "prestress": 1e3}}


def folded_strip(layer: int = 6, width: int = 6, step: float = 0.1, speed: float = 1.0, seed=1):
    """(nodes, edges, v0) of a square-mesh strip (spacing ``step``) folded in a U: a
    lower layer of ``layer`` rows at z = 0, three edges round the fold, the upper layer
    2 rho above moving down at ``speed`` onto the lower one; every node jittered by 5 %
    of the spacing (no strand exactly over another)."""
    rng = np.random.default_rng(seed)
    rho = 3.0 * step / np.pi  # three edges round the half circle
    end = (layer - 1) * step
    path = [(k * step, 0.0) for k in range(layer)]
    path += [
        (end + rho * np.cos(a), rho + rho * np.sin(a))
        for a in (-np.pi / 2 + k * np.pi / 3 for k in (1, 2))
    ]
    path += [(end - k * step, 2.0 * rho) for k in range(layer)]
    rows = len(path)
    nodes = np.array([[px, j * step, pz] for px, pz in path for j in range(width)])
    nodes += rng.uniform(-0.05, 0.05, nodes.shape) * step
    edges = [[a * width + b, (a + 1) * width + b] for a in range(rows - 1) for b in range(width)]
    edges += [[a * width + b, a * width + b + 1] for a in range(rows) for b in range(width - 1)]
    v0 = np.zeros_like(nodes)
    v0[np.repeat(np.arange(rows) > rows - layer, width), 2] = -speed
    return nodes, np.array(edges), v0


def _dots(u, v):
    return np.einsum("...j,...j->...", u, v)


def segment_distance(P: np.ndarray) -> np.ndarray:
    """Distances of segment pairs P (..., 4, 3) (a0, a1, b0, b1), from their closest
    points (Ericson, Real-Time Collision Detection 5.1.9)."""
    d1, d2, r = (
        P[..., 1, :] - P[..., 0, :],
        P[..., 3, :] - P[..., 2, :],
        P[..., 0, :] - P[..., 2, :],
    )
    a, e, b, c, f = _dots(d1, d1), _dots(d2, d2), _dots(d1, d2), _dots(d1, r), _dots(d2, r)
    den = a * e - b * b
    ok = den > 1e-14 * a * e
    s = np.where(ok, np.clip((b * f - c * e) / np.where(ok, den, 1.0), 0, 1), 0.0)
    t = (b * s + f) / e
    s = np.where(t < 0, np.clip(-c / a, 0, 1), np.where(t > 1, np.clip((b - c) / a, 0, 1), s))
    t = np.clip(t, 0, 1)
    return np.linalg.norm(r + s[..., None] * d1 - t[..., None] * d2, axis=-1)


def strand_crossings(frames, edges, samples: int = 50) -> list[tuple[int, int, int]]:
    """(frame interval k, edge a, edge b) wherever two edges that share no node pass
    through each other as the nodes move straight from frame k to k + 1: the sign of the
    volume (a1 - a0) x (b1 - b0) . (b0 - a0) changes between two of ``samples`` times
    and where it vanishes (found by bisection) the segments meet (closer than 1e-7 of
    their length), or a sampled distance is zero. Only pairs whose swept boxes overlap
    are sampled."""
    E = np.asarray(edges)
    found = []
    for k in range(len(frames) - 1):
        x0, x1 = np.asarray(frames[k]), np.asarray(frames[k + 1])
        ends = np.stack([x0[E[:, 0]], x0[E[:, 1]], x1[E[:, 0]], x1[E[:, 1]]], 1)
        lo, hi = ends.min(1), ends.max(1)
        meet = np.all((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None]), axis=2)
        a, b = np.nonzero(np.triu(meet, 1))
        apart = (E[a, 0] != E[b, 0]) & (E[a, 0] != E[b, 1]) & (E[a, 1] != E[b, 0])
        quads = np.c_[E[a], E[b]][apart & (E[a, 1] != E[b, 1])]
        pairs = np.c_[a, b][apart & (E[a, 1] != E[b, 1])]
        found += [(k, *map(int, pairs[i])) for i in _crossed(x0, x1, quads, samples)]
    return found


def _crossed(x0, x1, quads, samples) -> list[int]:
    """The node quadruples (K, 4) of segment pairs that pass through each other on the
    way from x0 to x1 (see strand_crossings)."""

    def volume(s):  # s (K,): each pair at its own time; the volumes and the points
        P = (1 - s)[:, None, None] * x0[quads] + s[:, None, None] * x1[quads]
        u, v, w = P[:, 1] - P[:, 0], P[:, 3] - P[:, 2], P[:, 2] - P[:, 0]
        return _dots(np.cross(u, v), w), P

    if not len(quads):
        return []
    out = set()
    grid = np.linspace(0.0, 1.0, samples + 1)
    prev = volume(np.zeros(len(quads)))[0]
    for s0, s1 in zip(grid[:-1], grid[1:], strict=True):
        vol, P = volume(np.full(len(quads), s1))
        touch = segment_distance(P) <= 0.0
        flip = np.flatnonzero((np.sign(vol) != np.sign(prev)) | touch)
        v_lo, prev = prev[flip], vol
        if not len(flip):
            continue
        lo, hi = np.full(len(flip), s0), np.full(len(flip), s1)
        sub = quads[flip]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            Pm = (1 - mid)[:, None, None] * x0[sub] + mid[:, None, None] * x1[sub]
            v_mid = _dots(np.cross(Pm[:, 1] - Pm[:, 0], Pm[:, 3] - Pm[:, 2]), Pm[:, 2] - Pm[:, 0])
            same = np.sign(v_mid) == np.sign(v_lo)
            lo, v_lo, hi = (
                np.where(same, mid, lo),
                np.where(same, v_mid, v_lo),
                np.where(same, hi, mid),
            )
        Ph = (1 - hi)[:, None, None] * x0[sub] + hi[:, None, None] * x1[sub]
        size = np.linalg.norm(Ph[:, 1] - Ph[:, 0], axis=1)
        met = touch[flip] | (segment_distance(Ph) <= 1e-7 * size)
        out.update(int(i) for i in flip[met])
    return sorted(out)


def boxes_apart(a, b) -> float:
    """The largest separation of two boxes, each (centre (3,), axes (3, 3) as columns,
    half sizes (3,)), along the 15 axes of the separating axis theorem (their faces'
    normals and the cross products of their edges): > 0 where they are apart (a lower
    bound of their distance), <= 0 where they overlap or touch."""
    (ca, Ra, ha), (cb, Rb, hb) = a, b
    axes = [*Ra.T, *Rb.T]
    axes += [np.cross(u, v) for u in Ra.T for v in Rb.T]
    best = -np.inf
    for n in axes:
        size = float(np.linalg.norm(n))
        if size < 1e-9:
            continue  # parallel edges: their normals are among the faces'
        n = n / size
        reach = float(np.abs(Ra.T @ n) @ ha + np.abs(Rb.T @ n) @ hb)
        best = max(best, abs(float((cb - ca) @ n)) - reach)
    return best


def net_under_gravity(n: int, edge_length: float) -> dict:
    """The paper's square net (1 m, E = 10 MPa, r = 1 cm, 1000 kg/m^3) of ``n`` cables at
    45 degrees, pinned at its ends, under gravity: the geometry, material and load tables
    of a case, for the tests that add bodies to it."""
    return {
        "geometry": {
            "kind": "square_net",
            "n": n,
            "alpha": math.pi / 4,
            "size": 1.0,
            "edge_length": edge_length,
        },
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
    }
