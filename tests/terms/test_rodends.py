"""The 6x6 supports of rod ends (``catenet.terms.rodends``, ``catenet.model.rodends``):
exact gradient and Hessian by finite differences (small and large turns, any
orientation), the series stiffness's limits (a rigid support is the clamp's energy
EI / l |t - t0|^2, a zero one holds nothing), and the wrench the reactions report."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.model.rodends import RodEnds, end_stiffness, spring6_matrix
from catenet.terms.base import check_derivatives
from catenet.terms.rodends import RodEndSupport


def _spd(rng, n=6) -> np.ndarray:
    a = rng.normal(size=(n, n))
    return a @ a.T + 0.1 * np.eye(n)


def _term(rng, k6=None, ei=2.0):
    nodes = rng.normal(size=(5, 3))
    c, o = np.array([0, 3]), np.array([1, 4])
    t0 = nodes[o] - nodes[c]
    length = np.linalg.norm(t0, axis=1)
    t0 /= length[:, None]
    ks = np.stack([_spd(rng) if k6 is None else k6 for _ in range(2)])
    series = np.stack([end_stiffness(ks[i], t0[i], ei, length[i]) for i in range(2)])
    return RodEndSupport(RodEnds(c, o, t0, ks, series), nodes, 5), nodes


@pytest.mark.parametrize("move", [1e-3, 0.3, 1.0])
def test_gradient_and_hessian_are_exact(move):
    rng = np.random.default_rng(7)
    term, nodes = _term(rng)
    x = nodes + move * rng.normal(size=nodes.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-7


def test_a_rigid_support_is_the_clamp_and_a_zero_one_holds_nothing():
    """S from K -> infinity: the translation held, the turn's energy EI / l |t - t0|^2
    (the clamp of catenet.model.rods); K = 0: no energy at all."""
    rng = np.random.default_rng(3)
    ei = 2.0
    term, nodes = _term(rng, k6=1e12 * np.eye(6), ei=ei)
    x = nodes.copy()
    d = nodes[4] - nodes[3]  # turn the second support's edge about its foot
    axis = np.cross(d, [0.3, -0.2, 1.0])
    axis /= np.linalg.norm(axis)
    theta = 0.7
    turned = (
        d * np.cos(theta)
        + np.cross(axis, d) * np.sin(theta)
        + axis * (axis @ d) * (1 - np.cos(theta))
    )
    x[4] = nodes[3] + turned
    t0, t = d / np.linalg.norm(d), turned / np.linalg.norm(turned)
    clamp = ei / np.linalg.norm(d) * np.sum((t - t0) ** 2)
    assert term.energy(x) == pytest.approx(clamp, rel=1e-9)
    free, nodes = _term(rng, k6=np.zeros((6, 6)))
    assert abs(free.energy(nodes + rng.normal(size=nodes.shape))) < 1e-14  # round-off of ei / l


def test_the_wrench_balances_the_gradient():
    """The reactions' force -(S q)_u at c and moment d x f_o about c are the term's whole
    action: the same resultant force as its gradient, the same moment about c."""
    rng = np.random.default_rng(11)
    term, nodes = _term(rng)
    x = nodes + 0.2 * rng.normal(size=nodes.shape)
    grad = np.zeros_like(x)
    term.gradient(x, grad)
    held = np.zeros_like(x)
    term.held_force(x, held)
    assert np.allclose(held.sum(axis=0), -grad.sum(axis=0), atol=1e-12 * np.abs(grad).max())
    moments = term.moments(x)
    for k, (c, o) in enumerate(zip(term.c, term.o, strict=True)):
        about_c = np.cross(x[o] - x[c], -grad[o])  # the gradient's moment about c
        assert np.allclose(moments[k], about_c)


@pytest.mark.parametrize(
    "stiffness, says",
    [
        ([[1.0] * 6] * 5 + [[1.0] * 5], "six rows of six"),
        ([[1.0, 2.0] + [0.0] * 4] + [[0.0] * 6] * 5, "not symmetric"),
        (np.diag([1.0, 1.0, 1.0, 1.0, 1.0, -1.0]).tolist(), "not positive semidefinite"),
        ([[0.0] * 6] * 6, "all zero"),
        ([1.0, 1.0, 1.0, -1.0, 1.0, 1.0], "must each be finite and >= 0"),
    ],
)
def test_bad_6x6_is_refused_naming_the_key(stiffness, says):
    from catenet.errors import ConfigError

    with pytest.raises(ConfigError, match=says) as err:
        spring6_matrix(stiffness, "supports.spring[0].stiffness")
    assert "supports.spring[0].stiffness" in str(err.value)


def test_a_singular_but_semidefinite_6x6_is_accepted():
    """A base that holds some motions rigidly coupled and others not at all (rank 2:
    sway and rocking tied, k_uu k_tt = k_ut^2; nothing else held), turned into skew axes:
    its zero eigenvalues are round-off, not a release of energy."""
    rng = np.random.default_rng(5)
    v = np.array([[2e6, 0, 0, 0, 1e6, 0], [0, 3e3, 0, -1e3, 0, 0]], dtype=float)
    local = v.T @ v
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    r6 = np.kron(np.eye(2), q)
    k = spring6_matrix((r6 @ local @ r6.T).tolist(), "supports.spring[0].stiffness")
    assert k is not None and np.allclose(k, r6 @ local @ r6.T)
