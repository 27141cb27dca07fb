"""Several free rigid bodies in one case, and free bodies beside fixed obstacles and
balls (catenet.case.rigid, catenet.case.clearance): two bodies dropped into one net
come to rest at the static equilibrium with both; two bodies and a free net in zero
gravity keep their momentum; a run stops (exit 1, the steps before kept) at the step
where a body meets the ground or another body, exactly for a box against a plane and
for two spheres (over the path between two steps, not only at its ends); bodies that
start overlapping are refused (exit 2)."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.case.clearance import BodiesMeet
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.solver.path import Settings, solve
from catenet.terms.rigid_contact import BodyContact


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


def ground_case(x: float) -> dict:
    """A pinned net (1 m) above the ground at z = -0.15, a 40 kg box thrown down at
    3 m/s from its bottom at z = 0.25, at x (beside the net when x > 0.75)."""
    return {
        "geometry": {
            "kind": "square_net", "n": 6, "alpha": math.pi / 4, "size": 1.0,
            "edge_length": 0.05,
        },
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [
            {"kind": "plane", "point": [0.0, 0.0, -0.15], "normal": [0.0, 0.0, 1.0]},
            {"kind": "box", "center": [x, 0.0, 0.3], "half_size": [0.15, 0.15, 0.05],
             "mass": 40.0, "velocity": [0.0, 0.0, -3.0], "distance": 0.005},
        ],
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.3},
    }  # fmt: skip


def test_a_box_that_would_go_through_the_ground_stops_the_run(tmp_path):
    """Beside the net the box falls freely: its bottom, 0.4 m above the ground, reaches
    it at t* = (sqrt(9 + 2 g 0.4) - 3) / g; the run stops at the first step past t*
    (exit 1, the message naming both), the file holding every step before, all above
    the ground. Over the net the same box is caught and the run ends normally."""
    g = 9.81
    t_star = (math.sqrt(9 + 2 * g * 0.4) - 3) / g
    res, out = run_cli(tmp_path, ground_case(1.2), "beside")
    assert res.exit_code == 1, res.output
    assert "obstacle[1] (a free box) meets obstacle[0] (plane) (they touch)" in res.output
    with h5py.File(out) as f:
        t = f["trajectory/time"][()]
        centre = f["trajectory/obstacles/1/center"][()]
    assert t[-1] < t_star + 1e-3 < t[-1] + 0.01 + 2e-3
    assert np.all(centre[:, 2] - 0.05 > -0.15)
    res, _ = run_cli(tmp_path, ground_case(0.0), "over")
    assert res.exit_code == 0, res.output


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
def test_two_spheres_that_meet_stop_the_run_at_that_step(tmp_path, dt):
    """They touch when their centres are 0.1 apart: at t = 0.15. With dt = 0.01 the run
    stops at the step where they overlap; with dt = 0.3 they would be through each other
    after one step (0.2 past), and the check over the centres' path between the steps
    still stops it there. 0.12 apart across, they pass: the run goes to its end."""
    res, out = run_cli(tmp_path, spheres_case(0.0, dt), "meet")
    assert res.exit_code == 1, res.output
    assert "obstacle[0] (a free sphere) meets obstacle[1] (a free sphere)" in res.output
    when = float(res.output.split("at t = ")[1].split(" s")[0])
    assert 0.15 <= when < 0.15 + dt + 1e-9
    scene = build(parse_case(spheres_case(0.12, dt)))
    assert solve(scene, Settings.of(scene.case.solver)).converged


def test_a_static_run_stops_where_a_body_meets_the_ceiling():
    """A static run: a 10 kg box on a net that 800 N at its centre push up into a ceiling
    (a plane facing down, 0.1 m above the box): the equilibrium of net and box has the
    box through it (the net's nodes stay below): BodiesMeet, the start kept as the last
    good state."""
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
            {"kind": "plane", "point": [0.0, 0.0, 0.2], "normal": [0.0, 0.0, -1.0]},
            {"kind": "box", "center": [0.0, 0.0, 0.052], "half_size": [0.15, 0.15, 0.05],
             "mass": 10.0, "distance": 0.005},
        ],
        "solver": {"method": "static"},
    }  # fmt: skip
    scene = build(parse_case(case))
    with pytest.raises(BodiesMeet, match=r"at load factor 1: obstacle\[1\] \(a free box\)") as e:
        solve(scene, Settings.of(scene.case.solver))
    assert e.value.last_good.time == 0.0


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
    with pytest.raises(
        ConfigError,
        match=r"obstacle\[1\] \(a free box\): it meets obstacle\[0\] \(plane\) at the start",
    ):
        build(parse_case(case))


def test_a_free_body_beside_a_moving_box_is_refused():
    case = ground_case(1.2)
    case["obstacle"][0] = {
        "kind": "box", "center": [0.0, 0.0, -0.5], "half_size": [0.1, 0.1, 0.1],
        "velocity": [0.0, 0.0, 0.1],
    }  # fmt: skip
    with pytest.raises(ConfigError, match=r"obstacle\[0\] \(kind 'box'\): an obstacle on a"):
        build(parse_case(case))
