"""``catenet export``: a result file's frames in other formats, one file per frame."""

from __future__ import annotations

from pathlib import Path

import click

from catenet.cli.common import HELP, errors_to_exit_codes, setup_logging, verbosity_options

FORMATS = ("vtu", "vtk", "xdmf")  # catenet.output.export.FORMATS (not imported for --help)


@click.command(name="export", context_settings=HELP)
@click.argument("path", type=click.Path(path_type=Path))
@click.option(
    "--to", "fmt", type=click.Choice(FORMATS), required=True, help="The format of the files."
)
@click.option(
    "-o",
    "--output",
    "output",
    type=click.Path(path_type=Path),
    default=None,
    help="Directory for the files; default: STEM-FORMAT beside the result file.",
)
@click.option(
    "--frames",
    default="all",
    show_default=True,
    help="Which frames: all, last, an index (negative: from the end) or start:stop[:step].",
)
@click.option(
    "--mode",
    type=click.IntRange(min=1),
    default=None,
    metavar="K",
    help="A file of catenet modes: mode K's animation frames (1 = the lowest) instead.",
)
@verbosity_options
def command(
    path: Path,
    fmt: str,
    output: Path | None,
    frames: str,
    mode: int | None,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Write the frames of the result file PATH as one FORMAT file each, through meshio:
    STEM_0000.vtu, STEM_0001.vtu, ... (a file without a trajectory: its final state,
    STEM_result.vtu), and for vtu and vtk a ParaView collection STEM.pvd with every
    frame's time.

    \b
    Each file: points at the frame's positions, one line cell per edge; point data
    displacement, fixed, velocity (dynamic runs) or reaction (final state); cell data
    tension [N], rest_length [m], EA [N]. The final state also carries what /result
    holds of bending_moment, curvature, peak_displacement (point data) and
    utilisation, peak_utilisation, peak_tension, twisting_moment, force_density
    (cell data).

    --mode K (a file of catenet modes): mode K's frames over one period,
    STEM_modeK_0000.vtu ..., times the phase, point data shape (mass-normalised).

    Writes through meshio (installed with catenet). Prints the directory and the number
    of files.
    Exit status 2 for a missing or unreadable file or a bad --frames.
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.output.export import export

        done = export(path, fmt, output, frames, mode=mode)
        if not quiet:
            where = done.files[0].parent
            extra = f" and {done.collection.name}" if done.collection else ""
            click.echo(f"{len(done.files)} {fmt} files{extra} in {where}")
