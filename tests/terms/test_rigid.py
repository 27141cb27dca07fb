"""Free rigid bodies of any shape (affine bodies on four lumped nodes,
catenet/terms/rigid.py): the four nodes carry the body's mass, centre and second moment
exactly; the orthogonality energy and the body-frame barrier pass finite differences and
exchange force and torque honestly; the step cap never lets a node in (nor nearer than
its floor) and a Newton step turns a body by at most TURN_MAX; a torque-free
body spinning near its intermediate axis keeps its angular momentum (drift falling as
dt^2 under newmark) and flips as Euler's equations say; a box released onto a net rests
at the static solve's equilibrium; a sphere body repeats the ball; bad input exits 2."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from meshes import icosphere, net_under_gravity

from catenet.case import build, parse_case
from catenet.kernels.shapes import box_max_step
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.contact import SphereBarrier
from catenet.terms.rigid import TURN_MAX, BodyFrame, Rigidity, inertia_problem, second_moment
from catenet.terms.rigid_contact import FLOOR_SHARE, ROUNDOFF, SLACK, BodyContact
from catenet.terms.shapes import BoxBarrier, CapsuleBarrier, MeshBarrier, rotation

INERTIA = np.array([[2.0, 0.3, -0.1], [0.3, 3.0, 0.2], [-0.1, 0.2, 4.0]])


def posed(frame, rng, c, R, strain=0.01):
    """The frame's nodes at centre c, turned by R and strained a little (A = R (1 + e))."""
    A = R @ (np.eye(3) + strain * rng.standard_normal((3, 3)))
    return c + frame.points @ A.T


def near_surface(shape_gap, frame, x, rng, count, lo=0.01, hi=0.12):
    """``count`` points at gaps in (lo, hi) of the body posed in x: drawn in the body
    frame around its centre, pushed out until their gap is in range."""
    c, A = frame.state(x)
    out = []
    while len(out) < count:
        u = rng.standard_normal(3)
        u /= np.linalg.norm(u)
        for r in np.linspace(0.05, 2.0, 400):
            X = frame.center + r * u
            g = shape_gap(X)
            if lo < g < hi:
                out.append(c + np.linalg.solve(A.T, X - frame.center))
                break
    return np.array(out)


def test_four_nodes_carry_the_mass_centre_and_second_moment_exactly():
    c0 = np.array([1.0, -2.0, 0.5])
    frame = BodyFrame(0, 7.0, INERTIA, c0)
    P, V = frame.place([0.1, 0.2, 0.3], [0.5, -1.0, 2.0])
    m = frame.mass / 4
    assert P.mean(axis=0) == pytest.approx(c0)
    J = m * (P - c0).T @ (P - c0)
    assert J == pytest.approx(second_moment(INERTIA), rel=1e-12)
    # I = tr(J) 1 - J: the four points' inertia tensor is the body's
    assert np.trace(J) * np.eye(3) - J == pytest.approx(INERTIA, rel=1e-12)
    x = np.vstack([P])
    v, w = frame.motion(x, V)
    assert v == pytest.approx([0.1, 0.2, 0.3]) and w == pytest.approx([0.5, -1.0, 2.0])
    p, L = frame.momentum(x, V)
    assert p == pytest.approx(7.0 * np.array([0.1, 0.2, 0.3]))
    expect = 7.0 * np.cross(c0, [0.1, 0.2, 0.3]) + INERTIA @ [0.5, -1.0, 2.0]
    assert L == pytest.approx(expect, rel=1e-12)
    R = rotation([1, 1, 0], 0.7)
    c, Rb = frame.pose(c0 + [1, 1, 1] + (P - c0) @ R.T)
    assert c == pytest.approx(c0 + 1) and Rb == pytest.approx(R)


def test_inertia_that_no_body_has_is_named():
    assert inertia_problem(INERTIA) is None
    assert "positive definite" in inertia_problem(np.diag([1.0, -1.0, 2.0]))
    assert "symmetric" in inertia_problem(INERTIA + np.triu(np.ones((3, 3)), 1))
    assert "I1 + I2 > I3" in inertia_problem(np.diag([1.0, 1.0, 3.0]))


