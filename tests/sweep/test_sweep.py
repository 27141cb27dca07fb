"""catenet sweep: value parsing, parallel and Dask runs against single solves, resume,
worker crashes, the scaling-law fit, figures and the command line.

The small sweep: n = 10, alpha in {0, pi/4}, p in {10, 100} Pa, edge length 0.05 (225
nodes) and rtol = 1e-11, so that a continuation step and a solve from the flat net agree
to round-off (at the default rtol = 1e-8 they differ by ~1e-10 m, the Newton tolerance).
"""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from catenet import sweep as sw
from catenet.cli.sweep import command as sweep_command
from catenet.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "sweeps" / "paper.toml"

BASE = """
title = "small square net"

[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 1.0
edge_length = 0.05

[material]
E = 10e6
radius = 0.01
tension_only = true

[load]
pressure = 100.0

[solver]
method = "static"
rtol = 1e-11
"""

SMALL = (
    BASE
    + """
[sweep]
geometry.alpha = [0.0, "pi/4"]
load.pressure = [10, 100]
"""
)


@pytest.fixture(scope="module")
def small_case(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("case") / "small.toml"
    path.write_text(SMALL)
    return path


def read_csv(directory: Path) -> list[dict]:
    keys, columns, table = sw.read_table(directory)
    # read_table reads the journal; check the CSV written from it agrees
    import csv

    with (directory / sw.CSV_FILE).open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(table["delta"])
    assert list(rows[0]) == columns if rows else True
    return rows


def reference_rows(case_path: Path) -> list[tuple[int, float, float, float, float]]:
    """(n, alpha, p, delta, max_strain) of every case by its own solve_static from the
    flat net, in this process."""
    import tomllib

    from catenet.case import apply_overrides, build, parse_case
    from catenet.solver.static import solve_static

    base = tomllib.loads(case_path.read_text())
    base.pop("sweep")
    out = []
    for alpha in (0.0, math.pi / 4):
        for p in (10, 100):
            data = apply_overrides(base, [f"geometry.alpha={alpha!r}", f"load.pressure={p}"])
            scene = build(parse_case(data))
            r = solve_static(scene.net, scene.loads, rtol=1e-11)
            delta = -(r.x[scene.probe, 2] - scene.net.nodes[scene.probe, 2])
            out.append((10, alpha, p, float(delta), float(r.max_strain)))
    return out


def check_rows(directory: Path, reference) -> None:
    rows = read_csv(directory)
    assert len(rows) == len(reference)
    for row, (_n, alpha, p, delta, strain) in zip(rows, reference, strict=True):
        assert float(row["geometry.alpha"]) == pytest.approx(alpha, abs=1e-15)
        assert float(row["load.pressure"]) == p
        assert row["converged"] == "true" and row["error"] == ""
        assert abs(float(row["delta"]) - delta) <= 1e-10
        assert abs(float(row["max_strain"]) - strain) <= 1e-10
        assert float(row["delta_over_L"]) == pytest.approx(float(row["delta"]), rel=1e-15)
        assert float(row["F_bar"]) == pytest.approx(p / (10e6 * math.pi * 1e-4), rel=1e-12)
        assert int(row["slack_edges"]) == 0


@pytest.fixture(scope="module")
def reference(small_case):
    return reference_rows(small_case)


# ---------------------------------------------------------------------------- values


def test_ranges_are_inclusive_and_exact():
    assert sw.expand_range("0:0.25:0.75") == [0.0, 0.25, 0.5, 0.75]
    assert sw.expand_range("10:8:34") == [10, 18, 26, 34]
    assert all(type(v) is int for v in sw.expand_range("10:8:34"))
    assert sw.expand_range("0:0.1:0.3") == [0.0, 0.1, 0.2, 0.3]  # no 0.30000000000000004
    assert sw.expand_range("0:pi/8:pi/4") == [0.0, math.pi / 8, math.pi / 4]
    assert sw.expand_range("1:-0.5:0") == [1.0, 0.5, 0.0]
    assert sw.expand_range("0:0.3:1") == [0.0, 0.3, 0.6, 0.9]  # stop not on a step
    for bad in ("0:0:1", "1:1:0", "0:1", "a:1:2", "0:1:2:3"):
        with pytest.raises(ValueError):
            sw.expand_range(bad)


def test_values_parse_like_toml_scalars_and_pi_expressions():
    assert sw.parse_param("geometry.n=10,18, 22").values == (10, 18, 22)
    p = sw.parse_param("geometry.alpha=0,pi/6,pi/4,2*pi/3,0:0.25:0.5")
    assert p.values == (0, math.pi / 6, math.pi / 4, 2 * math.pi / 3, 0.0, 0.25, 0.5)
    assert sw.parse_param("load.gravity=[0, 0, -9.81],[0,0,-1]").values == (
        [0, 0, -9.81],
        [0, 0, -1],
    )
    assert sw.parse_param('solver.linear=scipy,"auto"').values == ("scipy", "auto")
    assert sw.parse_param("material.tension_only=true,false").values == (True, False)
    assert sw.parse_param("load.pressure=1e-3,inf").values[0] == 1e-3
    assert sw.parse_param("load.pressure=10").is_load
    for bad in (
        "geometry.n",
        "geometry.n=",
        "=1,2",
        "geometry.n=1,,2",
        "geometry.n=1,",
        "geometry.alpha=pi/0",
        "n=1",
        "geometry.n=2*",
        "geometry.alpha=0:0:1",
    ):
        with pytest.raises(ConfigError):
            sw.parse_param(bad)


def test_paper_study_is_bundled_with_its_sweep_table():
    spec = sw.load_sweep(PAPER)
    assert spec.keys == ["geometry.n", "geometry.alpha", "load.pressure"]
    assert spec.params[0].values == (10, 18, 22, 26, 34)
    alphas = spec.params[1].values
    assert alphas[-2:] == (math.pi / 6, math.pi / 4)
    assert spec.params[2].values[-1] == 100
    assert len(spec.jobs) == 30 and spec.n_rows == 390
    assert spec.base_resolved["material"]["E"] == 10e6
    assert spec.base_resolved["geometry"]["edge_length"] == 0.01
    # a command-line --param replaces the table's values for its key
    spec = sw.load_sweep(PAPER, ["geometry.n=10"])
    assert spec.n_rows == 6 * 13


# ---------------------------------------------------------------------------- running


def test_two_workers_give_the_single_runs(small_case, reference, tmp_path):
    spec = sw.load_sweep(small_case)
    summary = sw.run_sweep(spec, tmp_path, workers=2)
    assert summary.total_rows == 4 and summary.failed_rows == 0
    check_rows(tmp_path, reference)
    # the HDF5 table holds the same columns
    import h5py

    with h5py.File(tmp_path / sw.H5_FILE) as f:
        g = f["table"]
        assert json.loads(g.attrs["columns"]) == spec.columns
        np.testing.assert_array_equal(
            g["delta"][:], [float(r["delta"]) for r in read_csv(tmp_path)]
        )
        assert g["converged"].dtype == bool
        assert "square_net" in f.attrs["case"]


def test_dask_cluster_gives_the_single_runs(small_case, reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    spec = sw.load_sweep(small_case)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        summary = sw.run_sweep(spec, tmp_path, scheduler=cluster.scheduler_address)
    assert summary.failed_rows == 0
    check_rows(tmp_path, reference)


def test_scheduler_without_dask_says_how_to_install(small_case, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed fails
    spec = sw.load_sweep(small_case)
    with pytest.raises(ConfigError, match=r"pip install catenet\[dask\]"):
        sw.run_sweep(spec, tmp_path, scheduler="tcp://127.0.0.1:1")


def test_resume_skips_finished_cases(small_case, reference, tmp_path):
    spec = sw.load_sweep(small_case)
    sw.run_sweep(spec, tmp_path, workers=1)
    check_rows(tmp_path, reference)
    # keep the header and the first job, marked so that a recomputation would show,
    # and a last line cut short by a crash
    lines = (tmp_path / sw.JOURNAL).read_text().splitlines()
    job0 = json.loads(lines[1])
    assert job0["index"] == 0
    for row in job0["rows"]:
        row["wall_time"] = -1.0
    (tmp_path / sw.JOURNAL).write_text(lines[0] + "\n" + json.dumps(job0) + "\n" + lines[2][:40])
    summary = sw.run_sweep(spec, tmp_path, workers=1)
    assert summary.skipped_jobs == 1 and summary.run_jobs == 1
    rows = read_csv(tmp_path)
    assert [float(r["wall_time"]) for r in rows[:2]] == [-1.0, -1.0]
    assert all(float(r["wall_time"]) > 0 for r in rows[2:])
    check_rows(tmp_path, reference)
    # nothing left to do
    assert sw.run_sweep(spec, tmp_path, workers=1).run_jobs == 0
    # another parameter set in the same directory is refused
    other = sw.load_sweep(small_case, ["load.pressure=10,50"])
    with pytest.raises(ConfigError, match="another base case or other parameters"):
        sw.run_sweep(other, tmp_path, workers=1)


def test_ctrl_c_keeps_finished_rows_and_stops_workers(small_case, reference, tmp_path):
    spec = sw.load_sweep(small_case)

    def progress(done, total, note):
        if done > 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sw.run_sweep(spec, tmp_path, workers=2, progress=progress)
    deadline = time.monotonic() + 10
    while multiprocessing.active_children() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not multiprocessing.active_children()
    rows = read_csv(tmp_path)
    assert 2 <= len(rows) < 4  # one job (two load levels) kept
    summary = sw.run_sweep(spec, tmp_path, workers=1)
    assert summary.skipped_jobs == 1
    check_rows(tmp_path, reference)


def test_a_killed_worker_is_reported_and_retried_once(small_case, tmp_path, monkeypatch):
    spec = sw.load_sweep(small_case, ["geometry.alpha=0,0.25,pi/4"])
    monkeypatch.setenv(sw.CRASH_VARIABLE, "1")
    summary = sw.run_sweep(spec, tmp_path, workers=2)
    assert (tmp_path / ".crash-1").exists()  # the hook did kill a worker
    assert 1 in summary.retried_jobs and not summary.crashed_jobs
    rows = read_csv(tmp_path)
    assert len(rows) == 6
    assert all(r["converged"] == "true" and r["error"] == "" for r in rows)
    assert [r["attempts"] for r in rows[2:4]] == ["2", "2"]
    journal = [json.loads(line) for line in (tmp_path / sw.JOURNAL).read_text().splitlines()]
    crashes = [rec for rec in journal if rec.get("kind") == "crash"]
    assert any(rec["index"] == 1 and "worker process died" in rec["error"] for rec in crashes)


def test_a_failing_case_is_recorded_and_the_sweep_goes_on(small_case, tmp_path):
    # max_iter = 1 cannot converge from the flat net: every row records its error
    spec = sw.load_sweep(small_case, ["solver.max_iter=1,200", "geometry.alpha=0"])
    summary = sw.run_sweep(spec, tmp_path, workers=1)
    rows = read_csv(tmp_path)
    assert summary.failed_rows == 2 and len(rows) == 4
    assert all(r["error"] and r["converged"] == "false" for r in rows[:2])
    assert all(not r["error"] and r["converged"] == "true" for r in rows[2:])


def test_save_runs_keeps_each_result_file(small_case, reference, tmp_path):
    pytest.importorskip("catenet.output")
    import h5py

    spec = sw.load_sweep(small_case)
    sw.run_sweep(spec, tmp_path, workers=1, save_runs=True)
    rows = read_csv(tmp_path)
    for row, ref in zip(rows, reference, strict=True):
        with h5py.File(tmp_path / row["run_file"]) as f:
            x = f["result/x"][:]
            z0 = f["mesh/nodes"][:, 2]
            probe = int(f["result"].attrs["probe"]) if "probe" in f["result"].attrs else None
            assert bool(f["result"].attrs["converged"])
            assert "square_net" in f.attrs["case"]
        if probe is not None:
            assert abs(-(x[probe, 2] - z0[probe]) - ref[3]) <= 1e-10


# ---------------------------------------------------------------------------- fit and figures


def test_the_fit_recovers_a_known_D():
    from catenet.study import f_alpha, fit_scaling

    rng = np.random.default_rng(1)
    n, alpha, F = np.meshgrid(
        [10, 18, 22, 26, 34],
        [0, 0.25, 0.5, 0.75, math.pi / 6, math.pi / 4],
        np.geomspace(3e-4, 3e-2, 8),
        indexing="ij",
    )
    n, alpha, F = n.ravel(), alpha.ravel(), F.ravel()
    exact = 0.38 * f_alpha(alpha, 1.45) * (F / n) ** 0.4
    fit = fit_scaling(F, n, alpha, exact)
    assert fit.D == pytest.approx(1.45, abs=1e-8)
    assert fit.beta == pytest.approx(0.4, abs=1e-8)
    assert fit.C == pytest.approx(0.38, rel=1e-8)
    noisy = exact * np.exp(0.01 * rng.standard_normal(exact.size))
    fit = fit_scaling(F, n, alpha, noisy)
    assert abs(fit.D - 1.45) < 3 * fit.sigma_D and fit.sigma_D < 0.01
    assert fit.rms_log == pytest.approx(0.01, rel=0.2)


def test_figures_and_report_of_a_small_sweep(small_case, tmp_path):
    from catenet.study import plot_sweep

    spec = sw.load_sweep(small_case)
    sw.run_sweep(spec, tmp_path / "s", workers=1)
    files = plot_sweep(tmp_path / "s", tmp_path / "fig")
    names = {f.name for f in files}
    assert {"fig5_force_displacement_n.png", "fig8_scaling.png", "report.md"} <= names
    report = (tmp_path / "fig" / "report.md").read_text()
    assert "D = " in report and "RMS" in report
    assert "Fig. 7a skipped" in report  # one value of n: noted, not an error
    assert "not checked" in report


# ---------------------------------------------------------------------------- command line


@pytest.mark.parametrize(
    "param, message",
    [
        ("geometry.n=10,,18", "empty value"),
        ("geometry.n", "key.path=v1,v2"),
        ("geometry.alpha=0:0:1", "step must not be 0"),
        ("geometry.n=11", "geometry.n = 11"),
        ("geometry.colour=1", "unknown key"),
        ("load.pressure=1:1:0", "sign"),
        ("material.E=-1e0", "--param material.E=-1e0: material.E = -1e0: must be"),
    ],
)
def test_bad_params_exit_2_with_a_clear_message(small_case, tmp_path, param, message):
    result = CliRunner().invoke(
        sweep_command, [str(small_case), "--param", param, "-o", str(tmp_path), "-q"]
    )
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert "Traceback" not in result.output


def test_a_value_keeps_its_spelling_in_messages_and_prints_plain_in_the_table(small_case, tmp_path):
    """``1_000e4`` is quoted as written where a message names it; the table holds the
    number as Python prints it (a CSV reader reads ``10000000.0``, not ``1_000e4``)."""
    param = sw.parse_param("material.E=1_000e4")
    assert str(param.values[0]) == "1_000e4" and param.values[0] == 1e7
    result = CliRunner().invoke(
        sweep_command, [str(small_case), "--param", "material.E=1_000e4", "-o", str(tmp_path), "-q"]
    )
    assert result.exit_code == 0, result.output
    rows = read_csv(tmp_path)
    assert rows and {row["material.E"] for row in rows} == {"10000000.0"}


def test_cli_interrupted_and_resumed(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(BASE)
    out = tmp_path / "out"
    args = [
        sys.executable,
        "-c",
        "from catenet.cli import main; main()",
        "sweep",
        str(case),
        "-o",
        str(out),
        "-p",
        "geometry.alpha=0:0.1:0.7",
        "-p",
        "load.pressure=10:10:100",
        "-j",
        "1",
    ]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, env=env)
    journal = out / sw.JOURNAL
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and len(journal.read_text().splitlines()) >= 2:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    done = len(read_csv(out))
    if proc.returncode != 0:  # stopped before the end (the usual case)
        assert proc.returncode == 130, err
        assert "interrupted" in err and "resume" in err
        assert 10 <= done < 80
    result = subprocess.run(args, capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stderr
    rows = read_csv(out)
    assert len(rows) == 80 and all(r["converged"] == "true" for r in rows)
    if done < 80:
        assert "already done" in result.stderr


def test_bundled_paper_case_runs_from_the_command_line(tmp_path):
    """configs/sweeps/paper.toml with a few of its values, as in the README."""
    out = tmp_path / "paper"
    result = CliRunner().invoke(
        sweep_command,
        [
            str(PAPER),
            "-p",
            "geometry.n=10",
            "-p",
            "geometry.alpha=0",
            "-p",
            "load.pressure=10,100",
            "-o",
            str(out),
            "-j",
            "1",
            "--plot",
        ],
    )
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert [r["load.pressure"] for r in rows] == ["10", "100"]
    # the paper's n = 10, alpha = 0 net at p = 100 Pa (F_bar = 0.032): delta/L = 0.056
    assert float(rows[1]["delta_over_L"]) == pytest.approx(0.0564, abs=5e-4)
    report = (out / "report.md").read_text()
    assert "Fig. 7 skipped" in report and "Fig. 8 skipped" in report


def test_a_sweep_with_an_obstacle_gives_the_single_runs(tmp_path):
    """Levels of a sweep share a workspace only where the scene has no terms besides
    the net's: an obstacle's barrier depends on the loads (its default stiffness) and on
    the swept keys, so every level of a contact sweep builds its own, and each row is
    the single run of its values."""
    from catenet.case import build, load_case
    from catenet.solver import path as sv

    source = Path("configs/contact/net_on_sphere.toml")
    spec = sw.load_sweep(source, ["load.pressure=100,300"])
    summary = sw.run_sweep(spec, tmp_path, workers=1)
    assert summary.failed_rows == 0
    rows = read_csv(tmp_path)
    for row in rows:
        case = load_case(source, [f"load.pressure={row['load.pressure']}"])
        scene = build(case)
        single = sv.solve(scene, sv.Settings.of(case.solver))
        delta = float(scene.net.nodes[scene.probe, 2] - single.x[scene.probe, 2])
        assert float(row["delta"]) == pytest.approx(delta, rel=1e-9)
