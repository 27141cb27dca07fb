"""Where a node a moving obstacle carries starts Newton's step (``Moving._predicted``): at
its predictor (where its own motion takes it) where the obstacle translates and the
node's straight path there, relative to the obstacle, meets it nowhere and keeps half its
gap; else at its start riding with the obstacle. Before, the predictor itself was carried,
so a node already moving with the obstacle was moved by its motion twice: a rope pushed
by a paddle started every step with the nodes in front one step's travel ahead of their
neighbours."""

from __future__ import annotations

import numpy as np
from click.testing import CliRunner

from catenet.cli import main
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier


def _paddle(velocity, omega=None, nodes=3):
    """A paddle 0.2 x 0.02 x 0.1 m (its +y face at y = 0.01) moving, over the first
    ``nodes`` nodes."""
    shape = BoxBarrier(np.arange(nodes), [0, 0, 0], [0.1, 0.01, 0.05], kappa=1.0, dhat=1e-3)
    return Moving(shape, [0, 0, 0], velocity, omega, reach=0.12)


X = np.array(
    [
        [0.0, 0.0105, 0.0],  # 0.5 mm in front of the +y face, riding at its speed
        [0.05, 0.0110, 0.0],  # 1 mm in front, at rest: the face runs into it
        [-0.05, 0.0105, 0.0],  # 0.5 mm in front, moving along the face (+x)
    ]
)
V = np.array([[0.0, 0.5, 0.0], [0.0, 0.0, 0.0], [0.3, 0.5, 0.0]])


def test_a_node_riding_with_the_paddle_starts_at_its_predictor_and_one_it_strikes_rides():
    """The paddle moves 2.5 mm along +y in a 5 ms step. The node moving with it starts the
    step at its predictor x + h v (before: 2.5 mm farther, its motion counted twice); the
    one at rest, which the paddle's face would pass, rides with the paddle from its start
    (its gap kept); the one sliding along the face keeps its own motion along it."""
    h = 0.005
    paddle = _paddle([0.0, 0.5, 0.0])
    base, trial = X.copy(), X + h * V
    moved = np.full(3, -1)
    assert paddle.carry(base, trial, 0.0, h, np.zeros(3, dtype=bool), moved) == 3
    assert np.allclose(base, X + [0.0, 0.0025, 0.0], rtol=0, atol=1e-15)
    assert np.allclose(trial[0], X[0] + h * V[0], rtol=0, atol=1e-15)
    assert np.allclose(trial[1], X[1] + [0.0, 0.0025, 0.0], rtol=0, atol=1e-15)
    assert np.allclose(trial[2], X[2] + h * V[2], rtol=0, atol=1e-15)
    gap = paddle.shape.gap(paddle._body(trial, *paddle.pose(h)))
    assert np.allclose(gap, [0.5e-3, 1e-3, 0.5e-3], rtol=1e-9)


def test_a_node_whose_predictor_would_enter_the_paddle_or_lose_half_its_gap_rides():
    """A node approaching the paddle at 0.3 m/s while the paddle comes at 0.5 m/s: its
    predictor ends 1.5 mm inside the paddle's path. One moving ahead of it at 0.44 m/s
    would end 0.3 mm nearer, keeping 0.2 of its 0.5 mm gap, less than half: it rides too.
    A turning paddle carries every node from its start."""
    h = 0.005
    x = X[:1].copy()
    for v in ([0.0, -0.3, 0.0], [0.0, 0.44, 0.0]):
        paddle = _paddle([0.0, 0.5, 0.0], nodes=1)
        base, trial = x.copy(), x + h * np.array(v)
        paddle.carry(base, trial, 0.0, h, np.zeros(1, dtype=bool))
        assert np.allclose(trial, base, rtol=0, atol=1e-15), v
    paddle = _paddle([0.0, 0.5, 0.0], [0.0, 0.0, 0.2], nodes=1)
    base, trial = x.copy(), x + h * np.array([0.0, 0.5, 0.0])
    paddle.carry(base, trial, 0.0, h, np.zeros(1, dtype=bool))
    assert np.allclose(trial, base, rtol=0, atol=1e-15)


PUSHED = """
[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 101

[material]
EA = 5.0e4
radius = 0.003
density = 1140.0
prestress = 50.0

[[obstacle]]
kind = "box"
center = [0.0, -0.05, 0.0]
half_size = [0.1, 0.01, 0.04]
velocity = [0.0, 0.5, 0.0]

[solver]
method = "dynamic"
integrator = "bdf2"
dt = 0.005
t_end = 0.3
"""


def test_a_cord_pushed_by_a_paddle_takes_fewer_iterations_and_stays_outside(tmp_path):
    """A 2 m cord (EA 50 kN, 50 N prestress, pinned ends) pushed at its middle by a
    paddle at 0.5 m/s, 2.5 mm a step: with the riding nodes started at their predictor the
    run takes under 4 Newton iterations a step (3.2; it took 14 with the predictor carried,
    876 iterations against 189, the same largest tension to every digit shown),
    and every node stays outside the paddle."""
    import h5py

    case = tmp_path / "pushed.toml"
    case.write_text(PUSHED)
    out = tmp_path / "r.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        frames, times = f["trajectory/x"][()], f["trajectory/time"][()]
        iterations = int(f["result"].attrs["iterations"])
    assert iterations < 4.0 * (len(times) - 1), iterations
    centre = np.stack([0 * times, -0.05 + 0.5 * times, 0 * times], axis=1)
    local = np.abs(frames - centre[:, None, :]) - [0.1, 0.01, 0.04]
    distance = np.linalg.norm(np.maximum(local, 0.0), axis=-1) + np.minimum(local.max(axis=-1), 0.0)
    assert distance.min() > 0.0
    assert frames[-1][50, 1] > 0.09  # pushed along with the paddle's face
