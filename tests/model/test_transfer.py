"""A coarse net's state carried along each cable onto a finer net of the same cables
(catenet.model.transfer): exact for displacements linear along every chain, None for nets
that are not a coarse and a fine net of the same cables."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.model import builders as geo
from catenet.model.net import Net
from catenet.model.transfer import Chains, transfer


def square(edge: float, alpha: float = 0.3) -> Net:
    return geo.square_net(6, alpha, 2.0, edge, geo.Material(EA=1.0)).net


def polyline(points, per_segment: int, fixed=(0, -1)) -> Net:
    """One cable through ``points``, each segment split into ``per_segment`` edges."""
    points = np.asarray(points, dtype=np.float64)
    nodes = [points[0]]
    for a, b in zip(points[:-1], points[1:], strict=True):
        t = np.arange(1, per_segment + 1)[:, None] / per_segment
        nodes.extend(a + t * (b - a))
    nodes = np.array(nodes)
    n = len(nodes)
    edges = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    return Net.from_arrays(nodes, edges, EA=1.0, fixed=[f % n for f in fixed])


@pytest.mark.parametrize("alpha", [0.0, 0.3, np.pi / 4])
def test_a_linear_field_carries_over_exactly(alpha):
    coarse, fine = square(0.2, alpha), square(0.03, alpha)
    A = np.array([[0.1, -0.2, 0.05], [0.3, 0.0, -0.1], [-0.2, 0.4, 0.2]])
    b = np.array([0.01, -0.02, 0.03])

    def field(X):
        return X @ A.T + b

    x = transfer(coarse, coarse.nodes + field(coarse.nodes), fine)
    assert x is not None and fine.n_nodes > 3 * coarse.n_nodes
    np.testing.assert_allclose(x - fine.nodes, field(fine.nodes), rtol=0, atol=1e-14)


def test_the_same_net_carries_over_unchanged():
    net = square(0.1)
    x = net.nodes + np.random.default_rng(1).normal(size=net.nodes.shape)
    np.testing.assert_allclose(transfer(net, x, net), x, rtol=0, atol=1e-14)


def test_along_a_bent_cable_by_arc_length():
    """An L-shaped cable (a bend where no joint is): a displacement linear in the arc
    length carries over exactly, though it is not linear in space; the bend moves with
    its coarse node."""
    pts = [[0, 0, 0], [3, 0, 0], [3, 1, 0]]
    coarse, fine = polyline(pts, 2), polyline(pts, 6)
    chains = Chains(coarse)
    assert chains.ok and chains.length.tolist() == [4.0]

    def arc(X):
        return np.where(X[:, 1] > 0, 3.0 + X[:, 1], X[:, 0])

    def field(s):
        return np.column_stack([0.1 * s, -0.05 * s, 0.02 * s + 0.3])

    x = transfer(coarse, coarse.nodes + field(arc(coarse.nodes)), fine)
    np.testing.assert_allclose(x - fine.nodes, field(arc(fine.nodes)), atol=1e-14)
    # a field that is not linear along the cable: linear between the coarse nodes
    s_c, s_f = arc(coarse.nodes), arc(fine.nodes)
    u_c = np.column_stack([s_c**2, np.zeros_like(s_c), np.zeros_like(s_c)])
    x = transfer(coarse, coarse.nodes + u_c, fine)
    np.testing.assert_allclose(x[:, 0] - fine.nodes[:, 0], np.interp(s_f, s_c, s_c**2))


def test_reversed_numbering_follows_the_joints():
    """The fine cable numbered from the other end: each node takes the displacement of
    its own place along the cable."""
    pts = [[0, 0, 0], [2, 0, 0]]
    coarse = polyline(pts, 2)
    fine = polyline(pts[::-1], 8)
    u = np.array([[0, 0, 0], [0, 0, -1.0], [0, 0, 0]])
    x = transfer(coarse, coarse.nodes + u, fine)
    expected = -(1.0 - np.abs(fine.nodes[:, 0] - 1.0))
    np.testing.assert_allclose(x[:, 2], expected, atol=1e-14)


def test_nets_of_other_cables_give_none():
    coarse = square(0.2)
    other = geo.square_net(8, 0.3, 2.0, 0.05, geo.Material(EA=1.0)).net  # other crossings
    assert transfer(coarse, coarse.nodes, other) is None
    moved = polyline([[0, 0, 0], [2, 0, 0]], 4)
    longer = polyline([[0, 0, 0], [2.5, 0, 0]], 8)  # a joint where the coarse has none
    assert transfer(moved, moved.nodes, longer) is None
    # supports elsewhere: a joint that is pinned on one net and free on the other
    pinned = polyline([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 2, fixed=(0, 2, -1))
    free = polyline([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 4, fixed=(0, 4, -1))
    assert transfer(pinned, pinned.nodes, free) is not None
    free_mid = polyline([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 4, fixed=(0, 3, -1))
    assert transfer(pinned, pinned.nodes, free_mid) is None


def test_a_ring_without_joints_has_no_chains():
    t = np.linspace(0, 2 * np.pi, 9)[:-1]
    nodes = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])
    edges = np.column_stack([np.arange(8), (np.arange(8) + 1) % 8])
    ring = Net.from_arrays(nodes, edges, EA=1.0, fixed=[], flies=True)
    assert not Chains(ring).ok
    assert transfer(ring, ring.nodes, ring) is None
