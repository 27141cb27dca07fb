"""The floor (benchmarks/peers/floor_step.py): its kernels' gradient and Hessian against
finite differences in contact, its steps keep every node out of the box, and it gives
catenet's answer on the drop through the impact."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.peers import floor_kernels as fk
from benchmarks.peers import floor_step as fs


def _contact_state():
    """The drop's floor model with the box lowered to 0.3 mm above the net, a step's
    inertia (h = 10 ms) about a nearby point."""
    _, scene = fs.drop_scene()
    floor = fs.Floor.of(scene)
    rng = np.random.default_rng(1)
    x = floor.x.copy()
    x[floor.body] += [0.0, 0.0, -0.1497]
    x[floor.free] += 1e-6 * rng.standard_normal(x[floor.free].shape)
    w = np.repeat(floor.mass[:, None], 3, axis=1) / 0.01**2
    a = x + 1e-4 * rng.standard_normal(x.shape)
    return floor, x, w, a


def test_the_floors_gradient_and_hessian_match_finite_differences_in_contact():
    floor, x, w, a = _contact_state()
    assert 0.0 < floor.gap(x) < floor.dhat  # nodes within the barrier's reach
    floor._phi(x, w, a)
    g = floor.g.copy()
    active = np.flatnonzero(floor.dofs >= 0)
    order = np.empty(len(active), dtype=np.int64)
    order[floor.dofs[active]] = active
    fk.hessian(x, floor.pos, floor.edges, floor.l0, floor.ea, floor.body, floor.B, floor.k,
               floor.c0, floor.box, floor.contact, floor.kappa, floor.dhat, w, floor.band,
               floor.C, floor.D, False)  # fmt: skip
    n1 = floor.n1
    H = np.zeros((n1 + 12, n1 + 12))
    for d in range(floor.p + 1):
        H[np.arange(d, n1), np.arange(n1 - d)] = floor.band[d, : n1 - d]
    H[n1:, :n1] = floor.C.T
    H[n1:, n1:] = np.tril(floor.D)
    H = H + np.tril(H, -1).T
    near = np.argsort([floor.gap_of(x, k) for k in range(len(floor.contact))])[:3]
    places = [floor.dofs[3 * floor.contact[k] + 2] for k in near] + list(range(n1, n1 + 12))
    h = 1e-7
    for p in places:
        dof = order[p]
        xp, xm = x.copy(), x.copy()
        xp.reshape(-1)[dof] += h
        xm.reshape(-1)[dof] -= h
        fd = (floor._phi(xp, w, a) - floor._phi(xm, w, a)) / (2 * h)
        assert fd == pytest.approx(g.reshape(-1)[dof], rel=1e-5, abs=1e-6 * np.abs(g).max())
        floor._phi(xp, w, a)
        gp = floor.g.reshape(-1)[order].copy()
        floor._phi(xm, w, a)
        column = (gp - floor.g.reshape(-1)[order]) / (2 * h)
        assert np.abs(column - H[:, p]).max() <= 1e-5 * np.abs(column).max()


def test_the_floor_and_catenet_agree_on_the_drop_through_the_impact():
    floor = fs.floor_drop(0.01, t_end=0.2)
    cat = fs.catenet_drop(0.01, t_end=0.2)
    assert floor["steps"] == cat["steps"] == 20
    p_floor, p_cat = floor["momentum"], cat["momentum"]
    assert p_cat[2] > -25.0  # the net holds the box (in free fall: -35.5 kg m/s)
    assert np.linalg.norm(p_floor - p_cat) <= 1e-6 * np.linalg.norm(p_cat)
    assert 0.0 < floor["closest"] < 1e-3 and 0.0 < cat["closest"] < 1e-3  # touching, never in
    assert floor["closest"] == pytest.approx(cat["closest"], rel=1e-4)
