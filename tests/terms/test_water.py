"""Water on a net (catenet/terms/water.py): the buoyancy and Morison terms' exact
derivatives, the wetted share of an edge across the surface, the scheme's velocity and
acceleration maps, and closed forms in dynamic runs: the terminal velocity of a sinking
cable, a neutrally buoyant line at rest, the added mass's frequency shift of a taut
string, with the energy balance closing (the drag's dissipation in the ledger)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.model.builders import Material, cable
from catenet.model.net import Loads, Net
from catenet.model.water import Hydro, Water
from catenet.scene import Scene
from catenet.solver import integrators
from catenet.solver.path import solve
from catenet.terms import check_derivatives
from catenet.terms.water import Buoyancy, WaterForce

RHO_W, G = 1025.0, 9.81


def hydro(m, **kw):
    values = dict(cd_n=1.2, cd_t=0.3, ca_n=1.0, ca_t=0.2, diameter=0.1, area=0.005)
    values.update(kw)
    return Hydro.uniform(m, **values)


def crossing_net():
    """Four nodes, three edges: one deep, one across the surface, one above it."""
    nodes = np.array([[0, 0, -1.0], [1, 0, -1.2], [2, 0.3, 0.02], [3, 0, 0.3]])
    return Net.from_arrays(nodes, [[0, 1], [1, 2], [2, 3]], EA=1e6, fixed=[0], line_density=10.0)


def test_buoyancy_derivatives_and_the_wetted_share():
    """Gradient and Hessian against finite differences (an edge deep, one across the
    surface, one within the smoothing band); the force is rho_w g A l0 times the wetted
    share: all of a deep edge, half of an edge centred on the surface (whatever its
    slope), none above; convex."""
    rng = np.random.default_rng(1)
    net = crossing_net()
    water = Water(RHO_W, g=G)
    term = Buoyancy(net, water, hydro(3))
    x = net.nodes + 0.01 * rng.standard_normal(net.nodes.shape)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-6
    nodes = np.array(
        [[0, 0, -5.0], [1, 0, -5.0], [0, 0, -1.0], [0.3, 0, 1.0], [0, 0, 2], [1, 0, 3]]
    )
    net = Net.from_arrays(nodes, [[0, 1], [2, 3], [4, 5]], EA=1e6, fixed=[], flies=True)
    term = Buoyancy(net, water, hydro(3, diameter=0.05))
    grad = np.zeros_like(nodes)
    term.gradient(nodes, grad)
    full = RHO_W * G * 0.005 * net.rest_length
    up = -grad[:, 2]
    assert up[0] + up[1] == pytest.approx(full[0], rel=1e-12)
    assert up[2] + up[3] == pytest.approx(0.5 * full[1], rel=1e-12)
    assert up[4] == up[5] == 0.0
    rows, cols = term.pattern()
    values = np.zeros(rows.size)
    term.hessian(nodes, values)
    dense = np.zeros((18, 18))
    np.add.at(dense, (rows, cols), values)
    assert np.linalg.eigvalsh(dense).min() > -1e-9 * np.abs(dense).max()


@pytest.mark.parametrize("static", [False, True])
def test_morison_derivatives(static):
    """Drag + added mass + the flow's inertia in a time step (random velocity and
    acceleration maps, a current and a wave) and in a static step (the current's drag on
    the cable at rest: linear): gradient and Hessian against finite differences."""
    rng = np.random.default_rng(2)
    net = crossing_net()
    from catenet.model.water import Wave

    water = Water(
        RHO_W,
        g=G,
        current=np.array([[-5.0, 0.5, 0.2], [0.0, 1.0, 0.0]]),
        waves=(Wave(1.0, 0.8, 0.3),),
        depth=30.0,
    )
    term = WaterForce(net, water, hydro(3))
    x = net.nodes + 0.01 * rng.standard_normal(net.nodes.shape)
    if static:
        term.begin_step(x, None)
    else:
        term.begin_step(x, 0.3, 0.2)
        centre = x + 0.05 * rng.standard_normal(x.shape)
        centre_a = x + 0.05 * rng.standard_normal(x.shape)
        term.set_motion(100.0, centre, 1e4, centre_a)
    grad_err, hess_err = check_derivatives(term, x + 0.002 * rng.standard_normal(x.shape))
    assert grad_err < 1e-7 and hess_err < 1e-6


def test_every_scheme_gives_its_velocity_and_acceleration():
    """Scheme.motion: v_{n+1} = k (y - c) and the equation of motion's acceleration
    k_a (y - c_a) agree with what each scheme's accept derives from the same y."""
    rng = np.random.default_rng(3)
    y_k, v_k, y = rng.standard_normal((3, 6))
    m = np.full(6, 2.0)
    free = np.arange(6)
    for name in integrators.INTEGRATORS:
        scheme = integrators.make(name)
        for step in range(2):  # bdf2's second step is a BDF2 step
            if name == "newmark" and scheme.a is None:
                scheme.a = rng.standard_normal(6)
            h = 0.1 if step == 0 else 0.08
            w, a = scheme.weights(m, y_k, v_k, h, 0.0)
            k, c, ka, c_a = scheme.motion(y_k, v_k, h)
            a_n = None if scheme.a is None else scheme.a.copy()
            v_new = scheme.accept(y, y_k, v_k, free, h)
            assert np.allclose(v_new, k * (y - c), rtol=1e-12, atol=1e-12)
            # inertia's gradient w (y - a) is M times the acceleration term (mu = 0)
            assert np.allclose(w * (y - a), m * ka * (y - c_a), rtol=1e-10, atol=1e-10)
            if name == "newmark":
                assert a_n is not None
            y_k, v_k = y.copy(), v_new.copy()
            y = y + 0.05 * rng.standard_normal(6)


