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
from catenet.model.motions import Vessel
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
    points and the weight swings out to the closed form within 1 % (0.4 % measured).
    Before, the steps had grown to 0.3 s while the weight hung still, stepped over the
    pulse, and the weight never moved: "converged", exit 0."""
    case = write(tmp_path, struck({}), "struck")
    out = tmp_path / "struck.h5"
    result = invoke("run", case, "-o", out)
    assert result.exit_code == 0, result.output
    assert largest_move(out) == pytest.approx(swing(), rel=1e-2)


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
    assert result.exit_code == 0 and "history" not in result.output, result.output
    assert largest_move(out) == pytest.approx(swing(), rel=2e-2)


def test_the_corners_of_loads_and_prescribed_paths():
    """Loads.corners: every point of a force's, gravity's or a support's history, of a
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
    assert loads.corners().tolist() == [0.0, 0.5, 1.0, 1.2, 2.0, 3.0, 4.0]
    assert Loads().corners().tolist() == []
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
