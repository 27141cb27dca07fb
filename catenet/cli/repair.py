"""``catenet repair``: make a result file open in every reader."""

from __future__ import annotations

from pathlib import Path

import click

from catenet.cli.common import HELP, errors_to_exit_codes, setup_logging, verbosity_options


@click.command(name="repair", context_settings=HELP)
@click.argument("paths", nargs=-1, required=True, type=click.Path(path_type=Path))
@verbosity_options
def command(paths: tuple[Path, ...], quiet: bool, verbose: int, debug: bool) -> None:
    """Mend result files so that every HDF5 reader, ParaView and meshio open them.

    \b
    A file that ordinary readers refuse (HDF5's "open for writing" mark left by a
    killed catenet of an earlier version), that holds incomplete frames (a full disk) or lacks
    the per-frame views its XDMF sidecar names is rewritten with its complete
    frames, in one step; the sidecar is rewritten to match; hidden spare copies a
    killed run left beside the file (.OUT.h5.spare) are removed. A file that needs
    nothing is left as it is.

    Prints what was done for each file. Exit status 2 for a missing file or one
    that is not a catenet result file.
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.output import repair

        for path in paths:
            done = repair(path)
            if quiet:
                continue
            if done.rewrote:
                click.echo(f"{path}: rewritten ({'; '.join(done.problems)})")
            else:
                click.echo(f"{path}: fine as it was")
            click.echo(f"  {done.frames} complete frames")
            if done.sidecar is not None:
                click.echo(f"  sidecar {done.sidecar}")
            for p in done.removed:
                click.echo(f"  removed {p}")
