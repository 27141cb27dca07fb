"""The barrier between strands (catenet/terms/strands.py): exact derivatives in every
regime of the segment distance, the candidate pairs of the grid against brute force, the
step cap of the continuous collision check, and a closed-form contact: a free strand
pressed onto a pinned one carries its whole load through the contact, at rest closer
than the activation distance."""

from __future__ import annotations

import numpy as np
import pytest
from meshes import segment_distance

from catenet.kernels.ccd import accd
from catenet.kernels.strands import EPS_PARALLEL, candidates, closest, sqdist
from catenet.model.net import Loads, Net
from catenet.solver.dynamic import solve_dynamic
from catenet.solver.workspace import Workspace
from catenet.terms import check_derivatives
from catenet.terms.strands import SelfContact, default_strand_stiffness


def _pair(a0, a1, b0, b1, dhat=1.0):
    nodes = np.array([a0, a1, b0, b1], dtype=float)
    net = Net.from_arrays(nodes, [[0, 1], [2, 3]], EA=1.0, fixed=[], flies=True)
    return SelfContact(net, kappa=3.0, dhat=dhat), nodes


#: (points, the regime closest() must find: s free, t free, mollified)
REGIMES = {
    "interior": (([0, 0, 0], [1, 0, 0], [0.5, -0.5, 0.3], [0.4, 0.5, 0.35]), True, True, False),
    "one clamped": (([0, 0, 0], [1, 0, 0], [1.2, -0.5, 0.3], [1.1, 0.5, 0.35]), False, True, False),
    "both clamped": (
        ([0, 0, 0], [1, 0, 0], [1.2, 0.1, 0.3], [1.8, 0.5, 0.35]),
        False,
        False,
        False,
    ),
    "nearly parallel, crossing": (
        ([0, 0, 0], [1, 0, 0], [0.2, 0.01, 0.3], [1.2, -0.012, 0.3]),
        True,
        True,
        True,
    ),
    "nearly parallel, overlapping": (
        ([0, 0, 0], [1, 0, 0], [0.3, 0.01, 0.3], [1.3, 0.02, 0.31]),
        True,
        False,
        True,
    ),
    "nearly parallel, end to end": (
        ([0, 0, 0], [1, 0, 0], [1.1, 0.001, 0.3], [2.1, 0.003, 0.32]),
        False,
        False,
        True,
    ),
}


@pytest.mark.parametrize("name", list(REGIMES))
def test_gradient_and_hessian_match_finite_differences_in_every_regime(name):
    points, s_free, t_free, mollified = REGIMES[name]
    term, x = _pair(*points)
    _, _, fs, ft = closest(x.ravel().copy(), 0)
    assert (fs, ft) == (s_free, t_free)
    u, v = x[1] - x[0], x[3] - x[2]
    e = np.dot(np.cross(u, v), np.cross(u, v))
    assert (e < EPS_PARALLEL * (u @ u) * (v @ v)) == mollified
    assert term.energy(x) > 0.0
    grad_err, hess_err = check_derivatives(term, x, step=1e-6)
    assert grad_err < 1e-7 and hess_err < 1e-6


def test_distance_is_the_segments_distance_and_nothing_acts_out_of_reach():
    rng = np.random.default_rng(3)
    P = rng.normal(size=(200, 4, 3))
    g, H = np.empty(12), np.empty((12, 12))
    mine = np.sqrt([sqdist(p.ravel().copy(), 0, g, H, False) for p in P])
    # brute force over a fine parameter grid: never below, close to the exact minimum
    s = np.linspace(0, 1, 201)
    a = P[:, None, 0] + s[None, :, None] * (P[:, None, 1] - P[:, None, 0])
    b = P[:, None, 2] + s[None, :, None] * (P[:, None, 3] - P[:, None, 2])
    brute = np.linalg.norm(a[:, :, None] - b[:, None, :], axis=-1).min(axis=(1, 2))
    assert np.all(mine <= brute + 1e-12) and np.all(brute - mine < 2e-3)
    assert mine == pytest.approx(segment_distance(P), rel=1e-12, abs=1e-14)
    term, x = _pair([0, 0, 0], [1, 0, 0], [0.5, -0.5, 1.01], [0.5, 0.5, 1.01])
    grad = np.zeros_like(x)
    assert term.gradient(x, grad) == 0.0 and not grad.any()
    assert term.hessian(x, np.empty(144)) is False


def test_parallel_strands_touching_have_infinite_energy():
    # exactly parallel (the mollifier is 0): the end point-edge barriers hold them apart
    term, x = _pair([0, 0, 0], [1, 0, 0], [0.5, 0, 0.0], [1.5, 0, 0.0], dhat=0.1)
    assert term.energy(x) == np.inf
    x[2:, 1] = 0.05
    assert 0.0 < term.energy(x) < np.inf


