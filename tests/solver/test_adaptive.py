"""Time steps chosen by accuracy (``solver.tolerance``; catenet/solver/adaptive.py): the
error falls with the tolerance at the scheme's order against a closed form, the steps
stay within their bounds, the case keys resolve and refuse what cannot run, and a case
run from the command line writes its irregular frames."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

import catenet as cn
from catenet.case import parse_case
from catenet.errors import ConfigError
from catenet.solver.adaptive import ErrorControl
from catenet.solver.dynamic import solve_dynamic
from tests.solver.test_energy import invoke, write

ROOT = Path(__file__).resolve().parents[2]


def spring(integrator: str, tolerance: float, **keys) -> tuple[float, int, list[float]]:
    """A 1 kg mass on an axial spring (EA = 100 N, l0 = 1 m; omega = 10 1/s) released 1 %
    beyond its 2 % equilibrium strain, over 2 s (3.2 periods): (|x - x_exact| at the end,
    steps, the steps' lengths). The mass is the spring's own (2 kg/m, lumped: 1 kg at
    each end), so that the steps are the positions' estimate's: a lumped mass
    (``point_mass``) would be a body, its momentum held to a tenth of the tolerance."""
    nodes = np.array([[0.0, 0.0, 0.0], [1.03, 0.0, 0.0]])
    net = cn.Net.from_arrays(
        nodes, [[0, 1]], EA=100.0, fixed=[0], rest_length=1.0, line_density=2.0
    )
    loads = cn.Loads(force=np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]))
    times = [0.0]
    r = solve_dynamic(
        net, loads, dt=1e-3, damping=0.0, t_end=2.0, rtol=1e-12, stop_at_equilibrium=False,
        integrator=integrator, tolerance=tolerance, on_step=lambda k, t, x, v: times.append(t),
        **keys,
    )  # fmt: skip
    assert r.converged and r.time == 2.0
    return abs(r.x[1, 0] - (1.02 + 0.01 * math.cos(20.0))), r.steps, list(np.diff(times))


@pytest.mark.parametrize(
    "integrator, order, loosest", [("bdf2", 2, 1e-3), ("implicit_euler", 1, 1e-2)]
)
def test_the_error_falls_with_the_tolerance_at_the_schemes_order(integrator, order, loosest):
    """Per tenfold tighter tolerance the steps grow about 10^(1/(p+1)) times (2.2 for
    bdf2, 3.2 for implicit Euler) and the error at the end falls. (Implicit Euler from
    1e-2: at 1e-5 it took 58 526 steps and a tenth of the suite's time, for the same
    ratios as at 1e-2 to 1e-4: 6302 / 1949 and 19 366 / 6302 steps.)"""
    runs = [spring(integrator, tol) for tol in (loosest, loosest / 10, loosest / 100)]
    errors = [e for e, _, _ in runs]
    steps = [n for _, n, _ in runs]
    expected = 10 ** (1 / (order + 1))
    for k in range(2):
        assert 0.7 * expected < steps[k + 1] / steps[k] < 1.4 * expected, steps
        assert errors[k + 1] < 0.5 * errors[k], errors
    assert errors[-1] < (2.5e-4 if order == 2 else 5e-4)  # of an amplitude of 1e-2 m


def bdf2_from_exact(t: np.ndarray, n: int) -> float:
    """The spring's bdf2 step from t[n] to t[n + 1] started on the closed form at t[n - 1]
    and t[n] (positions and velocities): x_{n+1} (catenet/solver/integrators.py, BDF2)."""
    h, h1 = t[n + 1] - t[n], t[n] - t[n - 1]
    omega = h / h1
    c2 = omega * omega / (1.0 + 2.0 * omega)
    b = h * (1.0 + omega) / (1.0 + 2.0 * omega)
    (x1, v1), (x0, v0) = (spring_exact(t[n]), spring_exact(t[n - 1]))
    x_bar = (1.0 + c2) * (x1 - 1.02) - c2 * (x0 - 1.02)
    v_bar = (1.0 + c2) * v1 - c2 * v0
    return 1.02 + (x_bar + b * v_bar) / (1.0 + 100.0 * b * b)  # x'' = -100 (x - 1.02)


def spring_exact(t: float) -> tuple[float, float]:
    return 1.02 + 0.01 * math.cos(10.0 * t), -0.1 * math.sin(10.0 * t)


@pytest.mark.parametrize("tolerance", [1e-3, 1e-4])
def test_the_accepted_steps_local_error_is_within_the_tolerance(tolerance, monkeypatch):
    """Each accepted bdf2 step's true local error (the step taken from the closed form's
    states, against the closed form at its end) over what the tolerance allows (tolerance
    times the reach so far, at least 1 % of the spring's length): in the median within
    it, nine steps in ten within 2.5 times it. The estimate is asymptotically right but
    looks back over three steps, so it lags where the third derivative turns. (The
    positions' estimate alone: the energy's allowance, which on this spring asks for
    steps about three times shorter over its three periods, is left out.)"""
    monkeypatch.setattr(ErrorControl, "energy_error", lambda self, stepper, h: 0.0)
    _, _, lengths = spring("bdf2", tolerance)
    t = np.concatenate([[0.0], np.cumsum(lengths)])
    shares, reach = [], 0.01 * 1.03
    for n in range(1, len(lengths) - 1):
        reach = max(reach, abs(spring_exact(t[n])[0] - 1.03))
        if (t[n + 1] - t[n]) / (t[n] - t[n - 1]) > 2.4:
            continue  # an implicit Euler step (catenet/solver/integrators.py, BDF2)
        error = abs(bdf2_from_exact(t, n) - spring_exact(t[n + 1])[0])
        shares.append(error / (tolerance * reach))
    assert len(shares) > 50
    assert np.median(shares) < 1.2 and np.percentile(shares, 90) < 2.5, shares
    assert np.median(shares) > 0.3  # and the steps are not far shorter than it asks


def test_the_steps_keep_within_dt_min_and_dt_max():
    _, _, lengths = spring("bdf2", 1e-5, dt_max=5e-3, dt_min=2e-3)
    assert max(lengths) <= 5e-3 * (1 + 1e-12) and min(lengths[:-1]) >= 2e-3 * (1 - 1e-12)
    _, _, free = spring("bdf2", 1e-3)
    assert max(free) > 5e-3  # unbounded, it takes longer steps


def drop(**solver) -> dict:
    case = tomllib.loads((ROOT / "benchmarks" / "peers" / "mujoco_drop.toml").read_text())
    case["solver"] = {k: v for k, v in case["solver"].items() if k != "dt"} | solver
    return case


def test_a_tolerance_without_dt_steps_by_accuracy_with_bdf2():
    solver = parse_case(drop(tolerance=3e-3)).solver
    assert solver.integrator == "bdf2" and solver.dt == pytest.approx(0.4 / 1000)
    fixed = parse_case(drop(dt=0.01)).solver  # dt alone: fixed steps, implicit Euler
    assert fixed.tolerance is None and fixed.dt == 0.01 and fixed.integrator == "implicit_euler"
    given = parse_case(drop(tolerance=1e-3, dt=2e-3, integrator="implicit_euler")).solver
    assert given.dt == 2e-3 and given.integrator == "implicit_euler"


@pytest.mark.parametrize(
    "solver, message",
    [
        ({"tolerance": 1e-3, "integrator": "newmark"}, "not for a run with contact"),
        ({"tolerance": 1e-3, "dt_min": 0.1, "dt_max": 0.01}, "solver.dt_min = 0.1: must be <="),
        ({"tolerance": 1e-3, "dt": 0.2, "dt_max": 0.01}, "solver.dt = 0.2: the first adaptive"),
        ({"tolerance": 1.5}, "solver.tolerance = 1.5"),
        ({"dt_max": -1.0}, "solver.dt_max = -1.0"),
    ],
)
def test_bad_step_keys_exit_2_naming_the_key(tmp_path, solver, message):
    r = invoke("run", write(tmp_path, drop(**solver)), "-o", tmp_path / "out.h5", "-q")
    assert r.exit_code == 2 and message in r.output, r.output


def test_the_drop_at_default_settings_and_its_result_file(tmp_path):
    """The drop without dt from the command line (its default tolerance, bdf2): the box
    thrown back up within 2 % of the fine-step answer (bdf2 at 0.31 ms: 16.17 kg m/s),
    every frame's time after the last, no node inside the box (the run's own check)."""
    out = tmp_path / "drop.h5"
    r = invoke("run", write(tmp_path, drop()), "-o", out, "-q")
    assert r.exit_code == 0, r.output
    with h5py.File(out, "r") as f:
        t = f["trajectory/time"][()]
        assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(0.4)
        assert len(np.unique(np.round(np.diff(t), 12))) > 3  # the steps did change
        velocity = f["result/obstacles/0/velocity"][()]
        mass = float(f["mesh/obstacles/0"].attrs["mass"])
    assert abs(mass * velocity[2] / 16.17 - 1) < 0.02
    assert len(t) < 250  # a frame a step: 148 (182 before the held nodes, 607 before the filter)


def test_settings_refuse_newmark_with_a_tolerance():
    with pytest.raises(ConfigError, match="not 'newmark'"):
        cn.Settings("dynamic", tolerance=1e-3, integrator="newmark")


def test_step_keys_a_run_ignores_are_named():
    from catenet.run.advice import ignored_solver_keys

    rest = parse_case(drop(tolerance=1e-3, t_end="rest", damping=1.0)).solver
    assert any("solver.tolerance = 0.001: ignored with solver.t_end = 'rest'" in m
               for m in ignored_solver_keys(rest))  # fmt: skip
    fixed = parse_case(drop(dt=0.01, dt_max=0.02)).solver
    assert any("solver.dt_max = 0.02: ignored without solver.tolerance" in m
               for m in ignored_solver_keys(fixed))  # fmt: skip
    static = parse_case(drop(method="static", tolerance=1e-3)).solver
    assert any("solver.tolerance = 0.001: ignored with solver.method = 'static'" in m
               for m in ignored_solver_keys(static))  # fmt: skip


def test_python_settings_resolve_as_a_case_file():
    """A tolerance from Python steps as a case file's does: bdf2, t_end / 1000 first;
    without one, 0.01 s and implicit Euler; crossed bounds refused."""
    adaptive = cn.Settings("dynamic", t_end=0.4, tolerance=1e-3)
    assert adaptive.integrator == "bdf2" and adaptive.dt == pytest.approx(4e-4)
    assert cn.Settings("dynamic", t_end=0.4, tolerance=1e-3, dt_max=1e-4).dt == 1e-4
    fixed = cn.Settings("dynamic", t_end=0.4)
    assert fixed.integrator == "implicit_euler" and fixed.dt == 0.01
    from_case = cn.Settings.of(parse_case(drop(tolerance=1e-3)).solver)
    assert from_case == dataclasses.replace(adaptive, damping=0.0)  # the drop is undamped
    with pytest.raises(ConfigError, match="solver.dt_min = 0.1: must be <="):
        cn.Settings("dynamic", tolerance=1e-3, dt_min=0.1, dt_max=0.01)


def test_a_tolerance_dt_min_cannot_meet_is_warned_about_once(caplog):
    with caplog.at_level("WARNING", logger="catenet.solver.adaptive"):
        _, _, lengths = spring("bdf2", 1e-8, dt_min=5e-3)
    said = [r.getMessage() for r in caplog.records if "solver.dt_min" in r.getMessage()]
    assert len(said) == 1 and "times solver.tolerance = 1e-08: taken" in said[0]
    assert min(lengths[:-1]) >= 5e-3 * (1 - 1e-12)


def solid_beside_a_cable(solid: dict):
    """The bdf2 stepper at its start and the error control (tolerance 1e-3) of a free
    ``solid`` (an [[obstacle]] table) beside a cable fixed at both ends, undamped."""
    from catenet.case import build
    from catenet.solver.adaptive import ErrorControl
    from catenet.solver.integrators import make
    from catenet.solver.path import workspace
    from catenet.solver.stepper import TimeStepper

    case = parse_case({
        "geometry": {"kind": "cable", "start": [5.0, 0.0, 0.0], "end": [6.0, 0.0, 0.0],
                     "nodes": 5},
        "material": {"E": 1e6, "radius": 0.01, "density": 1000.0},
        "supports": {"fixed": ["start", "end"]},
        "obstacle": [solid],
        "solver": {"method": "dynamic", "damping": 0.0, "t_end": 1.0},
    })  # fmt: skip
    scene = build(case)
    stepper = TimeStepper(scene.net, scene.loads, workspace(scene, cn.Settings.of(case.solver)),
                          make("bdf2"), 0.0, rtol=1e-8, max_iter=25, reuse=False)  # fmt: skip
    stepper.begin(None, None, 0.0, None, None)
    return stepper, ErrorControl.of(stepper, 1e-3, 0.0, 1.0, 5e-3, None, None)


def test_a_body_at_rest_measures_its_momentum_error_against_the_runs_momentum():
    """A 1 t ball at rest beside a cable whose free nodes move at 2 m/s: the ball's
    momentum scale is 1 % of the momentum the parts carry (sum of |m v|), not 1 % of its
    own mass at the scene's speed; once it moves, its own largest momentum."""
    from catenet.solver.adaptive import FLOOR

    stepper, control = solid_beside_a_cable({
        "kind": "sphere", "center": [0.0, 0.0, 1.0], "radius": 0.5, "mass": 1000.0,
        "angular_velocity": [0.0, 0.0, 0.0],
    })  # fmt: skip
    bodies = control.bodies
    assert bodies is not None and len(bodies.dofs) == 1
    at_rest = bodies.largest[0]
    v = np.zeros(len(stepper.free))
    ball = bodies.dofs[0].reshape(-1)
    cable = np.setdiff1d(np.arange(len(v)), ball)
    v[cable[cable % 3 == 0]] = 2.0  # the cable's free nodes along x
    bodies.saw(v)
    flow = 2.0 * float(stepper.m_free[cable[cable % 3 == 0]].sum())
    assert bodies.largest[0] == pytest.approx(FLOOR * flow) and bodies.largest[0] < at_rest
    v[ball.reshape(-1, 3)[:, 2]] = 0.1  # the ball moving at 0.1 m/s: its own momentum
    bodies.saw(v)
    assert bodies.largest[0] == pytest.approx(100.0)
    assert bodies.error(np.where(np.isin(np.arange(len(v)), ball), 1e-3, 0.0)) == pytest.approx(
        1000.0 * 1e-3 * math.sqrt(3.0) / 100.0
    )


