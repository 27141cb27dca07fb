"""``run_sweep``: the jobs the journal does not hold yet, run in this process, on a pool
of processes or on a Dask cluster; each finished job goes to the journal at once and the
tables are regenerated at the end (also after an error or Ctrl-C)."""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from catenet.errors import ConfigError
from catenet.sweep.jobs import Job, Sweep, case_api, overrides
from catenet.sweep.journal import (
    JOURNAL,
    Journal,
    directory_lock,
    prepare_directory,
    write_tables,
)
from catenet.sweep.solve import RUNNING_DIR, failed_rows, make_task, run_job
from catenet.sweep.workers import connect_dask, cores, run_dask, run_pool, threads_per_worker

log = logging.getLogger(__name__)


@dataclass
class SweepSummary:
    """What a call of ``run_sweep`` did."""

    directory: Path
    total_jobs: int
    total_rows: int
    skipped_jobs: int = 0
    run_jobs: int = 0
    failed_rows: int = 0
    retried_jobs: list[int] = field(default_factory=list)
    crashed_jobs: list[int] = field(default_factory=list)
    wall_time: float = 0.0
    interrupted: bool = False


class _Recorder:
    """Writes what the workers return into the journal, the summary and the progress."""

    def __init__(self, sweep: Sweep, journal: Journal, summary: SweepSummary, progress, total):
        self.sweep = sweep
        self.journal = journal
        self.summary = summary
        self.progress = progress
        self.total = total
        self.rows_done = 0

    def done(self, job: Job, rows: list[dict], attempts: int) -> None:
        summary = self.summary
        for r in rows:
            r["attempts"] = attempts
        full = [{**self.sweep.row_values(job, k), **r} for k, r in enumerate(rows)]
        self.journal.write(
            {"kind": "job", "index": job.index, "key": job.key, "attempts": attempts, "rows": full}
        )
        summary.run_jobs += 1
        summary.failed_rows += sum(1 for r in full if r["error"])
        if attempts > 1:
            summary.retried_jobs.append(job.index)
        self.rows_done += len(rows)
        if self.progress:
            failed = f"{summary.failed_rows} failed" if summary.failed_rows else ""
            self.progress(self.rows_done, self.total, failed)

    def crashed(self, job: Job, message: str) -> None:
        self.journal.write({"kind": "crash", "index": job.index, "error": message})
        log.warning("job %d (%s): %s", job.index, job.describe(), message)

    def gave_up(self, job: Job, message: str, attempts: int) -> None:
        self.summary.crashed_jobs.append(job.index)
        self.done(job, failed_rows(job, message), attempts)


def run_sweep(
    sweep: Sweep,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    save_runs: bool = False,
    progress: Callable[[int, int, str], None] | None = None,
) -> SweepSummary:
    """Run the jobs the journal of ``out`` does not hold yet; regenerate the tables.

    ``workers``: processes (default: all cores; 1 runs in this process). ``scheduler``:
    the address of a Dask scheduler instead. ``progress(done, total, note)`` counts the
    rows of this call (rows already in the journal are not in ``total``).
    Ctrl-C (KeyboardInterrupt) stops the workers; the finished jobs are kept and the
    tables written before it propagates."""
    out = Path(out)
    start = time.perf_counter()
    if workers is None:
        workers = cores()
    if workers < 1:
        raise ConfigError(f"--workers = {workers}: must be >= 1")
    if save_runs:
        try:
            from catenet.output import ResultWriter  # noqa: F401
        except ImportError as exc:
            raise ConfigError(f"--save-runs: needs catenet.output.ResultWriter: {exc}") from None
    jobs = sweep.jobs
    summary = SweepSummary(out, len(jobs), sweep.n_rows)
    from catenet.output.files import check_output_dir

    check_output_dir(out, what="sweep directory")
    client = connect_dask(scheduler) if scheduler else None  # before DIR exists
    try:
        out.mkdir(parents=True, exist_ok=True)
        _run(sweep, out, jobs, summary, client, workers, save_runs, progress)
    finally:
        if client is not None:
            with contextlib.suppress(Exception):
                client.close()
        summary.wall_time = time.perf_counter() - start
    return summary


