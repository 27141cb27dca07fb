"""Running a case: build the scene, solve it (static in load steps, or dynamic), and write
the result file while the run goes on.

``run_case`` is a plan (``plan``: everything a user can get wrong, the case, the restart
file, the output path, the linear backend, checked before the output file is created, so
bad input leaves no file behind), the solve with its file (``run_steps``), the load cases
from the base state, and the report. Once running it never loses what it has: a run
that fails to converge, is interrupted (``stop()`` returns True) or is refused a
non-finite state closes the file with its last good state in /result and
``converged = false``.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from catenet.errors import CatenetError, ConfigError
from catenet.run.report import CableSummary, RunReport, RunResult
from catenet.run.restart import RestartState, read_restart
from catenet.run.steps import Hooks, NoFile, Solved, run_steps

if TYPE_CHECKING:
    from catenet.case.parse import Case
    from catenet.output.writer import ResultWriter
    from catenet.scene import Scene

log = logging.getLogger(__name__)

__all__ = [
    "Plan",
    "RestartState",
    "output_path",
    "plan",
    "read_restart",
    "refuse_formfind",
    "run_case",
]

Progress = Callable[..., None]
Stop = Callable[[], bool]


def output_path(case: Case, out: str | Path | None = None) -> Path | None:
    """The file a run writes: ``out``, else the case's output.file (None: no file)."""
    if out is not None:
        return Path(out)
    file = case.output.file
    return Path(file) if file else None


def refuse_formfind(case: Case) -> None:
    """A case with a [formfind] table describes a net still to be form-found: running it
    would analyse its starting geometry. ConfigError saying what to do instead."""
    if case.formfind is not None:
        src = case.source or "CASE.toml"
        raise ConfigError(
            f"formfind: {src} is a form-finding case: find its shape with `catenet formfind "
            f"{src} -o OUT.h5`, then run the case OUT.toml it writes"
        )


@dataclass(frozen=True)
class Plan:
    """A run checked before anything is written (``plan``): the ``case``, its built
    ``scene``, the output ``path`` (None: no file), the ``restart`` state (None: from
    the start), the load ``cases`` to solve from the base state, the solve ``settings``
    with the resolved linear ``backend``, the ``trajectory`` estimate (None: no file)
    and the result file's run ``attrs``."""

    case: Any
    scene: Any
    path: Path | None
    restart: RestartState | None
    cases: tuple
    settings: Any
    backend: str
    trajectory: Any
    attrs: dict


def plan(case: Case, out=None, *, restart=None, scene=None, load_case=None) -> Plan:
    """Everything a user can get wrong, checked before the output file is created (the
    case, the restart file, the output path, the linear backend), and the warnings a case
    earns before it runs; ConfigError for the first problem. Arguments as ``run_case``'s."""
    from catenet.case import build
    from catenet.output import check_output_path
    from catenet.run import advice, contact_advice, history_advice
    from catenet.run.cases import pick
    from catenet.solver import path as sv
    from catenet.solver.linear import resolve_backend
    from catenet.solver.threads import set_threads

    refuse_formfind(case)
    path = output_path(case, out)
    if path is not None:  # before anything is built: a bad path is found at once
        check_output_path(path)
        _probe_directory(path)
    scene = build(case) if scene is None else scene
    cases = pick(scene, load_case)
    solver = case.solver
    state = read_restart(restart, scene) if restart is not None else None
    if path is not None:
        source = Path(case.source or "")
        if source.is_file() and _same_file(path, source):
            raise ConfigError(f"output file {str(path)!r}: is the case file itself")
        if restart is not None and _same_file(path, Path(restart)):
            raise ConfigError(
                f"--restart {restart}: is also the output file: give another one with -o"
            )
    for slip in advice.unit_slips(case, scene.net):  # a material no cable is made of
        log.warning("%s", slip)
    hopeless = advice.lines_without_catenary(case, scene)
    if hopeless:  # no static equilibrium to find: say so at once, not after minutes
        raise ConfigError(hopeless)
    notes = advice.ignored_solver_keys(solver) + advice.ignored_histories(case)
    notes += advice.ignored_contact_radius(case) + history_advice.stepped_over(case)
    notes += contact_advice.unlikely_friction(case)
    for message in notes + advice.between_nodes(scene):
        log.warning("%s", message)
    trajectory = None
    if path is not None:
        trajectory = advice.trajectory(case, scene.net, 0.0 if state is None else state.t)
    if trajectory is not None:
        if trajectory.bytes > advice.WARN_BYTES:
            log.warning("%s", trajectory.message())
        else:
            log.info("trajectory: up to %s", advice.format_bytes(trajectory.bytes))
    backend = resolve_backend(solver.linear)
    set_threads(solver.threads)
    attrs = {"linear_backend": backend, "threads": int(solver.threads)}
    if state is not None:
        attrs["restart_from"] = str(state.path)
        attrs["restart_time"] = float(state.t)
    if case.source:
        attrs["source"] = str(case.source)
    # The settings keep what the case asked for: "auto" picks its solver per system (the
    # band below a measured size, catenet.solver.banded), as a sweep or the API does.
    settings = sv.Settings.of(solver)
    return Plan(case, scene, path, state, cases, settings, backend, trajectory, attrs)


