"""``catenet sweep``: a case over the Cartesian product of parameter values."""

from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import click

from catenet.cli.common import (
    EXIT_FAILED,
    HELP,
    PathParam,
    Progress,
    errors_to_exit_codes,
    fail,
    setup_logging,
    verbosity_options,
)

if TYPE_CHECKING:
    from catenet.sweep import Sweep, SweepSummary


@click.command(name="sweep", context_settings=HELP)
@click.argument("case", type=click.Path(path_type=Path))
@click.option(
    "-p",
    "--param",
    "params",
    multiple=True,
    metavar="KEY.PATH=V1,V2,...",
    help="A swept key and its values: TOML scalars, expressions of pi (pi/4), inclusive "
    "ranges start:step:stop (0:0.25:0.75). Repeat for more keys; replaces the key's "
    "values in the case's [sweep] table.",
)
@click.option(
    "-o",
    "--output",
    "output",
    type=PathParam(file_okay=False, give="a sweep directory"),
    default=None,
    help="Sweep directory (default: out/<case name>). Re-running into it resumes.",
)
@click.option(
    "-j",
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Worker processes (default: all cores). 1 runs in this process.",
)
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="Run the jobs on a Dask distributed cluster (e.g. tcp://host:8786).",
)
@click.option(
    "--modes",
    type=click.IntRange(min=0),
    default=0,
    metavar="K",
    help="Also the K lowest natural frequencies of every row's equilibrium: columns "
    "f1..fK [Hz] (as catenet modes finds them).",
)
@click.option(
    "--case",
    "load_case",
    metavar="NAME",
    default=None,
    help="Report this [[load_case]] or [[combination]] of the case in every row (solved "
    "from the row's base state).",
)
@click.option("--save-runs", is_flag=True, help="Also keep each run's HDF5 file in DIR/runs/.")
@click.option("--plot", "plot", is_flag=True, help="Draw the sweep figures and report.md after.")
@verbosity_options
def command(
    case: Path,
    params: tuple[str, ...],
    output: Path | None,
    workers: int | None,
    scheduler: str | None,
    modes: int,
    load_case: str | None,
    save_runs: bool,
    plot: bool,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Run CASE over the Cartesian product of the --param values (and of the case's
    [sweep] table).

    \b
    Keys under load. (load.pressure, ...) are solved as one continuation per
    combination of the other keys: each load level starts from the previous
    equilibrium. Results: DIR/results.csv and DIR/results.h5 (group /table, one
    dataset per column), one row per case and load level; DIR/results.jsonl is the
    journal they are made from. A failed case is recorded with its error; a worker
    process that dies is retried once. Running the same command again skips the
    finished cases (resume after Ctrl-C or a crash).

    \b
    Example (the paper's study, Sec. 3.2):
      catenet sweep configs/sweeps/paper.toml -o out/paper
      catenet sweep case.toml -p geometry.n=10,18 -p "geometry.alpha=0,pi/4" \\
          -p load.pressure=10:10:100 -o out/small

    Exit status 0 when every row converged, 1 when some failed, 2 on bad input,
    130 when interrupted (finished rows are kept).
    """
    setup_logging(quiet, verbose, debug)
    with _sigterm_as_interrupt(), errors_to_exit_codes(debug):
        from catenet import sweep as sw

        spec = sw.load_sweep(case, params, modes=modes, load_case=load_case)
        out = output if output is not None else Path("out") / case.stem
        pool = _Pool(workers, scheduler)
        if not quiet:
            click.echo(_plan(spec, out, pool), err=True)
        summary = _run(spec, out, pool, save_runs, quiet)
        if not quiet:
            click.echo(_finished(summary, out), err=True)
        if plot:
            _plot(out, quiet)
        _exit_if_rows_failed(spec, out)


@dataclass(frozen=True)
class _Pool:
    """Where a sweep's jobs run: ``workers`` processes (None: every core) or the Dask
    cluster at ``scheduler``."""

    workers: int | None
    scheduler: str | None

    def describe(self, jobs: int) -> str:
        """Where ``jobs`` jobs run, as the sweep's first line says it."""
        from catenet import sweep as sw

        if self.scheduler:
            return f"Dask scheduler {self.scheduler}"
        k = self.workers or sw.cores()
        k_eff = min(k, jobs)
        if k == 1:
            return "this process"
        return f"{k_eff} worker processes x {sw.threads_per_worker(k_eff)} thread(s)"


def _plan(spec: Sweep, out: Path, pool: _Pool) -> str:
    """The line that opens a sweep: its cases, load levels and rows, where they run and
    the directory they go to."""
    jobs = spec.jobs
    n_load = len(jobs[0].levels) if jobs and jobs[0].levels else 1
    return (
        f"sweep: {len(jobs)} case(s) x {n_load} load level(s) = {spec.n_rows} rows "
        f"on {pool.describe(len(jobs))} -> {out}"
    )


def _run(spec: Sweep, out: Path, pool: _Pool, save_runs: bool, quiet: bool) -> SweepSummary:
    """The sweep run into ``out`` with a progress bar; interrupted, it exits with 130 and
    says how many rows are kept."""
    from catenet import sweep as sw

    progress = Progress("sweep", enabled=False if quiet else None)
    try:
        return sw.run_sweep(
            spec,
            out,
            workers=pool.workers,
            scheduler=pool.scheduler,
            save_runs=save_runs,
            progress=progress.update,
        )
    except KeyboardInterrupt:
        progress.close()
        header, done = sw.read_journal(out)
        rows = sum(len(r["rows"]) for r in done.values())
        fail(
            f"interrupted: {rows} of {spec.n_rows} rows done and kept in {out}; "
            "run the same command again to resume",
            130,
        )
    finally:
        progress.close()


def _finished(summary: SweepSummary, out: Path) -> str:
    """The line that closes a sweep: rows, cases skipped or retried, time and tables."""
    from catenet import sweep as sw

    parts = [f"{summary.total_rows} rows"]
    if summary.skipped_jobs:
        parts.append(f"{summary.skipped_jobs} case(s) already done")
    if summary.retried_jobs:
        parts.append(f"{len(summary.retried_jobs)} case(s) retried after a worker died")
    return (
        f"{', '.join(parts)}; {summary.wall_time:.1f} s. Tables: "
        f"{out / sw.CSV_FILE}, {out / sw.H5_FILE}"
    )


def _plot(out: Path, quiet: bool) -> None:
    """Draws the sweep's figures and report and prints their paths (unless ``quiet``)."""
    from catenet.cli.plot import sweep_figures

    for path in sweep_figures(out, None):
        if not quiet:
            click.echo(str(path))


def _exit_if_rows_failed(spec: Sweep, out: Path) -> None:
    """Exits with 1, saying how many, when any row of the sweep's journal failed."""
    from catenet import sweep as sw

    header, done = sw.read_journal(out)
    failed = sum(1 for rec in done.values() for r in rec["rows"] if r.get("error"))
    if failed:
        click.echo(
            f"catenet: {failed} of {spec.n_rows} rows failed or did not converge "
            f"(see the error column of {out / sw.CSV_FILE})",
            err=True,
        )
        sys.exit(EXIT_FAILED)


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """While the sweep runs, SIGTERM stops it like Ctrl-C: workers stopped, finished
    rows kept."""
    import signal

    def handler(signum, frame):
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
