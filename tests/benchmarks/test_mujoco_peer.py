"""The MuJoCo comparison (benchmarks/peers/mujoco_capture.py): its shared logic without
MuJoCo (the stiffness mapping, the box's geometry, the step search, the model's text),
catenet's side on a tiny scene, and MuJoCo's side where MuJoCo is installed."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from benchmarks.peers import mujoco_capture as mc
from benchmarks.peers import mujoco_net as mn
from benchmarks.peers import mujoco_scene as ms

THROW = """
title = "a net with four corner masses thrown at a spinning box"

[geometry]
kind = "graph"
nodes = [
  [-0.3, -0.3, 0.4], [0.0, -0.3, 0.4], [0.3, -0.3, 0.4],
  [-0.3,  0.0, 0.4], [0.0,  0.0, 0.4], [0.3,  0.0, 0.4],
  [-0.3,  0.3, 0.4], [0.0,  0.3, 0.4], [0.3,  0.3, 0.4],
]
edges = [[0, 1], [1, 2], [3, 4], [4, 5], [6, 7], [7, 8],
         [0, 3], [3, 6], [1, 4], [4, 7], [2, 5], [5, 8]]

[geometry.sets]
corners = [0, 2, 6, 8]
inner = [1, 3, 4, 5, 7]

[material]
E = 2e9
radius = 0.001
density = 1000.0

[[mass]]
node = "corners"
mass = 0.5
velocity = [0.0, 0.0, -3.0]

[[mass]]
node = "inner"
mass = 0.01
velocity = [0.0, 0.0, -3.0]

[[obstacle]]
kind = "box"
center = [0.0, 0.0, 0.0]
half_size = [0.2, 0.15, 0.1]
angle = 0.4
mass = 5.0
angular_velocity = [0.0, 0.0, 1.0]
distance = 0.005

