"""Several free rigid bodies in one case, and free bodies beside fixed obstacles and
balls (catenet.scene.rigid, catenet.scene.touching): two bodies dropped into one net
come to rest at the static equilibrium with both; two bodies and a free net in zero
gravity keep their momentum; a box lands on the ground (a plane's barrier on its
corners: finite-difference checks, reaction = weight); two spheres flying at each other
stop each other without ever overlapping, at any step (over the path between two
steps too), their momentum kept; a static run holds a box pushed against a fixed ball;
a ball dropped on a free box rests on it; bodies that start overlapping are refused
(exit 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner
from meshes import net_under_gravity

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.body_plane import BodyPlane
from catenet.terms.rigid_contact import BodyContact
from catenet.terms.touch import BodyTouch, BodyTouchFriction


def two_bowls(**solver) -> dict:
    """A 1 x 0.5 m grid net (0.1 m cells) pinned on its edge and along its middle line:
    two bowls of 5 x 5 cells; a 3 kg sphere body (density: it has six DOFs) over the
    middle of each, the centre of a cell: it rests cradled by that cell's four nodes
    (over a node it would balance on it, unstable)."""
    nx, ny, h = 11, 6, 0.1
    nodes = [[i * h - 0.5, j * h - 0.25, 0.0] for j in range(ny) for i in range(nx)]
    edges = [[j * nx + i, j * nx + i + 1] for j in range(ny) for i in range(nx - 1)]
    edges += [[j * nx + i, (j + 1) * nx + i] for j in range(ny - 1) for i in range(nx)]
    fixed = [j * nx + i for j in range(ny) for i in range(nx) if i in (0, 5, 10) or j in (0, 5)]
    r = 0.08
    density = 3.0 / (4 / 3 * math.pi * r**3)
    spheres = [
        {"kind": "sphere", "center": [x, 0.0, r + 0.004], "radius": r, "density": density,
         "distance": 0.005}
        for x in (-0.25, 0.25)
    ]  # fmt: skip
    return {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges, "fixed": fixed},
        "material": {"E": 2e8, "radius": 0.002, "density": 1000.0, "prestress": 50.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": spheres,
        "solver": solver,
    }


def test_two_bodies_in_one_net_rest_at_the_static_equilibrium_with_both():
    static = build(parse_case(two_bowls(method="static")))
    rs = solve(static, Settings.of(static.case.solver))
    assert rs.converged and len(static.rigid) == 2
    for body in static.rigid:  # each sank into its bowl, under it
        c, _ = body.frame.pose(rs.x)
        assert c[2] < body.center[2] - 0.004
    load = static.loads.external_force(static.net).sum(axis=0)
    assert np.abs(rs.reaction.sum(axis=0) + load).max() < 1e-8 * np.abs(load).max()
    dynamic = build(parse_case(two_bowls(method="dynamic", dt=0.02, damping=10.0, t_end=12.0)))
    rd = solve(dynamic, Settings.of(dynamic.case.solver))
    assert rd.converged and rd.equilibrium
    for a, b in zip(static.rigid, dynamic.rigid, strict=True):
        assert np.abs(a.frame.pose(rs.x)[0] - b.frame.pose(rd.x)[0]).max() < 1e-6
    net = static.net.n_net
    assert np.abs(rd.x[:net] - rs.x[:net]).max() < 1e-6


def test_two_bodies_and_a_free_net_keep_their_momentum():
    """No supports, no gravity, no damping: a 4 x 4 net thrown down between two boxes
    that fly at it from below, one turning: the total linear momentum of net and bodies
    stays what it was to the solver's tolerance at every step, though both bodies touch
    the net (each exchanges momentum with it through the barrier only)."""
    n = 4
    g = np.linspace(-0.3, 0.3, n)
    nodes = [[float(x), float(y), 0.2] for y in g for x in g]
    edges = [[j * n + i, j * n + i + 1] for j in range(n) for i in range(n - 1)]
    edges += [[j * n + i, (j + 1) * n + i] for j in range(n - 1) for i in range(n)]
    boxes = [
        {"kind": "box", "center": [x, 0.0, 0.0], "half_size": [0.08, 0.15, 0.08], "mass": 2.0,
         "velocity": [0.0, 0.0, 1.5], "angular_velocity": [0.0, w, 0.0], "distance": 0.005}
        for x, w in ((-0.3, 0.5), (0.3, 0.0))
    ]  # fmt: skip
    case = {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges},
        "material": {"E": 2e9, "radius": 0.001, "density": 1000.0, "tension_only": False},
        "mass": [{"node": i, "mass": 0.05, "velocity": [0.0, 0.0, -1.0]} for i in range(n * n)],
        "obstacle": boxes,
        "solver": {"method": "dynamic", "dt": 0.005, "damping": 0.0, "t_end": 0.12},
    }
    scene = build(parse_case(case))
    m = scene.net.mass[:, None]
    p0 = (m * scene.velocity).sum(axis=0)
    gaps, drift = [], []
    contacts = [t for t in scene.terms if isinstance(t, BodyContact)]

    def on_step(s):
        drift.append(float(np.abs((m * s.v).sum(axis=0) - p0).max()))
        gaps.append([float(t.gap(s.x).min()) for t in contacts])

    r = solve(scene, Settings.of(scene.case.solver), on_step=on_step)
    assert r.converged
    assert np.all(np.min(gaps, axis=0) < 0.005)  # both boxes reach the net
    scale = float(np.abs(m * scene.velocity).sum())
    assert max(drift) < 1e-6 * scale


def run_cli(tmp_path, case: dict, name: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(dumps_toml(case))
    out = tmp_path / f"{name}.h5"
    return CliRunner().invoke(main, ["run", str(path), "-o", str(out)]), out


def ground_case(x: float, **solver) -> dict:
    """A pinned net (1 m) above the ground at z = -0.15, a 40 kg box thrown down at
    3 m/s from its bottom at z = 0.25, at x (beside the net when x > 0.75)."""
    return {
        **net_under_gravity(6, 0.05),
        "obstacle": [
            {"kind": "plane", "point": [0.0, 0.0, -0.15], "normal": [0.0, 0.0, 1.0],
             "distance": 0.002},
            {"kind": "box", "center": [x, 0.0, 0.3], "half_size": [0.15, 0.15, 0.05],
             "mass": 40.0, "velocity": [0.0, 0.0, -3.0], "distance": 0.005},
        ],
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.3, **solver},
    }  # fmt: skip


def test_a_box_beside_the_net_lands_on_the_ground_and_rests_there():
    """Beside the net the box falls freely onto the ground (a plane: the barrier acts on
    its corners, ``catenet.terms.body_plane``): no corner ever below the ground; with
    damping it comes to rest level on it (its speed below 1e-9 m/s), its four lower
    corners within the barrier's reach, and the ground's reaction (their barrier
    forces) is the box's weight."""
    case = ground_case(1.2, damping=20.0, t_end=3.0, dt=0.02)
    scene = build(parse_case(case))
    plane = next(t for t in scene.terms if isinstance(t, BodyPlane))
    low = []

    def seen(step):
        low.append(plane.gap(step.x).min())

    r = solve(scene, Settings.of(scene.case.solver), on_step=seen)
    assert r.converged and np.abs(r.v).max() < 1e-9  # at rest
    assert min(low) > 0.0
    gaps = np.sort(plane.gap(r.x))
    assert np.all(gaps[:4] < 0.002) and np.all(gaps[4:] > 0.09)  # level, on four corners
    grad = np.zeros_like(r.x)
    plane.gradient(r.x, grad)
    reaction = -grad[scene.rigid[0].frame.nodes].sum(axis=0)
    assert np.allclose(reaction, [0.0, 0.0, 40.0 * 9.81], rtol=1e-6, atol=1e-6)
    _, R = scene.rigid[0].frame.pose(r.x)
    assert np.abs(R - np.eye(3)).max() < 1e-6
    over = build(parse_case(ground_case(0.0)))  # over the net: caught by it
    assert solve(over, Settings.of(over.case.solver)).converged


