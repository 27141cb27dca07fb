"""``catenet modes``: a case's equilibrium, then its lowest natural frequencies and modes."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from catenet.cli.common import (
    EXIT_FAILED,
    EXIT_OK,
    HELP,
    PathParam,
    Progress,
    case_options,
    errors_to_exit_codes,
    setup_logging,
    verbosity_options,
)


def _count(ctx, param, value):
    """--count as given: a positive integer, else exit 2 with the value named."""
    from catenet.errors import ConfigError

    try:
        count = int(value, 10)
    except (TypeError, ValueError):
        count = None
    if count is None or count < 1 or str(value).strip() != str(value):
        with errors_to_exit_codes():
            raise ConfigError(f"--count = {value!r}: must be a positive integer")
    return count


@click.command(name="modes", context_settings=HELP)
@click.argument(
    "case_file",
    metavar="CASE.toml",
    type=PathParam(exists=True, dir_okay=False, give="a case file"),
)
@case_options(
    "Result file (default: the case's output.file). Missing directories are created.",
    "material.prestress=2000",
)
@click.option(
    "--count",
    "-k",
    default="10",
    show_default=True,
    callback=_count,
    metavar="K",
    help="How many of the lowest modes.",
)
@click.option(
    "--case",
    "only_case",
    metavar="NAME",
    default=None,
    help="The modes about the state under this [[load_case]] or [[combination]] (solved "
    "from the base state); default: about the base state.",
)
@verbosity_options
def command(
    case_file: Path,
    out: Path | None,
    overrides: tuple[str, ...],
    count: int,
    only_case: str | None,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Solve CASE.toml's equilibrium (prestress, self-weight, loads: as `catenet run`
    does) and find its K lowest natural frequencies and mode shapes about it (supports
    held). Writes the result file of `catenet run` plus /modes (frequency [Hz], period
    [s], mass-normalised shape, effective_mass [kg], participation) and each mode as an
    animation in the XDMF sidecar; prints a table of the modes.

    \b
    Load cases: the modes are about the base state (/result), or with --case NAME
    about the state under that [[load_case]] or [[combination]] (/modes attribute
    load_case).
    Mass: material.density per unstressed volume (rho A l0 / 2 at each end of an
    edge) plus [[mass]] point masses. Zero-frequency modes (a node on slack edges
    only, a mechanism) are named, not listed.
    Exit status: 0 done; 1 the equilibrium failed (or is unstable, not at rest, or
    holds no stiffness);
    2 bad input (case file, --set, --count, a net without mass).
    """
    setup_logging(quiet, verbose, debug)
    code = EXIT_OK
    with errors_to_exit_codes(debug):
        from catenet.case import load_case
        from catenet.run.modes import modes_case

        case = load_case(case_file, overrides)
        bar = Progress("load", enabled=False if quiet else None)

        def progress(done: float, total: float, rest: float = float("nan")) -> None:
            bar.update(done, total, note=f"{done:.4g}")

        try:
            done = modes_case(case, out, count=count, progress=progress, load_case=only_case)
        finally:
            bar.close()
        if done.modes is None:
            click.echo(f"catenet: did not converge: {done.result.message}", err=True)
            code = EXIT_FAILED
        elif not quiet:
            _summary(case, done)
    sys.exit(code)


def _summary(case, done) -> None:
    from catenet.model.units import relabel
    from catenet.run.modes import mode_rows

    result, modes, path = done.result, done.modes, done.path
    s = modes.stats
    if done.load_case is not None:
        state = f"under {done.load_case}, from the base state: "
    elif case.load_cases:
        state = "the base state (--case NAME: under a load case): "
    else:
        state = ""
    lines = [
        f"{'case':<12} {case.title or case.source}",
        f"{'equilibrium':<12} {state}{result.message or 'converged'} ({result.iterations} "
        f"Newton iterations), max tension "
        f"{float(max(result.tension.max(initial=0.0), 0.0)):.6g} N",
        f"{'modes':<12} {modes.count} lowest of {s['dofs']} free DOFs ({s['method']}, "
        f"{s['backend']}, {s['seconds']:.3g} s, residual {s['residual']:.1e})",
    ]
    if s.get("bodies"):
        n = s["bodies"]
        lines.append(
            f"{'bodies':<12} {n} free bod{'y' if n == 1 else 'ies'}: 6 rigid motions each "
            "(the affine body's 6 strains, stiff and not physical, are left out)"
        )
    twisting = modes.twist is not None
    if twisting:
        n = int((modes.inertia > 0).sum())
        lines.append(
            f"{'torsion':<12} the twist angles of {n} rod edges with their rotational "
            "inertia: twist % is a mode's kinetic energy in them (dir tw: above 50 %)"
        )
    if modes.zero_modes:
        lines.append(f"{'zero modes':<12} {modes.zero_message}")
    lines.append(
        f"{'':<12} {'mode':>4} {'f [Hz]':>12} {'T [s]':>12} {'dir':>4} "
        f"{'m_eff x/y/z [% of free mass]':>30}{' twist %' if twisting else ''}   moves most"
    )
    for row in mode_rows(done.scene, modes):
        share = " ".join(f"{100 * v:9.2f}" for v in row.mass_share)
        twist = f" {100 * row.twist_share:7.2f}" if twisting else ""
        lines.append(
            f"{'':<12} {row.k:>4} {row.frequency:>12.6g} {row.period:>12.6g} "
            f"{row.direction:>4} {share:>30}{twist}   {row.moves}"
        )
    lines[1:] = relabel(lines[1:], case.units or "SI")  # the title as written
    if path is not None:
        side = Path(path).with_suffix(".xdmf")
        extra = f" (ParaView: {side}, a collection per mode)" if case.output.xdmf else ""
        lines.append(f"{'output':<12} {path}{extra}")
    click.echo("\n".join(lines))