def test_a_box_resting_on_a_net_from_its_equilibrium_stays_at_default_settings():
    """A 8 kg box with friction resting on a net, started from the static equilibrium
    (``solver.initial_state = "equilibrium"``), steps chosen by accuracy: nothing moves
    but round-off, and the box's momentum error was measured against the largest
    momentum seen, round-off's (2.5e-11 kg m/s), so every step was too long down to
    3e-10 s and the run stopped with "a force imbalance ... above the loads". The scale
    keeps 1e-6 of the body's mass times the speed floor: the run rests at once."""
    from catenet.case import build

    case = {
        "title": "a box resting on a net",
        "geometry": {"kind": "square_net", "n": 16, "alpha": 0.0, "size": 1.5,
                     "edge_length": 0.05},
        "material": {"E": 50.0e6, "radius": 0.004, "density": 1150.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "box", "center": [0.0, 0.0, 0.064],
                      "half_size": [0.2, 0.15, 0.06], "mass": 8.0, "distance": 0.005,
                      "friction": 0.5}],
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "damping": 0.0,
                   "t_end": 1.0},
    }  # fmt: skip
    scene = build(parse_case(case))
    result = cn.solve(scene, cn.Settings.of(scene.case.solver))
    assert result.converged
    box = scene.rigid[0].frame.nodes
    assert np.linalg.norm(result.v[box].mean(axis=0)) < 1e-6
