"""Steps chosen by accuracy end on every corner of a prescribed history (a point of a load's
or a motion's history, of a vessel's motion table, the end of a support's ramp): a step
across one takes the load at its end only, and a pulse between two step ends is stepped
over whole (catenet/solver/adaptive.py, ``corners``). Fixed steps longer than a piece of a
history are warned before the run (catenet/run/history_advice.py)."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

from catenet.model.histories import History
from catenet.model.motions import Vessel, corners
from catenet.model.net import Loads
from catenet.terms.body import Path
from tests.solver.test_energy import invoke, write

G, MASS, LENGTH = 9.81, 10.0, 2.0
PEAK, RISE = 1000.0, 0.01  # [N], [s]: a triangle of 1000 N over 20 ms, 10 N s


def struck(solver: dict) -> dict:
    """A 10 kg weight hanging at rest on a stiff 2 m bar, struck sideways at t = 1 s by a
    force pulse of 20 ms."""
    return {
        "geometry": {"kind": "graph", "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, -LENGTH]],
                     "edges": [[0, 1]], "fixed": [0]},
        "material": {"EA": 1e6, "area": 1e-5, "density": 1000.0},
        "load": {"gravity": [0.0, 0.0, -G],
                 "point": [{"node": 1, "force": [PEAK, 0.0, 0.0],
                            "history": [[0.0, 0.0], [1.0, 0.0], [1.0 + RISE, 1.0],
                                        [1.0 + 2 * RISE, 0.0]]}]},
        "mass": [{"node": 1, "mass": MASS}],
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "t_end": 3.0,
                   "damping": 0.0, **solver},
    }  # fmt: skip


def swing() -> float:
    """The pendulum's largest distance from where it hung, 2 L sin(theta / 2), after the
    pulse's impulse (PEAK RISE) gives it v0: cos theta = 1 - v0^2 / (2 g L) (its bar's
    mass, 0.02 kg, half at the weight)."""
    mass = MASS + 0.5 * 1e-5 * 1000.0 * LENGTH
    length = LENGTH * (1.0 + mass * G / 1e6)  # stretched by the weight
    v0 = PEAK * RISE / mass
    theta = math.acos(1.0 - v0 * v0 / (2.0 * G * length))
    return 2.0 * length * math.sin(0.5 * theta)


def largest_move(path) -> float:
    with h5py.File(path, "r") as f:
        x = f["trajectory/x"][()]
    return float(np.max(np.linalg.norm(x[:, 1] - x[0, 1], axis=1)))


def test_a_pulse_between_two_step_ends_is_landed_on(tmp_path):
    """At the default (no dt: steps chosen by accuracy), the steps land on the pulse's three
    points and the weight swings out to the closed form within 1 % (0.2 % measured).
    Before, the steps had grown to 0.3 s while the weight hung still, stepped over the
    pulse, and the weight never moved: "converged", exit 0."""
    case = write(tmp_path, struck({}), "struck")
    out = tmp_path / "struck.h5"
    result = invoke("run", case, "-o", out)
    assert result.exit_code == 0, result.output
    assert largest_move(out) == pytest.approx(swing(), rel=1e-2)


def test_a_pulse_from_rest_gives_its_impulse_however_long_the_rest(tmp_path):
    """A 50 N pulse (0.5 N s) on the hanging weight, after 1 s at rest: its speed after
    the pulse is the impulse over its mass within 0.2 %. The steps had grown over the
    rest, so the pulse's rising 10 ms was one step, which takes its load at its end: the
    rising half's impulse twice (2.2 % fast here; a string struck so rang 41 % too far).
    A load history's changing pieces are taken in RAMP_STEPS steps or more now."""
    data = struck({})
    data["load"]["point"][0]["force"] = [50.0, 0.0, 0.0]
    case = write(tmp_path, data, "small")
    out = tmp_path / "small.h5"
    result = invoke("run", case, "-o", out)
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        t, v = f["trajectory/time"][()], f["trajectory/v"][()]
    after = int(np.searchsorted(t, 1.0 + 2 * RISE + 1e-3))
    mass = MASS + 0.5 * 1e-5 * 1000.0 * LENGTH
    assert v[after, 1, 0] == pytest.approx(50.0 * RISE / mass, rel=2e-3)


