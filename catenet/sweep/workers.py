"""Where the jobs of a sweep run besides this process: a pool of spawned processes
(``concurrent.futures.ProcessPoolExecutor``) or a Dask distributed cluster (Dask's own
futures).

Both take the jobs to run (largest first), ``task(job, threads, crash_hook)`` (the
picklable task of ``catenet.sweep.solve.make_task``) and a recorder with
``done(job, rows, attempts)``, ``crashed(job, message)`` and
``gave_up(job, message, attempts)``. A job whose worker dies is run once more; after a
second death its rows are recorded as failed.

Why the pool is restarted by hand: a worker process that dies breaks a
``ProcessPoolExecutor`` for every job submitted to it (``BrokenProcessPool``), so the
jobs that had not started go to a new pool at once and those that had started are run
again one at a time (a marker file ``DIR/.running/<index>`` tells them apart), so that a
job that kills its worker again is known. Dask's ``retries=`` covers exceptions raised by
a task, not a lost worker (``KilledWorker`` after the scheduler's own retries), hence the
one resubmission here.
"""

from __future__ import annotations

import contextlib
import os
import re
import socket
from pathlib import Path

from catenet.errors import CatenetError, ConfigError
from catenet.sweep.solve import run_job

THREAD_VARIABLES = (
    "MKL_NUM_THREADS",
    "NUMBA_NUM_THREADS",
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
)
DIED = "worker process died while running this job (crashed or killed)"
NEVER_STARTED = "worker processes die before running a job (see the log above)"
TWICE = ", twice: not retried again"
RERUN = "dask worker died while running this job ({} time(s)); the scheduler ran it again"
CONNECT_TIMEOUT = "20s"  # for the scheduler to answer


def cores() -> int:
    """Cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def threads_per_worker(workers: int) -> int:
    return max(1, cores() // max(1, workers))


def _lost(job, message: str, crashes: dict[int, int], recorder) -> bool:
    """Count a worker's death during ``job``: True when the job is to run once more,
    False when it has died twice (then its rows are recorded as failed)."""
    crashes[job.index] = crashes.get(job.index, 0) + 1
    recorder.crashed(job, message)
    if crashes[job.index] >= 2:
        recorder.gave_up(job, message + TWICE, 2)
        return False
    return True


@contextlib.contextmanager
def _worker_environment(threads: int):
    """Thread counts for spawned workers, set in this process's environment while the
    pool starts them (a spawned child reads them before MKL, OpenMP or Numba load)."""
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    for k in THREAD_VARIABLES:
        os.environ[k] = str(threads)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _init_worker(threads: int, parent: int | None = None) -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    for k in THREAD_VARIABLES:
        os.environ[k] = str(threads)
    if parent is not None:
        die_with_parent(parent)


def die_with_parent(parent: int) -> None:
    """Asks Linux to kill this process when its parent ends (PR_SET_PDEATHSIG), so that a
    sweep whose parent is killed (SIGKILL: no chance to stop its pool) leaves no worker
    behind; the resource tracker then ends too (its last pipe closes). Ends at once if
    the parent is already gone. Elsewhere, nothing."""
    import signal
    import sys

    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # it ended before the request was made
        os._exit(1)


def run_pool(todo: list, task, recorder, workers: int, running: Path) -> None:
    """The jobs on a process pool of at most ``workers`` spawned processes, MKL, OpenMP
    and Numba threads ``cores // workers`` each; ``running``: the directory of the
    markers of started jobs."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: thread settings apply
    crashes: dict[int, int] = {}
    pending = list(todo)
    isolate: list = []
    blind = 0  # pool breaks that no started job explains
    while pending or isolate:
        if pending:
            batch, pending = pending, []
            width = min(workers, len(batch))
        else:
            batch, isolate = [isolate[0]], isolate[1:]
            width = 1
        threads = threads_per_worker(width)
        for job in batch:
            with contextlib.suppress(OSError):
                (running / str(job.index)).unlink()
        broken: list = []
        env = _worker_environment(threads)  # processes start at submit: keep it until then
        env.__enter__()
        try:
            pool = ProcessPoolExecutor(
                width, mp_context=ctx, initializer=_init_worker, initargs=(threads, os.getpid())
            )
        except BaseException:
            env.__exit__(None, None, None)
            raise
        try:
            futures = {}
            try:
                for job in batch:
                    futures[pool.submit(run_job, task(job, threads, True))] = job
            finally:
                env.__exit__(None, None, None)
            for fut in as_completed(futures):
                job = futures[fut]
                try:
                    result = fut.result()
                except BrokenProcessPool:
                    broken.append(job)
                    continue
                recorder.done(job, result["rows"], crashes.get(job.index, 0) + 1)
        except BaseException:
            _terminate(pool)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        if not broken:
            continue
        started = [job for job in broken if (running / str(job.index)).exists()]
        if not started:  # a worker died outside any job (at start-up?)
            blind += 1
            if blind >= 2:
                for job in broken:
                    recorder.crashed(job, NEVER_STARTED)
                    recorder.gave_up(job, NEVER_STARTED, crashes.get(job.index, 0) + 1)
                broken = []
        pending += [job for job in broken if job not in started]
        isolate += [job for job in started if _lost(job, DIED, crashes, recorder)]