def test_a_box_started_at_equilibrium_rests_on_the_ground_undamped():
    """docs/guide/bodies.md: a 40 kg box placed 4 mm above the ground falls onto its
    barrier and bounces there, undamped (up to 0.16 m/s over 0.5 s from the given
    start); with ``solver.initial_state = "equilibrium"`` the run starts from it at rest
    on the ground and stays there (below 1e-6 m/s, no corner below the ground)."""
    case = ground_case(1.2, damping=0.0, t_end=0.5, dt=0.01, initial_state="equilibrium")
    case["obstacle"][1].pop("velocity")
    case["obstacle"][1]["center"] = [1.2, 0.0, -0.15 + 0.05 + 0.004]  # 4 mm above it
    scene = build(parse_case(case))
    plane = next(t for t in scene.terms if isinstance(t, BodyPlane))
    low, fastest = [], []
    frame = scene.rigid[0].frame.nodes

    def seen(step):
        low.append(plane.gap(step.x).min())
        fastest.append(float(np.abs(step.v[frame]).max()))

    r = solve(scene, Settings.of(scene.case.solver), on_step=seen)
    assert r.converged and min(low) > 0.0
    assert max(fastest) < 1e-6, max(fastest)


def test_an_equilibrium_start_that_moves_a_body_far_says_so(caplog):
    """A 5 kg ball given 2 m above a net, with ``initial_state = "equilibrium"``: the start
    rests it on the net (2.045 m lower), so the drop the case describes never happens;
    the run says so (it ended at rest after one step in silence). The box above, 4 mm
    from where it rests, is not warned of."""
    case = {
        "geometry": {"kind": "square_net", "n": 10, "alpha": 0.0, "size": 1.0,
                     "edge_length": 0.05},
        "material": {"E": 2.0e9, "radius": 0.002, "density": 1140.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "sphere", "center": [0.0, 0.0, 2.15], "radius": 0.15,
                      "mass": 5.0}],
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "t_end": 0.1},
    }  # fmt: skip
    scene = build(parse_case(case))
    with caplog.at_level("WARNING", logger="catenet.solver.path"):
        solve(scene, Settings.of(scene.case.solver))
    assert "moved a free body 2.04" in caplog.text and "does not fall" in caplog.text
    caplog.clear()
    near = ground_case(1.2, damping=0.0, t_end=0.02, dt=0.01, initial_state="equilibrium")
    near["obstacle"][1].pop("velocity")
    near["obstacle"][1]["center"] = [1.2, 0.0, -0.15 + 0.05 + 0.004]
    scene = build(parse_case(near))
    with caplog.at_level("WARNING", logger="catenet.solver.path"):
        solve(scene, Settings.of(scene.case.solver))
    assert "moved a free body" not in caplog.text


