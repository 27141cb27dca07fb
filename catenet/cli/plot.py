"""``catenet plot``: figures from a result file or a sweep directory."""

from __future__ import annotations

from pathlib import Path

import click

from catenet.cli.common import HELP, errors_to_exit_codes, setup_logging, verbosity_options


@click.command(name="plot", context_settings=HELP)
@click.argument("path", type=click.Path(path_type=Path))
@click.option(
    "-o",
    "--output",
    "output",
    type=click.Path(path_type=Path),
    default=None,
    help="Figure file (.png, .svg or .pdf); default: the result file with .png. "
    "For a sweep directory: where the sweep figures go.",
)
@click.option(
    "--scale",
    type=float,
    default=1.0,
    show_default=True,
    help="Draw displacements this many times larger (small deflections become visible).",
)
@click.option(
    "--history",
    is_flag=True,
    help="Plot a dynamic run's histories against time instead (/history: support "
    "reactions, contact forces per obstacle or body, cable end tensions), into "
    "RESULT-history.png by default.",
)
@verbosity_options
def command(
    path: Path,
    output: Path | None,
    scale: float,
    history: bool,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Draw the figures of PATH: a result file (OUT.h5) or a sweep output directory.

    \b
    Result file: the deformed net over the undeformed one, coloured by tension
    (colour bar in N over the range of the data), in 3D and in a side view; for
    runs with a trajectory also the deflection of the probe node (positive down)
    against time (dynamic runs) or load factor (static runs in steps). The case's
    obstacles are drawn in light grey (a moving one where it is at the end). The
    paper's single-cable cases get the paper's axes and closed forms (Figs.
    2e-2f, Eqs. 14-17).
    A file of `catenet modes` also gets STEM-modes.png beside that figure: its
    lowest modes (up to six), each with its frequency.
    Sweep directory: each output column (deflection, largest displacement,
    tension, compression, reaction, strain, slack edges, peaks) against each
    swept parameter, sweep_<key>.png; for sweeps of the paper's square net also
    its figures 5-8 and report.md (catenet.study).

    --history: a dynamic run's histories (every time step): the reactions'
    resultant and that of each support set (else the largest supports), the
    contact force of each obstacle or body on the net, the tension at both ends
    of each named cable.

    Prints the path of every figure written. Exit status 2 for a missing or
    unreadable file or a file without the result layout.
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.errors import ConfigError

        if history:
            from catenet.plot.history import plot_history

            if path.is_dir():
                raise ConfigError(
                    f"{path}: --history: give a result file (RESULT.h5), not a directory"
                )
            if not path.exists():
                raise ConfigError(f"{path}: no such file or directory")
            if scale != 1.0:
                raise ConfigError("--history draws no net: give it without --scale")
            files = [plot_history(path, output)]
        elif path.is_dir():
            files = sweep_figures(path, output)
        elif not path.exists():
            raise ConfigError(f"{path}: no such file or directory")
        else:
            from catenet.plot.figure import plot_result
            from catenet.plot.modes import modes_output, plot_modes

            files = [plot_result(path, output, scale=scale)]
            drawn = plot_modes(path, modes_output(files[0]))
            if drawn is not None:
                files.append(drawn)
        if not quiet:
            for f in files:
                click.echo(str(f))


def sweep_figures(directory: Path, out: Path | None) -> list[Path]:
    """Every sweep's column figures, and the paper's figures and report for a sweep of
    the square net."""
    from catenet.errors import ConfigError
    from catenet.plot.sweep import is_square_net_sweep, plot_columns

    files = plot_columns(directory, out)
    if is_square_net_sweep(directory):
        from catenet.study import plot_sweep

        files += plot_sweep(directory, out)
    if not files:
        raise ConfigError(f"{directory}: the sweep has no row with numbers to plot yet")
    return files