def _terminate(pool) -> None:
    """Stop the pool's processes now (Ctrl-C); the stdlib has no public way before
    Python 3.14 (``terminate_workers``)."""
    for proc in list(getattr(pool, "_processes", {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()


def connect_dask(scheduler: str):
    """A Dask client of the scheduler at ``scheduler``; ConfigError without Dask,
    CatenetError when it cannot be reached (before anything is written)."""
    try:
        from distributed import Client
    except ImportError:
        raise ConfigError("--scheduler needs Dask distributed: pip install catenet[dask]") from None
    _reachable(scheduler)
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise CatenetError(f"--scheduler {scheduler}: cannot connect: {exc}") from None


_ADDRESS = re.compile(r"^(?:(tcp|tls)://)?(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9_.-]+):(\d{1,5})$")


def _reachable(scheduler: str) -> None:
    """ConfigError for what is not a scheduler address (``tcp://host:port``, ``host:port``),
    CatenetError when nothing listens there (a TCP connection, a few seconds at most):
    Dask itself would try for CONNECT_TIMEOUT and print its own traceback."""
    m = _ADDRESS.match(scheduler.strip())
    port = int(m.group(3)) if m else 0
    if not m or not 0 < port < 65536:
        raise ConfigError(
            f"--scheduler {scheduler!r}: must be a Dask scheduler address such as "
            "tcp://host:8786 (a host name or IP address and a port 1..65535)"
        )
    host = m.group(2).strip("[]")
    try:
        socket.create_connection((host, port), timeout=PROBE_SECONDS).close()
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise CatenetError(f"--scheduler {scheduler}: cannot connect: {reason}") from None


PROBE_SECONDS = 5.0


def run_dask(todo: list, task, recorder, client, tag: str) -> None:
    """The jobs on a Dask cluster (``client`` of ``connect_dask``), one task each (MKL and
    Numba threads 1 per task: a Dask worker runs as many tasks at once as it has
    threads). A task whose worker is lost beyond the scheduler's own retries
    (KilledWorker, lost connection) is run once more, then recorded as failed. A job
    the scheduler itself ran again after its worker died is recorded too (the task
    reports how often it was started, see ``run_job``)."""
    from distributed import as_completed

    crashes: dict[int, int] = {}
    futures: dict = {}
    try:

        def submit(job):
            attempt = crashes.get(job.index, 0)
            return client.submit(
                run_job,
                task(job, 1, True),
                key=f"catenet-sweep-{tag}-{job.index}-{attempt}",
                pure=False,
            )

        for job in todo:
            futures[submit(job)] = job
        ac = as_completed(list(futures), loop=client.loop)
        for fut in ac:
            job = futures.pop(fut)
            try:
                result = fut.result()
            except KeyboardInterrupt:
                raise
            except Exception as exc:
                message = f"dask worker lost ({type(exc).__name__}: {exc})"
                if _lost(job, message, crashes, recorder):
                    new = submit(job)
                    futures[new] = job
                    ac.add(new)
                continue
            ours = crashes.get(job.index, 0) + 1
            started = int(result.get("attempts", 1))
            if started > ours:  # the scheduler ran it again after its worker died
                recorder.crashed(job, RERUN.format(started - ours))
            recorder.done(job, result["rows"], max(ours, started))
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(list(futures))
        raise
