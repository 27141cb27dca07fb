"""Running a case: build the scene, solve it (static in load steps, or dynamic), and write
the result file while the run goes on.

``run_case`` checks everything a user can get wrong (the case, the restart file, the
output path, the linear backend) before it creates the output file, so bad input leaves no
file behind. Once running it never loses what it has: a run that fails to converge, is
interrupted (``stop()`` returns True) or is refused a non-finite state closes the file
with its last good state in /result and ``converged = false``.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.errors import CatenetError, ConfigError
from catenet.run.report import CableSummary, RunReport, RunResult
from catenet.solver.result import Timing

log = logging.getLogger(__name__)

__all__ = ["RestartState", "output_path", "read_restart", "refuse_formfind", "run_case"]

Progress = Callable[..., None]
Stop = Callable[[], bool]


@dataclass
class RestartState:
    """Where a dynamic run goes on from: time, positions, velocities and the newmark
    scheme's acceleration state (None: not in the file, or not a newmark case)."""

    path: Path
    t: float
    x: np.ndarray
    v: np.ndarray
    source: str
    a: np.ndarray | None = None
    peaks: dict | None = None  # the earlier run's peaks up to t (None: not in the file)


def output_path(case, out: str | Path | None = None) -> Path | None:
    """The file a run writes: ``out``, else the case's output.file (None: no file)."""
    if out is not None:
        return Path(out)
    file = case.output.file
    return Path(file) if file else None


def read_restart(path: str | Path, scene) -> RestartState:
    """The last stored state of an earlier dynamic run of the same net, checked against
    the scene. Raises ConfigError for a file that does not fit."""
    from catenet.output import read_frame, read_mesh

    path = Path(path)
    label = f"--restart {path}"
    if scene.case.solver.method != "dynamic":
        raise ConfigError(
            f"{label}: only dynamic runs can be restarted (solver.method = "
            f"{scene.case.solver.method!r}); set solver.method = 'dynamic'"
        )
    try:
        frame = read_frame(path)
    except ConfigError as exc:
        raise ConfigError([f"--restart: {p}" for p in exc.problems]) from None
    except OSError as exc:
        raise ConfigError(f"{label}: cannot be read: {exc}") from None
    try:
        problems = _mesh_mismatch(read_mesh(path, what=label), scene.net)
    except (TypeError, ValueError) as exc:  # /mesh datasets that are not numbers
        if isinstance(exc, ConfigError):
            raise
        problems = [f"its /mesh is damaged or not a catenet result file's ({exc})"]
    shape = scene.net.nodes.shape
    for name, arr in (("positions", frame.x), ("velocities", frame.v)):
        if arr is not None and arr.shape != shape:
            problems.append(
                f"its stored {name} ({frame.source}) have shape {arr.shape}: the case's net "
                f"needs {shape}: restart with the case that wrote it"
            )
    if problems:
        raise ConfigError([f"{label}: {p}" for p in problems])
    if frame.v is None:
        raise ConfigError(
            f"{label}: holds no velocities (/trajectory/v or /result/v): it is not the file "
            "of a dynamic run with output.every > 0"
        )
    if not (np.all(np.isfinite(frame.x)) and np.all(np.isfinite(frame.v))):
        raise ConfigError(f"{label}: its last stored state is not finite")
    t_end = scene.case.solver.t_end  # "rest": goes on to rest from any time
    if not isinstance(t_end, str) and not frame.t < t_end * (1 - 1e-12):
        raise ConfigError(
            f"{label}: its last state is at t = {frame.t:.6g} s, not before solver.t_end = "
            f"{t_end!r}: raise solver.t_end to go on"
        )
    a = frame.a if scene.case.solver.integrator == "newmark" else None
    if a is not None and not (a.shape == frame.x.shape and np.all(np.isfinite(a))):
        raise ConfigError(f"{label}: its stored accelerations (/trajectory/a) are not usable")
    if a is None and scene.case.solver.integrator == "newmark":
        log.info(
            "%s: holds no newmark acceleration state: the run goes on from the physical "
            "acceleration (not exactly as the uninterrupted run would)",
            label,
        )
    from catenet.output.reader import read_peaks

    peaks = read_peaks(path, frame.t)
    return RestartState(path, frame.t, frame.x, frame.v, frame.source, a, peaks)


