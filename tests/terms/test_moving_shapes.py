"""Boxes, capsules and meshes on a prescribed rigid motion (catenet/terms/moving.py):
the wrapper's derivatives, its equivalence with the fixed shape at the moved pose, no
node inside at any step while a rotating box sweeps through a net, a support in the
obstacle's way stopping the run with a clear message, and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from contact_cases import flat_case, moving_shapes, near
from meshes import CUBE_T, CUBE_V

from catenet.case import build, dumps_toml, parse_case
from catenet.errors import ConvergenceError
from catenet.model.histories import History
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier, rotation


@pytest.mark.parametrize("kind", ["box", "capsule", "mesh"])
def test_moving_shapes_pass_finite_differences_at_a_turned_and_moved_pose(kind):
    rng = np.random.default_rng(5)
    term = moving_shapes()[kind]
    term.begin_step(np.zeros((30, 3)), 0.8)
    assert np.linalg.norm(term.center - term.origin) > 0.4  # moved
    assert abs(np.trace(term.R) - 3.0) > 0.5  # and turned
    x = near(term, rng, 30, term.dhat)
    assert np.all(term.gap(x) > 0) and np.any(term.gap(x) > term.dhat)
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


def test_a_moving_box_at_time_t_is_the_box_turned_and_moved_there():
    """A box turned by ``angle`` about ``axis`` and moved by d equals the level box
    turning at angle/T about the axis and moving at d/T, at time T: gaps, forces,
    Hessians and first contacts."""
    rng = np.random.default_rng(11)
    n, T = 40, 0.7
    axis, angle, c0, d = np.array([1.0, 1.0, 0.3]), 1.3, np.array([0.2, -0.1, 0.4]), [0.5, 0, -0.2]
    half = [0.5, 0.4, 0.3]
    R = rotation(axis, angle)
    fixed = BoxBarrier(np.arange(n), c0 + d, half, R, kappa=7.0, dhat=0.04)
    level = BoxBarrier(np.arange(n), c0, half, None, kappa=7.0, dhat=0.04)
    w = axis / np.linalg.norm(axis) * angle / T
    moving = Moving(level, c0, np.array(d) / T, w, reach=float(np.linalg.norm(half)))
    moving.begin_step(np.zeros((n, 3)), T)
    x = near(moving, rng, n, 0.04)
    assert np.allclose(moving.gap(x), fixed.gap(x), atol=1e-12)
    g1, g2 = np.zeros_like(x), np.zeros_like(x)
    assert moving.gradient(x, g1) == pytest.approx(fixed.gradient(x, g2), rel=1e-10)
    assert np.allclose(g1, g2, rtol=1e-9, atol=1e-9 * np.abs(g2).max())
    h1, h2 = np.zeros(9 * n), np.zeros(9 * n)
    moving.hessian(x, h1)
    fixed.hessian(x, h2)
    assert np.allclose(h1, h2, rtol=1e-8, atol=1e-8 * np.abs(h2).max())
    for _ in range(20):
        dx = rng.standard_normal(x.shape)
        assert moving.max_step(x, dx) == pytest.approx(fixed.max_step(x, dx), rel=1e-9)


def test_a_history_scales_the_motion_by_the_integral_of_its_factor():
    """factor 0 then 2 from t = 1 s: at t = 1.5 s the pose is that of t = 1 s without one."""
    hist = History([[0.0, 0.0], [0.5, 0.0], [0.5 + 1e-9, 2.0], [3.0, 2.0]])
    plain, scaled = moving_shapes()["box"], moving_shapes(history=hist)["box"]
    c1, R1 = plain.pose(1.0)
    c2, R2 = scaled.pose(1.0)
    assert np.allclose(c1, c2, atol=1e-8) and np.allclose(R1, R2, atol=1e-8)
    c0, R0 = scaled.pose(0.4)
    assert np.allclose(c0, scaled.origin) and np.allclose(R0, np.eye(3))


def test_carry_moves_only_the_nodes_the_obstacle_may_reach_and_keeps_their_gaps():
    term = moving_shapes(n=60)["box"]
    rng = np.random.default_rng(2)
    x = np.vstack([near(term, rng, 30, 0.05), term.world(rng.uniform(2.0, 3.0, (30, 3)))])
    base, trial = x.copy(), x + 0.001
    carried = term.carry(base, trial, 0.0, 0.05, np.zeros(60, bool))
    assert carried == 30  # the near ones: the box moves ~0.06 m at most in 0.05 s
    term.begin_step(x, 0.05)
    assert np.allclose(term.gap(base)[:30], moving_shapes(n=60)["box"].gap(x)[:30], atol=1e-12)
    assert np.array_equal(base[30:], x[30:]) and np.array_equal(trial[30:], x[30:] + 0.001)


# --------------------------------------------------------------------------- scenes


def sweep_case(dt, t_end=0.5, **box):
    """The paper's square net hanging under gravity, a bar below it turning about y at
    pi rad/s: in 0.5 s one end sweeps up through the net's plane and lifts it 5 cm."""
    case = flat_case(method="dynamic", dt=dt, t_end=t_end, damping=5.0)
    case["load"] = {"gravity": [0, 0, -9.81]}
    case["obstacle"] = [
        {
            "kind": "box",
            "center": [0.0, 0.0, -0.3],
            "half_size": [0.35, 0.06, 0.06],
            "angular_velocity": [0.0, -math.pi, 0.0],
            "distance": 0.01,
            **box,
        }
    ]
    return case


