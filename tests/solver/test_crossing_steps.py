"""Steps chosen by accuracy never carry a ball or a body past a strand between two
states (catenet/solver/strikes.py's ``Strikes.crossing``): a 4 cm ball thrown at 15 m/s
at a wire, falling onto it from 3 m away, took steps of up to 0.146 s in free flight at
the default tolerance and crossed the wire between two of them, touching no node ("went
through each other", catenet/run/crossings.py). Near the net no step is longer than a
quarter of the ball's width at its closing speed, and the ball strikes the wire."""

from __future__ import annotations

import h5py
import numpy as np
from click.testing import CliRunner

from catenet.case import build, load_case
from catenet.cli import main
from catenet.solver.strikes import CROSS

THROWN = """
title = "a 4 cm ball thrown from 3 m away at 15 m/s at a wire, steps chosen by accuracy"

[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 41

[material]
E = 2e11
radius = 0.002
density = 7850.0
prestress = 500.0

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "sphere"
center = [0.1, -3.0, 0.2]
radius = 0.04
mass = 0.3
velocity = [0.0, 15.0, 0.0]
distance = 0.002

[solver]
method = "dynamic"
t_end = 0.26
damping = 0.0
"""


def test_a_ball_thrown_at_a_wire_strikes_it_at_default_steps(write_case, tmp_path):
    """No step that could bring the ball onto the wire moves it more than CROSS of its
    width; no frame pair has its centre change side of the wire within its radius of
    it; nothing warned."""
    path = write_case(THROWN)
    out = tmp_path / "o.h5"
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "went through" not in res.output
    (ball,) = build(load_case(path)).bodies
    with h5py.File(out, "r") as f:
        x, v, t = f["trajectory/x"][:], f["trajectory/v"][:], f["trajectory/time"][:]
    c, speed = x[:, ball.node], np.linalg.norm(v[:, ball.node], axis=1)
    wire = x[:, :41]
    for k in range(1, len(t)):
        h = t[k] - t[k - 1]
        off = np.linalg.norm(c[k - 1, 1:] - wire[k - 1, :, 1:].mean(axis=0)) - 0.04
        if off <= speed[k - 1] * h:  # the step could bring it onto the wire
            assert h <= CROSS * 0.08 / speed[k - 1] * 1.000001
        for s in np.linspace(0.0, 1.0, 21):  # the straight way between the two frames
            centre = (1 - s) * c[k - 1] + s * c[k]
            strand = (1 - s) * wire[k - 1] + s * wire[k]
            assert _distance(centre, strand) > 0.04 - 0.25 * 0.04  # never a quarter in
    assert speed[-1] < 0.8 * 15.0  # struck: it gave the wire half its speed


def _distance(point: np.ndarray, line: np.ndarray) -> float:
    """The distance of a point from a polyline (K, 3)."""
    a, b = line[:-1], line[1:]
    u = np.clip(np.einsum("ij,ij->i", point - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
    return float(np.min(np.linalg.norm(a + u[:, None] * (b - a) - point, axis=1)))
