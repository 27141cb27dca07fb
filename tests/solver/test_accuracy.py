"""Dynamic runs accurate at default settings (catenet/solver/adaptive.py, events.py): a
case with contact and no dt steps by accuracy with bdf2, newmark is refused in contact,
contact events are landed on, a bouncing ball keeps its analytic period with an error
that falls with the tolerance, and peaks are found between the steps."""

from __future__ import annotations

import math

import numpy as np
import pytest

import catenet as cn
from catenet.case import build, parse_case
from catenet.errors import ConfigError
from catenet.model.peaks import Peaks
from catenet.solver.adaptive import TOLERANCE
from tests.solver.test_energy import invoke, write

G = 9.81
FALL = 1.0  # the ball's fall to the plane [m]


def bounce(**solver) -> dict:
    """A 1 kg sphere (a free body) dropped FALL onto a ground plane whose barrier
    (1 mm, 1e7 N/m) holds the impact within 0.2 mm, frictionless and undamped, beside a
    short pinned cable it never meets; one bounce and its top in 1 s."""
    contact = {"distance": 1e-3, "stiffness": 1e7}
    return {
        "geometry": {"kind": "cable", "start": [5.0, 0.0, 0.0], "end": [6.0, 0.0, 0.0],
                     "nodes": 2},
        "material": {"E": 1e6, "radius": 0.01, "density": 1000.0},
        "supports": {"fixed": ["start", "end"]},
        "load": {"gravity": [0.0, 0.0, -G]},
        "obstacle": [
            {"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], **contact},
            {"kind": "sphere", "center": [0.0, 0.0, 0.1 + FALL], "radius": 0.1, "mass": 1.0,
             "angular_velocity": [0.0, 0.0, 0.0], **contact},
        ],
        "solver": {"method": "dynamic", "damping": 0.0, "t_end": 1.0, **solver},
    }  # fmt: skip


def run_bounce(**solver) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """(t, height of the ball's bottom, its vertical speed) at every step, and the steps."""
    case = parse_case(bounce(**solver))
    scene = build(case)
    frame = scene.rigid[0].frame
    rows = [(0.0, FALL, 0.0)]

    def seen(step) -> None:
        centre = frame.state(step.x)[0]
        rows.append((step.time, centre[2] - 0.1, float(step.v[frame.nodes, 2].mean())))

    result = cn.solve(scene, cn.Settings.of(case.solver), on_step=seen)
    assert result.converged
    t, z, v = np.array(rows).T
    return t, z, v, result.steps


def apexes(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The times where the speed turns from up to down (linear between steps)."""
    k = np.flatnonzero((v[:-1] > 0.0) & (v[1:] <= 0.0))
    return t[k] + (t[k + 1] - t[k]) * v[k] / (v[k] - v[k + 1])


def test_contact_without_dt_steps_by_accuracy_and_dt_alone_keeps_fixed_steps():
    """A run to a time with an obstacle and no dt: the default tolerance and bdf2; dt
    given alone: fixed steps and implicit Euler, as ever; a run to rest: fixed steps."""
    solver = parse_case(bounce()).solver
    assert solver.tolerance == TOLERANCE and solver.integrator == "bdf2"
    fixed = parse_case(bounce(dt=0.01)).solver
    assert fixed.tolerance is None and fixed.integrator == "implicit_euler" and fixed.dt == 0.01
    euler = parse_case(bounce(integrator="implicit_euler")).solver
    assert euler.tolerance == TOLERANCE and euler.integrator == "implicit_euler"
    rest = bounce(damping=1.0, t_end="rest")
    del rest["obstacle"][1]  # a fixed plane alone: dynamic relaxation
    resting = parse_case(rest).solver
    assert resting.tolerance is None and resting.integrator == "implicit_euler"


def test_newmark_with_contact_exits_2(tmp_path):
    r = invoke("run", write(tmp_path, bounce(integrator="newmark", dt=1e-3)), "-o",
               tmp_path / "out.h5", "-q")  # fmt: skip
    assert r.exit_code == 2, r.output
    assert "solver.integrator = 'newmark': not for a run with contact (obstacle[0]" in r.output
    with pytest.raises(ConfigError, match="use 'bdf2'"):
        parse_case(bounce(integrator="newmark"))


def test_a_ball_bouncing_keeps_its_analytic_period():
    """Free flight between bounces is exact for bdf2; the bounce is what the steps must
    resolve: the first step in contact starts at the touch (landed on, within the
    barrier's 1 mm), and the bounce is stepped through at constant steps, a 64th of it
    (catenet/solver/strikes.py's SOLID_BOUNCE), whatever the tolerance: the period
    2 sqrt(2 h / g) within 0.05 % at 1e-3 and 1e-4 (the error of the estimate's own
    steps fell tenfold per tenfold tighter, 0.23 % at 1e-3)."""
    period = 2.0 * math.sqrt(2.0 * FALL / G)
    errors, counts = [], []
    for tolerance in (1e-3, 1e-4):
        t, z, v, steps = run_bounce(tolerance=tolerance)
        first = apexes(t, v)[0]  # the top after the first bounce: one period from the start
        errors.append(abs(first - period) / period)
        counts.append(steps)
        touch = int(np.argmax(z < 1e-3))  # the first state within the barrier's reach
        assert 0.9e-3 < z[touch] < 1e-3  # landed on as it comes within reach
        assert t[touch] == pytest.approx(math.sqrt(2.0 * (FALL - 1e-3) / G), rel=1e-3)
        assert z.min() > 0.0  # never inside the plane
    assert max(errors) < 5e-4, errors
    assert counts[1] < 4 * counts[0], counts  # the steps grow as the tolerance's cube root


def test_the_bounce_at_default_settings_keeps_its_period_within_0_05_percent():
    """No tolerance given (the default of a run with contact): the top after the first
    bounce within 0.05 % of the analytic period (0.8 % when the bounce's steps were the
    estimate's, 4.3 % at 5e-3), the ball never inside the plane."""
    period = 2.0 * math.sqrt(2.0 * FALL / G)
    t, z, v, _ = run_bounce()
    assert abs(apexes(t, v)[0] / period - 1.0) < 5e-4
    assert z.min() > 0.0


def test_no_peak_is_read_between_steps_of_unequal_length_across_a_kink():
    """A tension that rises at 1 N/s to t = 8 (a fairlead pulled, then stopped) and falls
    at 10 N/s after, sampled at 6.8, 8.0 and 8.28 (a step cut short at the kink): the
    parabola through them tops at 10.1 N at t = 7.47, where the tension was 7.47 N;
    with steps that differ more than Peaks' EVEN the samples stand."""

    def tension(t: float) -> float:
        return t if t <= 8.0 else 8.0 - 10.0 * (t - 8.0)

    found = Peaks(np.zeros((1, 3)), 1, between=True)
    for t in (6.8, 8.0, 8.28):
        found.observe(t, np.zeros((1, 3)), np.array([tension(t)]))
    assert found.tension[0] == pytest.approx(8.0) and found.tension_time[0] == 8.0
    even = Peaks(np.zeros((1, 3)), 1, between=True)  # the same at equal steps: read
    for t in (7.6, 8.0, 8.4):
        even.observe(t, np.zeros((1, 3)), np.array([math.sin(t)]))
    assert even.tension[0] > math.sin(8.0)


def test_peaks_between_steps_lie_on_the_parabola_through_three_states():
    """A tension sin(t) sampled at steps of 0.4 (peak 1 at pi / 2, between samples): the
    peak between the steps within 0.1 % of 1 and its time within 0.01, where the largest
    sample is 0.8 % low; without ``between``, the sample."""
    times = np.arange(0.1, 3.0, 0.4)
    found, sampled = Peaks(np.zeros((1, 3)), 1, between=True), Peaks(np.zeros((1, 3)), 1)
    for t in times:
        for peaks in (found, sampled):
            peaks.observe(float(t), np.zeros((1, 3)), np.array([math.sin(t)]))
    assert found.tension[0] == pytest.approx(1.0, abs=1e-3)
    assert found.tension_time[0] == pytest.approx(math.pi / 2, abs=1e-2)
    assert sampled.tension[0] == pytest.approx(max(np.sin(times)))
    assert sampled.tension[0] < 0.995


def test_a_snap_is_a_rope_taut_then_slack_then_taut_again():
    """Peaks' snaps: a tension-only edge that starts slack and tightens has not snapped;
    one that was taut, went slack and is taut again has, at that state's time, with the
    largest tension before it; a bilateral edge through zero never snaps."""
    found = Peaks(np.zeros((1, 3)), 3, only=np.array([True, True, False]))
    rows = [(0.0, [0.0, 5.0, -1.0]), (1.0, [2.0, 0.0, 1.0]), (2.0, [3.0, 0.0, -1.0]),
            (3.0, [1.0, 9.0, 2.0]), (4.0, [0.0, 4.0, 0.0])]  # fmt: skip
    for t, tension in rows:
        found.observe(t, np.zeros((1, 3)), np.array(tension))
        if t < 3.0:
            assert not np.isfinite(found.snap_time)
    assert found.snap_time == 3.0 and found.before_snap == 5.0
    assert found.snapped.tolist() == [False, True, False]


def test_the_bounce_converges_as_its_steps_halve(monkeypatch):
    """The bounce's constant steps (a SOLID_BOUNCE-th of it) converge: the period's error
    at 16, 32, 64 and 128 steps to a bounce, 0.85 %, 0.14 %, 0.018 %, 0.0014 % measured,
    falls more than fourfold per halving. (The bounce's steps alone: the energy's
    allowance, left out here, shortens the steps into and out of the bounce, and with
    it the error at 16 is 0.10 %, at 32 0.13 %, then as without.)"""
    from catenet.solver import strikes
    from catenet.solver.adaptive import ErrorControl

    monkeypatch.setattr(ErrorControl, "energy_error", lambda self, stepper, h: 0.0)

    period = 2.0 * math.sqrt(2.0 * FALL / G)
    errors = []
    for per in (16, 32, 64, 128):
        monkeypatch.setattr(strikes, "SOLID_BOUNCE", per)
        t, _, v, _ = run_bounce()
        errors.append(abs(apexes(t, v)[0] / period - 1.0))
    assert all(b < a / 4.0 for a, b in zip(errors, errors[1:], strict=False)), errors