@pytest.mark.parametrize("dt", [1e-2, 1e-3])
def test_a_turning_bar_sweeps_through_a_hanging_net_without_any_node_inside(dt):
    parsed = parse_case(sweep_case(dt))
    scene = build(parsed)
    (bar,) = scene.terms
    assert isinstance(bar, Moving)
    probe = Moving(bar.shape, bar.origin, bar.velocity, bar.omega, reach=bar.reach)
    gaps, lift = [], []

    def check(s):
        probe.set_pose(s.time)  # the bar where it is at this step's end, independently
        gaps.append(float(probe.gap(s.x).min()))
        lift.append(float(s.x[:, 2].max()))

    r = solve(scene, Settings.of(parsed.solver), on_step=check)
    assert r.converged and r.time == pytest.approx(0.5)
    assert len(gaps) >= 0.5 / dt
    assert min(gaps) > 0.0  # no node inside, at any accepted step
    assert min(gaps) < bar.dhat  # and the bar did press on the net
    assert max(lift) > 0.03  # which it lifted


def test_a_support_in_the_obstacles_way_stops_the_run_with_a_clear_message(tmp_path):
    """A small box rising under a support: exit 1, the message names obstacle and node,
    and the steps before are in the result file."""
    from click.testing import CliRunner

    from catenet.cli import main
    from catenet.output.reader import read_result

    case = sweep_case(1e-2, t_end=0.5)
    scene = build(parse_case(case))
    node = int(np.flatnonzero(scene.net.fixed)[3])
    p = scene.net.nodes[node]
    case["obstacle"] = [
        {
            "kind": "box",
            "center": [p[0], p[1], -0.2],
            "half_size": [0.02, 0.02, 0.02],
            "velocity": [0.0, 0.0, 1.0],
            "distance": 0.005,
        }
    ]
    with pytest.raises(
        ConvergenceError, match=rf"obstacle\[0\] \(kind 'box'\) reaches support node {node}"
    ):
        parsed = parse_case(case)
        solve(build(parsed), Settings.of(parsed.solver))
    file = tmp_path / "case.toml"
    case["output"] = {"file": str(tmp_path / "out.h5")}
    file.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(file), "-q"])
    assert res.exit_code == 1, res.output
    assert f"reaches support node {node}" in res.output
    times = read_result(tmp_path / "out.h5").times
    assert 0.1 < times[-1] < 0.2  # it reaches z = 0 after 0.18 s


@pytest.mark.parametrize(
    "change, message",
    [
        ({"velocity": [0.0, math.nan, 1.0]}, "obstacle[0].velocity"),
        ({"angular_velocity": [0.0, 1.0]}, "obstacle[0].angular_velocity"),
        ({"angular_velocity": "fast"}, "obstacle[0].angular_velocity"),
        ({"history": [[1.0, 1.0], [0.5, 2.0]]}, "obstacle[0].history"),
        (
            {"angular_velocity": None, "history": [[0.0, 1.0]]},
            "obstacle[0].history: scales a prescribed motion",
        ),
        (
            {"method": "static"},
            "obstacle[0].angular_velocity = [0.0, -3.14159",
        ),
    ],
)
def test_bad_motions_exit_2_with_their_key_path(tmp_path, change, message):
    from click.testing import CliRunner

    from catenet.cli import main

    case = sweep_case(1e-2)
    box = case["obstacle"][0]
    for key, value in change.items():
        if key == "method":
            case["solver"] = {"method": "static", "steps": 2}
        elif value is None:
            box.pop(key)
        else:
            box[key] = value
    text = dumps_toml(case)
    if "nan" in str(change):
        text = text.replace("NaN", "nan")
    file = tmp_path / "case.toml"
    file.write_text(text)
    res = CliRunner().invoke(main, ["run", str(file), "-q"])
    assert res.exit_code == 2, res.output
    assert message in res.output