def test_rigidity_passes_finite_differences_and_exerts_no_force_or_torque():
    rng = np.random.default_rng(3)
    frame = BodyFrame(1, 5.0, INERTIA, [0.2, 0.1, -0.3])
    x = np.zeros((5, 3))
    x[1:] = posed(frame, rng, [0.3, 0.1, -0.2], rotation([1, 2, 3], 0.4))
    term = Rigidity(frame, 40.0, n_nodes=5)
    grad_err, hess_err = check_derivatives(term, x)
    assert grad_err < 1e-7 and hess_err < 1e-7
    g = np.zeros_like(x)
    term.gradient(x, g)
    assert np.abs(g).max() > 1.0
    assert np.abs(g.sum(axis=0)).max() < 1e-12 * np.abs(g).max()
    assert np.abs(np.cross(x, g).sum(axis=0)).max() < 1e-12 * np.abs(g).max()
    y = np.zeros_like(x)  # a rigid pose has no energy
    y[1:] = [4, 5, 6] + (frame.points) @ rotation([0, 1, 1], 2.0).T
    assert term.energy(y) < 1e-25


def _shapes(tmp_path, nodes, kappa, dhat, c0):
    V, T = icosphere(1)
    return {
        "box": BoxBarrier(
            nodes, c0, [0.5, 0.4, 0.3], rotation([0, 0, 1], 0.2), kappa=kappa, dhat=dhat
        ),
        "capsule": CapsuleBarrier(
            nodes, c0 - [0.4, 0, 0], c0 + [0.4, 0, 0], 0.3, kappa=kappa, dhat=dhat
        ),
        "sphere": SphereBarrier(nodes, c0, 0.5, kappa=kappa, dhat=dhat),
        "mesh": MeshBarrier(nodes, 0.6 * V + c0, T, kappa=kappa, dhat=dhat),
    }


@pytest.mark.parametrize("kind", ["box", "capsule", "sphere", "mesh"])
def test_body_contact_passes_finite_differences_and_balances_force_and_torque(kind, tmp_path):
    rng = np.random.default_rng(11)
    K = 8
    c0 = np.array([0.1, 0.2, 0.3])
    frame = BodyFrame(K, 5.0, INERTIA, c0)
    shape = _shapes(tmp_path, np.arange(K), 3.0, 0.2, c0)[kind]
    x = np.zeros((K + 4, 3))
    x[K:] = posed(frame, rng, c0 + [0.05, -0.02, 0.01], rotation([1, 2, 3], 0.3))

    def gap(X):
        buf = np.zeros((K + 4, 3))
        buf[0] = X
        return shape.gap(buf)[0]

    x[:K] = near_surface(gap, frame, x, rng, K)
    term = BodyContact(shape, frame, n_nodes=K + 4)
    g = term.gap(x)
    assert np.all(g > 0) and np.sum(g < 0.2) >= 4
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5
    f = np.zeros_like(x)
    term.gradient(x, f)
    assert np.abs(f.sum(axis=0)).max() < 1e-11 * np.abs(f).max()  # action = reaction
    assert np.abs(np.cross(x, f).sum(axis=0)).max() < 1e-11 * np.abs(f).max()  # no torque


