"""The edges' barrier (solver.edge_contact) against obstacles on a prescribed motion
(``catenet.terms.moving_edges``): finite differences at a turned and moved pose, its
equivalence with the fixed outline at that pose (gaps, energy, forces, first contact);
a plate swept into the middle of a long edge whose nodes are far from it, every step
checked at 41 points along every edge (none ever inside; with the nodes alone the plate
cuts through the edge), the obstacle's work in the energy balance, turning and moving;
an edge held at a support that the obstacle runs over stops the run; friction along the
edges rides on the obstacle's motion."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from click.testing import CliRunner
from test_edge_contact import CASES, _term

from catenet.case import build, parse_case
from catenet.cli import main
from catenet.errors import ConvergenceError
from catenet.solver import path as sv
from catenet.terms import check_derivatives
from catenet.terms.moving_edges import MovingEdges

V = np.array([0.3, -0.2, 0.5])
W = np.array([0.4, 1.1, -0.7])


def _moving(case: str, t: float = 0.8):
    """(the edge barrier of ``case`` on the motion (V, W) at time t, the same points in
    the body frame and in the world)."""
    shape, ends = CASES[case]
    body = np.array([*ends, [5.0, 5.0, 5.0]], dtype=np.float64)
    inner = _term(shape, body)
    term = MovingEdges(inner, np.zeros(3), V, W, reach=1.0)
    term.begin_step(np.zeros_like(body), t)
    return term, inner, body, term.world(body)


@pytest.mark.parametrize("case", ["box across an edge", "capsule", "cube mesh"])
def test_the_moving_edge_barrier_passes_finite_differences(case):
    term, inner, body, x = _moving(case)
    assert np.linalg.norm(term.center) > 0.4 and abs(np.trace(term.R) - 3.0) > 0.5
    assert term.gap(x) == pytest.approx(inner.gap(body), abs=1e-12)
    assert 0.0 < term.gap(x)[0] < inner.dhat
    g_err, h_err = check_derivatives(term, x, step=1e-7)
    assert g_err < 1e-6 and h_err < 1e-5, (g_err, h_err)


def test_the_moving_barrier_is_the_fixed_one_turned_and_moved():
    """Energy equal, forces turned by R, and the first contact of a motion the same as
    the fixed outline's of that motion turned back into its frame."""
    term, inner, body, x = _moving("box across an edge")
    g, g_b = np.zeros_like(x), np.zeros_like(x)
    assert term.gradient(x, g) == pytest.approx(inner.gradient(body, g_b), rel=1e-12)
    assert np.allclose(g, g_b @ term.R.T, atol=1e-12 * np.abs(g).max())
    dx = np.zeros_like(x)
    dx[:2] = (np.array([0.0, 0.0, -1.0]) @ term.R.T) * 0.2  # down onto the box's edge
    first = term.max_step(x, dx)
    assert 0.0 < first < 1.0
    assert first == pytest.approx(inner.max_step(body, dx @ term.R), rel=1e-12)


SWEEP = """
title = "a plate swept into the middle of a long edge"

[geometry]
kind = "graph"
nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]]
edges = [[0, 1], [1, 2], [2, 3]]
fixed = [0, 3]

[material]
E = 1e9
radius = 0.005
density = 7800.0
prestress = 200.0

[[obstacle]]
kind = "box"
center = [1.5, -0.3, 0.0]
half_size = [0.02, 0.1, 0.3]
velocity = [0.0, 1.0, 0.0]
angular_velocity = SPIN
distance = 0.005

[solver]
method = "dynamic"
dt = DT
t_end = 0.4
edge_contact = EDGES
"""
ALONG = np.linspace(0.0, 1.0, 41)[:, None, None]