def sinking_scene(density_line, d=0.05, area=0.002, cd=1.2, nodes=5, gravity_history=None):
    """A horizontal cable of 2 m, free, 10 m below the surface, under gravity (scaled by
    ``gravity_history`` if given)."""
    length = 2.0
    x = np.zeros((nodes, 3))
    x[:, 0] = np.linspace(0, length, nodes)
    x[:, 2] = -10.0
    edges = [[i, i + 1] for i in range(nodes - 1)]
    net = Net.from_arrays(x, edges, EA=1e7, fixed=[], line_density=density_line, flies=True)
    water = Water(RHO_W, g=G)
    h = hydro(nodes - 1, cd_n=cd, cd_t=0.0, ca_n=1.0, ca_t=0.0, diameter=d, area=area)
    loads = Loads(gravity=np.array([0.0, 0.0, -G]), gravity_history=gravity_history)
    scene = Scene.of(net, loads).with_terms(Buoyancy(net, water, h), WaterForce(net, water, h))
    return scene, length


@pytest.mark.parametrize("integrator", integrators.INTEGRATORS)
def test_sinking_cable_reaches_its_terminal_velocity(integrator):
    """A horizontal cable sinks at sqrt(2 W / (rho_w cd_n d l)), W its submerged weight,
    with every integrator (the drag implicit, Newton quadratic: few iterations per
    step); the energy balance closes: the work of gravity and buoyancy leaves as the
    drag's dissipation and the kinetic energy (added mass's included)."""
    line, d, area = 40.0, 0.05, 0.002
    scene, length = sinking_scene(line, d, area)
    weight = (line - RHO_W * area) * length * G
    terminal = math.sqrt(2 * weight / (RHO_W * 1.2 * d * length))
    rows = []
    r = solve(
        scene,
        method="dynamic",
        dt=0.02,
        t_end=2.6,
        damping=0.0,
        integrator=integrator,
        on_step=lambda s: rows.append(s.energy) and False,
    )
    assert np.allclose(r.v[:, 2], -terminal, rtol=1e-5)
    assert r.iterations <= 3 * r.steps  # the drag's exact Jacobian: Newton in 1-3
    k, _, c, work, lost, left = rows[-1]
    mass = (line + RHO_W * area) * length  # the added mass moves with it
    assert k == pytest.approx(0.5 * mass * terminal**2, rel=1e-4)
    assert lost > 0.8 * work
    assert abs(left) < 3e-3 * work


def test_neutrally_buoyant_line_stays_put():
    """A line as dense as the water, at rest below the surface, does not move."""
    area = 0.002
    scene, _ = sinking_scene(RHO_W * area, area=area)
    r = solve(scene, method="dynamic", dt=0.05, t_end=2.0, damping=0.0)
    assert np.abs(r.x - scene.net.nodes).max() < 1e-9
    assert np.abs(r.v).max() < 1e-9


