"""The supports' arithmetic: the elastic supports' term (finite differences of its
gradient and Hessian, its energy in closed form) and the guided nodes' projection of
the Newton system (``catenet.solver.guided``): P A P + d Q, whose step is the Newton
step of the potential on the guides, and the held part of the residual, the reaction."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.errors import ConfigError
from catenet.model.guides import Elastic, Guides, spring_matrix, unit
from catenet.model.net import Net
from catenet.solver.workspace import Workspace
from catenet.terms import check_derivatives
from catenet.terms.supports import ElasticSupport


def _net(springs=None, guides=None, n=6, seed=0) -> Net:
    rng = np.random.default_rng(seed)
    nodes = np.column_stack(
        [np.arange(n, dtype=float), rng.normal(0, 0.2, n), rng.normal(0, 0.2, n)]
    )
    edges = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    return Net.from_arrays(
        nodes, edges, EA=1e3, fixed=[0], tension_only=False, springs=springs, guides=guides
    )


def test_elastic_support_derivatives_and_energy():
    k3 = np.array([[3.0, 1.0, 0.5], [1.0, 2.0, -0.4], [0.5, -0.4, 1.5]]) * 1e2
    springs = Elastic.join([Elastic.of([2, 4], k3), Elastic.of([4, 5], [10.0, 0.0, 30.0])])
    net = _net(springs)
    term = ElasticSupport(net)
    x = net.nodes + np.random.default_rng(1).normal(0, 0.3, net.nodes.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-7
    u = x - net.nodes
    energy = 0.5 * (u[2] @ k3 @ u[2] + u[4] @ k3 @ u[4])
    energy += 0.5 * (10.0 * u[4, 0] ** 2 + 30.0 * u[4, 2] ** 2 + 10.0 * u[5, 0] ** 2)
    energy += 0.5 * 30.0 * u[5, 2] ** 2
    assert term.energy(x) == pytest.approx(energy, rel=1e-13)
    assert term.force(x)[2] == pytest.approx(-k3 @ u[2], rel=1e-13)
    assert term.holds and term.convex


def test_spring_matrix_accepts_and_refuses():
    assert np.array_equal(spring_matrix([1.0, 0.0, 2.0]), np.diag([1.0, 0.0, 2.0]))
    k = [[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 1.0]]
    assert np.array_equal(spring_matrix(k), np.array(k))
    for bad, why in (
        ([0.0, 0.0, 0.0], "not all zero"),
        ([1.0, -1.0, 0.0], ">= 0"),
        ([1.0, 2.0], "[kx, ky, kz]"),
        ([[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "symmetric"),
        ([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "positive semidefinite"),
        ("stiff", "[kx, ky, kz]"),
        ([float("nan"), 1.0, 1.0], "finite"),
    ):
        with pytest.raises(ConfigError, match="k =") as err:
            spring_matrix(bad, "k")
        assert why in str(err.value)


def test_guides_refuse_bad_input():
    with pytest.raises(ConfigError, match="must not be zero"):
        unit([0.0, 0.0, 0.0], "normal")
    with pytest.raises(ConfigError, match="three finite numbers"):
        unit([1.0, float("inf"), 0.0], "normal")
    net = _net()
    with pytest.raises(ConfigError, match="both fixed and on a roller"):
        net.with_guides(Guides.roller([0], [0, 0, 1]))
    with pytest.raises(ConfigError, match="more than one roller or slider"):
        net.with_guides(Guides.roller([3], [0, 0, 1]), Guides.slider([3], [1, 0, 0]))
    with pytest.raises(ConfigError, match="node indices must be in"):
        net.with_guides(Guides.roller([9], [0, 0, 1]))


def test_guides_projectors():
    g = Guides.join([Guides.roller([1], [0.0, 3.0, 4.0]), Guides.slider([2], [1.0, 1.0, 0.0])])
    assert g is not None and g.held_count == 1 + 2
    n = np.array([0.0, 0.6, 0.8])
    assert g.held[0] == pytest.approx(np.outer(n, n))
    d = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    assert g.tangent[1] == pytest.approx(np.outer(d, d))
    basis = g.basis()
    assert basis[0].shape == (3, 2) and basis[1].shape == (3, 1)
    assert basis[0].T @ basis[0] == pytest.approx(np.eye(2), abs=1e-15)
    assert np.abs(basis[0].T @ n).max() < 1e-15
    assert abs(abs(basis[1][:, 0] @ d) - 1.0) < 1e-15


@pytest.mark.parametrize("mtype", [None, 11])
def test_guided_newton_matrix_and_step(mtype):
    """The system's matrix with guides is P A P + d Q (A the unguided matrix, the same
    terms) and its Newton step is B (B^T A B)^-1 B^T (-g) with B the guides' bases: the
    step of the potential on the guides, exactly what x = X + B q would give."""
    rng = np.random.default_rng(4)
    guides = Guides.join(
        [Guides.roller([2], rng.normal(size=3)), Guides.slider([4], rng.normal(size=3))]
    )
    springs = Elastic.of([5], [5.0, 7.0, 9.0])
    plain = _net(springs)
    net = _net(springs, guides)
    x = net.nodes + rng.normal(0, 0.05, net.nodes.shape)
    x[0] = net.nodes[0]
    ws, ref = Workspace(net, mtype=mtype), Workspace(plain, mtype=mtype)
    a = ref.system.matrix(ref.system.hessian(x)).toarray()
    got = ws.system.matrix(ws.system.hessian(x)).toarray()
    p = np.eye(a.shape[0])
    rows = {2: 3 * 1, 4: 3 * 3}  # node 0 is fixed: node k's DOFs start at 3 (k - 1)
    q = np.zeros_like(a)
    for k, i in rows.items():
        j = list(guides.nodes).index(k)
        p[i : i + 3, i : i + 3] = guides.tangent[j]
        q[i : i + 3, i : i + 3] = guides.held[j] * np.trace(a[i : i + 3, i : i + 3]) / 3.0
    assert got == pytest.approx(p @ a @ p + q, abs=1e-10 * np.abs(a).max())
    # the step on the guides
    pot = ws.potential(_loads(net))
    ev = pot.evaluate(x)
    pot.factorize(x, 0.0)
    dy = pot.solve(-ev.g)
    columns = [np.eye(a.shape[0])[:, [c]] for c in range(a.shape[0])]
    basis = []
    for c in range(a.shape[0]):
        node = c // 3 + 1
        if node not in rows:
            basis.append(columns[c])
    for k, i in rows.items():
        j = list(guides.nodes).index(k)
        b = np.zeros((a.shape[0], guides.basis()[j].shape[1]))
        b[i : i + 3] = guides.basis()[j]
        basis.append(b)
    b = np.hstack(basis)
    ref_pot = ref.potential(_loads(net))
    g_full = ref_pot.evaluate(x).g
    want = b @ np.linalg.solve(b.T @ a @ b, -(b.T @ g_full))
    assert dy == pytest.approx(want, abs=1e-10 * np.abs(want).max())


def _loads(net: Net):
    from catenet.model.net import Loads

    f = np.zeros_like(net.nodes)
    f[:, 2] = -3.0
    f[3] = [2.0, -1.0, 0.5]
    return Loads(force=f)
