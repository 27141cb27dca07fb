"""The builders: the paper's square net (contract §2), single cables, graphs."""

from __future__ import annotations

import math

import numpy as np
import pytest

import catenet as cn

MAT = cn.Material.from_E(10e6, radius=0.01, density=1000.0)


def cable_lines(n, alpha, L):
    """The 2m lines of contract §2 as (point, direction) pairs."""
    m = n // 2
    d = L / (m + 1)
    u = np.array([math.cos(alpha), math.sin(alpha)])
    v = np.array([-math.sin(alpha), math.cos(alpha)])
    c = (np.arange(m) - (m - 1) / 2) * d
    return [(ck * v, u) for ck in c] + [(-ck * u, v) for ck in c]


@pytest.mark.parametrize("n", [2, 10, 18, 34])
@pytest.mark.parametrize("alpha", [0.0, 0.25, math.pi / 6, math.pi / 4, 1.3])
def test_square_net_topology(n, alpha):
    L, h = 1.0, 0.03
    sq = cn.square_net(n, alpha, L, h, MAT)
    net = sq.net
    xy = net.nodes[:, :2]
    assert np.all(np.abs(xy) <= L / 2 + 1e-12) and not net.nodes[:, 2].any()
    # Every edge lies on one of the lines and is no longer than the edge length.
    length = np.linalg.norm(xy[net.edges[:, 1]] - xy[net.edges[:, 0]], axis=1)
    assert length.max() <= h * (1 + 1e-9)
    np.testing.assert_allclose(net.rest_length, length)
    lines = cable_lines(n, alpha, L)
    mid = 0.5 * (xy[net.edges[:, 0]] + xy[net.edges[:, 1]])
    dist = np.min(
        [np.abs(w[0] * (mid[:, 1] - q[1]) - w[1] * (mid[:, 0] - q[0])) for q, w in lines],
        axis=0,
    )
    assert dist.max() < 1e-9
    # Crossings: every pair of lines (one per family) that meets inside the square shares
    # exactly one node, of degree 4 unless it lies on the boundary.
    m = n // 2
    for k in range(m):
        for j in range(m):
            q = lines[k][0] + (-(j - (m - 1) / 2) * L / (m + 1)) * lines[k][1]
            if np.all(np.abs(q) < L / 2 - 1e-9):
                hits = np.flatnonzero(np.linalg.norm(xy - q, axis=1) < 1e-9)
                assert hits.size == 1
                degree = np.sum(net.edges == hits[0])
                assert degree == 4
    # Both ends of every cable are pinned: the fixed nodes are exactly the boundary ones.
    on_boundary = np.isclose(np.abs(xy).max(axis=1), L / 2)
    assert np.array_equal(net.fixed, on_boundary)
    assert net.fixed.sum() == 2 * n or alpha > 0  # corners may be shared when alpha > 0


def test_segment_of_exact_multiple_gets_exact_edges():
    """A segment of exactly k edge lengths gets k edges, whatever the round-off."""
    sq = cn.square_net(2, 0.0, 1.0, 0.1, MAT)  # one cable per family through the centre
    assert sq.net.n_edges == 20  # two cables, each two segments of 0.5 = 5 edge lengths
    assert sq.net.n_nodes == 2 * 11 - 1


def test_center_node_is_a_joint_for_odd_m():
    for n in (10, 18, 22, 26, 34):
        sq = cn.square_net(n, math.pi / 4, 1.0, 0.01, MAT)
        assert np.allclose(sq.net.nodes[sq.center], 0.0)
        assert np.sum(sq.net.edges == sq.center) == 4


def test_paper_net_size():
    """n = 34 with 1 cm edges: about 10^4 DOF (the paper quotes about 13 000)."""
    sq = cn.square_net(34, 0.0, 1.0, 0.01, MAT)
    dofs = 3 * int((~sq.net.fixed).sum())
    assert 9000 < dofs < 13000


def test_pressure_load_is_p_L2_over_N():
    sq = cn.square_net(10, 0.0, 2.0, 0.05, MAT)
    f = cn.pressure_force(sq.net, 100.0, 2.0)
    assert np.allclose(f[:, 2], -100.0 * 4.0 / sq.net.n_nodes) and not f[:, :2].any()


@pytest.mark.parametrize("n", [0, 3, -2, 7])
def test_square_net_rejects_odd_or_nonpositive_n(n):
    with pytest.raises(cn.ConfigError, match="geometry.n"):
        cn.square_net(n, 0.0, 1.0, 0.01, MAT)


def test_cable_builder():
    net = cn.cable([0, 0, 0], [2, 0, 0], 5, MAT, length=2.2)
    assert net.n_nodes == 5 and net.n_edges == 4
    assert np.allclose(net.rest_length, 0.55)
    assert np.flatnonzero(net.fixed).tolist() == [0, 4]
    with pytest.raises(cn.ConfigError, match="geometry.end"):
        cn.cable([0, 0, 0], [0, 0, 0], 5, MAT)


@pytest.mark.parametrize(
    "nodes, edges, fixed, match",
    [
        ([[0, 0, 0], [1, 0, 0]], [[0, 0]], [0], "two different nodes"),
        ([[0, 0, 0], [1, 0, 0]], [[0, 2]], [0], "node indices"),
        ([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1], [1, 0]], [0], "unique"),
        ([[0, 0, 0], [0, 0, 0]], [[0, 1]], [0], "zero length"),
        ([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1]], [0], "belong to no edge"),
        ([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], [[0, 1], [2, 3]], [0], "no support"),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], [], "no node is fixed"),
    ],
)
def test_graph_rejects_impossible_nets(nodes, edges, fixed, match):
    with pytest.raises(cn.ConfigError, match=match):
        cn.graph(nodes, edges, fixed, MAT)
