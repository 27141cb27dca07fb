"""Finite-difference checks of the stretching kernels and of the assembled system.

The energy of an edge is U = 1/2 EA eps^2 l0; its gradient and Hessian are analytic in
the kernels. Central differences of U give the gradient to O(d^2), central differences
of the gradient give the Hessian to O(d^2); with d = 1e-6 relative, round-off and
truncation both sit near 1e-8 relative, so 1e-6 is a safe tolerance. The checks cover
bilateral and tension-only edges, slack edges, and the smoothed law of the static
solver's continuation.
"""

from __future__ import annotations

import numpy as np
import pytest

import catenet as cn
from catenet.kernels.shapes import box_max_step
from catenet.kernels.stretch import stretch_energy, stretch_gradient, stretch_hessian
from catenet.solver.system import System

D = 1e-6


def random_net(seed: int, tension_only: bool, n: int = 12, m: int = 25):
    """Random positions, random edges (some shortened, some stretched: slack and taut)."""
    rng = np.random.default_rng(seed)
    nodes = rng.uniform(-1.0, 1.0, (n, 3))
    pairs = {tuple(sorted(rng.choice(n, 2, replace=False))) for _ in range(4 * m)}
    edges = np.array(sorted(pairs)[:m], dtype=np.int64)
    length = np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)
    rest = length * rng.uniform(0.7, 1.3, len(edges))  # strains from about -0.23 to +0.43
    EA = rng.uniform(1.0, 10.0, len(edges))
    net = cn.Net.from_arrays(
        nodes, edges, EA=EA, fixed=[0], rest_length=rest, tension_only=tension_only
    )
    return net, rng


def law_args(net):
    """The stretch kernels' arguments of a net: edges, rest lengths, EA and its law."""
    law = net.law
    return net.edges, net.rest_length, net.EA, law.kind, law.params, law.table, law.tension_only


def energy(net, x, smooth=0.0):
    return stretch_energy(x, *law_args(net), smooth)


def gradient(net, x, smooth=0.0):
    g = np.zeros_like(x)
    stretch_gradient(x, *law_args(net), smooth, g)
    return g


@pytest.mark.parametrize("tension_only", [False, True])
@pytest.mark.parametrize("smooth", [0.0, 0.05])
@pytest.mark.parametrize("seed", range(3))
def test_gradient_matches_finite_differences(seed, tension_only, smooth):
    net, rng = random_net(seed, tension_only)
    x = net.nodes + 0.05 * rng.standard_normal(net.nodes.shape)
    g = gradient(net, x, smooth)
    fd = np.zeros_like(x)
    for i in range(x.shape[0]):
        for a in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, a] += D
            xm[i, a] -= D
            fd[i, a] = (energy(net, xp, smooth) - energy(net, xm, smooth)) / (2 * D)
    assert np.allclose(g, fd, rtol=1e-6, atol=1e-6 * np.abs(g).max())


@pytest.mark.parametrize("tension_only", [False, True])
@pytest.mark.parametrize("smooth", [0.0, 0.05])
@pytest.mark.parametrize("seed", range(3))
def test_hessian_blocks_match_finite_differences(seed, tension_only, smooth):
    net, rng = random_net(seed, tension_only)
    x = net.nodes + 0.05 * rng.standard_normal(net.nodes.shape)
    values = np.empty(36 * net.n_edges)
    stretch_hessian(x, *law_args(net), smooth, values)
    blocks = values.reshape(-1, 6, 6)
    for k, (i, j) in enumerate(net.edges):
        sub = cn.Net.from_arrays(
            x[[i, j]],
            [[0, 1]],
            EA=net.EA[k],
            fixed=[0],
            rest_length=net.rest_length[k],
            tension_only=tension_only,
        )
        xe = x[[i, j]].copy()
        fd = np.zeros((6, 6))
        for b in range(6):
            xp, xm = xe.copy(), xe.copy()
            xp.reshape(-1)[b] += D
            xm.reshape(-1)[b] -= D
            fd[:, b] = (gradient(sub, xp, smooth) - gradient(sub, xm, smooth)).reshape(-1) / (2 * D)
        scale = max(np.abs(blocks[k]).max(), 1e-12)
        assert np.allclose(blocks[k], fd, atol=1e-6 * scale), f"edge {k}"


def test_paper_eq8_lacks_the_length_factor():
    """The transverse stiffness of a stretched edge is EA eps / |e| (this code), not
    EA eps / l0 (the paper's Eq. 8 as printed): they differ by (1 + eps)."""
    l0, EA, eps = 1.0, 100.0, 0.5
    net = cn.Net.from_arrays(
        [[0, 0, 0], [1 + eps, 0, 0]], [[0, 1]], EA=EA, fixed=[0], rest_length=l0, tension_only=False
    )
    values = np.empty(36)
    stretch_hessian(net.nodes, *law_args(net), 0.0, values)
    transverse = values.reshape(6, 6)[4, 4]  # d2U / dy_j^2
    assert transverse == pytest.approx(EA * eps / (l0 * (1 + eps)))
    assert transverse != pytest.approx(EA * eps / l0)