def run_case(
    case,
    out: str | Path | None = None,
    *,
    restart: str | Path | None = None,
    progress: Progress | None = None,
    stop: Stop | None = None,
    interrupt: Stop | None = None,
    scene=None,
    on_done: Callable | None = None,
    load_case: str | None = None,
):
    """Builds, solves and writes a case; returns the Result.

    A case with ``[[load_case]]`` or ``[[combination]]`` tables: the Result is the base
    state's (/result), and ``result.cases`` holds each load case and combination solved
    from it (``catenet.run.cases``: /cases/<name>/, /envelope/), ``result.report.cases``
    their numbers; ``load_case`` names the only one to solve.

    ``out``: the HDF5 file (default: the case's output.file). ``restart``: the result
    file of an earlier dynamic run of the same case; the run goes on from its last stored
    frame (time, positions, velocities and, for newmark, the scheme's acceleration state)
    and writes a new file. ``progress(done, total)`` is called after every step (time and
    t_end, inf for a run to rest, or load factor and 1); dynamic runs add
    ``rest``, how far the state is from rest (``catenet.solver.path.Step.rest``). ``stop()`` is
    asked after every step; True ends the run there (``converged = False``, message
    "interrupted"). ``interrupt()`` (a signal handler's flag: it must be cheap) is asked
    before every Newton iteration as well, so that a long step stops too: the run ends as
    interrupted with the last equilibrium (static) or time step (dynamic).

    The result (a ``RunResult``) carries a ``RunReport``: the probe's z-deflection
    ``delta`` (positive down), ``delta_over_L``, ``size``, ``probe``, ``output`` (the file
    written, or None), warnings, per-cable statistics and the summary's numbers
    (``catenet.model.summary.summarize_result``: ``max_displacement``, reactions, slack
    edges, peaks, ...); ``result.peaks`` the peaks over every step. ConvergenceError and
    other run-time errors are re-raised after /result was written, with ``.output`` set
    to the file that holds it (None when none does).

    ``scene``: the case built already (``catenet.case.build``; default: built here).
    ``on_done(scene, workspace, result)`` is called after a solve that ended (not one
    that raised), with the workspace it used (``catenet modes`` goes on from there).
    """
    from catenet.run.cases import spoken_in
    from catenet.run.clock import Clock

    start = time.perf_counter()
    clock = Clock()  # start-up against solve time (/result startup_time, solve_time)
    with spoken_in(getattr(case, "units", None) or "SI"):  # warnings in the case's units
        run, ws, solved, report = _run(case, out, restart, scene, load_case,
                                       Hooks(progress, stop, interrupt), start, clock)  # fmt: skip
    done = RunResult.of(solved.result, report)
    if on_done is not None:
        on_done(run.scene, ws, done)
    return done


