"""The newmark integrator in contact: at its default rho_inf (0.8) it gains momentum in
impacts and does not converge with the step, and at any rho_inf its steps can fail at
first contact, so a run with contact says so (in the log and in the summary); at
rho_inf <= 0.5 a ball dropped onto a net rebounds with less momentum than it came in
with, the same at two steps, and straight up."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import small_net

from catenet.case import load_case
from catenet.case.kinds import warn
from catenet.cli import main
from catenet.run import integrator_advice as advice

SPHERE = """
[[obstacle]]
kind = "sphere"
center = [0.0, 0.0, -2.0]
radius = 0.5
"""
NEWMARK = small_net(method="dynamic", dt=0.01, t_end=0.03) + SPHERE
NEWMARK = NEWMARK.replace('method = "dynamic"', 'method = "dynamic"\nintegrator = "newmark"')

# A 12 kg ball dropped at 1 m/s from 0.15 m onto the net of benchmarks/peers/mujoco_drop.toml.
BALL = """
[geometry]
kind = "square_net"
n = 10
alpha = 0.7853981633974483
size = 1.0
edge_length = 0.05

[material]
E = 10e6
radius = 0.01
density = 1000.0

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "sphere"
center = [0.0, 0.0, 0.3]
radius = 0.15
mass = 12.0
velocity = [0.0, 0.0, -1.0]

[solver]
method = "dynamic"
integrator = "newmark"
dt = 0.001
damping = 0.0
t_end = 0.4
"""


@pytest.fixture(autouse=True)
def fresh_warnings():
    warn._WARNED.clear()
    yield
    warn._WARNED.clear()


def notes(write_case, text, *sets):
    return advice.newmark_contact(load_case(write_case(text), sets))


def test_newmark_with_an_obstacle_is_warned_about(write_case):
    (msg,) = notes(write_case, NEWMARK)
    assert msg.startswith("solver.integrator = 'newmark' with contact (solver.rho_inf = 0.8)")
    assert "gains momentum" in msg and "implicit_euler" in msg and "'bdf2'" in msg
    assert f"solver.rho_inf <= {advice.RHO_INF_CONTACT}" in msg


@pytest.mark.parametrize("rho_inf", [0.5, 0.0])
def test_at_low_rho_inf_the_warning_names_the_step_failures(write_case, rho_inf):
    (msg,) = notes(write_case, NEWMARK, f"solver.rho_inf={rho_inf}")
    assert "not validated in contact" in msg and "gains momentum" not in msg
    assert "solver.integrator = 'bdf2'" in msg and "'implicit_euler'" in msg


@pytest.mark.parametrize(
    "text, sets",
    [
        (NEWMARK, ('solver.integrator="implicit_euler"',)),
        (NEWMARK, ('solver.method="static"',)),
        (NEWMARK.replace(SPHERE, ""), ()),  # no contact
    ],
)
def test_no_warning_without_newmark_and_contact(write_case, text, sets):
    assert notes(write_case, text, *sets) == []


def test_free_bodies_and_self_contact_are_warned_about(write_case):
    body = NEWMARK.replace("radius = 0.5", "radius = 0.5\nmass = 5.0")
    assert len(notes(write_case, body)) == 1
    free = NEWMARK.replace(SPHERE, "").replace("[solver]", "[solver]\nself_contact = true")
    assert len(notes(write_case, free)) == 1


def test_the_run_logs_it_and_the_summary_shows_it(tmp_path, write_case, caplog):
    runner = CliRunner()
    with caplog.at_level(logging.WARNING):
        r = runner.invoke(main, ["run", str(write_case(NEWMARK)), "-o", str(tmp_path / "a.h5")])
    assert r.exit_code == 0, r.output
    lines = [line for line in r.stdout.splitlines() if line.startswith("warning ")]
    assert len(lines) == 1 and "(solver.rho_inf = 0.8)" in lines[0]
    assert "does not converge with the step" in r.stderr
    args = ["run", str(write_case(NEWMARK)), "-o", str(tmp_path / "b.h5")]
    r = runner.invoke(main, [*args, "--set", 'solver.integrator="implicit_euler"'])
    assert r.exit_code == 0, r.output
    # no word of newmark (implicit Euler's own loss in 3 steps from rest is said apart:
    # tests/run/test_integrator_loss.py)
    assert "newmark" not in r.stdout and "newmark" not in r.stderr
    warned = [line for line in r.stderr.splitlines() if "WARNING" in line]
    assert all("removed" in line and "implicit_euler" in line for line in warned)


def rebound(write_case, dt: float, rho_inf: float) -> np.ndarray:
    """The ball's momentum at t_end (kg m/s)."""
    from catenet.case.scene import build
    from catenet.solver import path as sv
    from catenet.solver.linear import resolve_backend

    sets = (f"solver.dt={dt}", f"solver.rho_inf={rho_inf}")
    case = load_case(write_case(BALL, f"ball{dt}.toml"), sets)
    scene = build(case)
    settings = sv.Settings.of(case.solver, linear=resolve_backend(case.solver.linear))
    result = sv.solve(scene, settings)
    assert result.converged
    k = int(np.argmax(scene.net.mass))  # the ball's centre
    return scene.net.mass[k] * result.v[k]


def test_a_ball_rebounds_slower_than_it_came_and_converges_at_rho_inf_0_5(write_case):
    incoming = 12.0 * np.sqrt(1.0 + 2.0 * 9.81 * 0.15)  # at first touch, 23.8 kg m/s
    coarse, fine = (rebound(write_case, dt, 0.5) for dt in (0.001, 0.0005))
    for p in (coarse, fine):
        assert 0.0 < p[2] < incoming  # upward, slower than it came (the net stays)
        assert np.hypot(p[0], p[1]) < 1e-6 * incoming  # the scene is symmetric
    assert abs(coarse[2] - fine[2]) < 0.01 * fine[2]