def test_a_pulses_steps_keep_to_dt_min(tmp_path):
    """The pulse's 16 steps a rise are never shorter than solver.dt_min = 4 ms: the 20
    ms pulse takes 6 steps (landing on its three points), not 56 of 0.26 ms."""
    solver = {"dt": 0.005, "dt_min": 0.004, "tolerance": 1e-3, "t_end": 1.2}
    case = write(tmp_path, struck(solver), "dtmin")
    out = tmp_path / "dtmin.h5"
    result = invoke("run", case, "-o", out, "--set", "output.every=1")
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        t = f["trajectory/time"][()]
    inside = (t[1:] > 1.0) & (t[1:] <= 1.0 + 2 * RISE + 1e-12)
    assert 3 <= int(np.count_nonzero(inside)) <= 8


def test_a_records_small_changes_take_few_steps():
    """A load history's piece takes RAMP_STEPS steps where it changes the load by its
    whole range, in proportion fewer where it changes it less (a sampled record)."""
    from catenet.solver.adaptive import ErrorControl

    control = ErrorControl(0.0, 1.0, order=2)
    control.ramps = np.array([[0.0, 0.16, 1.0], [0.16, 0.32, 0.125]])
    assert control._ramp(0.05) == pytest.approx(0.01)  # 16 steps over the whole range
    assert control._ramp(0.2) == pytest.approx(0.08)  # 2 over an eighth of it


def test_fixed_steps_longer_than_a_piece_of_a_history_are_warned(tmp_path):
    """At fixed 50 ms steps the pulse falls between two step ends: the run is warned before
    it runs, with the history's key path, its two points and a dt that resolves them; at
    5 ms it is not, and the weight swings within 2 % of the closed form."""
    case = write(tmp_path, struck({"dt": 0.05}), "coarse")
    result = invoke("run", case, "-o", tmp_path / "coarse.h5")
    assert result.exit_code == 0, result.output
    assert "load.point[0].history: its points at t = 1 and 1.01 s" in result.output
    assert "solver.dt <= 0.01 s" in result.output
    case = write(tmp_path, struck({"dt": 0.005}), "fine")
    out = tmp_path / "fine.h5"
    result = invoke("run", case, "-o", out)
    assert result.exit_code == 0 and "apart, less than solver.dt" not in result.output, (
        result.output
    )
    assert largest_move(out) == pytest.approx(swing(), rel=2e-2)


def test_the_corners_of_loads_and_prescribed_paths():
    """motions.corners: every point of a force's, gravity's or a support's history, of a
    vessel's motion table, and a support ramp's end; a ball's or obstacle's path: its
    history's points."""
    force = np.zeros((2, 3))
    loads = Loads(
        gravity=np.array([0.0, 0.0, -G]),
        gravity_history=History([[0.0, 0.0], [0.5, 1.0]]),
        parts=((force, History([[1.0, 0.0], [1.2, 1.0]])),),
        support_displacement=np.ones((2, 3)),
        ramp_time=np.array([0.0, 2.0]),
        vessels=((np.array([0]), Vessel([0.0, 0.0, 0.0], table=[[3.0] + [0.0] * 6,
                                                                 [4.0] + [1.0] * 6])),),
    )  # fmt: skip
    assert corners(loads).tolist() == [0.0, 0.5, 1.0, 1.2, 2.0, 3.0, 4.0]
    assert corners(Loads()).tolist() == []
    path = Path([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], History([[0.0, 1.0], [0.7, 0.0]]))
    assert path.corners() == (0.0, 0.7)
    assert Path([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]).corners() == ()