def test_the_step_cap_lets_no_node_in_and_is_exact_for_a_body_that_does_not_turn():
    rng = np.random.default_rng(5)
    K = 30
    c0 = np.zeros(3)
    frame = BodyFrame(K, 5.0, INERTIA, c0)
    box = BoxBarrier(np.arange(K), c0, [0.5, 0.4, 0.3], kappa=1.0, dhat=0.05)
    term = BodyContact(box, frame, n_nodes=K + 4)
    x = np.zeros((K + 4, 3))
    x[K:] = frame.center + frame.points
    u = rng.standard_normal((K, 3))
    x[:K] = 1.5 * u / np.linalg.norm(u, axis=1)[:, None]
    assert term.gap(x).min() > 0
    hits = 0
    for trial in range(40):
        dx = rng.standard_normal(x.shape)
        turn = 0.05 * rng.standard_normal((3, 3))  # the body turns (and strains) a little
        dx[K:] = 0.3 * rng.standard_normal(3) + frame.points @ turn.T
        t = term.max_step(x, dx)
        assert t > 0.0
        end = 4.0 if not math.isfinite(t) else 2.0 * t
        s = np.linspace(0.0, end, 801)[1:]
        inside = [term.gap(x + si * dx).min() <= 0.0 for si in s]
        first = s[int(np.argmax(inside))] if any(inside) else math.inf
        assert t <= first, (trial, t, first)  # never beyond the first contact
        if math.isfinite(first):
            hits += 1
            assert t > 0.5 * first  # and not far before it
    assert hits >= 20
    # A translation only (W = 0): the cap is the exact first contact with the box grown
    # by the floor (FLOOR_SHARE dhat here: the coordinates' round-off is far below it).
    dx = np.zeros_like(x)
    dx[:K] = -x[:K]
    dx[K:] = [0.2, 0.1, 0.0]
    relative = dx.copy()
    relative[:K] -= [0.2, 0.1, 0.0]  # the nodes' motion seen from the body
    floor = FLOOR_SHARE * box.dhat
    assert ROUNDOFF * np.finfo(float).eps * 2.0 < floor
    nodes = np.arange(K)
    exact = box_max_step(x, relative, nodes, box.center, box.axes, box.half, floor)
    assert math.isfinite(exact) and term.max_step(x, dx) == pytest.approx(exact, rel=1e-12)
    assert exact < box.max_step(x, relative)


@pytest.mark.parametrize("kind", ["box", "capsule", "sphere", "mesh"])
def test_no_step_brings_a_node_nearer_the_body_than_the_floor(kind, tmp_path):
    """However far a line search goes towards the cap (and however often: each Newton
    iteration starts where the last one got), a node comes no nearer the turning body
    than FLOOR_SHARE dhat (less SLACK of it per iteration spent at the floor): steps that
    all head into the body close in on the floor, not on the surface (where the barrier
    would be infinite within round-off)."""
    rng = np.random.default_rng(3)
    K = 12
    c0 = np.array([0.1, 0.2, 0.3])
    frame = BodyFrame(K, 5.0, INERTIA, c0)
    dhat = 0.05
    shape = _shapes(tmp_path, np.arange(K), 1.0, dhat, c0)[kind]
    term = BodyContact(shape, frame, n_nodes=K + 4)
    x = np.zeros((K + 4, 3))
    x[K:] = frame.center + frame.points
    u = rng.standard_normal((K, 3))
    x[:K] = c0 + 1.2 * u / np.linalg.norm(u, axis=1)[:, None]
    floor = FLOOR_SHARE * dhat
    for _ in range(60):
        dx = np.zeros_like(x)
        dx[:K] = c0 - x[:K]  # every node heads for the centre
        dx[K:] = frame.points @ (0.02 * rng.standard_normal((3, 3))).T  # the body turns
        t = term.max_step(x, dx)
        assert 0.0 <= t < 1.0
        x = x + (1.0 - 1e-12) * t * dx  # all but the whole way to the cap
        assert term.gap(x).min() >= floor * (1.0 - SLACK) ** 60
    assert term.gap(x).min() < 1.01 * floor  # it got there, and no further


def test_a_newton_step_turns_a_body_by_at_most_turn_max():
    """Rigidity caps a step at |t dA|_2 = TURN_MAX: a turn by theta about an axis
    (dA = [w]x theta, |dA|_2 = theta) goes TURN_MAX / theta of the way; a translation and
    the net's nodes are not capped."""
    K = 3
    frame = BodyFrame(K, 5.0, INERTIA, np.zeros(3))
    term = Rigidity(frame, 1e3, n_nodes=K + 4)
    x = np.zeros((K + 4, 3))
    x[K:] = frame.points
    for theta in (0.1, 1.0, 1e10):
        W = theta * np.array([[0.0, -0.6, 0.0], [0.6, 0.0, -0.8], [0.0, 0.8, 0.0]])
        dx = np.zeros_like(x)
        dx[K:] = frame.points @ W.T + [1.0, 2.0, 3.0]
        assert term.max_step(x, dx) == pytest.approx(TURN_MAX / theta, rel=1e-12)
    dx = np.zeros_like(x)
    dx[:K] = 5.0
    dx[K:] = [1.0, 2.0, 3.0]
    assert term.max_step(x, dx) > 1e12  # dA is round-off: 1 times the sum of B's rows


