"""Area loads lumped by tributary area (catenet/model/areas.py): totals exact, shares as
the cells give them, the open cells at a cable net's border closed through its outer
nodes, normal and plan loads alike on a flat net, nets that cover no area refused."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.errors import ConfigError
from catenet.model import builders as geo
from catenet.model.areas import area_load, with_chains


def grid(nx: int, ny: int, h: float = 1.0, z=None):
    """A rectangular grid of nx x ny nodes at spacing h, edges along x and y."""
    x, y = np.meshgrid(np.arange(nx) * h, np.arange(ny) * h)
    xyz = np.column_stack([x.ravel(), y.ravel(), np.zeros(nx * ny)])
    if z is not None:
        xyz[:, 2] = z(xyz[:, 0], xyz[:, 1])
    ids = np.arange(nx * ny).reshape(ny, nx)
    edges = np.concatenate(
        [
            np.column_stack([ids[:, :-1].ravel(), ids[:, 1:].ravel()]),
            np.column_stack([ids[:-1, :].ravel(), ids[1:, :].ravel()]),
        ]
    )
    return xyz, edges


def everything(xyz):
    return np.ones(len(xyz), dtype=bool)


def test_a_grid_shares_each_cell_equally_among_its_corners():
    xyz, edges = grid(4, 3, h=2.0)
    load = area_load(xyz, edges, everything(xyz), 5.0, "plan")
    fz = load.force[:, 2].reshape(3, 4)
    cell = 5.0 * 4.0  # pressure x cell area
    expect = -cell * np.array([[1, 2, 2, 1], [2, 4, 4, 2], [1, 2, 2, 1]]) / 4
    assert np.array_equal(fz, expect)
    assert load.area == 24.0 and np.all(load.force[:, :2] == 0.0)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 250.0])
def test_on_a_hypar_the_total_is_pressure_times_plan_area(scale):
    """z = k x y over a 7 x 5 rectangle (units from mm to km): the plan load's total is
    p times the plan area; the normal load's is -p times the surface's vector area
    (-k a b^2 / 2, -k a^2 b / 2, a b), exact for the bilinear surface."""
    a, b = 7.0 * scale, 5.0 * scale
    xyz, edges = grid(15, 11)
    xyz[:, 0] *= a / 14
    xyz[:, 1] *= b / 10
    xyz[:, 2] = 0.3 * xyz[:, 0] * xyz[:, 1] / scale
    p = 800.0
    plan = area_load(xyz, edges, everything(xyz), p, "plan")
    assert plan.force[:, 2].sum() == pytest.approx(-p * a * b, rel=1e-12, abs=0)
    assert plan.area == pytest.approx(a * b, rel=1e-12)
    normal = area_load(xyz, edges, everything(xyz), p, "normal")
    total = normal.force.sum(axis=0)
    k = 0.3 / scale
    vector = np.array([-k * a * b * b / 2, -k * a * a * b / 2, a * b])
    assert np.allclose(total, -p * vector, rtol=1e-12, atol=0)
    assert normal.area > a * b  # the surface is larger than its plan


def test_a_normal_pressure_on_a_flat_net_is_the_plan_load():
    sq = geo.square_net(10, 0.4, 3.0, 0.1, geo.Material(EA=1.0)).net
    nodes = sq.nodes + np.array([0.0, 0.0, 2.5])  # any height
    plan = area_load(nodes, sq.edges, everything(nodes), 120.0, "plan")
    normal = area_load(nodes, sq.edges, everything(nodes), 120.0, "normal")
    assert np.array_equal(plan.force, normal.force)
    assert np.array_equal(normal.normal, [0.0, 0.0, 1.0])


def test_a_vertical_net_takes_wind_normal_to_it_and_no_snow():
    xyz, edges = grid(5, 4)
    wall = xyz[:, [0, 2, 1]]  # in the plane y = 0
    wind = area_load(wall, edges, everything(wall), 100.0, "normal")
    # a vertical net's normal points to +x, else +y: pressure > 0 pushes along -y
    assert wind.normal @ [0, 1, 0] == pytest.approx(1.0)
    assert np.allclose(wind.force.sum(axis=0), [0.0, -100.0 * 12.0, 0.0], rtol=1e-12, atol=1e-9)
    with pytest.raises(ConfigError, match="covers no area"):
        area_load(wall, edges, everything(wall), 100.0, "plan")


@pytest.mark.parametrize("direction", ["normal", "plan"])
def test_one_edge_covers_no_area(direction):
    """Two nodes joined by one edge, out of the plan (the fuzz run of seed 19: a node set
    of two nodes of a hypar under an area load normal to it was an internal error)."""
    xyz = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.3], [2.0, 0.0, 1.0]])
    edges = np.array([[0, 1], [1, 2]])
    covered = np.array([True, True, False])
    with pytest.raises(ConfigError, match="covers no area: its nodes lie on a line"):
        area_load(xyz, edges, covered, 100.0, direction)


@pytest.mark.parametrize("alpha", [0.0, 0.3, np.pi / 4, 1.2])
def test_the_open_cells_of_a_cable_net_are_closed_through_its_outer_nodes(alpha):
    """The square net's cables end on the square, with no edge between their ends: the
    covered area is the convex polygon through the ends (on a square, the hull)."""
    from scipy.spatial import ConvexHull

    net = geo.square_net(10, alpha, 2.0, 0.07, geo.Material(EA=1.0)).net
    load = area_load(net.nodes, net.edges, everything(net.nodes), 1.0, "plan")
    hull = ConvexHull(net.nodes[:, :2]).volume
    assert load.area == pytest.approx(hull, rel=1e-12)
    assert load.force[:, 2].sum() == pytest.approx(-hull, rel=1e-12)
    assert np.all(load.force[:, 2] < 0)  # every node carries some


def test_a_concave_outline_is_kept():
    """An L-shaped grid: its notch is not covered."""
    xyz, edges = grid(5, 5)
    keep = ~((xyz[:, 0] > 2) & (xyz[:, 1] > 2))
    load = area_load(xyz, edges, keep, 1.0, "plan")
    assert load.area == pytest.approx(16.0 - 4.0, rel=1e-12)
    assert np.all(load.force[~keep] == 0.0)


def ringless_net(n: int = 3):
    """n x n cables 1 apart crossing in [1, n] x [1, n], each ending one further out on
    a support, no edge between the ends (a cable net without an edge ring)."""
    inner = [[float(i), float(j), 0.0] for j in range(1, n + 1) for i in range(1, n + 1)]
    ends, edges = [], []
    at = lambda i, j: (j - 1) * n + (i - 1)  # noqa: E731
    for k in range(1, n + 1):
        for a, b, chain in (
            ([0.0, k, 0.0], [n + 1.0, k, 0.0], [at(i, k) for i in range(1, n + 1)]),
            ([k, 0.0, 0.0], [k, n + 1.0, 0.0], [at(k, j) for j in range(1, n + 1)]),
        ):
            first, last = len(inner) + len(ends), len(inner) + len(ends) + 1
            ends += [a, b]
            path = [first, *chain, last]
            edges += [[u, v] for u, v in zip(path[:-1], path[1:], strict=True)]
    return np.array(inner + ends), np.array(edges)


@pytest.mark.parametrize("width", [1, 2, 3])
def test_part_of_a_net_without_an_edge_ring_covers_its_outline(width):
    """The western strip of a 3 x 3 ring-less net, x <= width: its border runs straight
    along a cable (the nodes of the line x = width), beside the open cells closed
    through the cable ends. Once refused as "edges cross": the closing edge was laid
    over the straight border's edges. Covered: the strip's rectangle [0, width] x [0, 4]
    less the two corner triangles of 1/2 cut by the ends' outline (a corner has no node)."""
    xyz, edges = ringless_net(3)
    keep = xyz[:, 0] <= width + 1e-9
    load = area_load(xyz, edges, keep, 1000.0, "plan")
    area = 4.0 * width - 2 * 0.5
    assert load.area == pytest.approx(area, rel=1e-12)
    assert load.force[:, 2].sum() == pytest.approx(-1000.0 * area, rel=1e-12)
    assert np.all(load.force[keep, 2] <= 0.0) and np.all(load.force[~keep] == 0.0)