@pytest.mark.parametrize("kind", ["capsule", "mesh"])
def test_a_moving_capsule_or_mesh_takes_the_same_keys(kind, tmp_path):
    """Translating up into the net for 0.1 s: the run finishes with every node outside."""
    import meshio

    case = sweep_case(1e-2, t_end=0.1)
    if kind == "capsule":
        obs = {"kind": "capsule", "start": [-0.2, 0, -0.2], "end": [0.2, 0, -0.2], "radius": 0.1}
    else:
        meshio.write_points_cells(tmp_path / "cube.stl", CUBE_V * 0.3, [("triangle", CUBE_T)])
        obs = {"kind": "mesh", "file": str(tmp_path / "cube.stl"), "offset": [-0.15, -0.15, -0.4]}
    case["obstacle"] = [{**obs, "velocity": [0, 0, 1.2], "angular_velocity": [0, 0, 2.0]}]
    parsed = parse_case(case)
    scene = build(parsed)
    (term,) = scene.terms
    probe = Moving(term.shape, term.origin, term.velocity, term.omega, reach=term.reach)
    gaps = []

    def check(s):
        probe.set_pose(s.time)
        gaps.append(float(probe.gap(s.x).min()))

    r = solve(scene, Settings.of(parsed.solver), on_step=check)
    assert r.converged and 0.0 < min(gaps) < term.dhat


@pytest.mark.parametrize("dt", [1e-5, 1e-3, 1e-1])
def test_the_capture_scene_with_a_tumbling_box_keeps_every_node_outside(dt):
    """The capture scene of tests/terms/test_shapes.py (the box 3 mm below the net's middle),
    the box tumbling at 1.6 rad/s: at every step size every accepted state is finite,
    outside the box where it is at that time, and the net touches it."""
    from contact_cases import capture_near

    data = capture_near(dt)
    data["obstacle"][0]["angular_velocity"] = [0.8, -0.6, 1.2]
    parsed = parse_case(data)
    scene = build(parsed)
    (box,) = scene.terms
    probe = Moving(box.shape, box.origin, box.velocity, box.omega, reach=box.reach)
    gaps = []

    def check(s):
        assert np.all(np.isfinite(s.x)) and np.all(np.isfinite(s.v))
        probe.set_pose(s.time)
        gaps.append(float(probe.gap(s.x).min()))

    r = solve(scene, Settings.of(parsed.solver), on_step=check)
    assert r.converged and len(gaps) >= 2
    assert 0.0 < min(gaps) < box.dhat


def test_a_support_passed_over_within_one_step_is_found():
    """A thin plate rising 0.5 m in one step passes a support at z = 0 that neither
    its start nor its end pose covers: the sweep finds it, at t = 0.19 / 10 s; a support
    beside its way is left alone."""
    plate = BoxBarrier(np.array([0]), [0, 0, -0.2], [0.1, 0.1, 0.01], None, kappa=1.0, dhat=1e-3)
    term = Moving(plate, [0, 0, -0.2], [0, 0, 10.0], reach=0.15, label="obstacle[3] (kind 'box')")
    x = np.array([[2.0, 0, 0], [0.05, 0.0, 0.0]])
    beside = np.array([[2.0, 0, 0], [0.3, 0.0, 0.0]])
    assert term.carry(beside.copy(), beside.copy(), 0.0, 0.05, np.array([False, True])) == 0
    with pytest.raises(
        ConvergenceError, match=r"obstacle\[3\] \(kind 'box'\) reaches support"
    ) as e:
        term.carry(x.copy(), x.copy(), 0.0, 0.05, np.array([False, True]))
    assert "node 1 at [0.05, 0, 0] at t = 0.019 s" in str(e.value)
