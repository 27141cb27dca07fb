"""Twist of rods (``catenet.terms.twist``): the exact gradient and Hessian against finite
differences (clamped chains, twisted, near straight; rings), the total twist against the
parallel transport chain it stands for, its count kept over many turns, invariance of a
ring under rigid motions, and which chains twist."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.model.net import Net
from catenet.model.rods import build_rods
from catenet.model.twist import build_twists, twisting_moment
from catenet.terms import check_derivatives
from catenet.terms.twist import Twist

GJ = 3.0


def _chain(x: np.ndarray, *, angle: float = 0.7, clamped=None) -> Twist:
    """A chain of edges along x's nodes, EI 2 and GJ 3, clamped at both ends (or at
    ``clamped``), its last end turned by ``angle``."""
    n = len(x) - 1
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0, n], tension_only=False)
    ends = np.array([0, n] if clamped is None else clamped)
    rods = build_rods(net, np.full(n, 2.0), np.zeros(n, np.int64), clamped=ends)
    twists = build_twists(net, np.full(n, GJ), np.zeros(n, np.int64), rods.clamps, rods.tangent)
    imposed = [(0, angle, None)] if len(twists) else []
    return Twist(twists, len(x), x, imposed)


def _ring(x: np.ndarray, angle: float = 1.3) -> Twist:
    m = len(x)
    k = np.arange(m)
    edges = np.column_stack([k, (k + 1) % m])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    rods = build_rods(net, np.full(m, 2.0), np.zeros(m, np.int64))
    twists = build_twists(net, np.full(m, GJ), np.zeros(m, np.int64), rods.clamps, rods.tangent)
    return Twist(twists, m, x, [(0, angle, None)])


def _wavy(n=6, amplitude=0.3, seed=1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.linspace(0.0, 5.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    return x + amplitude * rng.standard_normal(x.shape)


def _wobbly_ring(m=9) -> np.ndarray:
    a = 2.0 * np.pi * np.arange(m) / m
    return np.column_stack([np.cos(a), np.sin(a), 0.3 * np.sin(2.0 * a) + 0.1 * np.cos(3.0 * a)])


def _transport(u, v, w):
    b = np.cross(u, v)
    return w + np.cross(b, w) + np.cross(b, np.cross(b, w)) / (1.0 + u @ v)


def _chain_twist(term: Twist, x: np.ndarray) -> float:
    """Theta of an open segment straight from its definition: the head's director carried
    along every tangent to the tail's, and its angle to the tail's director (mod 2 pi)."""
    t = term.twists
    tangents = [t.head[0]]
    for a, b in zip(t.nodes[:-1], t.nodes[1:], strict=True):
        e = x[b] - x[a]
        tangents.append(e / np.linalg.norm(e))
    tangents.append(t.tail[0])
    u = t.head_dir[0]
    for a, b in zip(tangents[:-1], tangents[1:], strict=True):
        u = _transport(a, b, u)
    d, axis = t.tail_dir[0], t.tail[0]
    return math.atan2(float(np.cross(u, d) @ axis), float(u @ d))


@pytest.mark.parametrize("scale", [0.3, 1e-3])
def test_derivatives_match_finite_differences(scale):
    given = _wavy()
    term = _chain(given)
    x = given + scale * np.random.default_rng(2).standard_normal(given.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-7, (grad_err, hess_err)
    term.begin_step(x, None)  # frames carried to x: the same function
    assert check_derivatives(term, x) < (1e-7, 1e-7)


@pytest.mark.parametrize("offset", [1e-4, 1e-2])
def test_derivatives_near_straight(offset):
    """A straight twisted rod: the gradient vanishes there, the Hessian is the twist's
    own; near it no cancellation spoils either."""
    n = 5
    straight = np.column_stack([np.linspace(0.0, 2.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    term = _chain(straight, angle=2.0)
    g = np.zeros_like(straight)
    term.gradient(straight, g)
    assert np.abs(g).max() < 1e-14
    x = straight + offset * np.random.default_rng(3).standard_normal(straight.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-6 and hess_err < 1e-7, (grad_err, hess_err)


def test_ring_derivatives_and_rigid_motions():
    given = _wobbly_ring()
    term = _ring(given)
    x = given + 0.1 * np.random.default_rng(4).standard_normal(given.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-7, (grad_err, hess_err)
    c, s = math.cos(0.7), math.sin(0.7)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
    )
    moved = x @ turn.T + np.array([3.0, -1.0, 2.0])
    assert term.energy(moved) == pytest.approx(term.energy(x), rel=1e-12)


def test_the_total_twist_is_the_parallel_transport_chain():
    """Theta (by the per-vertex reference twists and lagged frames) is the angle from
    the head's director, carried along the chain, to the tail's: at states near and far
    from the frames' state, and the chain's own is untwisted as given."""
    given = _wavy(n=8, amplitude=0.4)
    term = _chain(given, angle=0.0)
    assert _chain_twist(term, given) == pytest.approx(0.0, abs=1e-12)
    rng = np.random.default_rng(5)
    for scale in (0.05, 0.2):
        x = given + scale * rng.standard_normal(given.shape)
        theta = float(term.moments(x)[0] * term.twists.compliance[0])
        assert math.remainder(theta - _chain_twist(term, x), 2 * math.pi) == pytest.approx(
            0.0, abs=1e-10
        )


def _holonomy(x: np.ndarray) -> float:
    """The angle by which parallel transport around a closed polygon turns a vector
    normal to its first edge (mod 2 pi)."""
    e = np.roll(x, -1, axis=0) - x
    t = e / np.linalg.norm(e, axis=1)[:, None]
    u0 = np.cross(t[0], [0.3, 0.5, 0.8])
    u0 /= np.linalg.norm(u0)
    u = u0
    for k in range(1, len(t) + 1):
        u = _transport(t[k - 1], t[k % len(t)], u)
    return math.atan2(float(np.cross(u0, u) @ t[0]), float(u0 @ u))


def _wound(term: Twist, coil, radii) -> float:
    """The ring's tracked twist after walking through the coils of ``radii``."""
    compliance = float(term.twists.compliance[0])
    theta = 0.0
    for r in radii:
        x = coil(r)
        theta = float(term.moments(x)[0]) * compliance
        term.begin_step(x, None)
        assert float(term.moments(x)[0]) * compliance == pytest.approx(theta, abs=1e-9)
        assert math.remainder(theta + _holonomy(x), 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    return theta


def test_the_twist_keeps_its_count_over_many_turns():
    """A ring wound into a coil step by step: its holonomy changes by more than 2 pi; the
    tracked twist agrees with it (mod 2 pi) at every step and ends the same whether the
    walk takes 60 steps or 240: no turn is lost or counted twice."""
    m = 120
    a = 2.0 * np.pi * np.arange(m) / m

    def coil(r: float) -> np.ndarray:
        q = 7.0  # turns about the core circle
        return np.column_stack(
            [(1.0 + r * np.cos(q * a)) * np.cos(a), (1.0 + r * np.cos(q * a)) * np.sin(a),
             r * np.sin(q * a)]
        )  # fmt: skip

    coarse = _wound(_ring(coil(0.0), angle=0.0), coil, np.linspace(0.0, 0.5, 61)[1:])
    fine = _wound(_ring(coil(0.0), angle=0.0), coil, np.linspace(0.0, 0.5, 241)[1:])
    assert abs(coarse) > 2.5 * math.pi
    assert coarse == pytest.approx(fine, abs=1e-9)


def test_twisting_moment_of_a_straight_rod_and_the_chains_that_twist():
    """GJ Phi / L on every edge of a straight rod; a chain with a free end or a pinned
    one does not twist (no segment), nor do edges without GJ."""
    n = 4
    x = np.column_stack([np.linspace(0.0, 2.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    term = _chain(x, angle=0.5)
    moment = twisting_moment(term.twists, term.moments(x), n)
    assert moment == pytest.approx(np.full(n, GJ * 0.5 / 2.0), rel=1e-14)
    assert len(_chain(x, clamped=[0]).twists) == 0
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0, n], tension_only=False)
    rods = build_rods(net, np.full(n, 2.0), np.zeros(n, np.int64), clamped=np.array([0, n]))
    gj = np.array([GJ, GJ, 0.0, GJ])  # a gap: no chain reaches from clamp to clamp
    assert len(build_twists(net, gj, np.zeros(n, np.int64), rods.clamps, rods.tangent)) == 0


def test_a_fold_makes_the_twist_undefined():
    n = 3
    x = np.column_stack([np.linspace(0.0, 3.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    term = _chain(x)
    folded = x.copy()
    folded[2] = folded[1] + np.array([-1.0, 0.0, 0.0])  # edge 1 turned back on edge 0
    assert term.energy(folded) == math.inf
