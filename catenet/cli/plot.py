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
@click.option(
    "--case",
    "case",
    metavar="NAME",
    default=None,
    help="Draw a load case, combination or the envelope over them (envelope), or "
    "the base state (base), into RESULT-NAME.png by default.",
)
@click.option(
    "--time",
    "time",
    metavar="T",
    type=float,
    default=None,
    help="Draw the stored frame of a dynamic run nearest to time T [s] (said when it "
    "is not at T), into RESULT-frameK.png by default.",
)
@click.option(
    "--frame",
    "frame",
    metavar="K",
    type=int,
    default=None,
    help="Draw stored frame K of the trajectory (0 the first, -1 the last).",
)
@click.option(
    "--x",
    "x",
    metavar="KEY",
    default=None,
    help="Sweep directory: the swept key on the horizontal axis (KEY[i]: element i of "
    "an array-valued key).",
)
@click.option(
    "--y",
    "y",
    metavar="COLUMN",
    multiple=True,
    help="Sweep directory: a column of the table to plot (repeat for more panels): "
    "summary columns, f1..fK of --modes, max_utilisation, COLUMN[i] of an array.",
)
@verbosity_options
def command(
    path: Path,
    output: Path | None,
    scale: float,
    history: bool,
    case: str | None,
    time: float | None,
    frame: int | None,
    x: str | None,
    y: tuple[str, ...],
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

    --case NAME: the load case, combination or envelope NAME (the envelope:
    the largest tension over the cases on the base state's shape, the plan
    view by the largest displacement); --time T, --frame K: a stored frame of
    the trajectory (its tensions, and a dynamic run's reactions at that step),
    marked on the time panel.

    Sweep directory: each output column (deflection, largest displacement,
    tension, compression, reaction, strain, slack edges, peaks, utilisation,
    frequencies) against each swept parameter, sweep_<key>.png; with --x KEY
    and --y COLUMN (repeatable) the chosen columns against that key,
    sweep_<columns>_vs_<key>.png, one line per value of the other keys. A
    name the table lacks lists what can be plotted. For sweeps of the paper's
    square net over geometry.n and geometry.alpha also its figures 5-8 and
    report.md (catenet.study).

    --history: a dynamic run's histories (every time step): the reactions'
    resultant and that of each support set (else the largest supports), the
    contact force of each obstacle or body on the net, the tension at both ends
    of each named cable.

    Prints the path of every figure written. Exit status 2 for a missing or
    unreadable file, a file without the result layout, a state, frame, time or
    column the file or table does not have (the message lists what it has).
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.errors import ConfigError

        _check_options(path, history, case, time, frame, x, y, scale)
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
            files = sweep_figures(path, output, x, list(y))
        elif not path.exists():
            raise ConfigError(f"{path}: no such file or directory")
        else:
            from catenet.plot.figure import plot_result
            from catenet.plot.modes import modes_output, plot_modes

            def say(note: str) -> None:
                if not quiet:
                    click.echo(f"catenet: {note}", err=True)

            files = [
                plot_result(path, output, scale=scale, say=say, case=case, time=time, frame=frame)
            ]
            if case is None and time is None and frame is None:
                drawn = plot_modes(path, modes_output(files[0]))
                if drawn is not None:
                    files.append(drawn)
        if not quiet:
            for f in files:
                click.echo(str(f))


def _check_options(path: Path, history, case, time, frame, x, y, scale) -> None:
    """One message for options that do not go together or with PATH's kind."""
    from catenet.errors import ConfigError

    state = [
        n for n, v in (("--case", case), ("--time", time), ("--frame", frame)) if v is not None
    ]
    sweep = [n for n, v in (("--x", x), ("--y", y)) if v]
    if history and (state or sweep):
        raise ConfigError(f"--history with {', '.join(state + sweep)}: give one of them")
    if path.is_dir() and state:
        raise ConfigError(
            f"{path}: {', '.join(state)}: choose a state of a result file (RESULT.h5); "
            "a sweep directory takes --x KEY --y COLUMN"
        )
    if sweep and path.exists() and not path.is_dir():
        raise ConfigError(f"{path}: {', '.join(sweep)}: plot a sweep's columns: give its directory")
    if sweep and scale != 1.0:
        raise ConfigError("--scale draws a net's displacements: a sweep's columns take none")


def sweep_figures(
    directory: Path, out: Path | None, x: str | None = None, y: list[str] | None = None
) -> list[Path]:
    """Every sweep's column figures (or the --x/--y one), and the paper's figures and
    report for a sweep of the square net over n and alpha."""
    from catenet.errors import ConfigError
    from catenet.plot.sweep import is_square_net_sweep, plot_chosen, plot_columns

    if x is not None or y:
        return plot_chosen(directory, out, x, y or [])
    files = plot_columns(directory, out)
    if is_square_net_sweep(directory):
        from catenet.study import plot_sweep

        files += plot_sweep(directory, out)
    if not files:
        raise ConfigError(f"{directory}: the sweep has no row with numbers to plot yet")
    return files