def spinning_case(dt: float, t_end: float) -> dict:
    """A 3 kg box (1 x 0.7 x 0.4 m) spinning at 2 rad/s about its intermediate axis,
    slightly off it, no gravity; a short cable far away is the net it never meets (run
    with newmark from Python: a case file with a body refuses it)."""
    return {
        "geometry": {"kind": "cable", "start": [20, 0, 0], "end": [21, 0, 0], "nodes": 3},
        "material": {"E": 1e9, "radius": 0.001, "density": 1000.0},
        "obstacle": [
            {
                "kind": "box",
                "center": [0.0, 0.0, 0.0],
                "half_size": [0.5, 0.35, 0.2],
                "mass": 3.0,
                "angular_velocity": [0.1, 2.0, 0.0],
            }
        ],
        "solver": {"method": "dynamic", "dt": dt, "damping": 0.0, "t_end": t_end},
    }  # fmt: skip


def test_a_torque_free_body_keeps_its_angular_momentum_and_flips_as_euler_says():
    from scipy.integrate import solve_ivp

    runs = {}
    for dt in (0.02, 0.01):
        scene = build(parse_case(spinning_case(dt, 6.0)))
        body = scene.rigid[0]
        frame = body.frame
        L0 = frame.momentum(scene.net.nodes, scene.velocity)[1]
        rows = []

        def on_step(s, frame=frame, rows=rows):
            _, R = frame.pose(s.x)
            L = frame.momentum(s.x, s.v)[1]
            rows.append((s.time, L, R.T @ frame.motion(s.x, s.v)[1]))

        r = solve(scene, Settings.of(scene.case.solver, integrator="newmark"), on_step=on_step)
        assert r.converged
        t = np.array([row[0] for row in rows])
        drift = max(float(np.linalg.norm(row[1] - L0)) for row in rows) / np.linalg.norm(L0)
        w_body = np.array([row[2] for row in rows])
        runs[dt] = (t, drift, w_body, body.inertia)
    (t, drift2, w2, inertia), (t1, drift1, w1, _) = runs[0.02], runs[0.01]
    assert drift1 < 1e-3 and 3.0 < drift2 / drift1 < 5.0  # second order

    def euler(_, w):
        return np.linalg.solve(inertia, -np.cross(w, inertia @ w))

    ref = solve_ivp(euler, (0, 6.0), [0.1, 2.0, 0.0], t_eval=t1, rtol=1e-11, atol=1e-12).y.T
    flip_ref = t1[np.argmax(ref[:, 1] < 0)]
    flip = t1[np.argmax(w1[:, 1] < 0)]
    assert 4.0 < flip_ref < 6.0 and abs(flip - flip_ref) < 0.05  # it turns over, on time
    assert np.abs(w1 - ref).max() < 0.05 * 2.0
    assert np.abs(w2[:, 1]).min() < 0.5 and w2[-1, 1] < -1.0  # the coarse run flips too


def box_on_net(method: str, **solver) -> dict:
    """A 10 kg square box (0.3 x 0.3 x 0.1 m) placed 2 mm above the paper's square net
    (n = 10, 5 cm edges), under gravity, with friction: frictionless, the flat face's
    equilibrium is unstable (the static solve says so), and where a damped run comes to
    rest, at it or slid off it, was round-off's to decide."""
    return {
        **net_under_gravity(10, 0.05),
        "obstacle": [
            {
                "kind": "box", "center": [0.0, 0.0, 0.052], "half_size": [0.15, 0.15, 0.05],
                "mass": 10.0, "distance": 0.005, "friction": 0.3,
            }
        ],
        "solver": {"method": method, **solver},
    }  # fmt: skip