@pytest.mark.parametrize("integrator", ["implicit_euler", "bdf2"])
def test_buoyancy_follows_a_gravity_history(integrator):
    """Buoyancy is the displaced water's weight: under a gravity history (a soft start
    from 0) it grows with gravity, so a neutrally buoyant line stays put at every
    factor, and a sinking one sinks from rest at the rate of its submerged weight; the
    energy balance books buoyancy's change with gravity as work and closes."""
    from catenet.model.histories import History

    area = 0.002
    ramp = History([[0.0, 0.0], [1.0, 1.0]])
    scene, _ = sinking_scene(RHO_W * area, area=area, gravity_history=ramp)
    r = solve(scene, method="dynamic", dt=0.05, t_end=2.0, damping=0.0, integrator=integrator)
    assert np.abs(r.x - scene.net.nodes).max() < 1e-9
    assert np.abs(r.v).max() < 1e-9

    line, d = 40.0, 0.05
    scene, length = sinking_scene(line, d, area, gravity_history=ramp)
    rows = []
    r = solve(
        scene,
        method="dynamic",
        dt=0.02,
        t_end=1.0,
        damping=0.0,
        integrator=integrator,
        on_step=lambda s: rows.append((s.time, s.energy, s.x[:, 2].mean())) and False,
    )
    t, energy, z = zip(*rows, strict=True)
    assert np.all(np.diff(z) <= 1e-12)  # it sinks from the start: never rises
    k, _, c, work, lost, left = energy[-1]
    assert work > 0.0 and abs(left) < 3e-3 * work, energy[-1]


def test_added_mass_lowers_a_taut_strings_frequency():
    """A taut string plucked into its first mode, in water without drag: its period
    grows by sqrt((m + m_a) / m) over the same string in air (the dynamic run's added
    mass, as catenet modes has it), to 1e-3."""
    rho, area, ea, tension = 7850.0, 1e-4, 2e7, 5000.0
    material = Material(EA=ea, line_density=rho * area)
    edges = 10

    def period(water: bool) -> float:
        net = cable([0, 0, -5], [10, 0, -5], edges + 1, material, length=10 / (1 + tension / ea))
        x0 = net.nodes.copy()
        s = np.linspace(0, 1, edges + 1)
        x0[:, 2] += 0.01 * np.sin(np.pi * s)
        scene = Scene.of(net, Loads())
        if water:
            h = hydro(net.n_edges, cd_n=0.0, cd_t=0.0, ca_n=1.0, ca_t=0.0, area=area)
            scene = scene.with_terms(WaterForce(net, Water(RHO_W), h))
        from catenet.solver.path import Start

        mid = edges // 2
        zs = []
        solve(
            scene,
            method="dynamic",
            dt=2e-3,
            t_end=0.6,
            damping=0.0,
            integrator="bdf2",
            start=Start(x=x0),
            on_step=lambda st: zs.append((st.time, st.x[mid, 2] + 5.0)) and False,
        )
        t, z = np.array(zs).T
        up = np.flatnonzero((z[:-1] < 0) & (z[1:] >= 0))
        crossing = t[up] - z[up] * (t[up + 1] - t[up]) / (z[up + 1] - z[up])
        return float(np.diff(crossing).mean())

    ratio = period(True) / period(False)
    assert ratio == pytest.approx(math.sqrt((rho + RHO_W) / rho), rel=1e-3)


@pytest.mark.parametrize("name", ["implicit_euler", "bdf2"])
def test_newton_converges_quadratically_with_the_drag(name):
    """A time step of a cable thrown through the water (the drag far from any
    linearisation): Newton's residuals fall as r_{k+1} = C r_k^2 with one C, down to the
    round-off floor: the drag's Jacobian is exact."""
    from catenet.solver.stepper import TimeStepper
    from catenet.solver.workspace import Workspace

    scene, _ = sinking_scene(40.0)
    net = scene.net
    ws = Workspace(net, terms=scene.terms)
    scheme = integrators.make(name)
    stepper = TimeStepper(net, scene.loads, ws, scheme, 0.0, rtol=1e-13, max_iter=50, reuse=False)
    v0 = np.zeros_like(net.nodes)
    v0[:, 0] = np.linspace(-1.0, 1.0, net.n_nodes)
    v0[:, 1:] = [0.5, 1.0]
    stepper.begin(net.nodes.copy(), v0, 0.0, None, None)
    newton, _ = stepper.solve_step(0.1)
    assert newton.converged
    r = np.array(newton.history)
    above = [k for k in range(1, r.size - 1) if r[k + 1] > 10 * r[-1]]
    assert len(above) >= 2
    c = np.array([r[k + 1] / r[k] ** 2 for k in above])
    assert c.max() < 10 * c.min()
