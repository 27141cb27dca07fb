"""Energy terms: finite-difference checks of every term, and the proof that the door for
new physics is open: a toy term defined in this one file plus its registration solves
with the same Newton, workspace and solve path as the paper's terms.

The toy is a linear spring of every node to its reference position X,

    E = k/2 sum_i |x_i - X_i|^2,   dE/dx_i = k (x_i - X_i),   d2E/dx_i2 = k I,

and its closed-form case a single bilateral edge along x (rest length l0, stiffness EA)
fixed at node 0 and pulled by F at node 1: the edge and the spring act in series on the
one free node, EA u / l0 + k u = F, so u = F / (EA/l0 + k) exactly (the edge stays
straight and the linear law is exact along its axis).
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

import catenet as cn
from catenet.scene import Scene
from catenet.solver.path import Settings, solve
from catenet.terms import (
    TERMS,
    ExternalForce,
    Inertia,
    Stretch,
    Term,
    check_derivatives,
    node_block_pattern,
    register,
)

# --------------------------------------------------------------------------- the toy term


@njit(cache=True)
def _spring_gradient(x, reference, k, grad):
    total = 0.0
    for i in range(x.shape[0]):
        for a in range(3):
            d = x[i, a] - reference[i, a]
            grad[i, a] += k * d
            total += 0.5 * k * d * d
    return total


@register("anchor_spring")
class AnchorSpring(Term):
    """Every node tied to its reference position by a spring of stiffness k [N/m]."""

    def __init__(self, net: cn.Net, k: float):
        self.reference = net.nodes.copy()
        self.k = float(k)
        self.n = net.n_nodes

    def pattern(self):
        return node_block_pattern(np.arange(self.n))

    def gradient(self, x, grad):
        return _spring_gradient(x, self.reference, self.k, grad)

    def hessian(self, x, values):
        values.reshape(-1, 3, 3)[:] = self.k * np.eye(3)

    def stiffness(self):
        return np.full(self.n, self.k)


def bar(EA=100.0, l0=1.0):
    return cn.Net.from_arrays(
        [[0.0, 0.0, 0.0], [l0, 0.0, 0.0]], [[0, 1]], EA=EA, fixed=[0], tension_only=False
    )


def test_the_toy_term_is_registered_by_name():
    assert TERMS["anchor_spring"] is AnchorSpring
    assert TERMS["stretch"] is Stretch


def test_the_toy_term_passes_finite_differences():
    rng = np.random.default_rng(3)
    net = bar()
    x = net.nodes + 0.1 * rng.standard_normal(net.nodes.shape)
    grad_err, hess_err = check_derivatives(AnchorSpring(net, 7.0), x)
    assert grad_err < 1e-8 and hess_err < 1e-8


@pytest.mark.parametrize("k", [0.0, 30.0, 1e4])
def test_the_toy_term_gives_the_closed_form_static_answer(k):
    EA, l0, F = 100.0, 1.0, 2.5
    net = bar(EA, l0)
    force = np.zeros((2, 3))
    force[1, 0] = F
    loads = cn.Loads(force=force)
    r = solve(Scene(net, loads, (AnchorSpring(net, k),)), Settings(rtol=1e-12))
    u = F / (EA / l0 + k)
    assert r.converged
    assert r.x[1] == pytest.approx([l0 + u, 0.0, 0.0], rel=1e-12, abs=1e-14)
    assert r.tension[0] == pytest.approx(EA * u / l0, rel=1e-10)
    # The support holds the edge only (the spring at node 0 is unstretched): reaction -N.
    assert r.reaction[0] == pytest.approx([-EA * u / l0, 0.0, 0.0], rel=1e-10)


def test_the_toy_term_holds_a_slack_net_that_would_be_a_mechanism():
    """A tension-only net whose edges are all 1.5 times too long has no stiffness of its
    own; the springs alone hold it: under a small uniform force f every free node moves
    by exactly f/k, and every edge stays slack."""
    mat = cn.Material.from_E(10e6, radius=0.01)
    net = cn.square_net(10, 0.3, 1.0, 0.1, mat).net
    net = net.with_rest_length(1.5 * net.rest_length)
    k = 1e3
    f = np.array([1e-3, -2e-3, -5e-3])
    force = np.zeros((net.n_nodes, 3))
    force[~net.fixed] = f
    r = solve(Scene(net, cn.Loads(force=force), (AnchorSpring(net, k),)), Settings(rtol=1e-10))
    free = ~net.fixed
    assert r.converged
    assert not r.tension.any()
    assert np.allclose(r.x[free] - net.nodes[free], f / k, rtol=1e-9, atol=0.0)


def test_a_dynamic_run_with_the_toy_term_settles_on_its_static_answer():
    EA, l0, F, k = 100.0, 1.0, 2.5, 30.0
    net = cn.Net.from_arrays(
        [[0.0, 0.0, 0.0], [l0, 0.0, 0.0]],
        [[0, 1]],
        EA=EA,
        fixed=[0],
        line_density=1.0,
        tension_only=False,
    )
    force = np.zeros((2, 3))
    force[1, 0] = F
    problem = Scene(net, cn.Loads(force=force), (AnchorSpring(net, k),))
    r = solve(problem, Settings(method="dynamic", dt=0.01, damping=20.0, t_end=50.0))
    assert r.equilibrium
    assert r.x[1, 0] == pytest.approx(l0 + F / (EA / l0 + k), rel=1e-7)


# --------------------------------------------------------------------------- the paper's terms


@pytest.mark.parametrize("tension_only", [False, True])
def test_stretch_term_passes_finite_differences(tension_only):
    rng = np.random.default_rng(1)
    nodes = rng.uniform(-1.0, 1.0, (8, 3))
    edges = [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 6], [6, 7], [7, 0], [0, 4], [2, 6]]
    e = np.array(edges)
    length = np.linalg.norm(nodes[e[:, 1]] - nodes[e[:, 0]], axis=1)
    rest = length * rng.uniform(0.8, 1.2, len(edges))  # some slack, some taut
    net = cn.Net.from_arrays(
        nodes,
        edges,
        EA=rng.uniform(1, 5, len(edges)),
        fixed=[0],
        rest_length=rest,
        tension_only=tension_only,
    )
    term = Stretch(net)
    grad_err, hess_err = check_derivatives(term, nodes + 0.01 * rng.standard_normal((8, 3)))
    assert grad_err < 1e-7 and hess_err < 1e-6
    smooth = term.with_law(net.law.smoothed(0.05)).scaled(3.0)
    grad_err, hess_err = check_derivatives(smooth, nodes + 0.01 * rng.standard_normal((8, 3)))
    assert grad_err < 1e-7 and hess_err < 1e-6


def test_inertia_and_load_terms_pass_finite_differences():
    rng = np.random.default_rng(2)
    x = rng.standard_normal((5, 3))
    inertia = Inertia(np.array([0, 1, 2, 6, 7, 8, 12, 13]))
    inertia.set_step(rng.uniform(1, 2, 8), rng.standard_normal(8))
    assert max(check_derivatives(inertia, x)) < 1e-8
    load = ExternalForce(rng.standard_normal((5, 3)))
    grad_err, _ = check_derivatives(load, x)
    assert grad_err < 1e-8
    assert load.pattern() is None


def test_a_term_outside_the_workspace_pattern_is_refused():
    """Terms that couple nodes no edge couples must be given when the workspace is built."""

    class Coupling(AnchorSpring):
        def pattern(self):
            return np.array([3, 9]), np.array([9, 3])  # x of node 1 with x of node 3

        def hessian(self, x, values):
            values[:] = 0.0

    net = cn.cable([0, 0, 0], [4, 0, 0], 5, cn.Material(EA=1.0))
    ws = cn.Workspace(net)
    with pytest.raises(ValueError, match="outside the workspace's sparsity pattern"):
        ws.system.target(Coupling(net, 1.0))
    # Node-local terms always fit.
    assert ws.system.target(AnchorSpring(net, 1.0)).size == 45
