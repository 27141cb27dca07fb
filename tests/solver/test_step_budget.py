"""``solver.max_iter`` in a dynamic run: the Newton iterations of one time step (25 when
not given; a static solve's 200), a step they do not solve halved. Before, a dynamic run
warned that the key was ignored, while its failure message advised a larger one."""

from __future__ import annotations

import h5py
import numpy as np
from click.testing import CliRunner

from catenet.cli import main
from catenet.solver.settings import STATIC_MAX_ITER, STEP_MAX_ITER, Settings

WIRE = """
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [80, 0, 10]
length = 84
nodes = 41
[material]
E = 160e9
radius = 0.012
density = 7850
[load]
gravity = [0, 0, -9.81]
[solver]
method = "dynamic"
"""


def test_the_budgets_of_a_static_solve_and_a_time_step():
    assert Settings().static_iterations == STATIC_MAX_ITER == 200
    assert Settings(method="dynamic").step_iterations == STEP_MAX_ITER == 25
    given = Settings(method="dynamic", max_iter=60)
    assert given.step_iterations == given.static_iterations == 60


def test_a_larger_budget_lets_a_relaxation_take_longer_steps(tmp_path):
    """A hanging steel wire relaxed to rest from straight: at 25 iterations a step, steps
    are cut (32 steps, 396 iterations, the way down overshooting to twice the final
    tension); at 100, longer steps converge (22 steps, 162 iterations); the same rest."""
    case = tmp_path / "wire.toml"
    case.write_text(WIRE)
    seen = {}
    for budget in (None, 100):
        out = tmp_path / f"r{budget}.h5"
        sets = [] if budget is None else ["--set", f"solver.max_iter={budget}"]
        done = CliRunner().invoke(main, ["run", str(case), "-o", str(out), *sets])
        assert done.exit_code == 0, done.output
        assert "ignored" not in done.output
        with h5py.File(out) as f:
            seen[budget] = (len(f["trajectory/time"]), f["result/tension"][()])
    assert seen[100][0] < seen[None][0]
    assert np.allclose(seen[100][1], seen[None][1], rtol=1e-6)


def test_a_step_that_its_budget_cannot_solve_names_the_budget(tmp_path):
    """A wire rope on a running belt with 2 Newton iterations a step: the step fails down
    to the smallest step, and the message names solver.max_iter as what bounds it."""
    from tests.terms.test_moving_stays import BELT

    case = tmp_path / "belt.toml"
    case.write_text(BELT)
    done = CliRunner().invoke(
        main, ["run", str(case), "-o", str(tmp_path / "r.h5"), "--set", "solver.max_iter=2"]
    )
    assert done.exit_code == 1, done.output
    assert "no convergence in 2 iterations (solver.max_iter = 2 bounds each time step" in (
        done.output
    )
