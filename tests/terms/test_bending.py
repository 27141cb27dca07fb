"""Bending of rods (``catenet.terms.bending``): the exact gradient and Hessian against
finite differences (bent, near-straight, straight, folded, naturally curved, clamped),
the energy of a circle, invariance under rigid motions, and which edges bend."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.errors import ConfigError
from catenet.model.net import Net
from catenet.model.rods import bending_moment, build_rods, rod_hinges
from catenet.terms import check_derivatives
from catenet.terms.bending import Bending


def _chain(x: np.ndarray, *, EI: float = 2.0, natural=False, clamped=(0,)) -> Bending:
    n = len(x) - 1
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    rods = build_rods(
        net,
        np.full(n, EI),
        np.zeros(n, np.int64),
        natural=np.full(n, natural),
        clamped=np.array(clamped),
    )
    return Bending(rods, len(x))


def _wavy(n=6, amplitude=0.3, seed=1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.linspace(0.0, 5.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    return x + amplitude * rng.standard_normal(x.shape)


@pytest.mark.parametrize("natural", [False, True])
@pytest.mark.parametrize("scale", [0.3, 1e-3])
def test_derivatives_match_finite_differences(natural, scale):
    given = _wavy()
    term = _chain(given, natural=natural)
    x = given + scale * np.random.default_rng(2).standard_normal(given.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-7, (grad_err, hess_err)


@pytest.mark.parametrize("offset", [0.0, 1e-6, 1e-4])
def test_derivatives_near_straight(offset):
    """Straight rods (s0 = 0): no cancellation near and at the straight state."""
    n = 5
    straight = np.column_stack([np.linspace(0.0, 2.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    term = _chain(straight)
    x = straight + offset * np.random.default_rng(3).standard_normal(straight.shape)
    grad_err, hess_err = check_derivatives(term, x)
    if offset == 0.0:  # the gradient vanishes: compare differences absolutely
        g = np.zeros_like(x)
        assert term.gradient(x, g) == 0.0 and not g.any()
    else:
        assert grad_err < 1e-6, grad_err
    assert hess_err < 1e-8, hess_err


def test_the_fold_is_a_smooth_maximum_with_finite_values():
    """At 180 degrees s = 2: the energy is 4 k, the gradient zero, the Hessian exact."""
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    x[2, 1] = 1e-12
    term = _chain(np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]]), EI=2.0, clamped=())
    g = np.zeros_like(x)
    energy = term.gradient(x, g)
    assert energy == pytest.approx(4.0 * 2.0 / 2.0)  # 4 k, k = EI / (l1 + l2)
    assert np.all(np.isfinite(g)) and np.max(np.abs(g)) < 1e-9
    _, hess_err = check_derivatives(term, x)
    assert hess_err < 1e-8


def test_naturally_curved_rod_is_unstressed_as_given_and_the_cone_tip_is_finite():
    given = _wavy()
    term = _chain(given, natural=True)
    g = np.zeros_like(given)
    assert term.gradient(given, g) == pytest.approx(0.0, abs=1e-20)
    assert np.max(np.abs(g)) < 1e-12
    straight = np.column_stack([np.linspace(0, 5, 7), np.zeros(7), np.zeros(7)])
    values = np.zeros(len(term.pattern()[0]))
    term.hessian(straight, values)  # pressed straight: below DELTA s0, finite
    assert np.all(np.isfinite(values)) and term.energy(straight) > 0.0


def test_circle_energy_and_moment_are_exact():
    """A closed polygon inscribed in a circle of radius R with equal chords: s / l = 1 / R
    at every hinge, so E = EI / (2 R^2) 2 pi R' (the polygon's length) and M = EI / R."""
    n, radius, EI = 24, 2.0, 3.0
    phi = 2 * math.pi * np.arange(n) / n
    x = np.column_stack([radius * np.cos(phi), radius * np.sin(phi), np.zeros(n)])
    edges = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    rods = build_rods(net, np.full(n, EI), np.zeros(n, np.int64))
    assert len(rods.hinges) == n  # the closed line bends at its first node too
    length = float(np.sum(net.rest_length))
    term = Bending(rods, n)
    assert term.energy(x) == pytest.approx(EI / (2 * radius**2) * length, rel=1e-12)
    moment, kappa = bending_moment(rods, x, n)
    assert moment == pytest.approx(np.full(n, EI / radius), rel=1e-12)
    assert kappa == pytest.approx(np.full(n, 1 / radius), rel=1e-12)


def test_rigid_motions_cost_nothing():
    given = _wavy()
    term = _chain(given, natural=True)  # the clamp aside: it holds the given direction
    free = Bending(
        build_rods(
            Net.from_arrays(
                given,
                np.column_stack([np.arange(6), np.arange(1, 7)]),
                EA=1.0,
                fixed=[0],
                tension_only=False,
            ),
            np.full(6, 2.0),
            np.zeros(6, np.int64),
            natural=np.ones(6, bool),
        ),
        7,
    )
    c, s = math.cos(0.7), math.sin(0.7)
    turned = given @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [3.0, -1.0, 2.0]
    assert free.energy(turned) == pytest.approx(0.0, abs=1e-20)
    assert term.energy(turned) > 0.0  # a clamp does not turn with the rod


def test_clamp_energy_of_a_small_rotation():
    """A clamped end edge turned by theta: E = EI / l |t - t0|^2 = EI / l 4 sin^2(theta / 2)."""
    x = np.array([[0.0, 0, 0], [0.5, 0, 0]])
    edges = np.array([[0, 1]])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    rods = build_rods(net, np.array([2.0]), np.zeros(1, np.int64), clamped=np.array([0]))
    theta = 0.01
    turned = np.array([[0.0, 0, 0], [0.5 * math.cos(theta), 0, 0.5 * math.sin(theta)]])
    term = Bending(rods, 2)
    assert term.energy(turned) == pytest.approx(2.0 / 0.5 * 4 * math.sin(theta / 2) ** 2)
    grad_err, hess_err = check_derivatives(term, turned)
    assert grad_err < 1e-7 and hess_err < 1e-7


def test_hinges_follow_lines_and_skip_joints():
    """Two lines meeting at node 2 (a joint: pinned) and an edge of no line."""
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [2, 5]])
    line = np.array([0, 0, 1, 1, -1])
    pairs = rod_hinges(edges, line, np.ones(5, bool))
    assert pairs[:, 2:].tolist() == [[0, 1, 2], [2, 3, 4]]
    bends = np.array([True, False, True, True, True])
    assert rod_hinges(edges, line, bends)[:, 2:].tolist() == [[2, 3, 4]]


def test_a_clamp_must_be_a_rod_end():
    x = np.column_stack([np.arange(4.0), np.zeros(4), np.zeros(4)])
    edges = np.column_stack([np.arange(3), np.arange(1, 4)])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    for node, why in ((1, "an interior node of a rod"), (0, "on no edge with EI > 0")):
        ei = np.array([0.0, 1.0, 1.0]) if node == 0 else np.ones(3)
        with pytest.raises(ConfigError, match=why):
            build_rods(net, ei, np.zeros(3, np.int64), clamped=np.array([node]))
