"""Strands inside solids (``catenet.run.crossings``): with contact at the nodes only, the
run warns where the edges between the nodes cut into an obstacle, a ball or a free body,
how deep (never deeper than they are: measured at points of the edges), when, and in how
many steps; also where a solid passes between the nodes within one step. No warning where
every edge meets the solids (``solver.edge_contact``), nor for a net draped on a sphere
whose chords dip by the polyhedron's own sagitta."""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, load_case
from catenet.cli import main
from catenet.run.crossings import DEEP, EdgeWatch

CONFIGS = Path(__file__).parents[2] / "configs" / "contact"


def along(n: int) -> np.ndarray:
    return np.linspace(0.0, 1.0, n)[:, None, None]


CUT = re.compile(r"edges cut ([0-9.e+-]+) m deep into (obstacle\[\d+\] \([^)]*\))")


def run(path, tmp_path, *sets):
    out = tmp_path / "o.h5"
    args = ["run", str(path), "-o", str(out)]
    for s in sets:
        args += ["--set", s]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    with h5py.File(out, "r") as f:
        kept = str(f["/result"].attrs["warnings"])
    return res.output, kept, out


def points(edges, x, n: int = 41):
    """(n, M, 3) points along every edge."""
    u = along(n)
    return (1.0 - u) * x[edges[:, 0]] + u * x[edges[:, 1]]


def box_depth(points_, center, axes, half) -> np.ndarray:
    """How deep each point lies in a box (its centre, axes as columns, half sizes)."""
    X = (points_ - center) @ axes
    e = np.abs(X) - half
    outside = np.linalg.norm(np.maximum(e, 0.0), axis=-1)
    return -np.where(outside > 0.0, outside, e.max(axis=-1))


CAPTURE = [
    "solver.dt=0.01", "solver.t_end=0.4", "obstacle.0.center=[0.0, 0.0, 2.97]",
]  # fmt: skip


def test_a_capture_with_node_contact_warns_how_deep_its_strands_cut_the_box(tmp_path):
    """The capture of configs/contact/ (its tumbling box moved under the net): the
    strands cut into the box between the nodes it holds off. The warning's depth is
    that of points of the edges (so never more than the deepest of 1001 points along
    every edge in the written steps, with the box's pose from its nodes, and within 5 %
    of it: the steps between are measured too); with edge contact nothing is warned."""
    case = CONFIGS / "envisat_capture.toml"
    printed, kept, out = run(case, tmp_path, *CAPTURE, "solver.edge_contact=false")
    ((depth, label),) = CUT.findall(printed)
    assert label == "obstacle[0] (a free box)"
    assert "solver.edge_contact = true" in printed and "edges cut" in kept
    scene = build(load_case(case, CAPTURE))
    (body,) = scene.rigid
    shape = scene.movers[0].shape
    edges = scene.net.edges[: scene.net.n_edges]
    with h5py.File(out, "r") as f:
        frames = f["trajectory/x"][:]
    deepest = 0.0
    for x in frames:
        c, A = body.frame.state(x)
        seen = box_depth(points(edges, x, 1001), c, A @ shape.axes, shape.half_size)
        deepest = max(deepest, float(seen.max()))
    assert deepest > 0.1  # the strands cut through the box's edges
    assert 0.95 * deepest < float(depth) <= deepest * (1 + 1e-3) + 1e-3
    printed, kept, _ = run(case, tmp_path, *CAPTURE, "solver.edge_contact=true")
    assert "edges cut" not in printed and "edges cut" not in kept


CORNER = """
title = "a cord sagging over a block between its nodes"

[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 5
length = 2.2

[material]
EA = 1e5
density = 1000.0
area = 1e-4

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "box"
center = [0.25, 0.0, -0.45]
half_size = [0.1, 0.1, 0.2]
"""