def _run(case, out, restart, scene, load_case, hooks: Hooks, start: float, clock):
    """``run_case``'s plan, solve (the base state, then its load cases) and report, with
    the warnings kept in the result file: (plan, workspace, Solved, RunReport)."""
    from catenet.run.cases import heard, solve_from_base, write_warnings
    from catenet.solver import path as sv

    with heard() as base_heard:  # the base state's warnings, kept in /result
        run = plan(case, out, restart=restart, scene=scene, load_case=load_case)
        with clock.solving():
            ws = sv.workspace(run.scene, run.settings)
        solved = _solve(run, ws, hooks, start, clock)
    result = solved.result
    unphysical = _implausible(run, result)  # the base state: a unit slip, a lost support
    case_numbers: dict = {}  # each load case's summary numbers, by name
    envelope: dict = {}  # the governing cases (catenet.run.cases.governing)
    if run.cases:
        case_numbers, envelope = solve_from_base(
            run.scene, run.settings, ws, result, run.cases, run.path, hooks.interrupt
        )
    with heard() as report_heard:
        report = _report(run, ws, result, solved.bodies, case_numbers, envelope, unphysical)
    if run.path is not None:
        write_warnings(run.path, base_heard.messages + report_heard.messages, unphysical)
    return run, ws, solved, report


def _solve(run: Plan, ws, hooks: Hooks, start: float, clock) -> Solved:
    """The base state's solve through ``run_steps``, with its result file (none without
    a path); a failure re-raised with ``.output`` the file that holds its last good
    state, and bad input found late leaving no file behind."""
    from catenet.output import ResultWriter
    from catenet.run.history import layout as history_layout

    case = run.case
    dynamic = case.solver.method == "dynamic"
    newmark = dynamic and case.solver.integrator == "newmark"
    writer = (
        ResultWriter(
            run.path,
            run.scene,
            every=case.output.every,
            xdmf=case.output.xdmf,
            accelerations=newmark,
            attrs=run.attrs,
            history=history_layout(run.scene) if dynamic else None,
        )
        if run.path is not None
        else NoFile()
    )
    with writer:
        try:
            args = (run.scene, run.settings, ws, writer)
            return run_steps(*args, restart=run.restart, hooks=hooks, begin=start, clock=clock)
        except CatenetError as exc:
            exc.output = run.path if writer.has_result else None
            if isinstance(exc, ConfigError):
                _remove(writer)  # bad input found late (exit 2): leave nothing behind
            elif exc.args and isinstance(exc.args[0], str):  # a failed run's lengths and
                exc.args = (_in_units(exc.args[0], run.case),)  # forces as the case's
            raise


def _in_units(message: str, case: Case) -> str:
    """A message whose numbers carry SI unit names (``2.5 m``, ``[N]``) as the case's
    ``units`` name them (``catenet.model.units.relabel``: 2.5 mm in an N-mm case)."""
    from catenet.model.units import relabel

    return relabel([message], case.units or "SI")[0]


def _implausible(run: Plan, result) -> str:
    """The verdict on a converged base state that no cable structure reaches (strains
    beyond 10x its law's range; in a static run, a node moved beyond 10x the structure's
    size): the message, and the result marked failed (``converged`` false: the equations
    were solved, the model is not what the user meant); "" when it is plausible."""
    from catenet.solver.result import Outcome

    message = implausible_message(run.case, run.scene, result)
    if message:
        result.converged, result.outcome, result.message = False, Outcome.FAILED, message
    return message


def implausible_message(case: Case, scene: Scene, result) -> str:
    """Why a converged, stable state is implausible (``_implausible``), else ""."""
    from catenet.run.advice import implausible, unit_slips

    if not result.converged or result.stable is False:
        return ""
    static = case.solver.method == "static"  # thrown nets and bodies fly far
    what, extreme = implausible(scene.net, result.x, float(scene.size) if static else 0.0)
    if not extreme:
        return ""
    slips = unit_slips(case, scene.net)
    message = f"implausible (check units and supports): {what}"
    if slips:  # the likely cause
        message = f"{message}; {slips[0]}"
    return _in_units(message, case)  # (a slip's SI values say "in SI": kept)


