"""``catenet report``: the tables of a result file as Markdown, CSV or HTML."""

from __future__ import annotations

from pathlib import Path

import click

from catenet.cli.common import HELP, errors_to_exit_codes, setup_logging, verbosity_options


@click.command(name="report", context_settings=HELP)
@click.argument("path", metavar="RESULT.h5", type=click.Path(path_type=Path))
@click.option(
    "-o",
    "--output",
    "output",
    metavar="FILE",
    default=None,
    help="Where the report goes: a file (md, html, xlsx), a directory (csv), or - for the "
    "standard output (md, html). Default: beside the result file, STEM.md, STEM.html, "
    "STEM.xlsx or the directory STEM-csv.",
)
@click.option(
    "--format",
    "fmt",
    metavar="md|csv|html|xlsx",
    default=None,
    help="Markdown (the default), CSV files (one per table), HTML with figures or an Excel "
    "workbook (a sheet per table); default: from the suffix of -o, else md.",
)
@verbosity_options
def command(
    path: Path, output: str | None, fmt: str | None, quiet: bool, verbose: int, debug: bool
) -> None:
    """Write the report of RESULT.h5: for the base state, each load case, each
    combination and the envelope over them, per cable (by name) the largest and
    least tension, the largest utilisation and the slack length; the reaction of each
    support set and supported node; the largest displacement of the free nodes and of
    each node set, and where; the applied loads against reactions and contact; the
    verdict and the warnings of each. A dynamic run adds its peaks with their times.

    \b
    Prints the path of every file written. Exit status 2 for a missing or
    unreadable file, a file without the result layout or a bad --format.
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.report import format_of, make_report, write_report

        kind = format_of(None if output is None else Path(output), fmt)
        if output == "-":
            from catenet.errors import ConfigError

            if kind == "csv":
                raise ConfigError("-o -: --format csv writes one file per table: give a directory")
            if kind == "xlsx":
                raise ConfigError("-o -: --format xlsx writes a workbook: give a file (.xlsx)")
            click.echo(make_report(path, kind), nl=False)
            return
        files = write_report(path, None if output is None else Path(output), kind)
        if not quiet:
            for f in files:
                click.echo(str(f))
