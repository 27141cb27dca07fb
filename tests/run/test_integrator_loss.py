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