def _sweep(edges=True, spin=(0.0, 0.0, 0.0), dt=0.005, ramp=False):
    """The sweep's scene, its states and times at every step and its Result; ``ramp``:
    the plate starts 0.12 m off the edge, its speed ramped from 0 to 1 m/s over 0.4 s
    (no impact), to t = 0.5 s."""
    text = SWEEP.replace("EDGES", str(edges).lower()).replace("DT", str(dt))
    data = tomllib.loads(text.replace("SPIN", str(list(spin))))
    if ramp:
        data["obstacle"][0]["center"] = [1.5, -0.12, 0.0]
        data["obstacle"][0]["history"] = [[0.0, 0.0], [0.4, 1.0]]
        data["solver"]["t_end"] = 0.5
    scene = build(parse_case(data))
    frames, times = [scene.net.nodes.copy()], [0.0]

    def keep(step):
        frames.append(step.x.copy())
        times.append(step.time)

    result = sv.solve(scene, sv.Settings.of(scene.case.solver), on_step=keep)
    assert result.converged, result.message
    return scene, np.array(frames), np.array(times), result


def _depths(scene, frames, times, spin) -> np.ndarray:
    """Per step, the least signed distance of 41 points along every edge to the plate at
    its pose then (negative: inside)."""
    from catenet.terms.moving import rotation_vector

    edges = scene.net.edges
    w = np.asarray(spin, dtype=float)
    half = np.array([0.02, 0.1, 0.3])
    out = []
    for x, t in zip(frames, times, strict=True):
        c = np.array([1.5, -0.3 + t, 0.0])
        R = rotation_vector(w, float(np.linalg.norm(w)) * t)
        p = ((1.0 - ALONG) * x[edges[:, 0]] + ALONG * x[edges[:, 1]] - c) @ R
        e = np.abs(p) - half
        outside = np.linalg.norm(np.maximum(e, 0.0), axis=-1)
        out.append(np.where(outside > 0.0, outside, e.max(axis=-1)).min())
    return np.array(out)


@pytest.mark.parametrize("spin", [(0.0, 0.0, 0.0), (0.0, 0.0, 1.5)])
def test_a_plate_swept_into_a_long_edge_never_has_a_point_of_it_inside(spin):
    """The plate meets the edge 1-2 in its middle, 0.5 m from either node, and pushes it
    0.1 m on: at every step every point of every edge stays the contact radius (5 mm)
    off the plate, and touches it; the obstacle's work is booked (the balance's
    remainder a small share of it: implicit Euler's loss in the plate's impact at 1 m/s,
    whatever the step)."""
    scene, frames, times, result = _sweep(True, spin)
    assert any(isinstance(t, MovingEdges) for t in scene.terms)
    depth = _depths(scene, frames, times, spin)
    assert depth.min() > 0.005 and depth.min() < 0.005 + 0.005
    assert np.abs(frames[-1][1:3, 1]).max() > 0.05  # the edge was pushed along
    kinetic, elastic, contact, work, lost, numerical = result.energy
    assert work > 10.0 and abs(kinetic + elastic + contact - work + lost) < 0.02 * work
    assert abs(numerical) < 0.02 * work


def test_with_the_nodes_alone_the_plate_cuts_through_the_edge():
    scene, frames, times, _ = _sweep(False)
    assert _depths(scene, frames, times, (0.0, 0.0, 0.0)).min() < -0.01


def test_the_obstacles_work_converges_with_the_step():
    """The plate's speed ramped up from rest (no impact): the obstacle's work (106 J)
    balances the net's energy to 1.4e-3 of it at dt = 0.01 s, and the remainder falls
    as the step is halved (implicit Euler's own loss)."""
    energy = [_sweep(True, dt=dt, ramp=True)[3].energy for dt in (0.01, 0.005)]
    work, rest = energy[0][3], [abs(e[-1]) for e in energy]
    assert work > 100.0 and rest[0] < 2e-3 * work
    assert rest[1] < 0.6 * rest[0], rest


def test_an_edge_at_a_support_in_the_obstacles_way_stops_the_run():
    text = SWEEP.replace("EDGES", "true").replace("DT", "0.005").replace("SPIN", "[0.0, 0.0, 0.0]")
    data = tomllib.loads(text)
    data["obstacle"][0]["center"] = [0.06, -0.3, 0.0]
    data["obstacle"][0]["velocity"] = [0.0, 3.0, 0.0]
    scene = build(parse_case(data))
    with pytest.raises(ConvergenceError, match="reaches the edge 0-1, held at a support"):
        sv.solve(scene, sv.Settings.of(scene.case.solver))