[solver]
method = "dynamic"
dt = 0.005
damping = 0.0
t_end = 0.2
"""


@pytest.mark.parametrize("EA, rest", [(3141.6, 0.0417), (1.26e6, 2.5), (10.0, 1e-3)])
def test_the_tendon_carries_catenets_edge_law(EA, rest):
    t = ms.tendon(EA, rest)
    assert t["stiffness"] == pytest.approx(EA / rest) and t["springlength"] == (0.0, rest)
    for length in np.linspace(0.0, 2.0 * rest, 41):
        assert ms.tendon_force(EA, rest, length) == pytest.approx(
            ms.edge_force(EA, rest, length), rel=1e-12, abs=1e-12 * EA
        )
    assert ms.tendon_force(EA, rest, 0.5 * rest) == 0.0  # slack, as catenet's edge
    with pytest.raises(ValueError, match="must be > 0"):
        ms.tendon(EA, 0.0)


def test_the_tendon_law_matches_catenets_own_tension():
    """A cable pulled by F at its free end: catenet's tension and length; the tendon of
    the mapping pulls with F at that length."""
    import catenet as cn

    mat = cn.Material.from_E(2e9, radius=0.001, density=0.0)
    cable = cn.cable(start=[0, 0, 0], end=[1.0, 0, 0], nodes=3, material=mat)
    force = np.zeros((3, 3))
    force[-1, 0] = 150.0
    free_end = cn.Net.from_arrays(
        cable.nodes, cable.edges, fixed=[True, False, False], EA=cable.EA,
        rest_length=cable.rest_length,
    )  # fmt: skip
    r = cn.solve_static(free_end, cn.Loads(force=force), rtol=1e-12)
    for e, (a, b) in enumerate(free_end.edges):
        length = float(np.linalg.norm(r.x[b] - r.x[a]))
        F = ms.tendon_force(free_end.EA[e], free_end.rest_length[e], length)
        assert F == pytest.approx(r.tension[e], rel=1e-9) and F == pytest.approx(150.0, rel=1e-8)


def test_box_distance_and_penetration_in_a_turned_box():
    c = np.array([1.0, -2.0, 0.5])
    R = ms.rotation([math.cos(0.3), 0.0, 0.0, math.sin(0.3)])  # 0.6 rad about z
    half = np.array([0.5, 0.2, 0.1])
    local = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.15], [0.6, 0.0, 0.0], [0.45, 0.1, 0.0]])
    pts = c + local @ R.T
    d = ms.box_distance(pts, c, R, half)
    assert d == pytest.approx([-0.1, 0.05, 0.1, -0.05])
    assert ms.penetration(pts[1:3], c, R, half) == 0.0
    assert ms.penetration(pts[1:3], c, R, half, radius=0.08) == pytest.approx(0.03)
    assert ms.penetration(pts, c, R, half) == pytest.approx(0.1)
    assert ms.rotation(ms.quaternion(R)) == pytest.approx(R)
    assert np.sum(ms.box_inertia(12.0, [0.15, 0.1, 0.05])) == pytest.approx(0.28)


def _threshold_run(dt_star: float, p_ok, calls: list):
    """A stub integrator: exact momentum up to dt_star, blown up above it."""

    def run(dt: float) -> ms.Outcome:
        calls.append(dt)
        if dt <= dt_star:
            return ms.Outcome(True, np.asarray(p_ok, float))
        return ms.Outcome(False, np.full(3, np.nan))

    return run


@pytest.mark.parametrize("dt_star, start", [(0.0123, 1e-3), (0.0123, 0.05), (7e-5, 1e-3)])
def test_the_step_search_brackets_a_known_stable_step(dt_star, start):
    calls: list = []
    b = ms.largest_stable_step(
        _threshold_run(dt_star, [1.0, 0.0, 0.0], calls), [1.0, 0.0, 0.0], 0.01,
        start=start, cap=1.0, ratio=1.1, floor=1e-6,
    )  # fmt: skip
    assert b.stable <= dt_star < b.unstable and b.unstable / b.stable <= 1.1
    assert [dt for dt, _ in b.tried] == calls


def test_the_step_search_stops_at_the_cap_and_refuses_a_hopeless_run():
    b = ms.largest_stable_step(
        _threshold_run(10.0, [0, 0, 1], []), [0, 0, 1], 0.01, start=0.01, cap=0.1
    )
    assert b.stable == 0.1 and b.unstable == math.inf
    with pytest.raises(ValueError, match="no stable step"):
        ms.largest_stable_step(
            _threshold_run(1e-9, [0, 0, 1], []), [0, 0, 1], 0.01, start=0.01, cap=1.0,
            floor=1e-4,
        )  # fmt: skip


def test_the_step_search_on_a_real_integrator_finds_its_stability_limit():
    """Symplectic Euler on a spring-mass (omega = 10 rad/s) is stable for dt < 2 / omega
    (its amplitude stays below omega x0 / sqrt(1 - (omega dt / 2)^2)) and blows up
    above; with a tolerance that passes any bounded answer, the search finds 0.2 s."""
    omega, m = 10.0, 2.0

    def run(dt: float) -> ms.Outcome:
        x, v = 1.0, 0.0
        for _ in range(int(round(20.0 / dt))):
            v -= dt * omega**2 * x
            x += dt * v
        finite = math.isfinite(v) and abs(v) < 1e3 * omega
        return ms.Outcome(finite, np.array([0.0, 0.0, m * v if finite else math.nan]))

    b = ms.largest_stable_step(
        run, [0.0, 0.0, 0.0], 1e3, start=1e-3, cap=1.0, scale=m * omega, ratio=1.02
    )
    assert b.stable < 2.0 / omega < b.unstable
    assert b.unstable / b.stable <= 1.02


def test_extrapolation_removes_the_first_order_error():
    """Implicit Euler on v' = -v: the extrapolated v(1) from h and h / 2 is far closer."""

    def v_end(h):
        return (1.0 / (1.0 + h)) ** round(1.0 / h)

    exact = math.exp(-1.0)
    coarse, fine = v_end(0.01), v_end(0.005)
    assert abs(ms.extrapolate(coarse, fine) - exact) < 0.02 * abs(fine - exact)
    assert ms.momentum_scale([[0, 0, 1], [3, 4, 0], [0, 0, -2]]) == 5.0
    assert ms.momentum_error([3, 4, 1], [3, 4, 0], scale=10.0) == pytest.approx(0.1)


@pytest.fixture(scope="module")
def throw(tmp_path_factory):
    path = tmp_path_factory.mktemp("mujoco") / "throw.toml"
    path.write_text(THROW)
    return path


