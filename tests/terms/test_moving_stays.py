"""Which nodes ride with a translating obstacle over a step (``Moving.stays``): those its
straight relative path would bring into it or to less than half their gap. A rope lying
on a belt that runs along it was carried along with the belt at every step (its end edges
strained by the belt's travel at each step's start, 11 Newton iterations a step); it now
stays where it is, and the step's equations, which the carry does not change, give the
same answer in about 2.5 iterations a step."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier


def _box(velocity, omega=None):
    """A box 1 x 1 x 0.2 m (top face at z = 0.1) over the nodes 0-3, moving."""
    shape = BoxBarrier(np.arange(4), [0, 0, 0], [0.5, 0.5, 0.1], kappa=1.0, dhat=0.01)
    return Moving(shape, [0, 0, 0], velocity, omega, reach=0.75)


X = np.array(
    [
        [0.0, 0.0, 0.105],  # on the top face, 5 mm up
        [0.0, 0.0, 0.3],  # 0.2 m above it
        [0.52, 0.0, 0.105],  # beyond its +x side, 5 mm up
        [-0.6, 0.0, 0.05],  # 0.1 m off its -x side, at mid height
    ]
)


def test_a_node_the_obstacle_slides_under_stays_and_one_it_runs_into_rides():
    """The box runs along +x by 0.2 m in the step: the node on its top face keeps its gap
    (stays), the one 0.2 m above too, the one beyond its +x side is run into, the one off
    its -x side is left behind (stays); rising by 0.2 m, it runs into the node above its
    face and the one 5 mm up; turning, nothing is left in place."""
    items = np.arange(4)[:, None]
    along = _box([1.0, 0.0, 0.0]).stays(items, X, 0.0, 0.2)
    assert along.tolist() == [True, True, False, True]
    rising = _box([0.0, 0.0, 1.0]).stays(items, X, 0.0, 0.2)
    assert rising.tolist() == [False, False, True, True]
    turning = _box([1.0, 0.0, 0.0], [0.0, 0.0, 0.1]).stays(items, X, 0.0, 0.2)
    assert not turning.any()


def test_a_node_the_obstacle_would_pass_through_in_a_step_rides():
    """A node 0.2 m off the box's -x side at mid height, the box running along -x by 1.5 m
    in the step: left in place, it would end 0.3 m beyond the box's +x side (its gap larger
    than at the start), having passed through the box: ridden. 0.2 m above the top face on
    the same path, it stays."""
    box = _box([-1.0, 0.0, 0.0])
    box.shape.nodes = np.array([0])
    through = np.array([[-0.7, 0.0, 0.0]])
    assert not box.stays(np.array([[0]]), through, 0.0, 1.5)[0]
    above = np.array([[-0.7, 0.0, 0.3]])
    assert box.stays(np.array([[0]]), above, 0.0, 1.5)[0]


BELT = """
[geometry]
kind = "graph"
nodes = [[-1.0, 0.0, 0.0031], [1.0, 0.0, 0.0031]]
fixed = [0, 1]
edge_length = 0.04

[[geometry.cable]]
name = "rope"
nodes = [0, 1]

[material]
E = 100e9
radius = 0.003
density = 7800.0
prestress = 500.0

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "box"                 # a conveyor belt running along the rope
center = [0.0, 0.0, -0.05]
half_size = [1.5, 0.5, 0.05]
velocity = [0.5, 0.0, 0.0]
friction = 0.2

[solver]
method = "dynamic"
integrator = "bdf2"
dt = 0.005
t_end = 0.2
damping = 5.0
edge_contact = true
"""


def test_a_rope_on_a_belt_running_along_it_is_not_pulled_along_at_each_step(tmp_path):
    """A wire rope (EA 2.83 MN, 500 N prestress) on a belt running along it at 0.5 m/s,
    mu = 0.2: the belt's friction pulls it along by mu times what it presses on the belt
    with (0.68 N of 3.41 N; the supports hold the rest of its weight), its
    tension 500.4 N, in 98 Newton iterations over 40 steps (453 while the belt carried the
    rope at each step's start: the same answer to every digit of the summary)."""
    case = tmp_path / "belt.toml"
    case.write_text(BELT)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 0, done.output
    iterations = int(done.output.split(" Newton iterations")[0].rsplit(" ", 1)[-1])
    assert iterations < 3 * 40  # at most 3 a step
    line = next(s for s in done.output.splitlines() if s.startswith("max tension"))
    assert float(line.split()[2]) == pytest.approx(500.425, abs=1e-3)
    resultant = next(s for s in done.output.splitlines() if s.startswith("contact"))
    drag, _, normal = (float(v) for v in resultant.split("[")[1].split("]")[0].split(","))
    assert drag == pytest.approx(0.2 * normal, rel=1e-3)  # sliding: mu N