def test_a_static_cord_sagging_through_a_block_between_its_nodes_is_warned(write_case, tmp_path):
    """A cord of four 0.55 m edges sags 0.4 m; a block stands under the middle of its
    third edge, between two nodes that it never touches: the edge passes through it.
    The warning names the block, the edge and its depth (that of points of the edge:
    at most the deepest of 1001, and within 1 % of it); with edge contact the cord rests
    on the block."""
    path = write_case(CORNER)
    printed, _, out = run(path, tmp_path)
    ((depth, label),) = CUT.findall(printed)
    assert label == "obstacle[0] (a box)" and "(edge 2 at load factor 1)" in printed
    with h5py.File(out, "r") as f:
        x = f["result/x"][:]
    edges = build(load_case(path)).net.edges
    seen = box_depth(
        points(edges, x, 1001), np.array([0.25, 0.0, -0.45]), np.eye(3), [0.1, 0.1, 0.2]
    )
    assert 0.99 * seen.max() < float(depth) <= seen.max() + 1e-9
    printed, _, out = run(path, tmp_path, "solver.edge_contact=true")
    assert "edges cut" not in printed


BALL = """
title = "a small fast ball through an edge of a net in one step"

[geometry]
kind = "square_net"
n = 4
alpha = 0.0
size = 1.0
edge_length = 0.2

[material]
EA = 1e6
density = 1000.0
area = 1e-5

[[obstacle]]
kind = "sphere"
center = [CX, CY, 0.14]
radius = 0.03
mass = 1.0
velocity = [0.0, 0.0, -25.0]

[solver]
method = "dynamic"
dt = 0.01
t_end = 0.02
damping = 0.0
"""


def test_a_ball_that_passes_an_edge_within_one_step_is_warned(write_case, tmp_path):
    """A 6 cm ball at 25 m/s over the middle of an edge of 0.2 m: it touches no node,
    and within one step of 10 ms (25 cm) it goes from 0.14 m above the net to 0.11 m below,
    so that no step's state has the edge inside it; between them it went through it,
    to its centre (0.03 m deep)."""
    net = build(load_case(write_case(BALL.replace("CX", "0").replace("CY", "0")))).net
    i, j = net.edges[0]
    mid = 0.5 * (net.nodes[i] + net.nodes[j])
    path = write_case(BALL.replace("CX", str(mid[0])).replace("CY", str(mid[1])))
    printed, _, out = run(path, tmp_path)
    ((depth, label),) = CUT.findall(printed)
    assert label == "obstacle[0] (a moving sphere)"
    assert 0.02 < float(depth) <= 0.03 + 1e-9
    (body,) = [line for line in printed.splitlines() if line.startswith("body")]
    assert "never touched" not in body  # (no node came near: the strands it cut did)
    assert "strands between the nodes cut into it (see the warning)" in body
    with h5py.File(out, "r") as f:  # no written state has an edge inside the ball
        frames, ball = f["trajectory/x"][:], build(load_case(path)).bodies[0]
    for x in frames:
        inside = np.linalg.norm(points(net.edges, x) - x[ball.node], axis=-1) < 0.03
        assert not inside.any()


def test_a_net_on_a_sphere_and_a_caught_ball_are_not_warned(tmp_path):
    """configs/contact/net_on_sphere.toml (a net draped on a sphere at rest) and the ball
    caught by a net (sphere_catch): their chords dip into the sphere by less than DEEP
    of their edges."""
    for name in ("net_on_sphere.toml", "sphere_catch.toml"):
        printed, kept, _ = run(CONFIGS / name, tmp_path)
        assert "edges cut" not in printed and "edges cut" not in kept, name


def test_the_watch_looks_only_between_states_with_edge_contact():
    """Edge contact keeps every edge out of the solids in every state: the watch looks
    only at the way between two states (passes), not at the states."""
    scene = build(load_case(CONFIGS / "net_on_sphere.toml", ["solver.edge_contact=true"]))
    assert EdgeWatch(scene).apart
    watch = EdgeWatch(build(load_case(CONFIGS / "net_on_sphere.toml")))
    assert watch and not watch.apart


ONE = """
[geometry]
kind = "cable"
start = [-0.1, 0.0, 2.0]
end = [0.1, 0.0, 2.0]
nodes = 2

[material]
EA = 1e5

[[obstacle]]
kind = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0
"""