def test_body_plane_derivatives_and_step_cap():
    """Gradient and Hessian of the body-plane barrier against finite differences, at a
    turned, slightly strained box with three corners within reach; the step cap is the
    first time a corner would reach the plane along a step."""
    case = ground_case(1.2)
    case["obstacle"][1].update(center=[1.2, 0.0, -0.085], axis=[1.0, 1.0, 0.0], angle=0.05)
    case["obstacle"][0]["distance"] = 0.05
    scene = build(parse_case(case))
    plane = next(t for t in scene.terms if isinstance(t, BodyPlane))
    x = scene.net.nodes.copy()
    nodes = scene.rigid[0].frame.nodes
    x[nodes] += 1e-4 * np.random.default_rng(3).standard_normal((4, 3))
    assert np.count_nonzero(plane.gap(x) < 0.05) >= 3
    grad_err, hess_err = check_derivatives(plane, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-6
    dx = np.zeros_like(x)
    dx[nodes] = [0.0, 0.0, -1.0]  # the body sinks: its lowest corner first
    t = plane.max_step(x, dx)
    assert t == pytest.approx(plane.gap(x).min(), rel=1e-12)
    assert plane.max_step(x, -dx) == math.inf


def spheres_case(offset: float, dt: float) -> dict:
    """Two sphere bodies (r = 0.05) flying at each other at 1 m/s each, 0.4 m apart
    centre to centre, their lines ``offset`` apart across; a pinned cable far away."""
    spheres = [
        {"kind": "sphere", "center": [s * 0.2, s * offset / 2, 1.0], "radius": 0.05,
         "density": 2000.0, "velocity": [-s * 1.0, 0.0, 0.0]}
        for s in (-1.0, 1.0)
    ]  # fmt: skip
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 5},
        "material": {"E": 1e9, "radius": 0.001, "density": 1000.0, "prestress": 10.0},
        "obstacle": spheres,
        "solver": {"method": "dynamic", "dt": dt, "damping": 0.0, "t_end": 0.5},
    }


