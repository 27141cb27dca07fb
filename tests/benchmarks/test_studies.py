"""Smoke tests of the benchmark studies (``python -m benchmarks``) and of the renderer of
docs/performance.md (no timing assertions: timings belong in the studies' output, not in
tests)."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from benchmarks.__main__ import main

ROOT = Path(__file__).resolve().parents[2]


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_bench_step_size_quick_writes_csv_figure_and_report(tmp_path):
    out = tmp_path / "results"
    docs = tmp_path / "docs"
    docs.mkdir()
    page = docs / "performance.md"
    shutil.copy(ROOT / "docs" / "performance.md", page)
    r = CliRunner().invoke(
        main, ["step-size", "render", "--quick", "-q", "-o", str(out), "--docs", str(page)]
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
    text = page.read_text()
    assert "Fig. B10" in text and "figures/bench-step-size.png" in text
    assert (docs / "figures" / "bench-step-size.png").exists()
    # The step-size table is the quick run's (its sizes only); the others are kept.
    table = text.split("<!-- results:step-size -->")[1].split("<!-- /results:step-size -->")[0]
    assert "| 22 |" not in table and "| 34 |" in table and "| 10 |" in table
    assert text.count("<!-- results:") == (ROOT / "docs" / "performance.md").read_text().count(
        "<!-- results:"
    )


def test_the_performance_page_is_rendered_from_the_committed_results(tmp_path):
    """docs/performance.md's tables are what the renderer makes of benchmarks/results."""
    from benchmarks.render import FRAGMENTS, MARKER, render

    committed = (ROOT / "docs" / "performance.md").read_text()
    assert {m["name"] for m in MARKER.finditer(committed)} == set(FRAGMENTS)
    page = tmp_path / "performance.md"
    page.write_text(committed)
    assert render(ROOT / "benchmarks" / "results", page) == []
    assert page.read_text() == committed


def test_render_refuses_an_unknown_fragment_and_keeps_missing_ones(tmp_path):
    from benchmarks.render import render

    page = tmp_path / "p.md"
    page.write_text("a\n<!-- results:nonsense -->\nx\n<!-- /results:nonsense -->\n")
    with pytest.raises(ValueError, match="nonsense"):
        render(tmp_path, page)
    page.write_text("a\n<!-- results:stress -->\nold\n<!-- /results:stress -->\n")
    assert render(tmp_path, page) == ["stress"]  # no stress.csv in tmp_path
    assert "old" in page.read_text()


def test_bench_rejects_an_unknown_study(tmp_path):
    r = CliRunner().invoke(main, ["nonsense", "-o", str(tmp_path)])
    assert r.exit_code == 2


def test_scale_study_runs_a_size_in_a_child_process(tmp_path):
    from benchmarks import scale

    study = scale.run(tmp_path, sizes=[(10, 1 / 30)])
    (row,) = study.rows
    assert row["converged"] and row["dofs"] > 500
    assert row["peak_rss_mib"] >= row["rss_after_import_mib"] > 0
    assert (tmp_path / "scale.csv").exists()


def test_baseline_reaches_catenets_equilibrium():
    """The plain NumPy/pypardiso baseline solves the same model to the same state."""
    pytest.importorskip("pypardiso")
    from scenes import paper_net

    from benchmarks.baseline import baseline_static
    from catenet.solver.static import solve_static

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
    from scenes import paper_net

    from benchmarks.solvers import PypardisoSpsolve, ReanalysingPardiso, install
    from catenet.solver.linear import pardiso_available
    from catenet.solver.static import Workspace, solve_static

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
    from benchmarks.pareto import _front

    rows = [
        {"case": "a", "seconds": 1.0, "error": 1e-3},
        {"case": "a", "seconds": 2.0, "error": 1e-6},
        {"case": "a", "seconds": 3.0, "error": 1e-3},
        {"case": "b", "seconds": 9.0, "error": 1.0},
    ]
    _front(rows)
    assert [r["pareto"] for r in rows] == [True, True, False, True]


# --- the cold-start study's arithmetic -------------------------------------------------


def test_cold_start_ratios_and_findings():
    """The study's ratios and its findings against the targets, from rows."""
    from benchmarks import cold_start as cs

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
    from benchmarks.cold_start import import_costs

    costs = dict(import_costs(["-c", "import json, email.message"], {}, str(tmp_path), top=50))
    assert costs["json"] > 0 and costs["email"] > 0


def test_tabulate_writes_the_table_the_figure_and_a_line_per_row(tmp_path):
    from benchmarks.common import Study, read_csv, tabulate

    rows = [{"n": 10, "seconds": 0.5}, {"n": 34, "seconds": 2.0, "note": "capped"}]
    drawn = []

    def figure(rows_, out_dir):
        drawn.append((rows_, out_dir))
        return out_dir / "bench-t.png"

    study = Study("t", rows, tmp_path / "t.csv")
    study.summary.append("first")
    got = tabulate(study, tmp_path, figure, lambda r: None if r["n"] == 10 else f"n = {r['n']}")
    assert got is study and study.figure == tmp_path / "bench-t.png"
    assert drawn == [(rows, tmp_path)]
    assert study.summary == ["first", "n = 34"]
    assert read_csv(study.csv) == [
        {"n": "10", "seconds": "0.5", "note": ""},
        {"n": "34", "seconds": "2", "note": "capped"},
    ]


def test_the_drop_study_measures_one_run():
    """benchmarks/drop.py's run of one integrator at one step: the box thrown back up, the
    counts and the energy shares of its balance (the study's rows)."""
    from benchmarks.drop import drop

    row = drop("bdf2", None, 1e-2)
    assert row["scheme"] == "bdf2" and row["converged"] and row["steps"] == 40
    assert 15.5 < row["momentum"] < 16.8  # the fine-step answer 16.2 +- 0.1 (docs/performance.md)
    assert row["created"] <= 1e-9 < row["lost"] < 0.2


def test_the_accuracy_study_measures_one_run():
    """benchmarks/accuracy.py's run of the drop at fixed bdf2 steps of 10 ms: the box's
    momentum as benchmarks/drop.py measures it (16.29 kg m/s), its counts."""
    from benchmarks.accuracy import once

    row = once("drop", 1e-2)
    assert row["run"] == "bdf2 fixed" and row["steps"] == 40 and row["h"] == 1e-2
    assert abs(row["value"] - 16.29) < 0.05
