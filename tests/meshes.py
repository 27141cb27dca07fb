"""Closed triangle meshes the tests share: a unit cube (vertices and outward triangles), an
icosphere, and writing a mesh to a file with meshio (a case's mesh obstacle reads it)."""

from __future__ import annotations

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
