"""An inelastic free body's contact (``inelastic = true``: catenet.terms.rigid_contact's
``BodyDamping``, a dashpot beside the barrier, and the implicit Euler step of an impact in
catenet.solver.stepper): its derivatives, its force law, a rod that falls flat onto a
heavy body and stays there at every step, the energy it books, and its keys."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from test_rigid import near_surface, posed, posed_body

from catenet.case import build, parse_case
from catenet.errors import ConfigError
from catenet.kernels.contact import barrier, damped_excess, damped_start
from catenet.solver.integrators import BDF2
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.rigid_contact import BodyContact, BodyDamping
from catenet.terms.shapes import rotation

NODE = 1.0 + 1000.0 * math.pi * 0.005**2 * 0.5  # the rod's node: point mass and half the rod
STRUCK = 2 * 0.5 * NODE * 2.0**2  # its kinetic energy at 2 m/s [J]
THROWN = Path(__file__).resolve().parents[2] / "benchmarks" / "peers" / "thrown_net.toml"


@pytest.mark.parametrize("kind", ["box", "capsule", "sphere", "mesh"])
def test_body_damping_passes_finite_differences_and_balances_force_and_torque(kind, tmp_path):
    rng = np.random.default_rng(5)
    K = 10
    c0 = np.array([0.1, 0.2, 0.3])
    frame, shape, x, gap = posed_body(kind, tmp_path, K, rng)
    x[: K // 2] = near_surface(gap, frame, x, rng, K // 2, lo=0.03, hi=0.2)  # in reach
    x[K // 2 : K] = near_surface(gap, frame, x, rng, K - K // 2, lo=0.201, hi=0.3)  # not
    contact = BodyContact(shape, frame, n_nodes=K + 4)
    term = BodyDamping(contact, 1.0)
    term.begin_step(x, 0.01, 0.0)  # gamma = 100; slopes and zero-force gaps at x
    assert term.gamma == pytest.approx(100.0)
    assert np.sum(term.lag < 0.0) >= 3 and np.sum(term.lag == 0.0) >= 1  # in reach, and not
    y = x.copy()
    y[:K] += 0.015 * rng.standard_normal((K, 3))  # some nearer, some farther
    y[K:] = posed(frame, rng, c0 + [0.05, -0.02, 0.012], rotation([1, 2, 3], 0.31))
    g = term.gap(y)
    assert np.all(g > 0) and np.sum(g < term.dstar) >= 2 and np.sum(g > term.dstar) >= 2
    assert np.sum((term.lag == 0.0) & (g < term.dhat)) >= 1  # struck within the step
    grad_err, hess_err = check_derivatives(term, y, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5
    f = np.zeros_like(y)
    term.gradient(y, f)
    assert np.abs(f).max() > 0
    assert np.abs(f.sum(axis=0)).max() < 1e-11 * np.abs(f).max()  # action = reaction
    assert np.abs(np.cross(y, f).sum(axis=0)).max() < 1e-11 * np.abs(f).max()  # no torque
    term.begin_step(x, None)  # a static step: no damping at all
    f[:] = 0.0
    assert term.gradient(y, f) == 0.0 and not f.any()


def test_the_damped_force_never_pulls_and_the_dashpot_only_takes_energy():
    dhat = 1e-3
    for gamma in (0.5, 10.0, 1e4):
        for d_n in (2e-3, 9e-4, 3e-4, 1e-5):  # out of reach, and deeper and deeper in
            bn, ds = damped_start(d_n, dhat, gamma)
            assert (bn == 0.0) == (d_n >= dhat)
            if bn < 0.0:  # the damped force is 0 at d*, beyond the start's gap
                assert d_n < ds < dhat
                assert (1 + gamma) * barrier(ds, dhat)[1] == pytest.approx(gamma * bn, rel=1e-9)
            psi_n = damped_excess(d_n, dhat, gamma, bn, ds)[0] if d_n < dhat else 0.0
            for d in np.geomspace(1e-7, 1.5e-3, 400):
                b = barrier(d, dhat)
                psi = damped_excess(d, dhat, gamma, bn, ds)
                assert b[1] + psi[1] <= 1e-12 * abs(b[1])  # barrier + dashpot: it pushes
                assert psi[0] - psi_n >= -1e-12 * max(abs(psi[0]), 1.0)  # it dissipates
    # A node resting where the step began feels the barrier's force alone.
    bn, ds = damped_start(4e-4, dhat, 50.0)
    assert damped_excess(4e-4, dhat, 50.0, bn, ds)[1] == pytest.approx(0.0, abs=1e-12)


ROD = """
title = "a rod falling flat onto a heavy free box"
[geometry]
kind = "graph"
nodes = [[-0.5, 0.0, 0.1], [0.5, 0.0, 0.1]]
edges = [[0, 1]]
[material]
E = 1e9
radius = 0.005
density = 1000.0
[[mass]]
node = 0
mass = 1.0
velocity = [0.0, 0.0, -2.0]
[[mass]]
node = 1
mass = 1.0
velocity = [0.0, 0.0, -2.0]
[[obstacle]]
kind = "box"
center = [0.0, 0.0, -1.0]
half_size = [2.0, 2.0, 1.0]
mass = 1e6
distance = 0.001
inelastic = {inelastic}
[solver]
method = "dynamic"
t_end = 0.12
damping = 0.0
integrator = "bdf2"
"""


def _rod(inelastic: bool, dt: float | None):
    import tomllib

    raw = tomllib.loads(ROD.format(inelastic=str(inelastic).lower()))
    if dt is not None:
        raw["solver"]["dt"] = dt
    case = parse_case(raw)
    scene = build(case)
    result = solve(scene, Settings.of(case.solver))
    v = result.v[:2]  # the rod's two nodes (the body's four follow)
    kinetic = 0.5 * NODE * float(np.sum(v * v))
    return result, kinetic


@pytest.mark.parametrize("dt", [0.01, 0.002, 5e-4, None])
def test_a_rod_that_strikes_an_inelastic_body_stays_on_it_at_every_step(dt):
    """Impact at 2 m/s (4.16 J): elastic, the rod leaves again (BDF2 keeps 90 % of the
    energy at 0.5 ms); inelastic, at 10, 2 and 0.5 ms steps and the default ones, it
    keeps less than 1e-4 of it, and the energy balance books the loss as dissipated."""
    result, kinetic = _rod(True, dt)
    assert result.converged
    assert kinetic < 1e-4 * STRUCK
    assert np.all(result.x[:2, 2] > 0.0)  # on the box's top face, not in it
    energy = result.energy  # kinetic, elastic, contact, work, dissipated, numerical
    assert energy[4] == pytest.approx(STRUCK, rel=0.01)
    assert abs(energy[5]) < 0.01 * STRUCK


def test_an_elastic_body_sends_the_rod_back():
    result, kinetic = _rod(False, 5e-4)
    assert kinetic > 0.85 * STRUCK and np.all(result.v[:2, 2] > 1.8)


def test_after_an_impact_bdf2_starts_afresh_with_implicit_euler_steps():
    scheme = BDF2()
    y, v = np.zeros(3), np.ones(3)
    scheme.weights(np.ones(3), y, v, 0.01, 0.0)
    scheme.accept(np.ones((1, 3)) * 0.01, np.zeros((1, 3)), np.ones((1, 3)), np.arange(3), 0.01)
    scheme.weights(np.ones(3), y + 0.01, v, 0.01, 0.0)
    assert scheme.remembers  # the second step is a BDF2 step
    scheme.restart = True  # an impact: the same step as implicit Euler's
    scheme.weights(np.ones(3), y + 0.01, v, 0.01, 0.0)
    scheme.restart = False
    assert not scheme.remembers
    x1 = np.ones((1, 3)) * 0.01
    scheme.accept(x1 + 0.01, x1, np.ones((1, 3)), np.arange(3), 0.01)
    scheme.weights(np.ones(3), y + 0.02, v, 0.01, 0.0)
    assert not scheme.remembers  # the states before the impact are no past
    scheme.accept(x1 + 0.02, x1 + 0.01, np.ones((1, 3)), np.arange(3), 0.01)
    scheme.weights(np.ones(3), y + 0.03, v, 0.01, 0.0)
    assert scheme.remembers  # BDF2 again, from the impact on


def test_the_thrown_net_on_an_inelastic_box_gives_the_same_momentum_at_every_step():
    """The thrown 11 x 11 net of benchmarks/peers/thrown_net.toml onto the free 8 t box
    (the elastic contact's answer moves by 5-14 % between 10 and 0.3 ms steps): the box's
    momentum at 2 s at 10 ms steps and at default steps within 2 % of 2.5 ms steps'."""
    import tomllib

    momenta = {}
    for dt in (0.01, 0.0025, None):
        raw = tomllib.loads(THROWN.read_text())
        raw["obstacle"][0]["inelastic"] = True
        raw["solver"].pop("dt")
        raw["solver"]["integrator"] = "bdf2"
        if dt is not None:
            raw["solver"]["dt"] = dt
        case = parse_case(raw, source=str(THROWN), base_dir=THROWN.parent)
        scene = build(case)
        (body,) = scene.rigid
        result = solve(scene, Settings.of(case.solver))
        assert result.converged
        momenta[dt] = body.mass * np.linalg.norm(result.v[body.frame.nodes].mean(axis=0))
    ref = momenta[0.0025]
    assert 3.0 < ref < 3.4
    assert abs(momenta[0.01] - ref) < 0.02 * ref
    assert abs(momenta[None] - ref) < 0.02 * ref


@pytest.mark.parametrize(
    ("table", "says"),
    [
        ('kind = "box"\ncenter = [0, 0, -1]\nhalf_size = [1, 1, 0.5]', "give mass or density"),
        ('kind = "sphere"\ncenter = [0, 0, -1]\nradius = 0.5\nmass = 2.0', "is a ball"),
        ('kind = "plane"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]', "unknown key"),
    ],
)
def test_inelastic_belongs_to_a_free_body(table, says):
    import tomllib

    raw = tomllib.loads(ROD.format(inelastic="false"))
    raw["obstacle"] = [tomllib.loads(table + "\ninelastic = true")]
    with pytest.raises(ConfigError) as err:
        parse_case(raw)
    assert "obstacle[0].inelastic" in str(err.value) and says in str(err.value)