@pytest.mark.roundoff
def test_a_box_released_on_a_net_rests_at_the_static_equilibrium_of_net_and_box():
    s_scene = build(parse_case(box_on_net("static")))
    rs = solve(s_scene, Settings.of(s_scene.case.solver))
    assert rs.converged
    frame = s_scene.rigid[0].frame
    c, R = frame.pose(rs.x)
    assert c[2] < 0.052 - 0.05 and np.abs(R - np.eye(3)).max() < 1e-5  # sank, level
    load = s_scene.loads.external_force(s_scene.net).sum(axis=0)
    assert load[2] < -10.0 * 9.81  # the box's weight is among the loads
    assert np.abs(rs.reaction.sum(axis=0) + load).max() < 1e-8 * np.abs(load).max()
    # (each step's Newton held to 25 iterations: with friction the state a damped run
    # comes to rest in depends on its steps, and the static one is the rest state of
    # those steps; longer ones, kept where a step still converging goes on, hold the
    # box 6 mm lower, tilted 0.0077 rad, at rest as well)
    d_scene = build(
        parse_case(box_on_net("dynamic", dt=0.05, damping=8.0, t_end=20.0, max_iter=25))
    )
    rd = solve(d_scene, Settings.of(d_scene.case.solver))
    assert rd.converged and rd.equilibrium
    assert np.abs(rd.x - rs.x).max() < 1e-6


def test_a_sphere_body_repeats_the_ball():
    """A sphere with mass is a ball (its centre a node); with angular_velocity it is a
    six-DOF body. Frictionless, it never spins up: both follow the same path."""
    case = {
        **net_under_gravity(10, 0.05),
        "obstacle": [
            {
                "kind": "sphere", "center": [0.0, 0.0, 0.3], "radius": 0.15, "mass": 10.0,
                "velocity": [0.4, -0.2, -1.0], "distance": 0.005,
            }
        ],
        "solver": {"method": "dynamic", "dt": 0.005, "damping": 0.0, "t_end": 0.4},
    }  # fmt: skip
    paths = []
    for spin in (None, [0.0, 0.0, 0.0]):
        c = copy.deepcopy(case)
        if spin is not None:
            c["obstacle"][0]["angular_velocity"] = spin
        scene = build(parse_case(c))
        if spin is None:
            assert not scene.rigid and scene.net.bodies == 1

            def centre(x):
                return x[-1].copy()
        else:
            assert len(scene.rigid) == 1 and scene.net.bodies == 4
            centre = lambda x, f=scene.rigid[0].frame: f.pose(x)[0]  # noqa: E731
        path = []
        settings = Settings.of(scene.case.solver)
        solve(scene, settings, on_step=lambda s, p=path, c=centre: p.append(c(s.x)))
        paths.append(np.array(path))
    assert len(paths[0]) == len(paths[1])
    assert np.abs(paths[0] - paths[1]).max() < 1e-6
    assert paths[0][:, 2].min() < 0.3 - 0.2  # it fell into the net


