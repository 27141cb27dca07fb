"""``catenet bench``: the n = 34 solve warm, the backend, threads and the cold start on
this machine (``catenet.run.bench``), written only where ``-o`` says."""

from __future__ import annotations

from pathlib import Path

import click

from catenet.cli.common import (
    HELP,
    PathParam,
    errors_to_exit_codes,
    setup_logging,
    verbosity_options,
)


@click.command(name="bench", context_settings=HELP)
@click.option(
    "-o",
    "--output",
    "out_dir",
    type=PathParam(file_okay=False),
    required=True,
    help="Directory for bench.csv and bench.json (nothing is written elsewhere).",
)
@click.option(
    "--repeats",
    type=click.IntRange(min=1),
    default=5,
    show_default=True,
    help="Warm solves timed (the median is reported).",
)
@click.option(
    "--threads",
    type=click.IntRange(min=1),
    default=None,
    help="MKL/Numba/OpenBLAS threads of the warm solve [default: as installed].",
)
@click.option("--no-cold", is_flag=True, help="Leave out the cold start (fresh processes).")
@verbosity_options
def command(
    out_dir: Path,
    repeats: int,
    threads: int | None,
    no_cold: bool,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Time catenet on this machine: the paper's n = 34 net (the bundled default case,
    about 10^4 DOF) solved warm, the linear-solver backend and the threads in use, and
    the cold start of `catenet --help` and `catenet run` in fresh processes. Writes
    OUTPUT/bench.csv (name, value, unit, note) and OUTPUT/bench.json (the same, with the
    machine). The repository's benchmarks/ holds the full timing studies."""
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.run.bench import check

        report = check(repeats=repeats, threads=threads, cold=not no_cold)
        csv_path, json_path = write(report, out_dir)
        if not quiet:
            for m in report.measures:
                value = f"{m.value:.4g}" if isinstance(m.value, float) else str(m.value)
                note = f"  ({m.note})" if m.note else ""
                click.echo(f"{m.name:<18} {value} {m.unit}".rstrip() + note)
            click.echo(f"written: {csv_path}, {json_path}")


def write(report, out_dir: Path) -> tuple[Path, Path]:
    """bench.csv and bench.json in ``out_dir`` (made if missing)."""
    import csv
    import json
    from dataclasses import asdict

    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path, json_path = out_dir / "bench.csv", out_dir / "bench.json"
    rows = [asdict(m) for m in report.measures]
    with open(csv_path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=["name", "value", "unit", "note"])
        writer.writeheader()
        writer.writerows(rows)
    json_path.write_text(json.dumps({"machine": report.machine, "measures": rows}, indent=2))
    return csv_path, json_path
