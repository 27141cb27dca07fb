"""Nodes that slide along one moving obstacle while another carries them
(``catenet.terms.pinch``): where every motion translates, the first contact over a step is
the shape's own along each node's straight path (``_straight_hit``), not conservative
advancement, which crept on by the small gap of a sliding node over the motions' largest
speed and, after MAX_ADVANCES, reported a contact that never comes (a false pinch, or
minutes of checking: a rope pressed against a stopped blade by the belt that slides under
it took 61 577 such evaluations in 0.6 s). And the nodes of a rope that a blade pushes
round its corner are re-carried together where one alone cannot be."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.terms import pinch
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier
from tests.terms import test_moving_stays as belt_cases
from tests.terms import test_pinch as pinch_cases

DT = 0.01


def _box(center, half, velocity, label):
    """A translating box's node barrier over the node 0."""
    shape = BoxBarrier(np.array([0]), center, half, kappa=1.0, dhat=1e-3)
    return Moving(shape, center, velocity, reach=float(np.linalg.norm(half)), label=label)


def _first_hit(x, carrier_v, blade_v, straight: bool, monkeypatch):
    """``_first_hit`` of a blade (0.1 x 0.002 x 0.1 m, velocity ``blade_v``) on the node x
    that a box far below (group 0, velocity ``carrier_v``) carries, over one step."""
    belt = _box([0.0, 0.0, -1.0], [1.0, 1.0, 0.5], carrier_v, "belt")
    blade = _box([0.0, 0.0, 0.0], [0.05, 0.001, 0.05], blade_v, "blade")
    movers = [belt, blade]
    weights = np.array([[1.0, 0.0]])
    if not straight:
        monkeypatch.setattr(pinch, "_translating", lambda *a: False)
    sweeps = np.array([m.sweep(0.0, DT) for m in movers])
    group = np.array([0, 1])
    watch = {1: np.array([0])}
    return pinch._first_hit(movers, group, sweeps, watch, np.array([x]), weights, 0.0, DT)


def _least_gap(x, carrier_v, blade_v) -> float:
    """The node's least gap to the blade over the step, on 2001 instants."""
    s = np.linspace(0.0, 1.0, 2001)[:, None]
    rel = np.asarray(x) + s * DT * (np.asarray(carrier_v) - np.asarray(blade_v))
    outside = np.maximum(np.abs(rel) - [0.05, 0.001, 0.05], 0.0)
    inside = np.minimum(np.max(np.abs(rel) - [0.05, 0.001, 0.05], axis=1), 0.0)
    return float(np.min(np.linalg.norm(outside, axis=1) + inside))


def test_a_node_sliding_along_a_blade_at_a_small_gap_is_not_reported_as_reached(monkeypatch):
    """The node 1 um off the blade's face, carried along it at 0.1 m/s while the blade
    runs along at 0.5 m/s: the gap never changes. The straight paths see that; conservative
    advancement crept along by 1 um over 6 mm per step and, after MAX_ADVANCES, called it
    a contact."""
    x = [0.0, 0.001 + 1e-6, 0.0]
    assert _first_hit(x, [0.1, 0, 0], [0.5, 0, 0], True, monkeypatch) is None
    assert _first_hit(x, [0.1, 0, 0], [0.5, 0, 0], False, monkeypatch) is not None


def test_the_straight_paths_find_what_advancement_finds(monkeypatch):
    """On 300 random nodes and motions (each clear of grazing: its least gap over the step
    at least 1e-6 m from zero), the first contact by the straight paths and by conservative
    advancement agree on whether the blade reaches the node."""
    rng = np.random.default_rng(7)
    cases = 0
    while cases < 300:
        x = rng.uniform([-0.08, -0.03, -0.08], [0.08, 0.03, 0.08])
        carrier_v, blade_v = rng.normal(0.0, 1.0, 3), rng.normal(0.0, 1.0, 3)
        if np.all(np.abs(x) < [0.05, 0.001, 0.05]):
            continue  # starts inside the blade
        least = _least_gap(x, carrier_v, blade_v)
        if abs(least) < 1e-6 or _least_gap(x, 0 * carrier_v, 0 * blade_v) > 0.02:
            continue  # grazing, or beyond the blade's watch
        with monkeypatch.context() as m:
            slow = _first_hit(x, carrier_v, blade_v, False, m)
        fast = _first_hit(x, carrier_v, blade_v, True, monkeypatch)
        assert (fast is None) == (slow is None) == (least > 0.0), (x, carrier_v, blade_v)
        cases += 1


