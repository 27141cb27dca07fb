"""``catenet run``: solve a case file (or the bundled default) and write its HDF5 result."""

from __future__ import annotations

import signal
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from catenet.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_OK,
    HELP,
    PathParam,
    Progress,
    case_options,
    collecting_later,
    errors_to_exit_codes,
    setup_logging,
    verbosity_options,
)

if TYPE_CHECKING:
    from catenet.case.parse import Case
    from catenet.errors import CatenetError
    from catenet.run.report import RunResult

EXIT_SIGINT = 130  # interrupted by Ctrl-C (SIGINT), as shells report it
#: How the edges' watch saw a body meet the net where no barrier did, in its summary
#: line (``catenet.run.crossings.EdgeWatch.met``).
UNSEEN = {
    "cut": "strands between the nodes cut into it",
    "through": "it and the net went through each other between two {steps}",
}


def _touch(body: dict, case) -> str:
    """How a body met the net, for its summary line: a static run's state at rest, a
    dynamic run's first contact, or how the edges' watch saw them meet unseen."""
    first, dynamic = body["first_contact"], case.solver.method == "dynamic"
    if first is None and body.get("unseen"):  # met between the nodes or the states
        return _unseen(body["unseen"], case.solver.edge_contact, dynamic)
    if not dynamic:
        return "not touching the net" if first is None else "resting on the net"
    return "never touched the net" if first is None else f"first contact at t = {first:.6g} s"


def _unseen(kinds: list[str], edge_contact: bool, dynamic: bool) -> str:
    """A body's summary line where no node (nor, with edge contact, strand) came within
    its barrier's reach but the edges' watch saw the net meet it."""
    steps = "time steps" if dynamic else "load steps"
    met = " and ".join(UNSEEN[k].format(steps=steps) for k in kinds)
    what = "node or strand" if edge_contact else "node"
    many = "s" if len(kinds) > 1 else ""
    return f"no {what} of the net came within its reach, but {met} (see the warning{many})"


class StopFlag:
    """Set by SIGINT / SIGTERM: the run finishes its current step, writes and closes the
    file and stops. A second SIGINT aborts at once (KeyboardInterrupt), a second SIGTERM
    ends the process as usual."""

    def __init__(self):
        self.signal: int | None = None
        self._previous: dict[int, Any] = {}

    def __call__(self) -> bool:
        return self.signal is not None

    def _handle(self, signum, frame) -> None:
        self.signal = signum
        name = signal.Signals(signum).name
        again = "Ctrl-C again to abort" if signum == signal.SIGINT else "again to kill"
        lead = "\n" if sys.stderr.isatty() else ""
        click.echo(
            f"{lead}catenet: {name}: stopping after the current step and closing the result "
            f"file ({again})",
            err=True,
        )
        # The next one of the same kind takes the default way out.
        restore = signal.default_int_handler if signum == signal.SIGINT else signal.SIG_DFL
        signal.signal(signum, restore)

    def __enter__(self) -> StopFlag:
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self._previous[sig] = signal.signal(sig, self._handle)
            except ValueError:  # not the main thread: no handlers, Ctrl-C aborts
                pass
        return self

    def __exit__(self, *exc) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


