"""Faults around a run: a disk full before the file is created or filling while it is
written (simulated: a file-size limit on a fresh interpreter, or a free-space figure that
says so), read-only and vanished output directories, an output path that is a directory,
two runs on one file, a sweep whose parent is killed or interrupted, and paths with
spaces, non-ASCII or undecodable names."""

from __future__ import annotations

import os
import resource
import shutil
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import catenet_command, small_net, spawn, subprocess_env, wait_for_frames
from fuzzing import HIDDEN, invoke, judge

pytestmark = pytest.mark.filterwarnings("ignore")

SMALL = small_net(t_end=0.3).replace("edge_length = 0.05", "edge_length = 0.1")


def hidden(root: Path) -> list[str]:
    return [p.name for p in root.rglob("*") if HIDDEN.match(p.name)]


def limited(limit: int, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    """``catenet *args`` with files limited to ``limit`` bytes: every write beyond fails
    with EFBIG, as writes to a full disk fail with ENOSPC (SIGXFSZ ignored)."""

    def limit_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    env = {**subprocess_env(), "TMPDIR": str(cwd)}  # the result saved elsewhere lands here
    return subprocess.run(
        catenet_command(*args),
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=limit_files,
    )


def test_a_full_disk_before_the_file_is_created(tmp_path, monkeypatch):
    """The free space is checked before anything is created: exit 1, one message, nothing
    left (HDF5 crashed with 94 lines of errors and left a spare)."""
    case = tmp_path / "case.toml"
    case.write_text(SMALL)
    monkeypatch.setattr(
        "catenet.output.files.shutil.disk_usage", lambda p: shutil._ntuple_diskusage(1, 1, 1000)
    )
    result = invoke(["run", case, "-o", tmp_path / "out" / "r.h5"])
    assert result.exit_code == 1, result.output
    assert "No space left on device (1000 bytes free" in result.output
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["case.toml", "out"]


@pytest.mark.parametrize("limit", [4_000, 8_000, 14_000, 20_000])
def test_writes_that_fail_while_the_file_is_created_never_crash(tmp_path, limit):
    """The header's writes fail (a disk that fills just then): exit 1 with catenet's
    message, no signal, no HDF5 error dump, no hidden file left."""
    (tmp_path / "case.toml").write_text(SMALL)
    proc = limited(limit, "run", "case.toml", "-o", "r.h5", "-q", cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr[-2000:]
    assert proc.stderr.startswith("catenet: error:") and "HDF5-DIAG" not in proc.stderr
    assert "Traceback" not in proc.stderr and not hidden(tmp_path)


def test_a_disk_that_fills_while_the_run_goes_on(tmp_path):
    """Exit 1, a clear message, and the file holds every frame flushed before, bit for
    bit those of a run with room."""
    (tmp_path / "case.toml").write_text(SMALL)
    whole = invoke(["run", tmp_path / "case.toml", "-o", tmp_path / "whole.h5", "-q"])
    assert whole.exit_code == 0, whole.output
    work = tmp_path / "full"
    work.mkdir()
    shutil.copy(tmp_path / "case.toml", work / "case.toml")
    proc = limited(60_000, "run", "case.toml", "-o", "r.h5", "-q", cwd=work)
    assert proc.returncode == 1, proc.stderr[-2000:]
    assert "writing failed" in proc.stderr and "Traceback" not in proc.stderr
    assert not hidden(work)
    with h5py.File(work / "r.h5") as cut, h5py.File(tmp_path / "whole.h5") as full:
        n = cut["trajectory/x"].shape[0]
        assert 1 <= n < full["trajectory/x"].shape[0]
        np.testing.assert_array_equal(cut["trajectory/x"][()], full["trajectory/x"][:n])
        assert np.all(np.isfinite(cut["trajectory/x"][()]))


def test_read_only_and_vanished_output_directories(tmp_path, monkeypatch):
    case = tmp_path / "case.toml"
    case.write_text(SMALL)
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    if os.geteuid() == 0:  # root writes anywhere: make the check see what a user would
        real = os.access
        monkeypatch.setattr(os, "access", lambda p, m: False if Path(p) == ro else real(p, m))
    result = invoke(["run", case, "-o", ro / "r.h5"])
    monkeypatch.undo()
    ro.chmod(0o755)
    assert result.exit_code == 2 and "permission denied" in result.output, result.output
    assert list(ro.iterdir()) == []
    # The directory removed while the run writes into it: exit 1, one message.
    # undamped trapezoidal steps: no rest before t_end; the energy check off (it ends this
    # run at t = 0.8 s, where the newmark steps have gained 1.4 % of the largest energy,
    # sometimes before the test saw its frames): this test is about the directory. The
    # run goes on to its end after the failed write (its final state saved aside): 6 s,
    # 600 steps, is long after the third frame and the removal
    long = small_net(t_end=6.0, damping=0.0).replace(
        'method = "dynamic"',
        'method = "dynamic"\nintegrator = "newmark"\nrho_inf = 1.0\nenergy_tolerance = 1e9',
    )
    (tmp_path / "long.toml").write_text(long)
    out = tmp_path / "gone" / "r.h5"
    proc = spawn("run", tmp_path / "long.toml", "-o", out, "-q")
    wait_for_frames(out, 3, proc)
    while out.parent.exists():  # the writer's spare comes and goes meanwhile
        shutil.rmtree(out.parent, ignore_errors=True)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 1, err
    assert err.startswith("catenet: error:") and "Traceback" not in err


def test_an_output_path_that_is_a_directory(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(SMALL)
    (tmp_path / "r.h5").mkdir()
    result = invoke(["run", case, "-o", tmp_path / "r.h5"])
    assert result.exit_code == 2 and "is a directory" in result.output
    assert judge(result, tmp_path).good


def test_two_runs_on_one_file(tmp_path):
    """While one run writes a file, a second run of it (and catenet repair) is refused
    with a clear message; the first run's file stays whole (both failed, one with a
    traceback, and left NaN frames and no /result)."""
    from catenet.case import load_case
    from catenet.case.scene import build
    from catenet.output import ResultWriter, read_result

    case = tmp_path / "case.toml"
    case.write_text(SMALL)
    scene = build(load_case(case))
    out = tmp_path / "r.h5"
    with ResultWriter(out, scene, every=1) as first:
        first.frame(0.0, scene.net.nodes)
        for command in (["run", case, "-o", out, "-q"], ["repair", out]):
            result = invoke(command)
            assert result.exit_code == 2, result.output
            assert "another catenet process is writing it" in result.output
        first.frame(0.1, scene.net.nodes + 0.01)
    assert read_result(out).n_frames == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml", "r.h5", "r.xdmf"]
    assert invoke(["run", case, "-o", out, "-q"]).exit_code == 0  # free again


SLOW_SWEEP = small_net(t_end=100.0, damping=0.05) + "\n[sweep]\ngeometry.alpha = [0, 0.1, 0.2]\n"


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(c) for c in text.split()]


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="reads /proc (Linux)")
def test_sigkill_of_a_sweeps_parent_ends_its_workers(tmp_path):
    """Workers and multiprocessing's resource tracker end with the parent (they ran on
    for ever, 260 MB each)."""
    case = tmp_path / "case.toml"
    case.write_text(SLOW_SWEEP)
    proc = spawn("sweep", case, "-o", tmp_path / "sw", "-j", "2", "-q")
    deadline = time.monotonic() + 120
    kids: list[int] = []
    while time.monotonic() < deadline and len(kids) < 3:  # two workers and the tracker
        kids = _children(proc.pid)
        time.sleep(0.2)
    assert len(kids) >= 2, kids
    time.sleep(1.0)  # the workers past their start-up
    proc.kill()
    proc.communicate(timeout=60)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and any(map(_alive, kids)):
        time.sleep(0.2)
    left = [k for k in kids if _alive(k)]
    for k in left:
        os.kill(k, signal.SIGKILL)
    assert not left


def test_sigint_of_an_in_process_sweep_records_only_finished_jobs(tmp_path, monkeypatch):
    """Ctrl-C while a job runs in this process: the job stops at a safe point and is not
    recorded (a KeyboardInterrupt inside NumPy came out as a TypeError, recorded as the
    job's error); the resume runs it and nothing finished again."""
    import catenet.sweep as sw
    from catenet.sweep import execute

    case = tmp_path / "case.toml"
    case.write_text(small_net(method="static") + "\n[sweep]\ngeometry.alpha = [0, 0.1, 0.2]\n")
    calls = []
    real = execute.run_job

    def job(task):
        calls.append(task["index"])
        if calls == [0, 1] and not sent:
            sent.append(True)
            os.kill(os.getpid(), signal.SIGINT)  # arrives while this job computes
        return real(task)

    sent: list = []

    monkeypatch.setattr(execute, "run_job", job)
    out = tmp_path / "sw"
    with pytest.raises(KeyboardInterrupt):
        sw.run_sweep(sw.load_sweep(case), out, workers=1)
    header, done = sw.read_journal(out)
    assert len(done) == 1 and not any(r.get("error") for rec in done.values() for r in rec["rows"])
    calls.clear()
    summary = sw.run_sweep(sw.load_sweep(case), out, workers=1)
    assert summary.skipped_jobs == 1 and len(calls) == 2
    header, done = sw.read_journal(out)
    assert len(done) == 3 and not any(r.get("error") for rec in done.values() for r in rec["rows"])


@pytest.mark.parametrize(
    "name", ["with space/r é.h5", "データ/結果.h5", "a b c/ü ñ ø.h5", "x" * 230 + ".h5"]
)
def test_paths_with_spaces_and_non_ascii_names(tmp_path, name):
    case = tmp_path / "c ä.toml"
    case.write_text(SMALL)
    out = tmp_path / name
    result = invoke(["run", case, "-o", out, "-q"])
    assert result.exit_code == 0, result.output
    assert judge(result, tmp_path).kind == "ok"
    plot = invoke(["plot", out, "-o", out.with_suffix(".png")])
    assert plot.exit_code == 0, plot.output