def _mesh_mismatch(mesh, net) -> list[str]:
    """How the net of a result file (an ``output.Mesh``) differs from the case's."""
    nodes, edges, rest, fixed = mesh.nodes, mesh.edges, mesh.rest_length, mesh.fixed
    if nodes.shape != net.nodes.shape or edges.shape != net.edges.shape:
        return [
            f"its net has {len(nodes)} nodes and {len(edges)} edges, the case's "
            f"{net.n_nodes} and {net.n_edges}: restart with the case that wrote it"
        ]
    problems = []
    if not np.array_equal(edges, net.edges):
        problems.append("its edges differ from the case's: restart with the case that wrote it")
    if not np.allclose(rest, net.rest_length, rtol=1e-12, atol=0.0):
        problems.append("its rest lengths differ from the case's")
    if not np.array_equal(fixed.astype(bool), net.fixed):
        problems.append("its supports differ from the case's")
    EA = mesh.EA
    if EA is not None and (EA.shape != net.EA.shape or not np.allclose(EA, net.EA, rtol=1e-12)):
        problems.append("its axial stiffnesses EA differ from the case's")
    return problems


def refuse_formfind(case) -> None:
    """A case with a [formfind] table describes a net still to be form-found: running it
    would analyse its starting geometry. ConfigError saying what to do instead."""
    if getattr(case, "formfind", None) is not None:
        src = getattr(case, "source", "") or "CASE.toml"
        raise ConfigError(
            f"formfind: {src} is a form-finding case: find its shape with `catenet formfind "
            f"{src} -o OUT.h5`, then run the case OUT.toml it writes"
        )


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
    from catenet.case import build
    from catenet.model import measures, summary
    from catenet.output import ResultWriter, check_output_path
    from catenet.run import advice
    from catenet.run.cases import pick, solve_from_base
    from catenet.run.clock import Clock
    from catenet.solver import path as sv
    from catenet.solver.linear import resolve_backend
    from catenet.solver.threads import set_threads

    start = time.perf_counter()
    clock = Clock()  # start-up against solve time (/result startup_time, solve_time)
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
        source = Path(getattr(case, "source", "") or "")
        if source.is_file() and _same_file(path, source):
            raise ConfigError(f"output file {str(path)!r}: is the case file itself")
        if restart is not None and _same_file(path, Path(restart)):
            raise ConfigError(
                f"--restart {restart}: is also the output file: give another one with -o"
            )
    notes = advice.ignored_solver_keys(solver) + advice.ignored_histories(case)
    for message in notes + advice.newmark_contact(case):
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
    settings = sv.Settings.of(solver, linear=backend)
    with clock.solving():
        ws = sv.workspace(scene, settings)
    attrs = {"linear_backend": backend, "threads": int(solver.threads)}
    if state is not None:
        attrs["restart_from"] = str(state.path)
        attrs["restart_time"] = float(state.t)
    if getattr(case, "source", ""):
        attrs["source"] = str(case.source)
    newmark = solver.method == "dynamic" and solver.integrator == "newmark"
    writer = (
        ResultWriter(
            path,
            scene,
            every=case.output.every,
            xdmf=case.output.xdmf,
            accelerations=newmark,
            attrs=attrs,
        )
        if path is not None
        else _NoFile()
    )
    bodies: dict = {}  # the free rigid bodies' summary, filled by _run
    with writer:
        try:
            result = _run(
                scene, settings, ws, writer, state, progress, stop, interrupt, start, clock, bodies
            )
        except CatenetError as exc:
            exc.output = path if writer.has_result else None
            if isinstance(exc, ConfigError):
                _remove(writer)  # bad input found late (exit 2): leave nothing behind
            raise
    case_numbers: dict = {}  # each load case's summary numbers, by name
    envelope: dict = {}  # the governing cases (catenet.run.cases.governing)
    if cases:
        case_numbers, envelope = solve_from_base(
            scene, settings, ws, result, cases, path, interrupt
        )
    beyond = advice.strain_beyond_law(scene.net, result.x)
    if beyond:
        log.warning("%s", beyond)
    numbers = summary.summarize_result(scene, result)
    cables = getattr(scene, "cables", None)
    if result.stable is False:  # name the mechanism's nodes and cables
        from catenet.solver.diagnose import describe_unstable, describe_unstable_bodies

        result.diagnosis = describe_unstable_bodies(ws.system, result.x) or describe_unstable(
            ws.system.stretch,
            result.x,
            ~scene.net.fixed,
            None if cables is None else cables.names,
            None if cables is None else cables.edge,
        )
    if cables is not None:  # per cable: the largest tension and the slack share
        top, slack = measures.cable_stats(
            scene.net, result.x, result.tension, cables.edge, len(cables.names)
        )
        per_cable = {
            name: CableSummary(float(t), float(s))
            for name, t, s in zip(cables.names, top, slack, strict=True)
        }
    report = RunReport(
        delta=float(numbers["delta"]),
        size=float(scene.size),
        probe=int(numbers["probe"]),
        output=None if path is None else str(path),
        backend=backend,
        strain_warning=beyond or "",
        trajectory_bytes=0 if trajectory is None else trajectory.bytes,
        cables=per_cable if cables is not None else None,
        bodies=bodies,
        summary=numbers,
        cases=case_numbers,
        envelope=envelope,
    )
    run = RunResult.of(result, report)
    if on_done is not None:
        on_done(scene, ws, run)
    return run