def _run(sweep, out, jobs, summary, client, workers, save_runs, progress) -> None:
    with directory_lock(out):
        done = prepare_directory(sweep, out)
        todo = [job for job in jobs if job.index not in done]
        summary.skipped_jobs = len(jobs) - len(todo)
        if summary.skipped_jobs:
            log.info(
                "%s: %d of %d jobs already done, skipped", out, summary.skipped_jobs, len(jobs)
            )
        rows_before = sum(len(rec["rows"]) for rec in done.values())
        rows_todo = summary.total_rows - rows_before
        if progress:
            progress(0, rows_todo, f"({rows_before} rows done before)" if rows_before else "")
        journal = Journal(out / JOURNAL)
        running = out / RUNNING_DIR
        running.mkdir(exist_ok=True)
        for stale in running.iterdir():
            with contextlib.suppress(OSError):
                stale.unlink()
        recorder = _Recorder(sweep, journal, summary, progress, rows_todo)

        def task(job: Job, threads: int, crash_hook: bool) -> dict:
            return make_task(
                sweep, job, out, save_runs=save_runs, threads=threads, crash_hook=crash_hook
            )

        try:
            if not todo:
                pass
            elif client is not None:
                tag = sweep.fingerprint[:8]
                run_dask(_largest_first(sweep, todo), task, recorder, client, tag)
            elif workers == 1:
                with deferred_interrupt() as interrupted:
                    for job in todo:
                        result = run_job(task(job, threads_per_worker(1), False))
                        if interrupted():  # its rows may hold the interrupt: redone on resume
                            raise KeyboardInterrupt
                        recorder.done(job, result["rows"], 1)
            else:
                run_pool(_largest_first(sweep, todo), task, recorder, workers, running)
        except KeyboardInterrupt:
            summary.interrupted = True
            raise
        finally:
            journal.close()
            write_tables(out)
            with contextlib.suppress(OSError):
                running.rmdir()  # empty unless a worker died


def _largest_first(sweep: Sweep, jobs: list[Job]) -> list[Job]:
    """Jobs by estimated cost (nodes x load levels), largest first, so that the workers
    finish together instead of waiting for one large job at the end."""
    case = case_api()
    estimate = case.estimate_size

    def cost(job: Job) -> float:
        try:
            level = list(job.levels[0]) if job.levels else []
            data = case.apply_overrides(sweep.base, overrides(list(job.settings) + level))
            parsed = case.parse_case(data, source=sweep.source, base_dir=Path(sweep.base_dir))
            return float(estimate(parsed.geometry)[0]) * max(1, len(job.levels))
        except Exception:  # a case that fails does so quickly
            return 0.0

    costs = {job.index: cost(job) for job in jobs}
    return sorted(jobs, key=lambda job: (-costs[job.index], job.index))


@contextlib.contextmanager
def deferred_interrupt():
    """Ctrl-C while jobs run in this process: the first SIGINT only sets a flag, which the
    Newton solves ask before every iteration (they stop at once) and the caller asks after
    each job (it then raises KeyboardInterrupt, and the interrupted job is not recorded,
    so a resume runs it again). A KeyboardInterrupt raised anywhere inside NumPy could
    come out as another exception and be recorded as the job's error. A second SIGINT
    raises KeyboardInterrupt at once."""
    import signal

    from catenet.solver.newton import interruptible

    got: list[int] = []

    def handler(signum, frame):
        got.append(signum)
        signal.signal(signal.SIGINT, signal.default_int_handler)

    try:
        previous = signal.signal(signal.SIGINT, handler)
    except ValueError:  # not the main thread: Ctrl-C is not ours to handle
        yield lambda: False
        return
    try:
        with interruptible(lambda: bool(got)):
            yield lambda: bool(got)
    finally:
        signal.signal(signal.SIGINT, previous)