def test_a_sine_motion_at_too_few_fixed_steps_a_period_is_warned():
    """A support's or a vessel's sine at fewer than PER_PERIOD fixed steps a period is
    warned with its key path and a dt that follows it; steps chosen by accuracy are not."""
    from catenet.case import parse_case
    from catenet.run.history_advice import PER_PERIOD, stepped_over

    case = struck({"dt": 0.05})
    del case["load"]["point"]
    case["supports"] = {
        "move": [{"node": 0, "sine": {"amplitude": [0.1, 0.0, 0.0], "period": 0.3}}]
    }
    (message,) = stepped_over(parse_case(case))
    assert message.startswith("supports.move[0].sine.period = 0.3 s: 6 steps")
    assert f"solver.dt <= {0.3 / PER_PERIOD:.3g} s" in message
    case["solver"]["dt"] = 0.03
    assert stepped_over(parse_case(case)) == []
    del case["solver"]["dt"]
    assert stepped_over(parse_case(case)) == []  # steps chosen by accuracy


def test_a_weight_whose_support_is_lifted_through_a_dashpot_at_every_tolerance(tmp_path):
    """A 20 kg weight hung at rest from its static equilibrium on a 2 m cord with a
    dashpot (c = 141.4 N s, about 5 % of critical), its support lifted 5 mm between t =
    0.2 and 0.3 s and held: the support's speed jumps at both corners, and with it the
    dashpot's pull. At the default, 1e-3 and 3e-4 the run ends (exit 0) and the largest
    support reaction, weight and dashpot, within 0.5 % of the exact one in its dynamic
    part (0.1 to 0.2 % measured). Before, at 1e-3 the steps after the first corner
    shrank to round-off and the run failed ("a body spun beyond what dt resolves"):
    the weight's momentum error was measured against the round-off scale of a body at
    rest (``Bodies.driven``), and bdf2 gave the support a third of its speed after it
    had stopped (``BDF2.corner``)."""
    from scipy.integrate import solve_ivp

    ea, l0, c, lift = 5e4, 2.0, 141.4, 0.005
    area = math.pi * 0.002**2
    m = 20.0 + 0.5 * 975.0 * area * l0  # the weight and half the cord
    k, ce = ea / l0, c / l0

    def support(t):  # lifted (up) and its speed
        return lift * np.interp(t, [0.2, 0.3], [0.0, 1.0]), (lift / 0.1 if 0.2 < t < 0.3 else 0)

    def motion(t, z):  # z: the weight's rise from rest and its speed
        y, dy = support(t)
        return [z[1], (k * (y - z[0]) + ce * (dy - z[1])) / m]

    peak, z = 0.0, [0.0, 0.0]
    for a, b in ((0.0, 0.2), (0.2, 0.3), (0.3, 1.2)):
        s = solve_ivp(motion, (a, b), z, rtol=1e-11, atol=1e-14, dense_output=True)
        t = np.linspace(a, b, 20001)
        y, dy = np.array([support(q) for q in t]).T
        u, du = s.sol(t)
        peak = max(peak, float(np.max(k * (y - u) + ce * (dy - du))))
        z = s.y[:, -1]
    case = {
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [0.0, 0.0, -l0],
                     "nodes": 2},
        "supports": {"fixed": ["start"],
                     "move": [{"node": "start", "displacement": [0.0, 0.0, lift],
                               "history": [[0.0, 0.0], [0.2, 0.0], [0.3, 1.0]]}]},
        "material": {"EA": ea, "radius": 0.002, "density": 975.0, "axial_damping": c},
        "mass": [{"node": "end", "mass": 20.0}],
        "load": {"gravity": [0.0, 0.0, -G]},
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "damping": 0.0,
                   "t_end": 1.2},
    }  # fmt: skip
    for tolerance in (None, 1e-3, 3e-4):
        if tolerance is not None:
            case["solver"]["tolerance"] = tolerance
        path = write(tmp_path, case, "lifted")
        out = tmp_path / "lifted.h5"
        result = invoke("run", path, "-o", out)
        assert result.exit_code == 0, (tolerance, result.output)
        with h5py.File(out, "r") as f:
            held = f["history/reaction"][:, 0, 2]
        assert float(np.max(held)) - m * G == pytest.approx(peak, rel=5e-3), tolerance


