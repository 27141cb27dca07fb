"""Smoke tests of the benchmark studies and ``catenet bench`` (no timing assertions:
timings belong in the studies' output, not in tests)."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_bench_step_size_quick_writes_csv_figure_and_report(tmp_path):
    out = tmp_path / "results"
    docs = tmp_path / "docs"
    r = CliRunner().invoke(
        main, ["bench", "step-size", "report", "--quick", "-o", str(out), "--docs", str(docs)]
    )
    assert r.exit_code == 0, r.output
    rows = _rows(out / "step-size.csv")
    assert {"n", "h", "wall_seconds", "steps", "time_ratio", "error_vs_static"} <= set(rows[0])
    assert {row["n"] for row in rows} == {"10", "34"}
    # Every run that reached equilibrium agrees with the static solution.
    for row in rows:
        if row["equilibrium"] == "True":
            assert float(row["error_vs_static"]) < 1e-5
    assert (out / "bench-step-size.png").stat().st_size > 0
    assert (out / "machine.json").exists()
    text = (docs / "readme-performance.md").read_text()
    assert "Fig. B10" in text and "figures/bench-step-size.png" in text
    assert (docs / "figures" / "bench-step-size.png").exists()


def test_bench_rejects_an_unknown_study(tmp_path):
    r = CliRunner().invoke(main, ["bench", "nonsense", "-o", str(tmp_path)])
    assert r.exit_code == 2


def test_scale_study_runs_a_size_in_a_child_process(tmp_path):
    from catenet.studies.bench import scale

    study = scale.run(tmp_path, sizes=[(10, 1 / 30)])
    (row,) = study.rows
    assert row["converged"] and row["dofs"] > 500
    assert row["peak_rss_mib"] >= row["rss_after_import_mib"] > 0
    assert (tmp_path / "scale.csv").exists()


def test_baseline_reaches_catenets_equilibrium():
    """The plain NumPy/pypardiso baseline solves the same model to the same state."""
    pytest.importorskip("pypardiso")
    from catenet.solver.static import solve_static
    from catenet.studies.bench.baseline import baseline_static
    from catenet.studies.bench.common import paper_net

    sq, loads = paper_net(10, edge=0.05)
    net = sq.net
    ref = solve_static(net, loads, rtol=1e-10)
    x, info = baseline_static(
        net.nodes, net.edges, net.rest_length, net.EA, net.fixed, loads.external_force(net)
    )
    assert info["converged"]
    delta = -ref.x[sq.center, 2]
    assert np.max(np.abs(x - ref.x)) < 1e-6 * delta


def test_bench_solver_variants_give_the_same_answer():
    """The solver variants the studies time against catenet (re-analysing PARDISO,
    pypardiso.spsolve) solve to catenet's answer."""
    from catenet.solver.linear import pardiso_available
    from catenet.solver.static import Workspace, solve_static
    from catenet.studies.bench.common import paper_net
    from catenet.studies.bench.solvers import PypardisoSpsolve, ReanalysingPardiso, install

    sq, loads = paper_net(10, edge=0.05)
    ref = solve_static(sq.net, loads, linear="scipy")
    if not pardiso_available():
        pytest.skip("the variants are PARDISO's; MKL is not available on this machine")
    variants = [("pardiso", ReanalysingPardiso), ("pardiso", PypardisoSpsolve)]
    for linear, cls in variants:
        ws = install(Workspace(sq.net, linear=linear), cls)
        res = solve_static(sq.net, loads, workspace=ws)
        assert np.max(np.abs(res.x - ref.x)) < 1e-9
        if cls is ReanalysingPardiso:
            assert res.stats.analyse_count >= res.stats.factorize_count > 1


def test_pareto_front_marks_non_dominated_rows():
    from catenet.studies.bench.pareto import _front

    rows = [
        {"case": "a", "seconds": 1.0, "error": 1e-3},
        {"case": "a", "seconds": 2.0, "error": 1e-6},
        {"case": "a", "seconds": 3.0, "error": 1e-3},
        {"case": "b", "seconds": 9.0, "error": 1.0},
    ]
    _front(rows)
    assert [r["pareto"] for r in rows] == [True, True, False, True]


