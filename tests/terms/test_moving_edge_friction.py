"""Friction along the edges of an obstacle on a prescribed motion (``EdgeFriction`` on a
``MovingEdges``): finite differences at a turned and moved pose, the lagged anchors and
normals carried with the obstacle, and the closed form of a bar dragged by a plate.

The bar: one edge of 2 m (steel, radius 5 mm: m = 1.225 kg, W = m g = 12.02 N) lying
across a plate 0.4 m wide, its nodes far off the plate (so only the edge touches it, at
the plate's two top edges), each node held by a spring k = 100 N/m along y. The plate
moves along y: Coulomb friction mu N, N = W, drags the bar. Below mu W / (2 k) = 18 mm
of the plate's travel the bar sticks and follows it (to the slip distance); beyond, it
slides: while the plate moves on, the friction on the bar is mu N exactly, and when the
plate stops the bar rests where the springs' pull 2 k y is at most mu W."""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from test_edge_contact import BOX, _term

from catenet.cli import main
from catenet.terms import check_derivatives
from catenet.terms.moving_edges import MovingEdges
from catenet.terms.segments import EdgeFriction

MU, K, SLIP = 0.3, 100.0, 1e-4
WEIGHT = 7800.0 * np.pi * 0.005**2 * 2.0 * 9.81  # N

BAR = """
title = "a bar dragged by a plate"

[geometry]
kind = "graph"
nodes = [[-1.0, 0.0, 0.0075], [1.0, 0.0, 0.0075]]
edges = [[0, 1]]
fixed = []

[material]
E = 2e11
radius = 0.005
density = 7800.0

[[supports.spring]]
nodes = [0, 1]
stiffness = [0.0, 100.0, 0.0]

[[obstacle]]
kind = "box"
center = [0.0, 0.0, -0.05]
half_size = [0.2, 0.2, 0.05]
velocity = [0.0, 1.0, 0.0]
friction = 0.3
slip = 1e-4
distance = 0.005

[load]
gravity = [0.0, 0.0, -9.81]

[solver]
method = "dynamic"
dt = 0.005
t_end = 2.0
edge_contact = true
"""


def _drag(tmp_path, speed: float, moving: float) -> dict:
    """The bar's run: the plate at rest for 0.3 s (the bar settles on it), then moving
    at ``speed`` [m/s] for ``moving`` s (ramped over 0.1 s at both ends: it travels
    speed x moving)."""
    data = tomllib.loads(BAR)
    plate = data["obstacle"][0]
    plate["velocity"] = [0.0, speed, 0.0]
    end = 0.3 + moving
    plate["history"] = [[0.0, 0.0], [0.3, 0.0], [0.4, 1.0], [end, 1.0], [end + 0.1, 0.0]]
    from catenet.case import dumps_toml

    case = tmp_path / "bar.toml"
    case.write_text(dumps_toml(data))
    out = tmp_path / "bar.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        energy = f["trajectory/energy"][:]
        return {
            "x": f["trajectory/x"][:],
            "time": f["history/time"][:],
            "contact": f["history/contact"][:, 0],
            "energy": dict(zip(f["trajectory/energy"].attrs["columns"], energy.T, strict=True)),
        }


def test_friction_on_a_moving_obstacle_passes_finite_differences():
    """At a turned and moved pose, within a step: sticking and sliding."""
    x = np.array([[-0.1, 0.35, 0.12], [0.2, 0.05, 0.13], [5.0, 5.0, 5.0]])
    moving = MovingEdges(_term(BOX, x), np.zeros(3), [0.3, -0.2, 0.5], [0.4, 1.1, -0.7], reach=1.0)
    world = moving.world(x)
    moving.begin_step(world, 0.0)
    friction = EdgeFriction(moving, mu=0.5, slip=1e-3)
    friction.begin_step(world, 0.05, 0.0)  # the obstacle moves on over the step
    assert len(friction.pairs) == 1
    at_end = moving.rigid(world, 0.0, 0.05)  # the edge carried with the obstacle
    for move in (2e-4, 5e-3):
        y = at_end + move * np.array([[1.0, 0.3, 0.0], [0.5, -0.2, 0.1], [0.0, 0.0, 0.0]])
        assert friction.energy(y) > 0.0
        assert max(check_derivatives(friction, y, step=1e-8)) < 1e-6
    # carried with the obstacle, the edge has not slid: its anchor is where it is
    assert friction.energy(at_end) < 1e-12 * friction.weight.max() * 1e-3