# the rope, belt and blade of tests/terms/test_pinch.py, the blade's history and the
# run's end left to each test
BELT_AND_BLADE = pinch_cases.BELT_AND_BLADE.replace(
    "history = [[0.0, 0.0], [0.05, 1.0], [0.2, 1.0]]", "history = HISTORY"
).replace("t_end = 0.12", "t_end = T_END")
assert "HISTORY" in BELT_AND_BLADE and "T_END" in BELT_AND_BLADE

STOPS = "[[0.0, 0.0], [0.05, 1.0], [0.12, 1.0], [0.15, 0.0], [0.6, 0.0]]"


def _wrapped_tension(face: float, radius: float = 0.005) -> float:
    """The hand tension of the rope (EA, rest length from its 100 N prestress) from its
    fixed end (-0.3, 0) round the blade's corner (-0.05, face) on a circle of the rope's
    radius, then along the blade's face to the middle (by symmetry, half of it)."""
    EA = 1e9 * math.pi * 0.005**2
    rest = 0.3 / (1.0 + 100.0 / EA)
    corner, end = np.array([-0.05, face]), np.array([-0.3, 0.0])
    d = float(np.linalg.norm(corner - end))
    tangent = math.sqrt(d * d - radius * radius)
    heading = math.atan2(*(corner - end)[::-1]) - math.asin(radius / d)
    touch = end + tangent * np.array([math.cos(heading), math.sin(heading)])
    turn = abs(math.atan2(*(touch - corner)[::-1]) + math.pi / 2)
    return EA * ((tangent + radius * turn + 0.05) / rest - 1.0)


def test_a_rope_pressed_against_a_stopped_blade_by_a_sliding_belt(tmp_path, monkeypatch):
    """The blade pushes the rope 39 mm along the belt and stops; the belt slides on under
    the rope and presses it against the blade (the stall's case). The rope wraps the
    blade's corners with the hand tension, no node enters the blade, and the check takes
    a few hundred point evaluations where conservative advancement took tens of thousands."""
    calls = {"carried": 0}
    carried = pinch._carried

    def counted(*args, **kwargs):
        calls["carried"] += 1
        return carried(*args, **kwargs)

    monkeypatch.setattr(pinch, "_carried", counted)
    case = tmp_path / "belt.toml"
    case.write_text(BELT_AND_BLADE.replace("HISTORY", STOPS).replace("T_END", "0.3"))
    out = tmp_path / "r.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        x = f["result/x"][()]
        tension = float(np.max(f["result/tension"][()]))
    face = 0.05 - 0.75 * (0.025 + 0.07 + 0.015) - 0.001  # the blade's travel, its face
    blade = np.abs(x[:, :2] - [0.0, face + 0.001]) - [0.05, 0.001]  # from its middle
    assert np.linalg.norm(np.maximum(blade, 0.0), axis=1).min() > 0.005  # the rope's radius
    assert tension == pytest.approx(_wrapped_tension(face), rel=5e-3)  # 873.3 N
    assert calls["carried"] < 2_000


def test_the_rope_at_the_blades_corner_is_re_carried_with_its_neighbour(tmp_path):
    """The blade keeps pushing the rope along the belt: at t = 0.187 s the node at its
    corner could be carried by no blend of belt and blade alone (riding with the blade, it
    bent the edge to the next node, carried more slowly, into the blade), and the run
    stopped with a pinch that was none. Both nodes now ride with the blade together."""
    case = tmp_path / "belt.toml"
    history = "[[0.0, 0.0], [0.05, 1.0], [0.2, 1.0]]"
    case.write_text(BELT_AND_BLADE.replace("HISTORY", history).replace("T_END", "0.19"))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 0, done.output
    assert "converged    yes" in done.output


def test_a_blade_meeting_a_rope_between_its_nodes_keeps_every_edge_out(tmp_path):
    """The rope with 0.1 m edges: the blade (0.1 m wide) meets the edges at its middle node
    and its corners between nodes. Re-carried alone, the middle node rode with the blade
    and bent both edges beside it into the blade's corners (2 mm deep at the step's end;
    the run then stalled at t = 0.085 s); with its neighbours carried by the same blend
    the run goes on, and no point of any edge comes within the rope's radius of the blade
    at any step."""
    case = tmp_path / "belt.toml"
    history = "[[0.0, 0.0], [0.05, 1.0], [0.2, 1.0]]"
    text = BELT_AND_BLADE.replace("HISTORY", history).replace("T_END", "0.12")
    case.write_text(text.replace("edge_length = 0.05", "edge_length = 0.1"))
    out = tmp_path / "r.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        frames, times = f["trajectory/x"][()], f["trajectory/time"][()]
        edges = f["mesh/edges"][()]
    assert times[-1] == pytest.approx(0.12)
    travel = np.where(times < 0.05, times**2 / 0.1, 0.025 + (times - 0.05))  # the history's
    centre = np.stack([0 * times, 0.05 - 0.75 * travel, 0 * times + 0.053], axis=1)
    u = np.linspace(0.0, 1.0, 41)[None, None, :, None]  # 41 points along every edge
    a, b = frames[:, edges[:, 0], None], frames[:, edges[:, 1], None]
    local = np.abs(a + u * (b - a) - centre[:, None, None, :]) - [0.05, 0.001, 0.05]
    distance = np.linalg.norm(np.maximum(local, 0.0), axis=-1) + np.minimum(local.max(axis=-1), 0.0)
    assert distance.min() > 0.005  # the rope's radius, at every step


