"""``catenet bench``: timing and accuracy studies (code in ``catenet.studies.bench``)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import click

from catenet.cli.common import (
    EXIT_FAILED,
    Progress,
    errors_to_exit_codes,
    setup_logging,
    verbosity_options,
)

# Kept here (not imported from catenet.studies.bench) so that `catenet bench --help` stays light.
STUDIES = (
    "step-size",
    "pareto",
    "scale",
    "baseline",
    "skips",
    "cold-start",
    "stress",
    "formfind",
    "flush",
    "reuse",
    "integrators",
)
CHOICES = (*STUDIES, "all", "report")


@click.command(name="bench")
@click.argument("studies", nargs=-1, required=True, type=click.Choice(CHOICES))
@click.option(
    "-o",
    "--output",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    required=True,
    help="Directory for the CSV tables and figures (nothing is written elsewhere).",
)
@click.option("--quick", is_flag=True, help="Smaller versions of the studies (~3 min in all).")
@click.option(
    "--threads",
    type=click.IntRange(min=1),
    default=1,
    show_default=True,
    help="BLAS/MKL/Numba threads of the in-process studies.",
)
@click.option(
    "--docs",
    "docs_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="report: where readme-performance.md and figures/ go (default: OUTPUT).",
)
@click.option(
    "--readme",
    "readme",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="report: also put the section into this README between its performance markers.",
)
@click.option(
    "--strict",
    is_flag=True,
    help="Exit with status 1 when a study has findings "
    "(e.g. a stress scene without a right answer).",
)
@verbosity_options
def command(
    studies,
    out_dir: Path,
    quick: bool,
    threads: int,
    docs_dir: Path | None,
    readme: Path | None,
    strict: bool,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Run timing and accuracy studies; each writes OUTPUT/<study>.csv and
    OUTPUT/bench-<study>.png.

    \b
    step-size   dynamic relaxation time against h (paper Fig. B10), n = 10, 22, 34
    pareto      run time against error (method, h, rtol, edge length)
    scale       static solve from 1e3 to 1e7 DOF (--quick: to 1e5): time split, memory
    baseline    catenet against plain NumPy/SciPy/pypardiso (and OpenSees if it imports)
    skips       what skipping saves: static, gravity, output, re-analysis, mtype, threads
    cold-start  catenet --help, catenet run with an empty and a warm JIT cache
    stress      hard scenes: right answer or a clear error, never a NaN
    formfind    force density method on roofs of 1e3 to 1e5 edges (--quick: to 1e4);
                a form-found 1e5-DOF roof under snow against a static solve
    reuse       modified Newton in dynamic runs (n = 34 relaxation, a net on a sphere)
                against a factorisation per iteration; an obstacle never touched
    integrators numerical damping of implicit Euler and newmark against h omega; time
                to rest of the damping study (mu = 0.1, 1, 10) with each
    all         every study above, in this order
    report      readme-performance.md and figures/ (in --docs, default OUTPUT) from
                OUTPUT's CSV files; with --readme, also that README's section
                (give it after the studies to run them first: all report)

    Findings (a default that is not the faster choice, a stress scene without a right
    answer) are printed at the end; --strict turns them into exit status 1.
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        names: list[str] = []
        for s in studies:
            for name in STUDIES if s == "all" else (s,):
                if name not in names:
                    names.append(name)
        findings: list[str] = []
        for name in names:
            if name == "report":
                continue
            findings += _run_one(name, out_dir, quick, threads, quiet)
        if "report" in studies:
            from catenet.studies.bench.report import write_report

            path = write_report(out_dir, out_dir if docs_dir is None else docs_dir, readme)
            if not quiet:
                click.echo(f"report written to {path}")
        for f in findings:
            click.echo(f"catenet: finding: {f}", err=True)
        if findings and strict:
            sys.exit(EXIT_FAILED)


def _run_one(name: str, out_dir: Path, quick: bool, threads: int, quiet: bool) -> list[str]:
    from catenet.studies.bench import study
    from catenet.studies.bench.common import write_machine

    out_dir.mkdir(parents=True, exist_ok=True)
    write_machine(out_dir)
    module = study(name)
    progress = Progress(name, enabled=None if not quiet else False)
    start = time.perf_counter()
    try:
        result = module.run(
            out_dir,
            quick=quick,
            threads=threads,
            progress=lambda done, total, note="": progress.update(done, total, note),
        )
    finally:
        progress.close()
    if not quiet:
        click.echo(f"== {name}: {module.TITLE} ({time.perf_counter() - start:.1f} s)")
        for line in result.summary:
            click.echo(f"  {line}")
        click.echo(
            f"  table: {result.csv}" + (f"  figure: {result.figure}" if result.figure else "")
        )
    return result.findings