def test_a_taut_wire_shaken_at_one_end_follows_the_sine(tmp_path):
    """A 3 m steel wire (1 mm, 500 N) in 10 edges, one end shaken across by 0.5 mm at
    1.5 times its first frequency, mass damping 20 1/s: at the default (no dt) its
    midspan's steady amplitude within 1 % of the chain's exact steady state (0.4 %
    measured). Its response is too small against its size for the error estimate to
    see: the steps grew to 30 periods, sampled the sine and gave it 64 % low (31 nodes);
    they now follow the sine at SINE_STEPS a period (catenet/solver/adaptive.py)."""
    count, tension, length, amplitude, mu = 11, 500.0, 3.0, 5e-4, 20.0
    a = length / (count - 1)
    line = 7850.0 * math.pi * 0.0005**2
    m, n = line * a, count - 2
    omega1 = 2.0 * math.sqrt(tension / (m * a)) * math.sin(math.pi / (2 * (n + 1)))
    omega = 1.5 * omega1
    case = {
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [length, 0.0, 0.0],
                     "nodes": count},
        "material": {"E": 2e11, "radius": 0.0005, "density": 7850.0, "prestress": tension},
        "supports": {"move": [{"node": "start", "sine": {
            "amplitude": [0.0, amplitude, 0.0], "period": 2.0 * math.pi / omega}}]},
        "solver": {"method": "dynamic", "damping": mu, "t_end": 0.6},
    }  # fmt: skip
    path = write(tmp_path, case, "shaken")
    out = tmp_path / "shaken.h5"
    result = invoke("run", path, "-o", out)
    assert result.exit_code == 0, result.output
    stiff = (tension / a) * (2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1))
    drive = np.zeros(n)
    drive[0] = tension / a * amplitude
    exact = np.linalg.solve(stiff - (omega**2 - 1j * omega * mu) * m * np.eye(n), drive)
    mid = (count - 1) // 2
    with h5py.File(out, "r") as f:
        t, y = f["trajectory/time"][()], f["trajectory/x"][:, mid, 1]
    late = t > 0.42  # the start's transient gone (e^(-mu t / 2))
    fit = np.column_stack([np.sin(omega * t[late]), np.cos(omega * t[late]), np.ones(late.sum())])
    sine, cosine, _ = np.linalg.lstsq(fit, y[late], rcond=None)[0]
    assert math.hypot(sine, cosine) == pytest.approx(abs(exact[mid - 1]), rel=1e-2)


def test_a_load_gone_at_a_historys_end_is_no_load_left_over(tmp_path):
    """A small roof net under a gust (rising over 0.5 s, held, gone at 1.6 s) at fixed bdf2
    steps of 5 ms: the step landed on the gust's end left 1e-14 N of its 100 N (the time's
    round-off), and the net's own forces' round-off above that stopped the run as "a
    body spun beyond what dt resolves". A load below the round-off of the largest one
    so far is none: the run ends at t_end."""
    case = {
        "title": "a small roof net under a gust",
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.0, "size": 1.0,
                     "edge_length": 0.05},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"pressure": 100.0,
                 "history": [[0.0, 0.0], [0.5, 1.0], [1.5, 1.0], [1.6, 0.0]]},
        "solver": {"method": "dynamic", "t_end": 1.61, "damping": 1.0, "dt": 5e-3,
                   "integrator": "bdf2"},
    }  # fmt: skip
    done = invoke("run", write(tmp_path, case), "-o", tmp_path / "gust.h5")
    assert done.exit_code == 0, done.output
    assert "reached t_end" in done.output