@pytest.mark.parametrize("dt", [0.01, 0.3])
def test_two_spheres_that_meet_stop_each_other(tmp_path, dt):
    """They would touch when their centres are 0.1 apart, at t = 0.15. With dt = 0.01,
    and with dt = 0.3 (where one free step would take them 0.2 through each other),
    their centres are never closer than the summed radii, at every step nor on the
    straight path between two steps; the total momentum is kept (zero); the impact
    took most of their speed. 0.12 apart across, they pass untouched."""
    scene = build(parse_case(spheres_case(0.0, dt)))
    a, b = scene.rigid
    states = [scene.net.nodes.copy()]
    total = []

    def seen(s):
        states.append(s.x.copy())
        total.append(a.frame.momentum(s.x, s.v)[0] + b.frame.momentum(s.x, s.v)[0])

    r = solve(scene, Settings.of(scene.case.solver), on_step=seen)
    assert r.converged
    gaps = []
    for x0, x1 in zip(states[:-1], states[1:], strict=True):
        for s in np.linspace(0.0, 1.0, 21):
            x = (1 - s) * x0 + s * x1
            gaps.append(np.linalg.norm(a.frame.state(x)[0] - b.frame.state(x)[0]) - 0.1)
    mass = 2000.0 * 4 / 3 * math.pi * 0.05**3
    assert min(gaps) > 0.0 and np.abs(total).max() < 1e-8 * mass
    va, vb = a.frame.motion(r.x, r.v)[0], b.frame.motion(r.x, r.v)[0]
    assert max(abs(va[0]), abs(vb[0])) < 0.5  # stopped (implicit Euler's loss in impact)
    res, _ = run_cli(tmp_path, spheres_case(0.0, dt), "meet")
    assert res.exit_code == 0, res.output
    scene = build(parse_case(spheres_case(0.12, dt)))
    (term,) = [t for t in scene.terms if isinstance(t, BodyTouch)]
    gaps = []
    r = solve(scene, Settings.of(scene.case.solver), on_step=lambda s: gaps.append(term.gap(s.x)))
    assert r.converged and min(gaps) > term.dhat  # never within reach


def test_a_static_run_holds_a_box_pushed_against_a_fixed_ball():
    """A static run: a 10 kg box on a net that 800 N at its centre push up towards a
    fixed ball above it: the box stops at the ball (within the pair's reach), and the
    ball's push on the box (its barrier and friction), its weight and the net's push
    balance."""
    case = {
        "geometry": {
            "kind": "square_net", "n": 6, "alpha": math.pi / 4, "size": 1.0,
            "edge_length": 0.05,
        },
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {
            "gravity": [0.0, 0.0, -9.81],
            "point": [{"node": "center", "force": [0.0, 0.0, 800.0]}],
        },
        "obstacle": [
            {"kind": "sphere", "center": [0.0, 0.0, 0.4], "radius": 0.1},
            {"kind": "box", "center": [0.0, 0.0, 0.052], "half_size": [0.15, 0.15, 0.05],
             "mass": 10.0, "distance": 0.005, "friction": 0.5},
        ],
        "solver": {"method": "static"},
    }  # fmt: skip
    scene = build(parse_case(case))
    r = solve(scene, Settings.of(scene.case.solver))
    assert r.converged
    (touch,) = [t for t in scene.terms if isinstance(t, BodyTouch)]
    assert 0.0 < touch.gap(r.x) < touch.dhat
    nodes = scene.rigid[0].frame.nodes
    net_push, ball = np.zeros_like(r.x), np.zeros_like(r.x)
    for term in scene.terms:
        if isinstance(term, (BodyTouch, BodyTouchFriction)):
            term.gradient(r.x, ball)
        elif getattr(term, "frame", None) is scene.rigid[0].frame:
            term.gradient(r.x, net_push)
    total = -net_push[nodes].sum(axis=0) - ball[nodes].sum(axis=0) + [0.0, 0.0, -98.1]
    assert np.abs(total).max() < 1e-6 * 800.0
    assert -ball[nodes].sum(axis=0)[2] < -1.0  # the ball pushes the box down