# --- start-up (issue 13): what catenet run reports and imports; the study's arithmetic ----


def test_catenet_run_reports_solve_and_startup_time_apart(write_case, tmp_path):
    """catenet run prints the solve time and the start-up time (imports, case, JIT cache)
    and stores them in /result; together they fit in the process's wall time, and the
    run imports neither pypardiso, scipy.sparse nor the studies."""
    import subprocess
    import sys
    import time

    import h5py
    from conftest import small_net, subprocess_env

    case = write_case(small_net(method="static"))
    out = tmp_path / "small.h5"
    code = (
        "import sys, runpy\n"
        "sys.argv = ['catenet', 'run', sys.argv[1], '-o', sys.argv[2]]\n"
        "try:\n"
        "    runpy.run_module('catenet', run_name='__main__')\n"
        "except SystemExit as exc:\n"
        "    heavy = sorted({m.split('.')[0] + ('.sparse' if m.startswith('scipy.sparse')"
        " else '') for m in sys.modules if m.startswith(('pypardiso', 'scipy.sparse',"
        " 'catenet.studies'))})\n"
        "    print('heavy:', heavy)\n"
        "    raise\n"
    )
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", code, str(case), str(out)],
        capture_output=True,
        text=True,
        env=subprocess_env(),
    )
    wall = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr
    assert "heavy: []" in proc.stdout
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("wall time"))
    assert "solve" in line and "start-up" in line and "JIT cache" in line
    with h5py.File(out, "r") as fh:
        a = fh["result"].attrs
        solve, startup = float(a["solve_time"]), float(a["startup_time"])
    assert 0 < solve and 0 < startup and solve + startup < wall


def test_clock_moves_jit_time_to_startup():
    """A kernel compiled inside the solve counts as start-up; writing is left out of the
    solve; without a solve block everything so far is start-up."""
    import numba

    from catenet.run.clock import Clock, since_process_start

    clock = Clock()
    assert clock.solve == 0.0 and clock.startup > 0.0

    @numba.njit
    def fresh(a):  # a new function: compiled on its first call
        return a + 1.0

    with clock.solving():
        assert fresh(1.0) == 2.0
        with clock.aside():
            sum(range(10_000))
    assert clock.jit > 0.0
    assert clock.startup >= clock.jit
    assert clock.solve < clock.jit  # the compile is not solving
    assert clock.startup <= since_process_start()


def test_cold_start_ratios_and_findings():
    """The study's ratios and its findings against the targets, from rows."""
    from catenet.studies.bench import cold_start as cs

    def row(command, cache, seconds, cpu):
        return {
            "command": command,
            "numba_cache": cache,
            "threads": "as installed",
            "seconds": seconds,
            "cpu_seconds": cpu,
            "runs": 3,
            "error": "",
        }

    rows = [
        row(cs.RUN, "empty (JIT compiles)", 2.5, 2.0),
        row(cs.RUN, "warm", 1.0, 0.8),
        row(cs.FLOOR, "", 0.8, 0.5),
        row(cs.PLAIN, "", 1.5, 1.0),
    ]
    cs._ratios(rows)
    assert rows[1]["ratio_to_floor"] == pytest.approx(1.25)
    assert rows[1]["ratio_to_plain"] == pytest.approx(1.0 / 1.5)
    study = cs.Study(cs.NAME, rows, None)
    cs._findings(rows, [], study)
    text = " ".join(study.findings)
    assert "empty Numba cache takes 2.50 s" in text
    assert "import floor" not in text and "plain script" not in text  # both within target
    rows[1]["seconds"] = 1.3
    cs._ratios(rows)
    study = cs.Study(cs.NAME, rows, None)
    cs._findings(rows, ["numpy"], study)
    text = " ".join(study.findings)
    assert "1.62x the import floor" in text and "0.87x the plain script" in text
    assert "catenet --help imports numpy" in text


def test_import_costs_sums_own_times_by_package(tmp_path):
    from catenet.studies.bench.cold_start import import_costs

    costs = dict(import_costs(["-c", "import json, email.message"], {}, str(tmp_path), top=50))
    assert costs["json"] > 0 and costs["email"] > 0