def test_the_grid_finds_exactly_the_close_pairs_of_a_random_tangle():
    rng = np.random.default_rng(7)
    nodes = rng.uniform(0, 1, size=(120, 3))
    edges = np.array([[i, i + 1] for i in range(119)] + [[i, i + 40] for i in range(0, 80, 3)])
    grow = rng.uniform(0, 0.05, len(edges))
    reach = 0.03
    pairs = candidates(nodes, edges, grow, reach)
    a, b = np.triu_indices(len(edges), 1)
    apart = ~np.any(edges[a][:, :, None] == edges[b][:, None, :], axis=(1, 2))
    P = np.stack(
        [nodes[edges[a, 0]], nodes[edges[a, 1]], nodes[edges[b, 0]], nodes[edges[b, 1]]], 1
    )
    near = apart & (segment_distance(P) <= reach + grow[a] + grow[b])
    assert len(pairs) == near.sum() > 50
    assert {tuple(p) for p in pairs.tolist()} == set(
        zip(a[near].tolist(), b[near].tolist(), strict=True)
    )


def test_the_collision_check_stops_before_two_strands_meet():
    # b drops through a: they would meet at t = 0.5 of the step
    P = np.array([0, 0, 0, 1, 0, 0, 0.5, -0.5, 1.0, 0.5, 0.5, 1.0], dtype=float)
    dP = np.array([0, 0, 0, 0, 0, 0, 0, 0, -2.0, 0, 0, -2.0])
    t = accd(P, dP, 4.0, 0.0, 0)  # r and kind given: the signature the kernels compile
    assert 0.4 < t < 0.5
    g, H = np.empty(12), np.empty((12, 12))
    assert sqdist(P + t * dP, 0, g, H, False) > 0.0
    assert accd(P, -dP, 4.0, 0.0, 0) == np.inf  # moving apart
    # sliding along each other never meets: the check lets the whole step through
    slide = np.array([0, 0, 0, 0, 0, 0, 1.0, 0, 0, 1.0, 0, 0])
    assert accd(P, slide, 1.0, 0.0, 0) == np.inf


def _strands(scale, n=11):
    """A taut strand of n nodes along x (pinned ends, length scale) and a free strand of
    two nodes across it, 1 % of the scale above."""
    xs = (np.linspace(-0.5, 0.5, n) + 0.033) * scale
    nodes = np.r_[np.c_[xs, np.zeros(n), np.zeros(n)], [[0, -0.05 * scale, 0.01 * scale]]]
    nodes = np.r_[nodes, [[0, 0.05 * scale, 0.01 * scale]]]
    edges = [[i, i + 1] for i in range(n - 1)] + [[n, n + 1]]
    rest = np.r_[np.full(n - 1, 0.099 * scale), 0.1 * scale]
    net = Net.from_arrays(
        nodes, edges, EA=1e4 * scale**2, fixed=[0, n - 1], line_density=0.01 * scale**2,
        rest_length=rest, flies=True,
    )  # fmt: skip
    return net, n


@pytest.mark.parametrize("scale, load", [(1.0, 20.0), (50.0, 5e4), (0.02, 3e-3)])
def test_a_strand_pressed_onto_another_rests_on_it_with_the_whole_load(scale, load):
    net, n = _strands(scale)
    force = np.zeros_like(net.nodes)
    force[n:, 2] = -load / 2  # on the free strand's two nodes
    dhat = 1e-3 * scale
    term = SelfContact(net, kappa=default_strand_stiffness(load, dhat), dhat=dhat)
    ws = Workspace(net, terms=[term])
    res = solve_dynamic(
        net, Loads(force=force), dt=0.01, damping=20.0, t_end=20.0, workspace=ws, rtol=1e-9
    )
    assert res.equilibrium
    x = res.x
    gaps = term.distances(x)
    assert 0.0 < gaps.min() < dhat  # touching, within the stated accuracy
    push = np.zeros_like(x)
    term.gradient(x, push)
    # the contact carries the free strand's load, and pushes the pinned one back
    assert -push[n:].sum(axis=0) == pytest.approx([0, 0, load], abs=1e-6 * load)
    assert push.sum(axis=0) == pytest.approx(0.0, abs=1e-9 * load)
    assert x[n:, 2].max() < 0.0  # it went down with the strand below


def test_the_pattern_grows_with_new_pairs_and_only_then_is_rebuilt():
    net, n = _strands(1.0)
    term = SelfContact(net, kappa=1.0, dhat=1e-3)
    ws = Workspace(net, terms=[term])
    nnz, solver = ws.system.nnz, ws.solver
    potential = ws.potential(Loads())
    term.begin_step(net.nodes, 0.01, 0.0)
    assert not ws.refresh(potential) and ws.solver is solver  # the same pairs
    x = net.nodes.copy()
    x[n:, 2] = 0.0005  # the free strand now lies on the pinned one
    term.begin_step(x, 0.02, 0.01)
    assert term.grew and ws.refresh(potential)
    assert not term.grew and ws.system.nnz > nnz and potential.solver is ws.solver is not solver
    values = np.empty(144 * len(term.known))
    assert term.hessian(x, values) and len(term.pairs) >= 1


def test_the_radii_held_the_step_only_where_they_cut_the_last_one_asked_about():
    """As a free body's contact: a solve's wild first step that runs a node past its
    radius holds it, a later modest one does not (``held`` of the last step asked)."""
    net, n = _strands(1.0)
    term = SelfContact(net, kappa=1.0, dhat=1e-3)
    term.begin_step(net.nodes, 0.01, 0.0)
    wild = np.zeros_like(net.nodes)
    wild[n, 1] = 10.0  # far past the node's radius (a tenth of the shortest edge)
    term.max_step(net.nodes, wild)
    assert term.held
    term.max_step(net.nodes, 1e-4 * wild)
    assert not term.held