def test_a_ball_dropped_on_a_free_box_rests_on_it():
    """A ball (a sphere with mass alone: one node) dropped onto a 40 kg box lying on the
    ground: it never enters the box (its centre's height above the box's top at every
    step at least its radius), and at rest the ground carries both weights."""
    case = ground_case(1.2, damping=0.0, t_end=1.5, dt=0.01)
    case["obstacle"][1].update(center=[1.2, 0.0, -0.0995], velocity=[0.0, 0.0, 0.0])
    case["obstacle"].append(
        {"kind": "sphere", "center": [1.25, 0.03, 0.2], "radius": 0.05, "mass": 2.0,
         "distance": 0.002}
    )  # fmt: skip
    scene = build(parse_case(case))
    ball = scene.bodies[0].node
    box = scene.rigid[0].frame
    heights = []

    def seen(s):
        c, R = box.pose(s.x)
        heights.append(float((s.x[ball] - c) @ R[:, 2]) - 0.05)

    r = solve(scene, Settings.of(scene.case.solver), on_step=seen)
    assert r.converged and min(heights) > 0.05
    assert heights[-1] < 0.05 + 0.002 and abs(r.v[ball][2]) < 1e-3  # it may slide, on it
    planes = [t for t in scene.terms if isinstance(t, BodyPlane)]
    grad = np.zeros_like(r.x)
    for p in planes:
        p.gradient(r.x, grad)
    assert -grad[box.nodes].sum(axis=0)[2] == pytest.approx(42.0 * 9.81, rel=1e-3)


def test_bodies_that_start_overlapping_are_refused():
    case = spheres_case(0.0, 0.01)
    case["obstacle"][1]["center"] = [-0.15, 0.0, 1.0]
    with pytest.raises(
        ConfigError,
        match=r"obstacle\[0\] \(a free sphere\): it meets obstacle\[1\] .* at the start",
    ):
        build(parse_case(case))
    case = ground_case(1.2)
    case["obstacle"][1]["center"] = [1.2, 0.0, -0.12]
    with pytest.raises(ConfigError, match=r"obstacle\[1\] \(a free box\): its point .* starts in"):
        build(parse_case(case))


def test_a_free_body_beside_a_moving_box_is_refused():
    case = ground_case(1.2)
    case["obstacle"][0] = {
        "kind": "box", "center": [0.0, 0.0, -0.5], "half_size": [0.1, 0.1, 0.1],
        "velocity": [0.0, 0.0, 0.1],
    }  # fmt: skip
    with pytest.raises(ConfigError, match=r"obstacle\[0\] \(kind 'box'\): an obstacle on a"):
        build(parse_case(case))


def test_a_body_in_free_flight_is_no_contact_in_the_summary():
    """A sphere that falls beside the two bowls and never reaches the net: its frame's
    rigidity is the body's own (round-off forces on its frame nodes), not a contact, so
    the run touches no node and its summary says no contact."""
    from catenet.run.runner import run_case

    data = two_bowls(method="dynamic", dt=0.01, t_end=0.05, damping=0.0)
    data["obstacle"][1]["center"] = [2.0, 0.0, 0.5]  # far from the net
    data["obstacle"][1]["velocity"] = [0.3, 0.0, 0.0]
    data["obstacle"][1]["angular_velocity"] = [0.0, 5.0, 0.0]
    data["obstacle"] = data["obstacle"][1:]
    result = run_case(parse_case(data), None)
    summary = result.report.summary
    assert summary["contact_nodes"] == 0 and summary["max_contact"] == 0.0, summary
    assert result.report.bodies[0]["first_contact"] is None