def test_the_anchors_ride_with_the_obstacle():
    """A pair that sticks keeps its anchor on the obstacle's surface: after the step,
    the anchor is the step's start anchor moved rigidly with the obstacle."""
    x = np.array([[-0.1, 0.35, 0.12], [0.2, 0.05, 0.13], [5.0, 5.0, 5.0]])
    moving = MovingEdges(_term(BOX, x), np.zeros(3), [0.3, -0.2, 0.5], [0.4, 1.1, -0.7], reach=1.0)
    world = moving.world(x)
    moving.begin_step(world, 0.0)
    friction = EdgeFriction(moving, mu=0.5, slip=1e-3)
    friction.begin_step(world, 0.0, 0.0)
    start = friction.anchor.copy()
    friction.begin_step(world, 0.05, 0.0)
    assert np.allclose(friction.anchor, moving.rigid(start, 0.0, 0.05), atol=1e-14)
    c0, R0 = moving.pose(0.0)
    c1, R1 = moving.pose(0.05)
    assert np.allclose(moving.center, c1) and np.allclose(moving.R, R1)


def test_a_bar_sticks_to_a_plate_that_moves_less_than_mu_w_over_2k(tmp_path):
    """Plate travel 10 mm < mu W / (2 k) = 18 mm: the bar goes along to within the slip
    distance, the friction 2 k y below mu W; the plate's work is booked, what friction
    dissipates (the slip distance's creep) is small and never negative."""
    run = _drag(tmp_path, speed=0.05, moving=0.2)  # travels 0.05 x 0.2 = 10 mm
    travel = 0.01
    assert MU * WEIGHT / (2 * K) > 1.5 * travel
    y = run["x"][-1, :, 1]
    assert np.allclose(y, travel, atol=5 * SLIP)
    friction = run["contact"][-1]
    assert friction[2] == pytest.approx(WEIGHT, rel=1e-6)  # N: the bar's weight
    assert friction[1] == pytest.approx(2 * K * y[0], rel=1e-6) and friction[1] < MU * WEIGHT
    e = run["energy"]
    assert e["external_work"][-1] > 0.0 and e["dissipated"].min() >= -1e-12
    assert e["dissipated"][-1] < 0.1 * e["external_work"][-1]


def test_a_bar_slides_on_a_plate_at_mu_n(tmp_path):
    """Plate travel 90 mm: the bar sticks until the springs pull mu W, then slides: while
    the plate moves on at constant speed, the friction on the bar is mu N (N its weight)
    to 1e-6; at rest again the springs' pull 2 k y is within mu W. The plate's work is
    what friction dissipated and the springs hold, to the integrator's own loss."""
    run = _drag(tmp_path, speed=0.1, moving=0.8)
    t, contact = run["time"], run["contact"]
    steady = (t > 0.7) & (t < 1.1)
    ratio = contact[steady, 1] / contact[steady, 2]
    assert np.allclose(ratio, MU, rtol=1e-6)
    assert np.allclose(contact[steady, 2], WEIGHT, rtol=1e-6)
    y = run["x"][-1, :, 1]
    assert 0.0 < 2 * K * y[0] <= MU * WEIGHT * (1 + 1e-6)
    e = run["energy"]
    work, lost = e["external_work"][-1], e["dissipated"][-1]
    assert lost > 0.5 * MU * WEIGHT * (0.09 - 0.03) and e["dissipated"].min() >= -1e-12
    held = (
        e["kinetic"][-1]
        + e["elastic"][-1]
        + e["contact"][-1]
        - (e["kinetic"][0] + e["elastic"][0] + e["contact"][0])
    )
    assert abs(held - work + lost) < 0.02 * work