HELD = """
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [4.0, 0.0, 0.0]
nodes = 2
[material]
E = 1e9
radius = 0.005
density = 1000.0
[supports]
fixed = ["start", "end"]
[[obstacle]]
kind = "capsule"
start = [1.5, -1.0, 0.3]
end = [1.5, 1.0, 0.3]
radius = 0.05
velocity = [0.0, 0.0, -0.5]
[solver]
method = "dynamic"
dt = 0.01
t_end = 1.0
edge_contact = true
"""


def test_an_edge_with_both_nodes_fixed_in_the_obstacles_way_stops_the_run(tmp_path):
    """A user's model from the edge-contact guide: a bar pushed down onto the middle of a
    single edge between two supports (no free node, so no barrier of the edge) passed
    through it and the run ended "converged". The obstacle reaches the edge's capsule at
    0.3 - 0.5 t = 0.05 + 0.005: t = 0.49 s: the run stops there, naming it."""
    case = tmp_path / "held.toml"
    case.write_text(HELD)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 1, done.output
    assert "reaches the edge 0-1, held at a support, at t = 0.49 s" in done.output


def test_friction_along_the_edges_of_a_moving_obstacle_rides_on_its_motion():
    """(Refused before.) The friction along the edges rides on the moving barrier; the
    bar dragged by a plate in test_moving_edge_friction.py checks it against Coulomb."""
    from catenet.terms.segments import EdgeFriction

    text = SWEEP.replace("EDGES", "true").replace("DT", "0.005").replace("SPIN", "[0.0, 0.0, 0.0]")
    data = tomllib.loads(text.replace("distance = 0.005", "distance = 0.005\nfriction = 0.3"))
    scene = build(parse_case(data))
    rubs = [t for t in scene.terms if isinstance(t, EdgeFriction)]
    assert len(rubs) == 1 and isinstance(rubs[0].rides_on, MovingEdges)


THIN = HELD.replace(
    """kind = "capsule"
start = [1.5, -1.0, 0.3]
end = [1.5, 1.0, 0.3]
radius = 0.05
velocity = [0.0, 0.0, -0.5]""",
    """kind = "box"
center = [1.5, 0.0, 0.31]
half_size = [0.2, 0.5, 0.002]
velocity = [0.0, 0.0, -1.0]""",
).replace("dt = 0.01", "dt = 0.02")


def test_a_plate_thinner_than_its_travel_per_step_does_not_pass_a_held_edge(tmp_path):
    """A plate 4 mm thick (14 mm with the edge's contact radius on both sides) moving
    20 mm per step: its step ends are at z = 10 mm above and 10 mm below the edge, so a
    check at the steps' ends alone saw it pass. Swept over the step, the plate's lower
    edges reach the edge's capsule at z_c - 2 mm = 5 mm: t = (0.31 - 0.007) / 1 m/s =
    0.303 s, inside the step from 0.3 to 0.32 s."""
    assert "dt = 0.02" in THIN and "half_size = [0.2, 0.5, 0.002]" in THIN
    case = tmp_path / "thin.toml"
    case.write_text(THIN)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 1, done.output
    assert "reaches the edge 0-1, held at a support, at t = 0.303 s" in done.output


ONE_HELD = THIN.replace("nodes = 2", "nodes = 3").replace(
    "center = [1.5, 0.0, 0.31]", "center = [0.3, 0.0, 0.3075]"
)


def test_a_thin_plate_does_not_pass_an_edge_at_a_support_within_a_step(tmp_path):
    """The same plate over the edge 0-1 of a cable of two edges (node 0 fixed, node 1
    free, 2 m away), 0.5 mm above the edge's capsule at t = 0.3 s. Its free node rides
    with the plate through the step, its fixed node stays, so the edge turns about node
    0 and the plate moves through it by 15-19 mm, more than its 14 mm: at the step's
    end the edge was clear on the far side and the run went on with the edge through
    the plate. Swept, the plate reaches it at once: t = 0.3005 s."""
    case = tmp_path / "one.toml"
    case.write_text(ONE_HELD)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 1, done.output
    assert "reaches the edge 0-1, held at a support, at t = 0.3005" in done.output