def test_body_friction_passes_finite_differences_and_balances_force_and_torque():
    from catenet.terms.friction import Friction
    from catenet.terms.rigid_contact import BodyFriction

    rng = np.random.default_rng(2)
    K = 8
    c0 = np.array([0.1, 0.2, 0.3])
    frame = BodyFrame(K, 5.0, INERTIA, c0)
    box = BoxBarrier(np.arange(K), c0, [0.5, 0.4, 0.3], kappa=3.0, dhat=0.2)
    x = np.zeros((K + 4, 3))
    x[K:] = posed(frame, rng, c0, rotation([1, 2, 3], 0.3))

    def gap(X):
        buf = np.zeros((K + 4, 3))
        buf[0] = X
        return box.gap(buf)[0]

    x[:K] = near_surface(gap, frame, x, rng, K, hi=0.15)
    contact = BodyContact(box, frame, n_nodes=K + 4)
    term = BodyFriction(Friction(box, mu=0.4, slip=0.01), contact)
    term.begin_step(x, 0.1, 0.0)  # lagged normal forces and anchors at x
    y = x.copy()
    y[:K] += 0.02 * rng.standard_normal((K, 3))  # slid: some past the slip distance
    y[K:] = posed(frame, rng, c0 + 0.01, rotation([1, 2, 3], 0.35))
    assert term.energy(y) > 0
    grad_err, hess_err = check_derivatives(term, y, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5
    f = np.zeros_like(y)
    term.gradient(y, f)
    assert np.abs(f.sum(axis=0)).max() < 1e-11 * np.abs(f).max()
    assert np.abs(np.cross(y, f).sum(axis=0)).max() < 1e-11 * np.abs(f).max()
    # A state that moves with the body rigidly, nodes and all, has no friction energy.
    turn = rotation([0, 1, 0], 0.7)
    z = c0 + [1.0, -2.0, 0.5] + (x - c0) @ turn.T
    assert term.energy(z) < 1e-12 * term.energy(y)


def test_body_friction_with_no_node_pressed_on_the_body_is_not_evaluated(monkeypatch):
    """A net in flight towards the body (every lagged normal force 0): the friction's
    gradient is 0 and its Hessian skipped without evaluating either; once a node is
    pressed on the body at a step's start, both are what the friction kernels give."""
    from catenet.terms import rigid_contact
    from catenet.terms.friction import Friction
    from catenet.terms.rigid_contact import BodyFriction

    rng = np.random.default_rng(3)
    K = 6
    c0 = np.array([0.0, 0.0, 0.0])
    frame = BodyFrame(K, 5.0, INERTIA, c0)
    box = BoxBarrier(np.arange(K), c0, [0.5, 0.4, 0.3], kappa=3.0, dhat=0.2)
    x = np.zeros((K + 4, 3))
    x[K:] = posed(frame, rng, c0, np.eye(3))
    x[:K] = [0.0, 0.0, 2.0] + 0.1 * rng.standard_normal((K, 3))  # far above the box
    term = BodyFriction(Friction(box, mu=0.4, slip=0.01), BodyContact(box, frame, n_nodes=K + 4))
    term.begin_step(x, 0.1, 0.0)
    assert not term.touching
    called = []

    def counted(name):
        real = getattr(rigid_contact, name)
        return lambda *a: called.append(name) or real(*a)

    for name in ("frame_friction_gradient", "frame_friction_hessian"):
        monkeypatch.setattr(rigid_contact, name, counted(name))
    grad = np.zeros_like(x)
    assert term.gradient(x, grad) == 0.0 and not grad.any()
    assert term.hessian(x, np.zeros(81 * K + 144)) is False
    assert not called
    x[0] = [0.0, 0.0, 0.35]  # 5 cm above the top face: within the barrier's 0.2 m
    term.begin_step(x, 0.2, 0.1)
    assert term.touching
    y = x.copy()
    y[0, 0] += 0.05  # slid past the slip distance
    assert term.gradient(y, grad) > 0.0 and np.abs(grad).max() > 0.0
    assert term.hessian(y, np.zeros(81 * K + 144)) is True
    assert called == ["frame_friction_gradient", "frame_friction_hessian"]


def test_friction_slows_a_ball_spinning_on_a_net():
    """A sphere body spinning about the vertical, resting on the net: frictionless, no
    torque reaches it and it keeps its spin (but for implicit Euler's own small
    dissipation); with friction the net grips it and takes its spin."""
    spins = {}
    for mu in (0.0, 0.5):
        case = {
            **net_under_gravity(10, 0.05),
            "obstacle": [
                {
                    "kind": "sphere", "center": [0.0, 0.0, 0.152], "radius": 0.15,
                    "mass": 10.0, "distance": 0.005, "angular_velocity": [0.0, 0.0, 2.0],
                    "friction": mu,
                }
            ],
            "solver": {"method": "dynamic", "dt": 0.01, "damping": 2.0, "t_end": 0.25},
        }  # fmt: skip
        scene = build(parse_case(case))
        frame = scene.rigid[0].frame
        seen = []
        r = solve(
            scene,
            Settings.of(scene.case.solver),
            on_step=lambda s, f=frame, seen=seen: seen.append(f.motion(s.x, s.v)[1]),
        )
        assert r.converged
        spins[mu] = np.array(seen)
    still = spins[0.0]
    assert np.abs(still[:, :2]).max() < 1e-9 and np.abs(still[:, 2] - 2.0).max() < 0.03
    assert np.abs(spins[0.5][:, 2] - 2.0).max() > 0.5