def _run(
    scene, settings, ws, writer, state, progress, stop, interrupt, begin, clock=None, bodies=None
):
    """Solves through the one solve path, writing frames as the steps come; on failure
    or interruption the last good state becomes /result (converged = false). ``bodies``
    (a dict) receives the free rigid bodies' summary (``BodyWatch.stats``)."""
    bodies = {} if bodies is None else bodies
    from catenet.errors import Interrupted
    from catenet.model.peaks import Peaks
    from catenet.run.bodies import BodyWatch
    from catenet.solver import path as sv
    from catenet.solver.newton import interruptible
    from catenet.solver.result import Outcome, finish

    dynamic = settings.method == "dynamic"
    total = 1.0 if not dynamic else math.inf if isinstance(settings.t_end, str) else settings.t_end
    start = None
    written = {"step": -1}
    watch = BodyWatch(scene)  # free bodies: first contact, final spin (the summary's)

    if clock is None:
        from catenet.run.clock import Clock

        clock = Clock()

    def keep(step, t, x, v, tension=None, force=False, a=None) -> None:
        if (force or writer.wants(step)) and written["step"] != step:
            with clock.aside():  # writing is neither start-up nor solving
                tension = ws.system.tension(x) if tension is None else tension
                writer.frame(t, x, v, tension, a=a)
            written["step"] = step

    if dynamic:
        v_start = getattr(scene, "velocity", None)  # [[mass]] velocity: initial velocities
        if state is None:
            start = sv.Start(v=v_start, t=0.0)
        else:
            start = sv.Start(state.x, state.v, state.t, state.a)
        x0 = scene.net.nodes.copy() if state is None else state.x.copy()
        x0[scene.net.fixed] = scene.loads.support_positions(scene.net, time=start.t)
        v0 = start.v if start.v is not None else np.zeros_like(x0)
        a0 = start.a
        if a0 is None and settings.integrator == "newmark" and writer.wants(0):
            from catenet.solver.dynamic import start_acceleration

            a0 = start_acceleration(
                scene.net, scene.loads, x0, v0, damping=settings.damping, t=start.t, workspace=ws
            )
        keep(0, start.t, x0, v0, a=a0)

    def on_step(step: sv.Step) -> bool:
        watch.see(step.time, step.x)  # free bodies: their first contact
        last = step.index == settings.steps and not dynamic
        tension = step.result.tension if step.result is not None else None
        keep(step.index, step.time, step.x, step.v, tension, force=last, a=step.a)
        if progress is not None:
            if dynamic:
                progress(step.time, total, rest=step.rest)
            else:
                progress(step.time, total)
        if stop is not None and stop():
            keep(step.index, step.time, step.x, step.v, tension, force=dynamic, a=step.a)
            return True
        return False

    peaks = Peaks(scene.net.nodes, scene.net.n_edges)  # kept when the run fails
    if state is not None and state.peaks is not None and peaks.seed(state.peaks):
        log.info("--restart: the peaks go on from those of %s", state.path)
    try:
        with interruptible(interrupt), clock.solving():
            res = sv.solve(scene, settings, workspace=ws, start=start, on_step=on_step, peaks=peaks)
    except CatenetError as exc:
        good = exc.last_good
        if isinstance(exc, ConfigError) or good is None:
            raise
        stopped = isinstance(exc, Interrupted)
        x = _usable(good.x, None, scene)
        t = float(good.time)
        if dynamic:  # the last good state is the file's last frame, then /result
            try:
                keep(good.steps, t, x, good.v, force=True, a=good.a)
            except CatenetError:
                pass
        # The residual of the state kept (a dynamic run's: its static part under the loads
        # at its time), not of the failed solve's iterate, which may not even be finite.
        residual = _static_residual(ws, scene, x, t, dynamic)
        if not math.isfinite(residual):  # a term's gradient beyond floating point there:
            start = [r for r in getattr(exc, "history", None) or () if math.isfinite(r)]
            residual = start[0] if start else residual  # the failed solve's first residual
        res = finish(
            ws.system,
            scene.loads,
            x,
            1.0 if dynamic else t,
            load_time=t if dynamic else None,
            converged=False,
            equilibrium=False,
            iterations=int(good.iterations),
            residual=residual,
            steps=int(good.steps),
            time=t,
            v=good.v,
            a=good.a,
            message="interrupted" if stopped else str(exc),
            outcome=Outcome.INTERRUPTED if stopped else Outcome.FAILED,
            wall_time=time.perf_counter() - begin,
            stats=ws.stats(),
            timing=_timing(clock),
            peaks=peaks,
        )
        if stopped:  # within a step: like a stop between steps, not a failure
            log.info("interrupted during %s", "a time step" if dynamic else "a load step")
            _write_result(writer, res)
            return res
        _write_result(writer, res, failed=exc)
        raise
    if dynamic:
        keep(res.steps, res.time, res.x, res.v, force=True, a=res.a)
    else:
        res.wall_time = time.perf_counter() - begin
    if res.outcome is Outcome.INTERRUPTED:
        log.info("interrupted at %s %.6g", "t =" if dynamic else "load factor", res.time)
    res.wall_time = time.perf_counter() - begin
    res.timing = _timing(clock)
    if watch:
        bodies.update(watch.stats(res.x, res.v))
    _write_result(writer, res)
    return res


