"""``catenet bench``: the check a user runs on their own machine writes only where -o says."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

from conftest import subprocess_env


def test_bench_measures_the_warm_solve_backend_threads_and_cold_start(tmp_path):
    work = tmp_path / "cwd"
    work.mkdir()
    out = tmp_path / "bench"
    proc = subprocess.run(
        [sys.executable, "-m", "catenet", "bench", "-o", str(out), "--repeats", "2"],
        cwd=work,
        capture_output=True,
        text=True,
        env=subprocess_env(),
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in out.iterdir()) == ["bench.csv", "bench.json"]
    assert list(work.iterdir()) == []  # nothing written where it was run
    with open(out / "bench.csv", newline="") as fh:
        rows = {r["name"]: r for r in csv.DictReader(fh)}
    assert rows["backend"]["value"] in ("pardiso", "scipy")
    assert rows["converged"]["value"] == "True"
    assert int(rows["dofs"]["value"]) > 9000 and int(rows["newton_iterations"]["value"]) > 0
    for name in ("solve_median", "solve_min", "cold_help", "cold_run"):
        assert float(rows[name]["value"]) > 0 and rows[name]["unit"] == "s"
    assert float(rows["solve_min"]["value"]) <= float(rows["solve_median"]["value"])
    assert int(rows["numba_threads"]["value"]) >= 1
    data = json.loads((out / "bench.json").read_text())
    assert data["machine"]["cores"] >= 1
    assert [m["name"] for m in data["measures"]] == list(rows)
    assert "solve_median" in proc.stdout and "written:" in proc.stdout


def test_bench_needs_an_output_directory():
    proc = subprocess.run(
        [sys.executable, "-m", "catenet", "bench"],
        capture_output=True,
        text=True,
        env=subprocess_env(),
    )
    assert proc.returncode == 2 and "-o" in proc.stderr