def test_the_scene_handed_to_mujoco_is_catenets_net_and_box(throw):
    samples = mc._samples(0.2, 4)
    case, scene = mc.build(throw)
    spec = mc.scene_arrays(case, scene, samples)
    body = scene.rigid[0]
    n = int(body.frame.nodes[0])
    assert len(spec["nodes"]) == n == 9 and len(spec["edges"]) == 12
    assert sum(spec["mass"]) == pytest.approx(float(scene.net.mass[:n].sum()))
    assert sum(spec["mass"]) + spec["box"]["mass"] == pytest.approx(float(scene.net.mass.sum()))
    assert spec["box"]["inertia"] == pytest.approx(np.diag(ms.box_inertia(5.0, [0.2, 0.15, 0.1])))
    axes = np.asarray(spec["box"]["axes"])
    assert axes[:, 0] == pytest.approx([math.cos(0.4), math.sin(0.4), 0.0])
    root = ET.fromstring(mn.mjcf(spec, "discrete", "Newton", 1e-3, 0, 1e-3))
    assert root.find("option").get("integrator") == "discrete"
    tendons = root.findall("tendon/spatial")
    assert len(tendons) == 12
    EA, rest = np.asarray(spec["EA"]), np.asarray(spec["rest_length"])
    k = [float(t.get("stiffness")) for t in tendons]
    assert k == pytest.approx(EA / rest, rel=1e-15)
    assert [float(t.get("springlength").split()[1]) for t in tendons] == pytest.approx(rest)
    bodies = root.findall("worldbody/body")
    masses = [float(b.find("inertial").get("mass")) for b in bodies[:-1]]
    assert masses == pytest.approx(spec["mass"], rel=1e-15)
    box = bodies[-1].find("geom")
    assert box.get("type") == "box" and box.get("condim") == "1"  # frictionless, as catenet
    assert box.get("solref") == "0.001 1"


def test_catenets_side_keeps_momentum_before_contact_and_never_penetrates(throw):
    samples = mc._samples(0.2, 8)
    res = mc.catenet_side(throw, (), 0.005, samples)
    assert res["finite"] and res["time"][-1] == pytest.approx(0.2)
    assert np.all(np.asarray(res["time"]) >= np.asarray(samples) - 1e-9)
    assert res["penetration"] == 0.0
    total = np.asarray(res["total_momentum"])
    scale = 4 * 0.5 * 3.0  # the corner masses' momentum
    # no gravity, no supports: the whole system's momentum is kept, contact or not
    assert np.abs(total - total[0]).max() < 1e-6 * scale
    assert total[0] == pytest.approx([0, 0, -3.0 * float(np.sum(mc.build(throw)[1].net.mass[:9]))])
    p, L = np.asarray(res["momentum"]), np.asarray(res["angular_momentum"])
    first = res["first_contact"]  # the first step with a node within the barrier's reach
    assert 0.0 < first < 0.2 and min(res["gap"]) < 0.005
    before = np.asarray(res["time"]) < first
    assert before[0] and not before.all()
    assert np.abs(p[before]).max() < 1e-9 * scale  # the box only spins until then
    # its spin about a principal axis: kept but for implicit Euler's damping of the
    # rotation, below (omega dt)^2 a step (omega = 1 rad/s)
    Iz = ms.box_inertia(5.0, [0.2, 0.15, 0.1])[2]
    drift = 0.005**2 * np.asarray(res["time"])[before] / 0.005
    assert np.abs(L[before][:, :2]).max() < 1e-9 * Iz
    assert np.all(np.abs(L[before][:, 2] / Iz - 1.0) < drift)
    assert np.abs(p[-1]).max() > 1e-3 * scale  # and takes momentum from the net after


def test_mujocos_side_keeps_momentum_and_meets_the_box(throw, tmp_path):
    pytest.importorskip("mujoco")
    samples = mc._samples(0.2, 8)
    case, scene = mc.build(throw)
    spec = mc.scene_arrays(case, scene, samples)
    run = mn.Run(spec, "discrete", "Newton", 1e-3, 0, 1e-3)
    out = run.go(samples)
    assert out["finite"] and len(out["momentum"]) == len(samples)
    p = np.asarray(out["momentum"])
    assert np.abs(p[0]).max() < 1e-9  # before contact the box only spins
    Iz = ms.box_inertia(5.0, [0.2, 0.15, 0.1])[2]
    assert out["angular_momentum"][0] == pytest.approx([0.0, 0.0, Iz], rel=1e-6, abs=1e-9)
    assert np.abs(p[-1]).max() > 1e-3


def test_the_scenes_may_be_written_one_at_a_time(tmp_path):
    import csv

    mc.write([{"scene": "capture", "tool": "catenet", "stable_dt": 0.25}], tmp_path)
    mc.write(
        [{"scene": "drop", "tool": "catenet", "steps": 10, "tried_stable": [[1, 2]]}], tmp_path
    )
    mc.write([{"scene": "drop", "tool": "MuJoCo discrete", "steps": 4000}], tmp_path)
    with open(tmp_path / "peers-mujoco.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["scene"], r["tool"]) for r in rows] == [
        ("drop", "MuJoCo discrete"),
        ("capture", "catenet"),
    ]
    assert rows[0]["steps"] == "4000" and rows[1]["stable_dt"] == "0.25"
    assert "tried_stable" not in rows[0]
