"""``solver.max_iter`` in a dynamic run: the Newton iterations of one time step (25 when
not given; a static solve's 200), a step they do not solve halved; not given, at fixed
steps to a time, a step still converging at 25 goes on, up to 100. Before, a dynamic run warned
that the key was ignored, while its failure message advised a larger one."""

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
    from catenet.solver.newton import EXTEND
    from catenet.solver.settings import MAX_ITER_SHOWN

    assert Settings().static_iterations == STATIC_MAX_ITER == 200
    assert f"up to {EXTEND} times that" in MAX_ITER_SHOWN  # (the case keys' table)
    assert STEP_MAX_ITER == 25  # a time step's (``solve_dynamic``, max_iter not given)
    given = Settings(method="dynamic", max_iter=60)
    assert given.max_iter == given.static_iterations == 60  # given: every solve's


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


def test_a_step_still_converging_at_its_budget_goes_on(monkeypatch):
    """A light stiff net thrown onto a box at 10 ms steps, unguarded (its Newton takes up
    the slack cords a ring per iteration, its residual falling slowly): held to 25
    iterations a step, its steps are cut (16 steps, 243 iterations when measured); with
    the budget not given, a step still converging at 25 goes on (12 steps, 158), no
    solve beyond 100 iterations. A 101 x 101 net of the same kind at 10 ms to 0.03 s:
    1303 iterations in 58 steps, cut to 39 us, and 331 in 8."""
    from catenet.solver import newton
    from catenet.solver.path import solve
    from tests.solver.test_safeguarded_newton import thrown

    monkeypatch.setattr(newton, "SAFEGUARD_ALPHA", 0.0)  # never safeguarded
    counts = []
    original = newton._Newton.verdict

    def verdict(run):
        reason = original(run)
        if reason is not None:
            counts.append(run.it)
        return reason

    monkeypatch.setattr(newton._Newton, "verdict", verdict)
    scene = thrown()
    goes_on = solve(scene, Settings.of(scene.case.solver))
    assert max(counts) > STEP_MAX_ITER and max(counts) <= 4 * STEP_MAX_ITER
    counts.clear()
    held = solve(scene, Settings.of(scene.case.solver, max_iter=STEP_MAX_ITER))
    assert max(counts) == STEP_MAX_ITER  # given: a hard budget
    assert goes_on.converged and held.converged
    assert goes_on.steps < held.steps and goes_on.iterations < held.iterations


def test_a_run_to_rest_keeps_its_budget(monkeypatch):
    """Dynamic relaxation to rest (its steps a way to the equilibrium), steps chosen by
    accuracy (planned anew after a cut) and a given max_iter keep the budget as it is;
    only fixed steps to a time with the default go on."""
    import tomllib

    from catenet.case import build, parse_case
    from catenet.solver import stepper
    from catenet.solver.path import solve

    seen = []
    original = stepper.solve_newton

    def spy(*args, **kwargs):
        seen.append(kwargs.get("extend", False))
        return original(*args, **kwargs)

    monkeypatch.setattr(stepper, "solve_newton", spy)
    raw = tomllib.loads(WIRE)
    runs = [("rest", None, None, False), (2.0, None, None, True), (2.0, 25, None, False)]
    runs.append((2.0, None, 1e-3, False))
    for t_end, budget, tolerance, extends in runs:
        seen.clear()
        raw["solver"] = {"method": "dynamic", "t_end": t_end, "dt": 0.05, "damping": 2.0}
        if budget is not None:
            raw["solver"]["max_iter"] = budget
        if tolerance is not None:
            raw["solver"]["tolerance"] = tolerance
        scene = build(parse_case(raw))
        solve(scene, Settings.of(scene.case.solver))
        assert seen and set(seen) == {extends}


def _course(history: list[float], it: int | None = None):
    from catenet.solver.newton import _Newton

    run = object.__new__(_Newton)
    run.history, run.max_iter = history, 25
    run.it = len(history) - 1 if it is None else it
    return run.on_course()


def test_a_residual_that_bumps_on_its_way_down_is_still_on_course():
    """Past its budget a solve goes on while its best residual of the last five accepted
    steps is 3 % below its best before them. A minimiser of Phi need not lower |grad Phi|
    at every step: at the 101 x 101 net's first contact at 10 ms the residual fell from
    3838 to 1906 N and then rose to 4959 N on one extrapolated step (Phi still falling),
    which the rule on the last step alone took for a stall and cut; with the later cuts,
    960 Newton iterations in 29 steps to 0.05 s, against 208 in 7 judged by the best. A
    solve that creeps is still cut."""
    down = [1e4 * 0.9**k for k in range(30)]
    assert _course(down)
    bumped = down[:-1] + [3.0 * down[-7]]  # the last step above the one five before
    assert bumped[-1] > bumped[-6]
    assert _course(bumped)
    creeping = [1e4 * 0.998**k for k in range(30)]  # 1 % over five steps
    assert not _course(creeping)
    stuck = down[:24] + [down[23] * (1.0 + 0.01 * k) for k in range(1, 7)]
    assert not _course(stuck)  # no new best in the last five: cut
    assert not _course(down, it=100)  # never past 4 times the budget