@pytest.mark.parametrize("share", [0.5 * DEEP, 2.0 * DEEP])
def test_a_chord_is_a_crossing_beyond_its_share_of_the_edge(write_case, share):
    """A sphere of radius 1 and one edge of 0.2 m moved across it, its middle ``share``
    of its length deep: a crossing beyond DEEP only, at the time it got there."""
    watch = EdgeWatch(build(load_case(write_case(ONE))), dynamic=True)
    x = np.array([[-0.1, 0.0, 2.0], [0.1, 0.0, 2.0]])
    watch.see(0.0, x)
    x[:, 2] = 1.0 - share * 0.2
    watch.see(1.0, x)
    (message,) = watch.warnings() or [""]
    assert bool(message) == (share > DEEP)
    if message:
        ((depth, label),) = CUT.findall(message)
        assert label == "obstacle[0] (a sphere)" and "edge 0 at t = 1 s, in 1 step)" in message
        assert float(depth) == pytest.approx(share * 0.2, rel=1e-2)  # its middle, found


MOVING = """
title = "a block swept through a cord within one step"

[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 3

[material]
E = 2e9
radius = 0.003
density = 1150.0
prestress = 100.0

[[obstacle]]
kind = "box"
center = [0.5, -0.1, 0.0]
half_size = [0.05, 0.05, 0.1]
velocity = [0.0, 30.0, 0.0]

[solver]
method = "dynamic"
dt = 0.01
t_end = 0.02
damping = 1.0
"""


def test_an_obstacle_on_a_motion_through_an_edge_within_one_step_is_warned(write_case, tmp_path):
    """A 10 cm block on a prescribed motion at 30 m/s crosses the middle of a cord's 1 m
    edge within one step of 10 ms (from 0.1 m before it to 0.2 m past it): measured at the
    block's pose at each time between the steps, it went in as deep as the block's half
    width, 0.05 m."""
    printed, _, _ = run(write_case(MOVING), tmp_path)
    ((depth, label),) = CUT.findall(printed)
    assert label == "obstacle[0] (a moving box)" and "in 1 step)" in printed
    assert float(depth) == pytest.approx(0.05, rel=1e-2)


THROUGH = re.compile(
    r"((?:edge|node) \d+) and (obstacle\[\d+\] \([^)]*\)) went through each other between two "
    r"time steps \(near t = [0-9.e+-]+ s, ([0-9.e+-]+) m deep"
)
FAR = re.compile(
    r"the equilibrium at load factor ([0-9.e+-]+) lies on the far side of (obstacle\[\d+\] "
    r"\([^)]*\)) from the state before it \(the straight way between them takes "
    r"((?:edge|node) \d+) ([0-9.e+-]+) m deep through it"
)

STRAND = """
title = "a 4 cm ball at 2 m/s onto a strand 11 mm beside its centre, every edge a capsule"

[geometry]
kind = "square_net"
n = 8
alpha = 0.0
size = 1.0
edge_length = 0.25

[material]
E = 1e8
radius = 0.002
density = 1000.0

[[obstacle]]
kind = "sphere"
center = [0.0, 0.1, 0.2]
radius = 0.02
mass = 0.5
velocity = [0.0, 0.0, -2.0]
distance = 0.001

[solver]
method = "dynamic"
integrator = "bdf2"
t_end = 0.3
damping = 0.0
edge_contact = true
"""


def _ball_at_end(out, path) -> np.ndarray:
    """The ball's centre at the end; every written state keeps it off every strand."""
    scene = build(load_case(path))
    (ball,) = scene.bodies
    edges = scene.net.edges[: scene.net.n_edges]
    with h5py.File(out, "r") as f:
        frames = f["trajectory/x"][:]
    for x in frames:
        assert np.linalg.norm(points(edges, x, 201) - x[ball.node], axis=-1).min() > 0.02
    return frames[-1][ball.node]


