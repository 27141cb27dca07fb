"""A dynamic run whose integrator removes much of the energy on its own says so: the
box of benchmarks/peers/mujoco_drop.toml dropped onto the net, at the default 10 ms
steps, leaves with half its momentum under implicit Euler (49 % of the energy gone) and
within 1 % under bdf2 (``catenet.run.integrator_advice.integrator_loss``)."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from catenet.case import load_case
from catenet.run import integrator_advice as advice
from catenet.run.runner import run_case

DROP = Path(__file__).parents[2] / "benchmarks" / "peers" / "mujoco_drop.toml"


@pytest.mark.parametrize("integrator, warned", [("implicit_euler", True), ("bdf2", False)])
def test_the_integrators_own_loss_is_named(integrator, warned, caplog, tmp_path):
    case = load_case(DROP, [f"solver.integrator={integrator}", "solver.t_end=0.3"])
    with caplog.at_level(logging.WARNING):
        result = run_case(case, tmp_path / "drop.h5")  # not the case's own out/ file
    lost = -float(result.energy[-1]) / result.energy_scale
    said = [r.getMessage() for r in caplog.records if "on its own" in r.getMessage()]
    assert (lost > advice.LOSS_WARN) == warned
    assert bool(said) == warned
    if warned:
        assert f"{lost:.0%}" in said[0] and "'bdf2'" in said[0] and "solver.dt = 0.01" in said[0]


def test_a_run_to_rest_is_not_warned(tmp_path):
    """Dynamic relaxation removes the energy on purpose: no warning."""
    case = load_case(DROP, ["solver.t_end=rest", "solver.damping=5.0"])
    assert case.solver.t_end == "rest"
    assert advice.integrator_loss(case, run_case(case, tmp_path / "rest.h5")) is None


def test_a_damped_transient_is_warned_and_a_damped_relaxation_is_not(caplog, tmp_path):
    """A 100 kg mass let go on an unstretched 3 m rope (no contact, the default damping
    1/s and 10 ms implicit Euler steps) to t = 1 s: the integrator took 26 % of the
    energy on its own, the peak tension 18 % short of 2 m g, and nothing was said (the
    paper's damped runs were exempt); a damped run that comes to rest before its t_end
    (the paper's damping study, configs/damping_mu1.toml) is relaxation, not warned."""
    rope = {
        "title": "a mass let go on a rope",
        "geometry": {"kind": "graph", "nodes": [[0, 0, 0], [0, 0, -3.0]], "edges": [[0, 1]],
                     "fixed": [0]},
        "material": {"EA": 2e5, "radius": 0.006, "density": 1140.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "mass": [{"node": 1, "mass": 100.0}],
        "solver": {"method": "dynamic", "t_end": 1.0},
    }  # fmt: skip
    from catenet.case import parse_case

    case = parse_case(rope)
    assert case.solver.damping > 0 and case.solver.integrator == "implicit_euler"
    said = advice.integrator_loss(case, run_case(case, tmp_path / "rope.h5"))
    assert said is not None and "removed 26%" in said and "solver.dt = 0.01 s" in said
    study = load_case(Path(__file__).parents[2] / "configs" / "damping_mu1.toml", [])
    assert advice.integrator_loss(study, run_case(study, tmp_path / "study.h5")) is None


def pulled_chain(tolerance: float) -> dict:
    """A 300 m chain in 50 m of water, its fairlead pulled 3 m over 8 s then held, to
    t = 12 s (its steps chosen by accuracy: no dt)."""
    return {
        "title": "a chain pulled by its fairlead",
        "geometry": {"kind": "graph", "nodes": [[-275.0, 0.0, -49.99], [-120.0, 0.0, -49.99],
                     [-60.0, 0.0, -40.0], [0.0, 0.0, -5.0]], "edge_length": 5.0,
                     "sets": {"anchor": [0], "fairlead": [3]},
                     "cable": [{"name": "chain", "nodes": [0, 1, 2, 3]}]},
        "supports": {"fixed": ["anchor", "fairlead"], "move": [{"node": "fairlead",
                     "displacement": [3.0, 0.0, 0.0], "history": [[0.0, 0.0], [8.0, 1.0]]}]},
        "material": {"EA": 3.0e8, "area": 0.0082, "density": 7850.0, "hydro_diameter": 0.103,
                     "cd_n": 1.33, "cd_t": 0.64, "ca_n": 1.0, "ca_t": 0.5},
        "water": {"density": 1025.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, -50.0], "distance": 0.01}],
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "t_end": 12.0,
                   "tolerance": tolerance},
    }  # fmt: skip


def test_a_loss_of_the_motions_energy_is_warned(tmp_path):
    """The chain's motion after its fairlead stops holds a small share of the run's
    largest energy (its weight and stretch): at the default tolerance the integrator
    took half its largest kinetic energy (51 %, and under LOSS_WARN of the largest
    energy) and its peak tension came out 248 kN, 10 % below 1e-4's 275 kN (to 40 s,
    the newcomer's run: 249 kN against 271 kN at 3e-5); warned. At 1e-4 the loss is
    3.7 % of the kinetic energy: not warned."""
    from catenet.case import parse_case

    runs = {}
    for tolerance in (3e-3, 1e-4):
        case = parse_case(pulled_chain(tolerance))
        result = run_case(case, tmp_path / f"chain{tolerance:g}.h5")
        runs[tolerance] = (advice.integrator_loss(case, result), result)
    said, coarse = runs[3e-3]
    lost = -float(coarse.energy[-1])
    assert lost < advice.LOSS_WARN * coarse.energy_scale
    assert lost > advice.MOTION_WARN * coarse.energy_motion
    assert said is not None and "of the motion's largest kinetic energy" in said
    quiet, fine = runs[1e-4]
    assert quiet is None
    assert coarse.peaks is not None and fine.peaks is not None
    assert coarse.peaks.tension.max() < 0.95 * fine.peaks.tension.max()
