"""What the README promises of sweeps: a Dask worker killed mid-job is reported (a
warning, a crash record in the journal, attempts = 2), no lock file stays behind in the
sweep directory, and an unreachable scheduler leaves no directory."""

from __future__ import annotations

import json
import logging
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from catenet import sweep as sw
from catenet.errors import CatenetError
from catenet.sweep import workers

CASE = """
[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 1.0
edge_length = 0.05

[material]
E = 10e6
radius = 0.01

[load]
pressure = 100.0

[sweep]
geometry.alpha = [0.0, 0.5]
load.pressure = [10, 100]
"""


@pytest.fixture
def case(tmp_path) -> Path:
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    return path


def journal(directory: Path) -> list[dict]:
    return [json.loads(line) for line in (directory / sw.JOURNAL).read_text().splitlines()]


def test_a_killed_dask_worker_is_reported_and_counted(case, tmp_path, caplog):
    """The first job's worker process is killed (SIGKILL) once the job has started; Dask
    reruns the task on the restarted worker, and the sweep says so."""
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "out"
    killed: dict = {}
    done = threading.Event()

    def kill_first_job():
        running = out / ".running"
        while not done.is_set():
            for marker in running.glob("*") if running.is_dir() else ():
                try:
                    pid = int(marker.read_text().split()[0])
                except (OSError, ValueError, IndexError):
                    continue
                os.kill(pid, signal.SIGKILL)
                killed.update(index=int(marker.name), pid=pid)
                return
            time.sleep(0.01)

    killer = threading.Thread(target=kill_first_job, daemon=True)
    spec = sw.load_sweep(case)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        killer.start()
        try:
            with caplog.at_level(logging.WARNING):
                summary = sw.run_sweep(spec, out, scheduler=cluster.scheduler_address)
        finally:
            done.set()
            killer.join()
    assert killed, "no job was seen running"
    index = killed["index"]
    assert summary.failed_rows == 0 and index in summary.retried_jobs
    rows = [r for rec in journal(out)[1:] if rec.get("kind") == "job" for r in rec["rows"]]
    assert len(rows) == 4 and all(r["converged"] and not r["error"] for r in rows)
    by_job = {rec["index"]: rec for rec in journal(out)[1:] if rec.get("kind") == "job"}
    assert by_job[index]["attempts"] == 2
    assert all(r["attempts"] == 2 for r in by_job[index]["rows"])
    assert all(rec["attempts"] == 1 for i, rec in by_job.items() if i != index)
    crashes = [rec for rec in journal(out) if rec.get("kind") == "crash"]
    assert [c["index"] for c in crashes] == [index] and "dask worker died" in crashes[0]["error"]
    assert any("dask worker died" in r.getMessage() for r in caplog.records)
    _, _, table = sw.read_table(out)
    assert sorted(table["attempts"]) == [1, 1, 2, 2]


def test_the_lock_file_goes_when_the_sweep_ends(case, tmp_path):
    spec = sw.load_sweep(case)
    sw.run_sweep(spec, tmp_path / "ok", workers=1)
    assert not (tmp_path / "ok" / ".lock").exists()
    assert (tmp_path / "ok" / sw.CSV_FILE).exists()

    def stop(done, total, note):  # Ctrl-C after the first job
        if done > 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sw.run_sweep(spec, tmp_path / "cut", workers=1, progress=stop)
    assert not (tmp_path / "cut" / ".lock").exists()
    assert sw.run_sweep(spec, tmp_path / "cut", workers=1).skipped_jobs == 1


def test_the_lock_still_keeps_out_a_second_sweep(case, tmp_path):
    from catenet.errors import ConfigError
    from catenet.sweep.journal import directory_lock

    tmp_path.mkdir(exist_ok=True)
    with directory_lock(tmp_path):
        assert (tmp_path / ".lock").exists()
        with pytest.raises(ConfigError, match="another sweep is writing"):
            with directory_lock(tmp_path):
                pass
        assert (tmp_path / ".lock").exists()  # the refused one removes nothing
    assert not (tmp_path / ".lock").exists()
    with directory_lock(tmp_path):  # and it can be taken again
        pass


def test_an_unreachable_scheduler_leaves_no_directory(case, tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(workers, "CONNECT_TIMEOUT", "1s")
    out = tmp_path / "never"
    with pytest.raises(CatenetError, match="--scheduler tcp://127.0.0.1:1: cannot connect"):
        sw.run_sweep(sw.load_sweep(case), out, scheduler="tcp://127.0.0.1:1")
    assert not out.exists()