def test_a_ball_stepped_through_a_strand_with_edge_contact_is_warned(write_case, tmp_path):
    """Every edge a capsule, the ball is kept off every strand in every state; but given
    20 ms steps (4 cm, its diameter) the step's solution has the ball on the strand's far
    side: it ends 0.1 m below the net, where 5 ms steps (and the steps chosen by accuracy)
    bounce it back above. The long steps are warned, the short ones not."""
    path = write_case(STRAND)
    printed, kept, out = run(path, tmp_path, "solver.dt=0.02")
    ((edge, label, depth),) = THROUGH.findall(printed)
    assert label == "obstacle[0] (a moving sphere)"
    assert "went through each other" in kept and "give a shorter solver.dt" in printed
    assert 0.0 < float(depth) <= 0.02
    assert _ball_at_end(out, path)[2] < -0.1  # through the net, falling on
    (body,) = [line for line in printed.splitlines() if line.startswith("body")]
    assert "first contact at t = " in body, body  # (it met a strand's barrier first)
    for sets in (["solver.dt=0.005"], []):
        printed, kept, out = run(path, tmp_path, *sets)
        assert "went through" not in printed and "went through" not in kept, sets
        assert _ball_at_end(out, path)[2] > 0.0, sets  # bounced back above the net


def test_an_obstacle_swept_through_a_strand_in_one_step_is_warned(write_case, tmp_path):
    """The 4 cm ball of STRAND on a prescribed motion at 40 m/s, right over the strand:
    given 10 ms steps (0.4 m), its first step takes it from 0.2 m above the strand to
    0.2 m below, the strand left in place: warned. At 1 ms steps it pushes the strand
    down 0.14 m before the strand slips off its side; nothing is warned."""
    case = write_case(
        STRAND.replace("mass = 0.5\n", "")
        .replace("velocity = [0.0, 0.0, -2.0]", "velocity = [0.0, 0.0, -40.0]")
        .replace("t_end = 0.3", "t_end = 0.015")
        .replace('integrator = "bdf2"\n', "")
    )
    printed, _, out = run(case, tmp_path, "solver.dt=0.01")
    ((what, label, depth),) = THROUGH.findall(printed)
    assert label == "obstacle[0] (a moving sphere)" and what.startswith("edge ")
    i, j = build(load_case(case)).net.edges[int(what.split()[1])]
    with h5py.File(out, "r") as f:
        frames = f["trajectory/x"][:]
    assert np.abs(frames[:, [i, j], 2]).max() < 1e-3  # the strand never moved
    (body,) = [line for line in printed.splitlines() if line.startswith("body")]
    assert "went through each other between two time steps (see the warning)" in body
    printed, _, out = run(case, tmp_path, "solver.dt=0.001")
    assert "went through" not in printed
    (body,) = [line for line in printed.splitlines() if line.startswith("body")]
    assert "first contact at t = " in body
    with h5py.File(out, "r") as f:
        frames = f["trajectory/x"][:]
    assert frames[:, [i, j], 2].min() < -0.1  # pushed down ahead of it


SLACK = """
title = "a slack 46 m cord over a 40 m span, loaded over a sphere and a box (kN, m)"
units = "kN-m"

[geometry]
kind = "cable"
start = [-20.0, 0.0, 0.0]
end = [20.0, 0.0, 0.0]
nodes = 9
length = 46.0

[material]
EA = 2e5
area = 0.001
density = 7.85

[[load.line]]
force = [0.0, 0.0, -5.0]

[[obstacle]]
kind = "sphere"
center = [-8.0, 0.0, -4.0]
radius = 3.0
distance = 0.01

[[obstacle]]
kind = "box"
center = [9.0, 0.0, -4.0]
half_size = [3.7, 2.0, 3.0]
angle = 0.2
distance = 0.01

[solver]
method = "static"
steps = 4
edge_contact = true
"""


def test_a_slack_cord_loaded_past_a_sphere_in_one_load_step_is_warned(write_case, tmp_path):
    """The slack cord starts straight, 1 m above the sphere; slack, it has no stiffness,
    and its first load step (a quarter of the load) finds it hanging under the sphere:
    an equilibrium on the sphere's far side from the start. The watch says so at load
    factor 0.25, and how to check: a damped run to rest (the cord falls on the sphere,
    slides off its side and swings under it) ends at the same equilibrium, unwarned."""
    path = write_case(SLACK)
    printed, kept, out = run(path, tmp_path)
    ((when, label, edge, depth),) = FAR.findall(printed)
    assert (when, label) == ("0.25", "obstacle[0] (a sphere)") and "far side" in kept
    assert "solver.t_end = 'rest'" in printed and float(depth) > 1.0
    with h5py.File(out, "r") as f:
        static = f["result/x"][:]
    assert static[3, 2] < -4.0 - 3.0  # under the sphere's bottom
    printed, kept, out = run(path, tmp_path, "solver.method=dynamic", 'solver.t_end="rest"')
    assert "far side" not in printed and "went through" not in printed
    with h5py.File(out, "r") as f:
        rest = f["result/x"][:]
    assert np.abs(rest - static).max() < 1e-3