@click.command(name="run", context_settings=HELP)
@click.argument(
    "case_file",
    metavar="[CASE.toml]",
    required=False,
    type=PathParam(exists=True, dir_okay=False, give="a case file"),
)
@case_options(
    "Result file (default: the case's output.file). Missing directories are created.",
    "solver.method=dynamic",
)
@click.option(
    "--restart",
    metavar="OLD.h5",
    type=PathParam(exists=True, dir_okay=False, give="a result file"),
    default=None,
    help="Continue a dynamic run from the last frame stored in OLD.h5 (time, positions, "
    "velocities), writing a new file.",
)
@click.option(
    "--case",
    "only_case",
    metavar="NAME",
    default=None,
    help="Solve only this [[load_case]] or [[combination]] (after the base state).",
)
@verbosity_options
def command(
    case_file: Path | None,
    out: Path | None,
    overrides: tuple[str, ...],
    restart: Path | None,
    only_case: str | None,
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Solve CASE.toml (default: the bundled square net, n = 34, alpha = pi/4) and write
    the HDF5 result file with its trajectory, plus an XDMF sidecar for ParaView.

    \b
    Exit status: 0 converged; 1 did not converge, failed while running or was
    interrupted (130 for Ctrl-C); 2 bad input (case file, --set values, paths).
    Ctrl-C or SIGTERM stops after the current step: the file is closed with the
    last state in /result (converged = false). A second Ctrl-C aborts at once.
    """
    setup_logging(quiet, verbose, debug)
    code = EXIT_OK
    with errors_to_exit_codes(debug):
        with collecting_later():
            from catenet.case import load_case
            from catenet.run.runner import output_path

        case = load_case(case_file, overrides)
        path = output_path(case, out)
        with StopFlag() as stop:
            result = _solve(case, path, restart, only_case, stop, quiet)
        code = _exit_code(case, result, path, stop.signal, quiet)
    sys.exit(code)


def _progress(dynamic: bool, quiet: bool) -> tuple[Progress, Callable[..., None]]:
    """The run's progress bar and the callback that moves it: load factors of a static
    run, a dynamic run's approach to rest."""
    bar = Progress("rest" if dynamic else "load", enabled=None)
    if quiet:
        bar.enabled = False
    relax = Relaxation()

    def progress(done: float, total: float, rest: float = float("nan")) -> None:
        if dynamic:  # toward rest, not t_end: dynamic relaxation stops at equilibrium
            frac, note = relax.update(done, rest)
            bar.update(frac, 1.0, note=note, eta=False)
        else:
            bar.update(done, total, note=f"{done:.4g}")

    return bar, progress


def _solve(
    case: Case,
    path: Path | None,
    restart: Path | None,
    only_case: str | None,
    stop: StopFlag,
    quiet: bool,
) -> RunResult:
    """The case solved into ``path`` with a progress bar (its RunResult); a failure that
    left a result file says where its last good state is."""
    from catenet.errors import CatenetError
    from catenet.run.runner import run_case

    dynamic = case.solver.method == "dynamic"
    bar, progress = _progress(dynamic, quiet)
    try:
        return run_case(
            case,
            path,
            restart=restart,
            progress=progress,
            stop=stop,
            interrupt=stop,
            load_case=only_case,
        )
    except CatenetError as exc:
        bar.close()
        _name_last_good(exc, dynamic)
        raise
    finally:
        bar.close()


def _name_last_good(exc: CatenetError, dynamic: bool) -> None:
    """Adds to the message of a run's error the file that holds its last good state,
    where one does (never for bad input)."""
    from catenet.errors import ConfigError

    written = exc.output
    if written is not None and not isinstance(exc, ConfigError):
        good = exc.last_good
        at = None if good is None else good.time
        label = ""
        if at is not None:
            label = f", t = {at:.6g} s" if dynamic else f", load factor {at:.6g}"
        exc.args = (
            f"{exc}\n  the last good state is in {written} (/result{label}; the file marks "
            "the run converged = false)",
        )


def _exit_code(
    case: Case, result: RunResult, path: Path | None, signum: int | None, quiet: bool
) -> int:
    """The exit status of a finished run, with its summary (unless ``quiet``) and its
    problems on stderr; ``signum``: the signal that stopped it, if one did."""
    if signum is not None:
        return _stopped(case, result, path, signum, quiet)
    if result.report.implausible:  # solved, but no answer: summary and error
        if not quiet:
            _summary(case, result, path)
        click.echo(f"catenet: error: the result is {result.report.implausible}", err=True)
        return EXIT_FAILED
    if not result.converged:
        click.echo(f"catenet: did not converge: {result.message}", err=True)
        return EXIT_FAILED
    if result.stable is False:
        if not quiet:
            _summary(case, result, path)
        click.echo(
            f"catenet: error: the equilibrium found is unstable: {result.diagnosis}",
            err=True,
        )
        return EXIT_FAILED
    if not quiet:
        _summary(case, result, path)
    failed = [r.name for r in result.cases if not r.converged]
    if failed:
        which = "its message in /cases/<name>" if quiet else "its row above"
        click.echo(
            f"catenet: error: load case {', '.join(failed)} failed (did not "
            f"converge, collapsed or implausible: {which} says which; its "
            "last good state is in /cases/<name>, converged = false)",
            err=True,
        )
        return EXIT_FAILED
    return EXIT_OK


def _stopped(case: Case, result: RunResult, path: Path | None, signum: int, quiet: bool) -> int:
    """The exit status of a run a signal stopped (130 for SIGINT), with what it left."""
    if result.outcome == "interrupted":  # catenet.solver.result.Outcome
        where = f"; the state so far is in {path}" if path is not None else ""
        click.echo(
            f"catenet: interrupted at {_where(case, result)}{where} (/result converged = false)",
            err=True,
        )
    else:  # the signal came during the last step: the run is complete
        if not quiet:
            _summary(case, result, path)
        click.echo("catenet: stopped by a signal after the run had finished", err=True)
    return EXIT_SIGINT if signum == signal.SIGINT else EXIT_FAILED


class Relaxation:
    """The progress of dynamic relaxation toward rest, on a log scale: the state's
    distance from rest (max(static residual, inertial force) / tolerance, 1 at rest)
    against the largest seen, so the bar fills as the residual falls decade by decade."""

    def __init__(self):
        self.first = 1.0

    def update(self, t: float, rest: float) -> tuple[float, str]:
        import math

        if math.isnan(rest):  # not measured while the supports still move
            return 0.0, f"t = {t:.4g} s (supports moving)"
        if math.isinf(rest):
            return 0.0, f"t = {t:.4g} s"
        self.first = max(self.first, rest)
        frac = 1.0 if rest <= 1.0 else 1.0 - math.log(rest) / math.log(self.first)
        return frac, f"t = {t:.4g} s, residual {rest:.2g} x tolerance"


def _where(case, result) -> str:
    """Where an interrupted run stopped: its time or load factor and the steps it had
    finished (the state may lie inside the next one: "step 1 of 2" at load factor 0.94
    named the finished step as the one it was in)."""
    if case.solver.method == "dynamic":
        return f"t = {result.time:.6g} s ({result.steps} time steps done)"
    return f"load factor {result.time:.6g} ({result.steps} of {case.solver.steps} load steps done)"


def _times(result) -> str:
    """The wall time of the process so far, split into the solve and the start-up."""
    backend, timing = result.report.backend, result.timing
    if timing is None:
        return f"{'wall time':<12} {result.wall_time:.3g} s ({backend})"
    from catenet.run.clock import since_process_start

    return (
        f"{'wall time':<12} {since_process_start():.3g} s: solve {timing.solve:.3g} s "
        f"({backend}), start-up {timing.startup:.3g} s (imports, case, JIT cache)"
    )


def _timing(case) -> bool | str:
    """How the summary dates peaks: "rest" for a run to rest (dynamic relaxation's
    pseudo-time), True for another dynamic run (times), False for load factors."""
    if case.solver.method != "dynamic":
        return False
    return "rest" if case.solver.t_end == "rest" else True


def _balance(row, scale: float, motion: float = float("nan")) -> str:
    """The summary's line of a dynamic run's energy balance [J]; its numerical part as a
    share of ``scale``, the run's largest energy (the last row's where not known), and of
    the motion's energy (``motion``, its largest kinetic energy, with what damping, drag
    and friction took) where that is under a tenth of it (a prestressed net's small
    motion, whose loss the largest energy's share hides as -0.00 %) and the numerical part
    is beyond the energies' round-off (a net at rest: 3e-15 J was "+4810591 %")."""
    from catenet.solver.energy import at_roundoff

    k, u, c, w, d, rest = (float(v) for v in row)
    largest = max(abs(k), abs(u), abs(c), abs(w), 1e-300)
    largest = scale if scale > 0 else largest  # (nan: not known)
    what = "loss" if rest <= 0.0 else "gain"
    moving = motion + max(d, 0.0)
    small = 0 < moving < 0.1 * largest and not at_roundoff(rest, largest)
    of_motion = f", {rest / moving:+.2%} of the motion's" if small else ""
    return (
        f"{'energy':<12} kinetic {k:.4g} J, elastic {u:.4g} J, contact {c:.4g} J; work in "
        f"{w:.4g} J, dissipated {d:.4g} J; numerical {rest:.3g} J ({rest / largest:+.2%} of "
        f"the run's largest energy{of_motion}: the integrator's own {what}, "
        "/trajectory/energy)"
    )


def _line_records(path: Path) -> list:
    """The named lines' records of a dynamic run's /history ([] where it has none)."""
    from catenet.errors import ConfigError
    from catenet.report.lines import line_records, lines_history

    try:
        history = lines_history(path)
    except (ConfigError, OSError):
        return []
    return [] if history is None else line_records(history)


def _summary(case, result, path: Path | None) -> None:
    from catenet.case.timing import time_dependence
    from catenet.cli.summary import (
        cases_table,
        envelope_lines,
        line_lines,
        state_lines,
        support_line,
        utilisation_line,
    )
    from catenet.model.units import relabel
    from catenet.run.advice import LARGE_BYTES, format_bytes

    s = result.report
    numbers = {**s.summary, "delta_over_L": s.delta_over_L, "size": s.size}
    warn = bool(s.strain_warning)
    state = "yes" if result.converged else "no"
    detail = result.message or ""
    if result.stable is False:  # an unstable equilibrium is no answer: never "yes"
        state, detail = "no", "an unstable equilibrium"
    elif s.implausible:  # nor a state no cable reaches
        state, detail = "no", "implausible: see the error below"
    elif result.stability == "post-collapse":
        detail = f"{detail}; post-collapse: the path collapsed on its way here".lstrip("; ")
    if case.solver.method == "dynamic" and not result.equilibrium:
        advice = "raise solver.t_end"
        if case.solver.damping == 1.0 and case.water is None:  # (the relaxation's default)
            advice += (
                " (nothing here depends on time, so the run relaxes to rest: damped by "
                "solver.damping = 1 1/s, the default; for the free motion give "
                "solver.damping = 0)"
            )
        why = time_dependence(case.load, case.supports, case.solver, case.obstacles, case.masses)
        if _prescribed(case):  # the rest test is off while anything is driven
            advice = "obstacles on prescribed motions: the run ends at solver.t_end, not at rest"
        elif why:  # a transient: its motion to t_end is the answer (catenet/case/timing.py)
            advice = f"a transient ({why}): its motion to solver.t_end is the answer"
            if why == "solver.damping = 0":
                advice += _damped_by(case)
        detail = f"{detail}; not yet at equilibrium: {advice}".lstrip("; ")
    spent = f"{result.iterations} Newton iterations"
    if result.nested is not None:  # a nested start: the coarse net's too
        spent += f" {result.nested.describe()}"
    lines = [
        f"{'case':<12} {case.title or case.source}",
        f"{'converged':<12} {state} ({detail}; {spent}, "
        f"{result.steps} {'time' if case.solver.method == 'dynamic' else 'load'} "
        f"step{'' if result.steps == 1 else 's'}, "
        f"residual {result.residual:.3g} N)",
        *state_lines(
            numbers,
            _timing(case),
            len(result.tension),
            warn,
            case.water is not None,
            case.solver.method == "dynamic" and case.solver.initial_state == "equilibrium",
        ),  # fmt: skip
        _times(result),
    ]
    if result.energy is not None:  # a dynamic run's balance (catenet.solver.energy)
        lines.insert(-1, _balance(result.energy, result.energy_scale, result.energy_motion))
    for k, b in sorted(s.bodies.items()):  # free rigid bodies and balls, one line each
        head = f"{'body':<12} obstacle[{k}] ({b['kind']}): "
        touch = _touch(b, case)
        if case.solver.method != "dynamic":  # at rest: where it is is the answer
            lines.insert(-1, head + touch)
            continue
        if b.get("ball"):  # a ball: a point, no spin
            lines.insert(-1, head + f"speed {b['speed']:.4g} m/s at the end; {touch}")
            continue
        axis = ", ".join(f"{c:.3g}" for c in b["axis"])
        lines.insert(
            -1,
            head + f"spin {b['spin']:.4g} deg/s about [{axis}], speed {b['speed']:.4g} m/s "
            f"at the end; {touch}",
        )
    if case.solver.method == "dynamic" and case.water is not None and path is not None:
        lines[-1:-1] = line_lines(_line_records(path))  # lines in water: over the run
    if s.cases:
        table = cases_table(s.cases, len(result.tension))
        lines[-1:-1] = table + envelope_lines(s.envelope)
    lines.insert(-1, utilisation_line(s.summary, s.cases))
    anchors = support_line(s.summary, s.cases)
    if anchors is not None:
        lines.insert(-1, anchors)
    lines[1:] = relabel(lines[1:], case.units or "SI")  # the title as written
    if path is not None:
        side = Path(path).with_suffix(".xdmf")
        extra = f" (ParaView: {side})" if case.output.xdmf else ""
        estimate = int(s.trajectory_bytes)
        if estimate >= LARGE_BYTES:
            size = Path(path).stat().st_size if Path(path).is_file() else 0
            extra += (
                f"; {format_bytes(size)} written, {format_bytes(estimate)} estimated "
                "before the run (output.every keeps fewer frames)"
            )
        lines.append(f"{'output':<12} {path}{extra}")
    click.echo("\n".join(lines))


def _prescribed(case) -> bool:
    """Whether an obstacle of the case moves on a prescribed motion (a velocity or spin
    and no mass: not a free body), a ball on a path included."""
    return any(
        (
            getattr(o, "velocity", None) is not None
            or getattr(o, "angular_velocity", None) is not None
        )
        and not getattr(o, "free", False)
        and getattr(o, "mass", None) is None
        for o in case.obstacles
    )


def _damped_by(case) -> str:
    """What damps a run at solver.damping = 0: "undamped" where nothing does (the water
    and the ropes' axial damping do: a line in water was called undamped)."""
    others = [
        name
        for name, on in (
            ("the water's drag", case.water is not None),
            ("the ropes' axial damping", bool(case.material.axial_damping)),
        )
        if on
    ]
    return f"; damped only by {' and '.join(others)}" if others else "; undamped, it never rests"


__all__ = ["EXIT_BAD_INPUT", "EXIT_FAILED", "EXIT_OK", "EXIT_SIGINT", "command"]
