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
    from catenet.static import solve_static
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
    from catenet.linsolve import pardiso_available
    from catenet.static import Workspace, solve_static
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
            assert res.stats["analyse_count"] >= res.stats["factorize_count"] > 1


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