def test_parallel_cables_without_cross_ties_share_the_strips_between_them():
    ends = []
    edges = []
    for k in range(4):
        base = len(ends)
        ends += [[x, 1.5 * k, 0.0] for x in np.linspace(0.0, 6.0, 7)]
        edges += [[base + i, base + i + 1] for i in range(6)]
    xyz, edges = np.array(ends), np.array(edges)
    load = area_load(xyz, edges, everything(xyz), 2.0, "plan")
    assert load.force[:, 2].sum() == pytest.approx(-2.0 * 6.0 * 4.5, rel=1e-12)


def test_a_node_set_covers_the_chains_of_nodes_between_its_nodes():
    """Nodes 0..3 given, 4.. split the cables: a chain is covered when both its ends are."""
    edges = np.array([[0, 4], [4, 5], [5, 1], [1, 6], [6, 2], [2, 3]])
    covered = np.zeros(7, dtype=bool)
    covered[[0, 1]] = True
    out = with_chains(covered, 4, edges)
    assert out.tolist() == [True, True, False, False, True, True, False]


@pytest.mark.parametrize(
    "nodes, edges, message",
    [
        ([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1], [1, 2]], "lie on a line"),
        ([[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 1]], "lie on a line"),
        (
            [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 1]],
            [[0, 1], [1, 2], [2, 0], [1, 3]],
            "nodes 1 and 3 lie at one point",
        ),
    ],
)
def test_nets_that_cover_no_area_are_refused(nodes, edges, message):
    xyz = np.array(nodes, dtype=float)
    with pytest.raises(ConfigError, match=message):
        area_load(xyz, np.array(edges), everything(xyz), 1.0, "plan")


def test_edges_that_cross_in_the_drawing_are_refused():
    """Two layers: a grid and a second one above it, shifted, joined at one corner."""
    a, ea = grid(3, 3)
    b = a + [0.5, 0.5, 1.0]
    xyz = np.concatenate([a, b])
    edges = np.concatenate([ea, ea + 9, [[0, 9]]])
    with pytest.raises(ConfigError, match="cross"):
        area_load(xyz, edges, everything(xyz), 1.0, "plan")