def _static_residual(ws, scene, x, at: float, dynamic: bool = False) -> float:
    """|grad E - f| over the free DOFs at x under the loads at load factor ``at`` (a
    dynamic run's: at time ``at``) [N]."""
    net = scene.net
    _, grad = ws.system.gradient(x)
    if dynamic:
        force = scene.loads.external_force(net, time=at)
    else:
        force = scene.loads.external_force(net, at)
    return float(np.linalg.norm((grad - force)[~net.fixed]))


def _timing(clock) -> Timing:
    """The run's solve and start-up seconds (``catenet.run.clock.Clock``)."""
    return Timing(solve=clock.solve, startup=clock.startup)


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def _write_result(writer, res, failed: BaseException | None = None) -> None:
    """Writes /result; when the run itself failed, a failure to write is only logged (the
    run's own error is the one to report)."""
    if failed is None:
        writer.result(res)
        return
    try:
        writer.result(res)
    except CatenetError as exc:
        log.error("%s", exc)


def _usable(state, fallback, scene) -> np.ndarray:
    """A finite state to report: the error's, else the last equilibrium, else the start."""
    for x in (state, fallback):
        if x is not None and np.shape(x) == scene.net.nodes.shape and np.all(np.isfinite(x)):
            return np.array(x, dtype=np.float64)
    x = scene.net.nodes.copy()
    x[scene.net.fixed] = scene.loads.support_positions(scene.net, factor=1.0)
    return x


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


def _remove(writer) -> None:
    for p in (getattr(writer, "path", None), getattr(writer, "sidecar", None)):
        if p is not None:
            try:
                writer.close()
                Path(p).unlink(missing_ok=True)
            except OSError:
                pass


class _NoFile:
    """Stands in for ResultWriter when a run writes no file."""

    every = 0
    frames = 0
    has_result = False

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        return None

    def wants(self, step: int) -> bool:
        return False

    def frame(self, *args, **kwargs) -> None:
        pass

    def result(self, res, **attrs) -> None:
        pass

    def close(self) -> None:
        pass