def test_a_load_case_is_watched_from_the_base_state(write_case, tmp_path):
    """The slack cord of SLACK unloaded in its base state, its line load a load case:
    the case's first load step finds it under the sphere, and the warning is said with
    the case's name and kept with its results (``/cases/<name>``)."""
    case = SLACK.replace("[[load.line]]", '[[load_case]]\nname = "snow"\n[[load_case.line]]')
    printed, _, out = run(write_case(case), tmp_path)
    ((when, label, edge, depth),) = FAR.findall(printed)
    assert (when, label) == ("0.25", "obstacle[0] (a sphere)") and float(depth) > 1.0
    with h5py.File(out, "r") as f:
        assert "far side of obstacle[0] (a sphere)" in str(f["cases/snow"].attrs["warnings"])
        assert "far side" not in str(f["result"].attrs["warnings"])  # not the base state's


BOOM = """
title = "a crane boom on a prescribed path at 4 m/s up through a 6 m debris net (kN, m)"
units = "kN-m"

[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 6.0
edge_length = 0.25

[material]
E = 5.0e6
radius = 0.006
density = 1.14
prestress = 2.0

[[obstacle]]
kind = "capsule"
start = [0.2, -4.0, -0.3]
end = [0.2, 4.0, -0.3]
radius = 0.15
velocity = [0.0, 0.0, 4.0]
distance = 0.01

[solver]
method = "dynamic"
dt = 0.1
t_end = 0.3
damping = 1.0
"""


def test_nodes_a_step_carried_through_a_solid_are_warned_beside_the_edges_cut(write_case, tmp_path):
    """With contact at the nodes, a boom swept up through the net in steps of 0.4 m
    (1.3 times its width) both cuts the strands between the nodes it holds off and
    carries some nodes through itself: each is warned, the node by name. That node
    starts above the boom's axis and ends below it, within the boom's radius of the
    axis across it when it went through."""
    path = write_case(BOOM)
    printed, kept, out = run(path, tmp_path)
    ((what, label, depth),) = THROUGH.findall(printed)
    assert label == "obstacle[0] (a moving capsule)" and what.startswith("node ")
    assert "edges cut" in printed and "went through" in kept
    node = int(what.split()[1])
    with h5py.File(out, "r") as f:
        x, t = f["trajectory/x"][:], f["trajectory/time"][:]
    axis = -0.3 + 4.0 * t  # the boom's axis height at each frame
    below = x[:, node, 2] < axis
    assert not below[0] and below[-1]  # it began above the boom and ended below it
    k = int(np.argmax(below))  # the step that took it across
    across = np.abs(x[k - 1 : k + 1, node, 0] - 0.2).max()
    assert across < 0.15  # through the boom, not round its side
    assert float(depth) > 0.05 * 0.3


def test_a_pass_turns_the_point_round_beyond_a_right_angle(write_case):
    """A node carried round a box's corner in one step (from over its top to beside
    its side: 90 degrees) is no pass, however deep the straight way cuts the corner; one
    carried from over the top to under the bottom is."""
    box = ONE.replace('kind = "sphere"', 'kind = "box"')
    box = box.replace("radius = 1.0", "half_size = [1.0, 1.0, 1.0]")
    scene = build(load_case(write_case(box)))
    for end, through in (([1.05, 0.0, -0.2], False), ([0.8, 0.0, -1.05], True)):
        watch = EdgeWatch(scene, dynamic=True)
        x = np.array([[0.6, 0.0, 1.05], [0.9, 0.0, 1.05]])
        watch.see(0.0, x)
        x[0] = end
        x[1] = np.asarray(end) + [0.3, 0.0, 0.0]
        watch.see(1.0, x)
        told = [w for w in watch.warnings() if "went through" in w]
        assert bool(told) == through, end