# the wire rope on the belt of tests/terms/test_moving_stays.py, and a paddle 20 mm thick,
# 0.3 m wide, 1 mm above the belt, pushing it across
PADDLE = belt_cases.BELT.replace(
    "[solver]",
    """[[obstacle]]
kind = "box"
center = [0.0, 0.03, 0.051]
half_size = [0.15, 0.01, 0.05]
velocity = [0.0, -0.2, 0.0]

[solver]""",
).replace("t_end = 0.2", "t_end = 0.15")


def test_a_paddle_pushing_a_rope_across_a_belt_re_carries_every_node_in_front_of_it(
    tmp_path,
):
    """A wire rope on a belt running along it, pushed sideways by a paddle 0.3 m wide.
    Before, the belt carried every node along at each step's start, so some eight nodes
    and edges in front of the paddle needed re-carrying in one step, beyond the check's 16
    rounds: a pinch that was none, the step halved until the run gave up at t = 0.21 s.
    Now the belt leaves the rope in place (its path along the belt's face is clear:
    ``Moving.stays``) and the check's rounds grow with the items it watches. It runs on,
    no point of an edge inside the paddle."""
    case = tmp_path / "paddle.toml"
    case.write_text(PADDLE)
    out = tmp_path / "r.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        frames, times = f["trajectory/x"][()], f["trajectory/time"][()]
        edges = f["mesh/edges"][()]
    centre = np.stack([0 * times, 0.03 - 0.2 * times, 0 * times + 0.051], axis=1)
    u = np.linspace(0.0, 1.0, 41)[None, None, :, None]
    a, b = frames[:, edges[:, 0], None], frames[:, edges[:, 1], None]
    local = np.abs(a + u * (b - a) - centre[:, None, None, :]) - [0.15, 0.01, 0.05]
    distance = np.linalg.norm(np.maximum(local, 0.0), axis=-1) + np.minimum(local.max(axis=-1), 0.0)
    assert distance.min() > 0.003  # the rope's radius, at every step
    assert frames[-1][:, 1].min() < -0.012  # pushed a rope radius beyond the face at -0.01


JAWS_AT_A_STEPS_END = """
[geometry]
kind = "cable"
start = [-0.5, 0.0, 0.0]
end = [0.5, 0.0, 0.0]
nodes = 51

[material]
EA = 5.0e4
radius = 0.003
density = 1140.0
prestress = 30.0

[[obstacle]]
kind = "box"
center = [0.0, 0.0, -0.03]
half_size = [0.05, 0.1, 0.02]
velocity = [0.0, 0.0, 0.1]

[[obstacle]]
kind = "box"
center = [0.0, 0.0, 0.03]
half_size = [0.05, 0.1, 0.02]
velocity = [0.0, 0.0, -0.1]

[solver]
method = "dynamic"
integrator = "bdf2"
dt = 0.005
t_end = 0.1
edge_contact = true
"""


def test_jaws_that_close_on_the_rope_exactly_at_a_steps_end_stop_with_the_pinch(tmp_path):
    """Two jaws closing at 0.1 m/s each on a 6 mm cord meet its surface at t = 0.07 s, a
    step's end at 5 ms steps: the straight paths' first contact is then at the step's end,
    which counts as reached. Taken as clear, the step was accepted with the cord at zero
    gap (its barrier energy infinite) and the run ended "refusing to write a non-finite
    state"; it stops with the pinch, naming both jaws and the node."""
    case = tmp_path / "jaws.toml"
    case.write_text(JAWS_AT_A_STEPS_END)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 1, done.output
    assert "pinch the node" in done.output and "non-finite" not in done.output
    assert "obstacle[0]" in done.output and "obstacle[1]" in done.output
