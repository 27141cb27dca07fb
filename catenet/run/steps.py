"""A case's solve with its result file: the steps of the one solve path
(``catenet.solver.path``) written as they come, and on failure or interruption the last
good state kept as /result (``run_steps``, which ``catenet.run.runner.run_case`` calls
once everything a user can get wrong has been checked)."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from catenet.errors import CatenetError, ConfigError, ConvergenceError
from catenet.solver.result import Outcome, Result, Timing

log = logging.getLogger(__name__)

__all__ = ["Hooks", "NoFile", "Solved", "run_steps"]


@dataclass(frozen=True)
class Hooks:
    """What a caller hears and says during a run (``catenet.run.runner.run_case``):
    ``progress(done, total[, rest=])`` after every step, ``stop()`` asked after every
    step (True ends the run there), ``interrupt()`` asked before every Newton iteration
    (a signal handler's flag: cheap)."""

    progress: Callable[..., None] | None = None
    stop: Callable[[], bool] | None = None
    interrupt: Callable[[], bool] | None = None


@dataclass
class Solved:
    """A run's base state: its Result and the free rigid bodies' summary
    (``BodyWatch.stats``, by obstacle index; empty without bodies)."""

    result: Result
    bodies: dict = field(default_factory=dict)


class _Frames:
    """The frames a run keeps: each step at most once, written aside from the solve
    time (``catenet.run.clock.Clock``); with a ``history`` (``catenet.run.history``), a
    dynamic run's row of every step."""

    def __init__(self, writer, ws, clock, history=None):
        self.writer, self.ws, self.clock = writer, ws, clock
        self.history = history
        self.written = -1

    def record(self, t: float, x) -> None:
        """The history's row of the state x at time t (none without a history)."""
        if self.history is not None:
            with self.clock.aside():
                self.history.record(t, x)

    def keep(self, step, t, x, v, tension=None, force=False, a=None, last=False, energy=None):
        if (force or self.writer.wants(step)) and self.written != step:
            with self.clock.aside():  # writing is neither start-up nor solving
                tension = self.ws.system.tension(x) if tension is None else tension
                self.writer.frame(t, x, v, tension, a=a, last=last, energy=energy)
            self.written = step


def run_steps(scene, settings, ws, writer, *, restart=None, hooks=Hooks(), begin, clock) -> Solved:
    """Solves through the one solve path from the start (or ``restart``'s state), writing
    frames as the steps come; on failure or interruption the last good state becomes
    /result (converged = false). ``begin``: when the run began (perf_counter)."""
    from catenet.errors import Interrupted
    from catenet.model.peaks import Peaks
    from catenet.run.bodies import BodyWatch
    from catenet.run.crossings import EdgeWatch
    from catenet.solver import path as sv
    from catenet.solver.newton import interruptible

    dynamic = settings.method == "dynamic"
    frames = _Frames(writer, ws, clock, _recorder(scene, ws, writer, restart) if dynamic else None)
    start = _dynamic_start(scene, settings, ws, restart, frames) if dynamic else None
    watch = BodyWatch(scene)  # free bodies: first contact, final spin (the summary's)
    crossed = EdgeWatch(scene, ws.system.terms, dynamic)  # edges into solids (node contact)
    first = start.x if start is not None and start.x is not None else None
    crossed.see(start.t if start is not None else 0.0, scene.net.nodes if first is None else first)
    on_step = _stepping(settings, frames, watch, hooks, crossed)
    peaks = Peaks.of(scene.net)  # kept when the run fails
    if restart is not None and restart.peaks is not None and peaks.seed(restart.peaks):
        log.info("--restart: the peaks go on from those of %s", restart.path)
    try:
        with interruptible(hooks.interrupt), clock.solving():
            res = sv.solve(scene, settings, workspace=ws, start=start, on_step=on_step, peaks=peaks)
    except CatenetError as exc:
        if isinstance(exc, ConfigError) or exc.last_good is None:
            raise
        res = _kept(exc, scene, settings, ws, frames, peaks, begin, clock)
        _tell(crossed, res)
        if isinstance(exc, Interrupted):  # within a step: like a stop between steps
            log.info("interrupted during %s", "a time step" if dynamic else "a load step")
            _write_result(writer, res)
            return Solved(res)
        _write_result(writer, res, failed=exc)
        raise
    if dynamic:
        frames.keep(res.steps, res.time, res.x, res.v, force=True, a=res.a)
    if res.outcome is Outcome.INTERRUPTED:
        log.info("interrupted at %s %.6g", "t =" if dynamic else "load factor", res.time)
    _tell(crossed, res)
    res.wall_time = time.perf_counter() - begin
    res.timing = _timing(clock)
    bodies = watch.stats(res.x, res.v) if watch else {}
    for k, how in crossed.met().items():  # no barrier saw these: the summary says so
        if k in bodies:
            bodies[k]["unseen"] = how
    _write_result(writer, res)
    return Solved(res, bodies)


def _dynamic_start(scene, settings, ws, restart, frames: _Frames):
    """A dynamic run's Start (the scene's initial velocities, or ``restart``'s state)
    with its first frame kept: positions with the supports in place, velocities, the
    newmark scheme's acceleration and the energies held."""
    from catenet.solver import path as sv
    from catenet.solver.energy import held_energy

    if restart is None:
        start = sv.Start(v=scene.velocity, t=0.0)  # [[mass]] velocity: initial velocities
    else:
        start = sv.Start(restart.x, restart.v, restart.t, restart.a)
    x0 = scene.net.nodes.copy() if restart is None else restart.x.copy()
    for term in ws.system.terms:  # a rod end turned along a history: where it is at t0
        if term.driven:
            term.begin_run(x0, start.t)
    if restart is None and settings.initial_state == "equilibrium":  # at rest, at t = 0
        with frames.clock.solving():  # the summary's solve time counts it
            x0 = sv.equilibrium_start(scene, settings, ws, 0.0)
        start = sv.Start(x0.copy(), start.v, start.t)
    x0[scene.net.fixed] = scene.loads.support_positions(scene.net, time=start.t)
    v0 = start.v if start.v is not None else np.zeros_like(x0)
    a0 = start.a
    if a0 is None and settings.integrator == "newmark" and frames.writer.wants(0):
        from catenet.solver.dynamic import start_acceleration

        a0 = start_acceleration(
            scene.net, scene.loads, x0, v0, damping=settings.damping, t=start.t, workspace=ws
        )
    frames.record(start.t, x0)  # before the frame: the two reach the file together
    frames.keep(0, start.t, x0, v0, a=a0, energy=held_energy(ws.system, x0, v0))
    return start


def _recorder(scene, ws, writer, restart):
    """The history's recorder of a dynamic run whose file keeps one (None: no file), its
    first rows a restart's."""
    if getattr(writer, "history", None) is None:
        return None
    from catenet.run.history import Recorder

    recorder = Recorder(scene, ws, writer, writer.history.layout)
    if restart is not None:
        recorder.seed(restart.path, restart.t)
    return recorder


def _tell(crossed, res) -> None:
    """The end state seen by the edges' watch, and its warnings logged."""
    if crossed:
        crossed.see(res.time, res.x)
        for message in crossed.warnings():
            log.warning("%s", message)


def _stepping(settings, frames: _Frames, watch, hooks: Hooks, crossed):
    """The solve path's ``on_step``: each step's frame kept, the bodies and the edges
    watched, progress told, and True where ``hooks.stop()`` ends the run (its frame
    kept)."""
    dynamic = settings.method == "dynamic"
    total = 1.0 if not dynamic else math.inf if isinstance(settings.t_end, str) else settings.t_end

    def on_step(step) -> bool:
        watch.see(step.time, step.x)  # free bodies: their first contact
        with frames.clock.aside():  # edges into solids: the runner's check, not the solve
            crossed.see(step.time, step.x)
        last = step.index == settings.steps and not dynamic
        tension = step.result.tension if step.result is not None else None

        def keep_step(force: bool, last: bool = False) -> None:
            frames.keep(step.index, step.time, step.x, step.v, tension, force=force, a=step.a,
                        last=last, energy=step.energy)  # fmt: skip

        if dynamic:
            frames.record(step.time, step.x)
        keep_step(force=last, last=last)  # a static run's last step: /result follows at once
        if hooks.progress is not None:
            if dynamic:
                hooks.progress(step.time, total, rest=step.rest)
            else:
                hooks.progress(step.time, total)
        if hooks.stop is not None and hooks.stop():
            keep_step(force=dynamic)
            return True
        return False

    return on_step


def _kept(exc: CatenetError, scene, settings, ws, frames: _Frames, peaks, begin: float, clock):
    """The Result of the last good state of a run that failed or was interrupted (its
    ``exc.last_good``), its frame kept (dynamic): converged = false."""
    from catenet.errors import Interrupted
    from catenet.solver.result import finish
    from catenet.solver.stability import CollapseError

    good = exc.last_good
    assert good is not None
    dynamic = settings.method == "dynamic"
    stopped = isinstance(exc, Interrupted)
    x = _usable(good.x, None, scene)
    t = float(good.time)
    if dynamic:  # the last good state is the file's last frame, then /result
        try:
            frames.keep(good.steps, t, x, good.v, force=True, a=good.a)
        except CatenetError:
            pass
    # The residual of the state kept (a dynamic run's: its static part under the loads
    # at its time), not of the failed solve's iterate, which may not even be finite.
    residual = _static_residual(ws, scene, x, t, dynamic)
    if not math.isfinite(residual):  # a term's gradient beyond floating point there:
        history = exc.history if isinstance(exc, ConvergenceError) else []
        start = [r for r in history if math.isfinite(r)]
        residual = start[0] if start else residual  # the failed solve's first residual
    return finish(
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
        stability=exc.verdict if isinstance(exc, CollapseError) else "",
    )


def _static_residual(ws, scene, x, at: float, dynamic: bool = False) -> float:
    """|grad E - f| over the free DOFs at x under the loads at load factor ``at`` (a
    dynamic run's: at time ``at``) [N]."""
    net = scene.net
    _, grad = ws.system.gradient(x)
    if dynamic:
        force = scene.loads.external_force(net, time=at)
    else:
        force = scene.loads.external_force(net, at)
    r = grad - force
    r[net.fixed] = 0.0
    if net.guides is not None:  # rollers and sliders: their free directions
        r[net.guides.nodes] = net.guides.project(r[net.guides.nodes])
    return float(np.linalg.norm(r))


def _timing(clock) -> Timing:
    """The run's solve and start-up seconds (``catenet.run.clock.Clock``)."""
    return Timing(solve=clock.solve, startup=clock.startup)


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


class NoFile:
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
