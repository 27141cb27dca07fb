"""``catenet validate``: catenet against the analytic cable solutions (paper Sec. 3.1)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from catenet.cli.common import (
    EXIT_FAILED,
    HELP,
    PathParam,
    errors_to_exit_codes,
    setup_logging,
    verbosity_options,
)


@click.command(name="validate", context_settings=HELP)
@click.option(
    "-o",
    "--output",
    "output",
    type=PathParam(dir_okay=False, give="a file path such as out/validation.csv"),
    default=None,
    help="Also write the table as CSV to this file.",
)
@verbosity_options
def command(output: Path | None, quiet: bool, verbose: int, debug: bool) -> None:
    """Check catenet against the analytic cable solutions and print the error table.

    \b
    (i)  cable pinned at both ends under a midpoint load (Eqs. 16-17), F/EA from 1e-4
         to 5 % strain: the discrete model is exact, tolerance 1e-9;
    (ii) catenary with its ends moved inward by dL (Eqs. 14-15) against the exact
         elastic catenary at N = 11 .. 161 nodes: error <= 2 (h/L)^2 and observed
         order (polyfit of log err on log h) in [1.8, 2.2]; the deviation from the
         inextensible Eq. 15 is reported as information.
    (iii) every material law on a bar pulled along its axis: the paper's strain at
         F = 1e-4 EA (1e-3), 50 % strain at each law's force for it (1e-9).
    (iv) rods (EI = 1 N m^2, L = 1 m): Euler buckling of a pinned strut (1e-3 at 50
         edges), a cantilever's tip under an end load against the elastica (1e-4 of L
         at 100 edges), first natural frequencies (simply supported, cantilever,
         clamped-clamped: 1e-3), a thin ring under a diametral load (Roark: both
         diameters' changes and the moment under the load, 1e-3 at 400 edges).
    (v)  the OC3-Hywind spar's three mooring lines on a frictionless seabed: the
         published surge, heave and yaw restoring stiffness (1e-3 at 150 edges a line).
    (vi) twisted rods (EI = 1, GJ = 0.8 N m^2): a straight rod's twisting moment
         (exact), a helix under end force and moment (Love; 1e-3 at 200 edges),
         Greenhill's critical twist of a clamped rod (1e-3 at 100 edges), Michell's
         critical twist of a ring (1e-3 at 200 edges), the first torsional frequency
         of a shaft clamped-free and clamped-clamped (1e-3 at 50 edges).

    Exit status 0 when every check passes, 1 when one fails, 2 on bad options.
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.errors import ConfigError

        if output is not None and not output.resolve().parent.is_dir():
            raise ConfigError(f"--output = {str(output)!r}: its directory does not exist")

        from catenet.solver.threads import set_threads
        from catenet.validate import table as validation

        set_threads(1)  # a run's default (solver.threads): the checks' systems are small
        rows = validation.run()
        if not quiet:
            click.echo(validation.format_table(rows))
            click.echo(
                f"\norder: slope of polyfit(log h, log err) over N = "
                f"{', '.join(map(str, validation.CATENARY_NODES))}, required in "
                f"[{validation.ORDER_BAND[0]}, {validation.ORDER_BAND[1]}]; "
                "info rows have no tolerance."
            )
        for r in rows:
            if r.note and r.passed is not False:
                click.echo(
                    f"catenet: note: {r.case}, {r.quantity}, N = {r.resolution}: {r.note}", err=True
                )
        if output is not None:
            validation.write_csv(rows, output)
            if not quiet:
                click.echo(f"table written to {output}")
        failed = [r for r in rows if r.passed is False]
        for r in failed:
            click.echo(
                f"catenet: FAILED {r.case}, {r.quantity}, N = {r.resolution}: {r.failure()}",
                err=True,
            )
        if failed:
            click.echo(f"catenet: {len(failed)} of {len(rows)} checks failed", err=True)
            sys.exit(EXIT_FAILED)
        if not quiet:
            checked = sum(r.passed is not None for r in rows)
            click.echo(f"all {checked} checks passed")
