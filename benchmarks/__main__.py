"""The benchmark studies from the command line.

    python -m benchmarks STUDY... [-o DIR] [--quick] [--threads N] [--strict]
    python -m benchmarks render [-o DIR] [--docs docs/performance.md]
    python benchmarks/<study>.py [-o DIR] [--quick] ...      (the same, one study)

Each study writes ``DIR/<study>.csv`` and ``DIR/bench-<study>.png`` (default DIR:
benchmarks/results, where the committed tables live). ``all`` runs every study in order;
``render`` fills the tables of docs/performance.md from DIR's CSV files and copies the
figures to docs/figures/ (give it after the studies to run them first: ``all render``).
Findings (a default that is not the faster choice, a stress scene without a right answer)
are printed at the end; ``--strict`` turns them into exit status 1.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import click

if __package__ in (None, ""):  # python benchmarks/__main__.py
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import STUDIES, study  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CHOICES = (*STUDIES, "all", "render")


@click.command(name="python -m benchmarks")
@click.argument("studies", nargs=-1, required=True, type=click.Choice(CHOICES))
@click.option(
    "-o",
    "--output",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=ROOT / "benchmarks" / "results",
    show_default="benchmarks/results",
    help="Directory of the CSV tables and figures.",
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
    "page",
    type=click.Path(dir_okay=False, path_type=Path),
    default=ROOT / "docs" / "performance.md",
    show_default="docs/performance.md",
    help="render: the page whose tables are filled (its figures go to figures/ beside it).",
)
@click.option("--strict", is_flag=True, help="Exit with status 1 when a study has findings.")
@click.option("-q", "--quiet", is_flag=True, help="No progress or summaries.")
def main(studies, out_dir: Path, quick: bool, threads: int, page: Path, strict: bool, quiet):
    """Run timing and accuracy studies and render docs/performance.md from their tables."""
    names: list[str] = []
    for s in studies:
        for name in STUDIES if s == "all" else (s,):
            if name not in names and name != "render":
                names.append(name)
    findings: list[str] = []
    for name in names:
        findings += run_one(name, out_dir, quick=quick, threads=threads, quiet=quiet)
    if "render" in studies:
        from benchmarks.render import render

        missing = render(out_dir, page)
        if not quiet:
            gaps = f" (no results for {', '.join(missing)})" if missing else ""
            click.echo(f"rendered {page}{gaps}")
    for f in findings:
        click.echo(f"benchmarks: finding: {f}", err=True)
    if findings and strict:
        sys.exit(1)


def run_one(name: str, out_dir: Path, *, quick=False, threads=1, quiet=False) -> list[str]:
    """Runs one study into ``out_dir``; its findings."""
    from benchmarks.common import write_machine

    out_dir.mkdir(parents=True, exist_ok=True)
    write_machine(out_dir)
    module = study(name)

    def progress(done: float, total: float, note: str = "") -> None:
        if not quiet:
            line = f"\r  {name}: {done:g}/{total:g} {note}"[:100]
            click.echo(line.ljust(100), nl=False, err=True)

    start = time.perf_counter()
    result = module.run(out_dir, quick=quick, threads=threads, progress=progress)
    if not quiet:
        click.echo("", err=True)
        click.echo(f"== {name}: {module.TITLE} ({time.perf_counter() - start:.1f} s)")
        for line in result.summary:
            click.echo(f"  {line}")
        figure = f"  figure: {result.figure}" if result.figure else ""
        click.echo(f"  table: {result.csv}{figure}")
    return result.findings


def script(name: str) -> None:
    """``python benchmarks/<study>.py ARGS``: that study with ARGS."""
    main([name, *sys.argv[1:]], prog_name=f"python benchmarks/{STUDIES[name].split('.')[-1]}.py")


if __name__ == "__main__":
    main(prog_name="python -m benchmarks")