def _report(
    run: Plan, ws, result, bodies: dict, case_numbers: dict, envelope: dict, unphysical: str
):
    """The RunReport of a solved run: the warnings its state earns (strain beyond the
    law, at the end or at a peak), the summary's numbers, a mechanism named, per cable
    the largest tension and the slack share; ``unphysical``: the base state's verdict
    (``_implausible``)."""
    from catenet.model import measures, summary
    from catenet.run import advice, integrator_advice

    scene, case = run.scene, run.case
    beyond = advice.strain_beyond_law(scene.net, result.x, case.units or "SI")
    if unphysical:  # the run's error says it all
        pass
    elif beyond:
        log.warning("%s", beyond)
    else:  # the peaks of the run: a rope strained beyond its law for an instant
        dynamic = case.solver.method == "dynamic"
        passed = advice.peak_strain_beyond_law(scene.net, result.peaks, dynamic)
        if passed and not (dynamic and case.solver.t_end == "rest"):
            log.warning("%s", passed)
    if lost := integrator_advice.integrator_loss(case, result):
        log.warning("%s", lost)
    if snatched := integrator_advice.snatch(case, result, ws.system.terms):
        log.warning("%s", snatched)
    if any(t.moving for t in ws.system.terms):  # two obstacles squeezing the net's end state
        from catenet.terms.pinch import squeeze_note

        top = float(abs(result.tension).max(initial=0.0))
        if squeezed := squeeze_note(ws.system.terms, result.x, float(result.time), top):
            log.warning("%s", squeezed)
    from catenet.model.joints import turn_warning, twisting_members
    from catenet.run.contact_advice import capstan_warning, wrap_warning

    if wrapped := wrap_warning(scene.net, ws.system.terms, result.x, result.tension):
        log.warning("%s", wrapped)
    if held := capstan_warning(scene.net, ws.system.terms, result.x, result.tension):
        log.warning("%s", held)
    for term in ws.system.terms:
        turned = term.name == "joints" and turn_warning(
            term.joints, result.x, scene.net, scene.cables, *twisting_members(ws.system.terms)
        )
        if turned:
            log.warning("%s", turned)
    numbers = summary.summarize_result(scene, result)
    cables = scene.cables
    if result.stable is False:  # name the mechanism's nodes and cables
        from catenet.solver.endstate import diagnose_unstable

        result.diagnosis = diagnose_unstable(
            ws,
            result.x,
            None if cables is None else cables.names,
            None if cables is None else cables.edge,
            factor=result.time if case.solver.method == "static" else None,
        )
    per_cable = None
    if cables is not None:  # per cable: the largest tension and the slack share
        top, slack = measures.cable_stats(
            scene.net, result.x, result.tension, cables.edge, len(cables.names)
        )
        per_cable = {
            name: CableSummary(float(t), float(s))
            for name, t, s in zip(cables.names, top, slack, strict=True)
        }
    return RunReport(
        delta=float(numbers["delta"]),
        size=float(scene.size),
        probe=int(numbers["probe"]),
        output=None if run.path is None else str(run.path),
        backend=run.backend,
        strain_warning=beyond or "",
        implausible=unphysical,
        trajectory_bytes=0 if run.trajectory is None else run.trajectory.bytes,
        cables=per_cable,
        bodies=bodies,
        summary=numbers,
        cases=case_numbers,
        envelope=envelope,
    )


def _probe_directory(path: Path) -> None:
    """Creates and removes a file in the nearest existing directory of ``path``: what
    permissions alone do not tell (a read-only or special file system, root's access
    to /proc) is found before anything is computed. Raises ConfigError in one sentence."""
    import tempfile

    parent = Path(path).absolute().parent
    while not parent.exists():
        parent = parent.parent
    try:
        with tempfile.TemporaryFile(dir=parent, prefix=".catenet-probe-"):
            pass
    except OSError as exc:
        why = exc.strerror or type(exc).__name__
        raise ConfigError(
            f"output file {str(path)!r}: cannot be written: creating a file in {parent} "
            f"fails ({why}); give a path in a writable directory with -o or output.file"
        ) from None


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _remove(writer: ResultWriter | NoFile) -> None:
    """Closes a result file and removes it with its sidecar (a run without a file: nothing)."""
    if isinstance(writer, NoFile):
        return
    for p in (writer.path, writer.sidecar):
        try:
            writer.close()
            p.unlink(missing_ok=True)
        except OSError:
            pass
