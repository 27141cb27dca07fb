"""Moving rigid spheres: a ball whose centre is a node of the net (two-way coupled through
the barrier contact, integrated in the same implicit step), and a ball on a prescribed
path. Finite differences of the pair term, exact first contact of the relative motion,
momentum exchanged honestly (net + ball change by the impulse of the loads and the
supports' reactions, step by step), rest at the static equilibrium of net + ball weight,
no node ever inside a ball, and bad input."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from contact_cases import G, catch_case

from catenet.case import build, parse_case
from catenet.solver.path import Settings, solve
from catenet.terms import Stretch, check_derivatives
from catenet.terms.body import Ball, Guide, Path


def ball_of(scene) -> Ball:
    (ball,) = [t for t in scene.terms if isinstance(t, Ball)]
    return ball


def around(rng, c, radius, n, lo=0.002, hi=0.07):
    u = rng.standard_normal((n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    return c + u * (radius + rng.uniform(lo, hi, n))[:, None]


def test_ball_contact_passes_finite_differences_in_the_net_and_the_centre():
    rng = np.random.default_rng(7)
    c = np.array([0.1, -0.2, 0.3])
    x = np.vstack([around(rng, c, 0.5, 6), [[2.0, 2.0, 2.0]], c])  # node 6: far, no contact
    ball = Ball(np.arange(7), 7, 0.5, kappa=30.0, dhat=0.05, n_nodes=8)
    gap = ball.gap(x)
    assert np.all(gap > 0) and (gap < 0.05).sum() >= 3 and gap[6] > 0.05
    grad_err, hess_err = check_derivatives(ball, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5
    # Action equals reaction: the contact forces on the net and on the ball cancel.
    g = np.zeros_like(x)
    ball.gradient(x, g)
    assert np.abs(g[7]).max() > 0 and np.abs(g.sum(axis=0)).max() < 1e-12 * np.abs(g).max()


def test_guide_spring_passes_finite_differences_and_follows_its_path():
    from catenet.model.histories import History

    path = Path([0, 0, 1], [2.0, 0, 0], History([[0, 1], [1, 1], [2, 0]]))
    assert path(0.5) == pytest.approx([1.0, 0, 1])
    assert path(2.0) == pytest.approx([2 * 1.5, 0, 1])  # 1 s at full speed, 1 s ramping down
    assert path(5.0) == pytest.approx(path(2.0))
    guide = Guide(1, path, 1e3, n_nodes=2)
    guide.begin_step(None, 0.5)
    x = np.array([[0.0, 0, 0], [0.9, 0.1, 1.05]])
    grad_err, hess_err = check_derivatives(guide, x)
    assert grad_err < 1e-7 and hess_err < 1e-9
    assert guide.lag(x) == pytest.approx(math.sqrt(0.01 + 0.01 + 0.0025))
    guide.begin_step(x, None)  # a static load step keeps the anchor
    assert guide.anchor == pytest.approx([1.0, 0, 1])


def test_first_contact_of_the_relative_motion_is_exact():
    ball = Ball(np.arange(1), 1, 1.0, kappa=1.0, dhat=0.1, n_nodes=2)
    x = np.array([[3.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    dx = np.array([[-2.0, 0.0, 0.0], [4.0, 0.0, 0.0]])  # closing at 6 m per unit step
    assert ball.max_step(x, dx) == pytest.approx(2.0 / 6.0)
    assert ball.max_step(x, -dx) == math.inf  # moving apart
    assert ball.max_step(x, np.array([[1.0, 0, 0], [1.0, 0, 0]])) == math.inf  # together
    # A glancing pass: the node misses the ball.
    x[0, 1] = 1.2  # passes 1.2 m from the centre of a ball of radius 1
    assert ball.max_step(x, np.array([[-6.0, 0, 0], [0, 0, 0]])) == math.inf


def test_the_scene_appends_the_ball_as_a_node_with_its_mass_and_velocity():
    scene = build(parse_case(catch_case()))
    net = scene.net
    assert net.bodies == 1 and net.n_net == net.n_nodes - 1
    c = net.n_nodes - 1
    assert np.array_equal(net.nodes[c], [0, 0, 0.3]) and not net.fixed[c]
    assert net.mass[c] == pytest.approx(10.0)
    assert np.array_equal(scene.velocity[c], [0, 0, -1.0]) and not scene.velocity[:c].any()
    f = scene.loads.external_force(net)
    assert f[c] == pytest.approx([0, 0, -10.0 * 9.81])  # its weight, through load.gravity
    (body,) = scene.bodies
    assert (body.node, body.obstacle, body.radius, body.mass, body.prescribed) == (
        c,
        0,
        0.15,
        10.0,
        False,
    )
    ball = ball_of(scene)
    assert ball.center == c and c not in ball.nodes and not net.fixed[ball.nodes].any()


def test_an_undamped_drop_exchanges_momentum_honestly_and_no_node_enters_the_ball():
    """mu = 0: net + ball change momentum, every step, by exactly the impulse of gravity
    and of the supports' reactions (the barrier is internal: its forces on net and ball
    cancel); in free flight the ball falls as m dv = m g h; no node is ever inside."""
    case = catch_case(coarse=True)
    case["obstacle"][0]["velocity"] = [0.4, -0.2, -1.0]  # a slanted throw: every direction
    scene = build(parse_case(case))
    net = scene.net
    ball = ball_of(scene)
    stretch = Stretch(net)
    free = ~net.fixed
    c = net.n_nodes - 1
    m = net.mass[:, None]
    weight = scene.loads.external_force(net)[free].sum(axis=0)
    last = {"t": 0.0, "p": (m * scene.velocity)[free].sum(axis=0), "v": scene.velocity[c]}
    worst, gaps, touched, flights, held = [0.0], [], [False], [], []

    def on_step(s):
        h = s.time - last["t"]
        g = np.zeros_like(s.x)
        stretch.gradient(s.x, g)
        reaction = g[net.fixed].sum(axis=0)  # the supports' force on the net
        p = (m * s.v)[free].sum(axis=0)
        impulse = h * (weight + reaction)
        worst[0] = max(worst[0], float(np.abs(p - last["p"] - impulse).max()))
        held.append(h * reaction)
        gap = ball.gap(s.x)
        gaps.append(float(gap.min()))
        if gap.min() >= ball.dhat and not touched[0]:  # free flight
            flights.append(float(np.abs(s.v[c] - last["v"] - h * np.array(G)).max()))
        touched[0] |= bool(gap.min() < ball.dhat)
        last.update(t=s.time, p=p, v=s.v[c].copy())

    r = solve(scene, Settings.of(scene.case.solver), on_step=on_step)
    assert r.converged and touched[0] and flights
    assert min(gaps) > 0.0
    scale = 10.0 * 1.0  # the ball's initial momentum [kg m/s]
    assert worst[0] < 1e-7 * scale
    assert np.abs(np.sum(held, axis=0)).max() > 0.5 * scale  # the supports did take a share
    assert max(flights) < 1e-9
    assert abs(r.x[c, 0]) > 0.01  # the slanted throw carried it sideways


def test_a_damped_drop_rests_at_the_static_equilibrium_of_net_and_ball_weight():
    case = catch_case(damping=4.0, dt=0.02, t_end=20.0)
    scene = build(parse_case(case))
    r = solve(scene, Settings.of(scene.case.solver))
    assert r.converged and r.equilibrium
    ball = ball_of(scene)
    assert 0.0 < ball.gap(r.x).min() < ball.dhat
    # The static solve: the ball placed just above the flat net (inside the barrier's
    # reach), free under its weight, found by Newton's load steps from there.
    static = copy.deepcopy(case)
    static["solver"] = {"method": "static"}
    static["obstacle"][0].pop("velocity")
    static["obstacle"][0]["center"] = [0.0, 0.0, 0.152]
    s_scene = build(parse_case(static))
    rs = solve(s_scene, Settings.of(s_scene.case.solver))
    assert rs.converged
    c = scene.net.n_nodes - 1
    assert np.abs(rs.x - r.x).max() < 1e-6
    assert rs.x[c, 2] < 0.152 - 0.05  # the ball sank into the net
    # Balance: the supports carry the net's and the ball's weight.
    load = s_scene.loads.external_force(s_scene.net).sum(axis=0)
    assert np.abs(rs.reaction.sum(axis=0) + load).max() < 1e-6 * np.abs(load).max()


@pytest.mark.parametrize("dt", [0.1, 0.02, 0.004])
def test_a_ball_on_a_prescribed_path_pushes_into_the_net_and_never_swallows_a_node(dt):
    """A ball driven up through the net's plane at 0.5 m/s (stopping at t = 0.4 s): the
    net is pushed up and wraps it; at every step size every node stays outside, and the
    ball keeps to its path within force / k."""
    case = catch_case(coarse=True, dt=dt, damping=5.0, t_end=0.6)
    case["load"] = {"gravity": G}
    case["obstacle"] = [
        {
            "kind": "sphere",
            "center": [0.05, 0.0, -0.2],
            "radius": 0.15,
            "velocity": [0.0, 0.0, 1.0],
            "history": [[0.0, 0.5], [0.4, 0.5], [0.4001, 0.0]],
            "distance": 0.005,
        }
    ]
    scene = build(parse_case(case))
    ball = ball_of(scene)
    (guide,) = [t for t in scene.terms if isinstance(t, Guide)]
    (body,) = scene.bodies
    assert body.prescribed
    gaps, lags = [], []

    def on_step(s):
        gaps.append(float(ball.gap(s.x).min()))
        lags.append(guide.lag(s.x))

    r = solve(scene, Settings.of(scene.case.solver), on_step=on_step)
    assert r.converged
    assert min(gaps) > 0.0
    c = scene.net.n_nodes - 1
    end = guide.path(1.0)
    assert end == pytest.approx([0.05, 0.0, -0.2 + 0.5 * 0.4 + 0.5 * 0.5 * 1e-4])
    assert np.abs(r.x[c] - end).max() < 1e-3
    assert max(lags) < 1e-3
    probe = scene.probe
    assert r.x[probe, 2] > 0.05 - 0.01  # the net's centre was lifted onto the ball's cap
    assert ball.gap(r.x).min() < ball.dhat


@pytest.mark.parametrize(
    "change, message",
    [
        ({"mass": -1.0}, "obstacle[0].mass = -1.0: must be finite and > 0"),
        ({"center": [0.0, 0.0, 0.1]}, "obstacle[0] (kind 'sphere'): node"),
        ({"history": [[0, 1]], "velocity": None}, "obstacle[0].history: scales the velocity"),
        ({"mass": None, "solver": "static"}, "moves in dynamic runs only"),
        ({"solver": "static"}, "obstacle[0].velocity = [0.0, 0.0, -1.0]: a free ball's"),
        ({"kind": "plane", "point": [0, 0, -1]}, "obstacle[0].mass"),
    ],
)
def test_bad_moving_spheres_exit_2_with_their_key_path(tmp_path, change, message):
    from click.testing import CliRunner

    from catenet.case import dumps_toml
    from catenet.cli import main

    case = catch_case()
    obs = case["obstacle"][0]
    if change.pop("solver", None):
        case["solver"] = {"method": "static"}
    if change.get("kind") == "plane":
        for k in ("center", "radius", "velocity"):
            obs.pop(k)
    for k, v in change.items():
        if v is None:
            obs.pop(k, None)
        else:
            obs[k] = v
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert not (tmp_path / "out.h5").exists()


def test_the_catch_example_runs_short_and_writes_the_ball_for_paraview_and_plot(tmp_path):
    """configs/contact/sphere_catch.toml, short (the full run is in test_contact): the
    result file names the ball (/mesh/bodies) and its centre's trajectory reads back, the
    XDMF sidecar has a "bodies" block beside the net's, and ``catenet plot`` draws it."""
    from pathlib import Path

    import meshio
    from click.testing import CliRunner

    from catenet.cli import main
    from catenet.output import read_bodies, read_result

    config = Path(__file__).parents[2] / "configs" / "contact" / "sphere_catch.toml"
    out = tmp_path / "catch.h5"
    args = ["run", str(config), "-o", str(out), "--set", "solver.t_end=0.5"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    b = read_bodies(out)
    assert len(b) == 1 and b.radius.tolist() == [0.15] and b.mass.tolist() == [10.0]
    assert not b.prescribed[0]
    r = read_result(out)
    c = int(b.node[0])
    assert c == r.mesh.nodes.shape[0] - 1 and not r.mesh.fixed[c]
    assert b.center.shape == (len(b.times), 1, 3) and b.times[-1] == pytest.approx(0.5)
    assert b.center[0, 0] == pytest.approx([0, 0, 0.65])
    assert np.array_equal(b.final[0], r.x[c])
    # It fell freely until the net caught it (mu damps the net only): implicit Euler's
    # z_k = z_0 - g h^2 k (k + 1) / 2 with h = 0.02 s, to round-off.
    k = int(np.searchsorted(b.times, 0.2))
    assert k == 10 and b.times[k] == pytest.approx(0.2)
    assert b.center[k, 0, 2] == pytest.approx(0.65 - 9.81 * 0.02**2 * k * (k + 1) / 2, abs=1e-12)
    assert b.center[-1, 0, 2] < 0.2 and b.velocity[-1, 0, 2] > b.velocity[:, 0, 2].min() + 1.0
    nodes = r.mesh.nodes.shape[0] - 1
    assert (np.linalg.norm(r.x[:nodes] - r.x[c], axis=1) > 0.15).all()
    # ParaView: a Polyvertex "bodies" collection; meshio reads the net's (the last one).
    text = out.with_suffix(".xdmf").read_text()
    assert 'Name="bodies"' in text and 'TopologyType="Polyvertex"' in text
    with meshio.xdmf.TimeSeriesReader(out.with_suffix(".xdmf")) as reader:
        points, cells = reader.read_points_cells()
        assert cells[0].type == "line" and len(points) == nodes + 1
    from catenet.output.repair import write_sidecar_for

    out.with_suffix(".xdmf").unlink()
    write_sidecar_for(out)  # catenet repair's sidecar names the ball too
    assert 'Name="bodies"' in out.with_suffix(".xdmf").read_text()
    # catenet export: the ball a vertex cell with its radius.
    res = CliRunner().invoke(main, ["export", str(out), "--to", "vtu", "--frames", "last"])
    assert res.exit_code == 0, res.output
    (vtu,) = (tmp_path / "catch-vtu").glob("*.vtu")
    m = meshio.read(vtu)
    assert [c.type for c in m.cells] == ["line", "vertex"]
    assert m.cells[1].data.tolist() == [[c]] and m.cell_data["radius"][1].tolist() == [0.15]
    png = tmp_path / "catch.png"
    res = CliRunner().invoke(main, ["plot", str(out), "-o", str(png)])
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 10_000


def test_a_net_without_bodies_reads_back_none(tmp_path):
    from catenet.output import read_bodies
    from catenet.run.runner import run_case

    case = catch_case(t_end=0.02)
    case.pop("obstacle")
    out = tmp_path / "net.h5"
    run_case(parse_case(case), out)
    b = read_bodies(out)
    assert len(b) == 0 and b.final is None


def test_balls_stop_at_the_ground_at_fixed_spheres_and_at_each_other():
    """Beside the net: ball A falls onto the ground plane and ball B onto A; ball C onto
    a fixed sphere. Every step keeps surfaces apart (the plane moved out by the radius,
    the sphere grown by it, two balls at the sum of their radii), and each touches."""
    case = catch_case(coarse=True, dt=0.01, damping=5.0, t_end=0.6)
    ball = {"kind": "sphere", "radius": 0.1, "mass": 1.0, "distance": 0.005}
    case["obstacle"] = [
        {"kind": "plane", "point": [0, 0, -0.3], "distance": 0.005},
        {**ball, "center": [2.0, 0.0, 0.0]},  # A: 0.2 m above the ground
        {**ball, "center": [2.0, 0.0, 0.4]},  # B: above A
        {"kind": "sphere", "center": [-2.0, 0.0, 0.0], "radius": 0.2, "distance": 0.005},
        {**ball, "center": [-2.0, 0.0, 0.5]},  # C: above the fixed sphere
    ]
    scene = build(parse_case(case))
    a, b, c = (body.node for body in scene.bodies)
    assert [body.obstacle for body in scene.bodies] == [1, 2, 4]
    gaps = []

    def on_step(s):
        x = s.x
        gaps.append(
            (
                x[a, 2] - 0.1 + 0.3,  # A above the ground
                x[b, 2] - 0.1 + 0.3,  # B above the ground
                np.linalg.norm(x[b] - x[a]) - 0.2,  # B on A
                np.linalg.norm(x[c] - [-2.0, 0, 0]) - 0.3,  # C on the fixed sphere
            )
        )

    r = solve(scene, Settings.of(scene.case.solver), on_step=on_step)
    assert r.converged
    gaps = np.array(gaps)
    assert gaps.min() > 0.0
    assert (gaps.min(axis=0)[[0, 2, 3]] < 0.005).all()  # each came within the barrier


def test_a_ball_no_longer_passes_through_a_box(caplog):
    """Boxes, capsules and meshes stop a ball too (tests/terms/test_ball_shapes.py): no more
    "does not collide" warning, a barrier on the ball's centre instead."""
    case = catch_case(coarse=True)
    case["obstacle"].append(
        {"kind": "box", "center": [3.0, 0.0, 0.0], "half_size": [0.1, 0.1, 0.1]}
    )
    with caplog.at_level("WARNING"):
        scene = build(parse_case(case))
    assert "does not collide" not in caplog.text
    c = scene.net.n_nodes - 1
    assert [type(t).__name__ for t in scene.terms if list(t.nodes) == [c]] == ["BoxBarrier"]


def test_a_ball_that_starts_on_the_ground_is_refused():
    from catenet.errors import ConfigError

    case = catch_case(coarse=True)
    case["obstacle"][0]["center"] = [2.0, 0.0, 0.0]
    case["obstacle"].append({"kind": "plane", "point": [0, 0, -0.1]})
    with pytest.raises(ConfigError, match=r"obstacle\[0\] \(kind 'sphere'\): starts inside"):
        build(parse_case(case))