def test_slack_edge_contributes_nothing_but_keeps_its_entries():
    net = cn.Net.from_arrays(
        [[0, 0, 0], [0.5, 0, 0]], [[0, 1]], EA=1.0, fixed=[0], rest_length=1.0, tension_only=True
    )
    assert energy(net, net.nodes) == 0.0
    assert not gradient(net, net.nodes).any()
    system = System(net)
    data = system.hessian(net.nodes)
    assert system.nnz == 6  # the pattern keeps the slack edge's (zero) entries
    assert not data.any()


@pytest.mark.parametrize("upper", [True, False])
def test_assembled_matrix_equals_dense_hessian(upper):
    """The reduced CSR matrix (supports eliminated, upper triangle or full) equals the
    dense sum of the edge blocks restricted to the free DOFs."""
    net, rng = random_net(7, True, n=15, m=40)
    net = cn.Net.from_arrays(
        net.nodes, net.edges, EA=net.EA, fixed=[0, 3], rest_length=net.rest_length
    )
    x = net.nodes + 0.02 * rng.standard_normal(net.nodes.shape)
    system = System(net, upper=upper)
    shift = rng.uniform(1.0, 2.0, system.n_free)
    system.hessian(x, shift)
    got = system.matrix().toarray()
    values = np.empty(36 * net.n_edges)
    stretch_hessian(x, *law_args(net), 0.0, values)
    dense = np.zeros((3 * net.n_nodes, 3 * net.n_nodes))
    for k, (i, j) in enumerate(net.edges):
        dofs = np.r_[3 * i : 3 * i + 3, 3 * j : 3 * j + 3]
        dense[np.ix_(dofs, dofs)] += values[36 * k : 36 * k + 36].reshape(6, 6)
    free = system.free_dofs
    want = dense[np.ix_(free, free)] + np.diag(shift)
    assert np.allclose(got, want, atol=1e-12 * np.abs(want).max())
    assert np.allclose(got, got.T)


def test_lumped_mass_and_reactions_balance():
    """m_i = sum rho A l0 / 2; reactions and applied loads sum to zero at equilibrium."""
    mat = cn.Material.from_E(10e6, radius=0.01, density=1000.0)
    sq = cn.square_net(10, 0.3, 1.0, 0.05, mat)
    net = sq.net
    assert net.mass.sum() == pytest.approx(mat.line_density * net.rest_length.sum())
    loads = cn.Loads(force=cn.pressure_force(net, 100.0, 1.0), gravity=np.array([0, 0, -9.81]))
    r = cn.solve_static(net, loads, rtol=1e-10)
    total = r.reaction.sum(axis=0) + loads.external_force(net).sum(axis=0)
    assert np.abs(total).max() < 1e-8 * np.abs(loads.external_force(net)).sum()
    assert not r.reaction[~net.fixed].any()


@pytest.mark.parametrize("offset", [0.0, 0.03])
def test_box_first_entry_up_to_a_horizon_is_exact(offset):
    """``box_max_step`` with ``upto`` skips the nodes whose path to t = upto clears the
    box's bounds: up to upto it finds the same first entry as without (bit for bit), and
    beyond it nothing earlier than the true entry."""
    rng = np.random.default_rng(11)
    half = np.array([0.3, 0.2, 0.1])
    axes = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    axes *= np.sign(np.linalg.det(axes))
    center = np.array([0.1, -0.2, 0.05])
    nodes = np.arange(40)
    checked = 0
    for _ in range(300):
        x = center + rng.uniform(-1.0, 1.0, size=(40, 3))
        dx = rng.normal(scale=0.5, size=(40, 3))
        full = box_max_step(x, dx, nodes, center, axes, half, offset)
        for upto in (0.5, 1.0, 3.0):
            t = box_max_step(x, dx, nodes, center, axes, half, offset, upto)
            if full <= upto:
                assert t == full
                checked += 1
            else:
                assert t > upto and t >= full
    assert checked > 100


def test_the_grids_median_is_numpys():
    """segments._median (a quickselect, cheaper to compile than np.median) gives
    np.median's value exactly: odd and even counts, ties, spread magnitudes."""
    from catenet.kernels.segments import _median

    rng = np.random.default_rng(7)
    for n in [*range(1, 40), 999, 1000]:
        for trial in range(12):
            if trial % 3 == 0:
                x = rng.integers(0, 4, n).astype(float)  # many ties
            else:
                x = rng.random(n) * 10.0 ** rng.integers(-3, 3)
            before = x.copy()
            assert _median(x) == np.median(x), (n, trial)
            assert np.array_equal(x, before)  # the input is left as it was
