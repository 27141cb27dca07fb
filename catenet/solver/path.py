"""One solve path: a scene under solver settings, static (in load steps) or dynamic.

``catenet run``, ``catenet sweep``, the benchmark studies and ``catenet validate`` all call
``solve``; nothing else dispatches on the method. A scene is a ``catenet.scene.Scene``:
a net, its loads and the internal energy terms it adds to the stretching of its edges,
read from a case file or built in Python.

Static runs find the equilibria at load factors k/steps, k = 1..steps, each from the
last (a force-displacement curve; one step: the equilibrium directly). Dynamic runs are
the paper's implicit Euler from a start state to t_end or to equilibrium. ``on_step``
sees every equilibrium or time step as a ``Step``; returning True stops the run there
(the result is then not converged, its message "interrupted"). Every one of those states
(and a dynamic run's start) goes to ``peaks`` (``catenet.model.peaks.Peaks``, a new one
unless given), the result's ``peaks``: each edge's largest tension and each node's largest
displacement over the whole run, not only over the frames a file keeps. A run that fails raises
an error whose ``last_good`` (``catenet.errors.LastGood``: positions, velocities, time or
load factor, steps, iterations) is the last good state, so that callers can keep it.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.errors import (
    CatenetError,
    ConfigError,
    ConvergenceError,
    Interrupted,
    LastGood,
    with_last_good,
)
from catenet.model.peaks import Peaks
from catenet.model.transfer import transfer
from catenet.scene import Scene
from catenet.solver.loadsteps import continuation
from catenet.solver.nested import NestedStart, coarse_factor, coarse_scene, free_dofs
from catenet.solver.result import Outcome, Result
from catenet.solver.settings import METHODS, Settings  # noqa: F401 (the path's face)
from catenet.solver.start import start_state
from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Start:
    """Where a run starts: positions (N, 3), velocities (dynamic; None: the scene's
    initial velocities, if any, else at rest), time and the newmark scheme's
    acceleration state (N, 3) (a restart's; None: the physical acceleration)."""

    x: np.ndarray | None = None
    v: np.ndarray | None = None
    t: float = 0.0
    a: np.ndarray | None = None


@dataclass
class Step:
    """An equilibrium of a static run (``time`` = load factor, ``result`` its Result) or
    an accepted time step of a dynamic run (``v`` the velocities, ``a`` the newmark
    scheme's acceleration state, else None; ``rest``: how far the state is from rest,
    max(static residual, inertial force) / tolerance, at most 1 at rest; nan until the
    supports have settled)."""

    index: int
    time: float
    x: np.ndarray
    v: np.ndarray | None = None
    result: Result | None = None
    rest: float = float("nan")
    a: np.ndarray | None = None
    energy: np.ndarray | None = None  # a dynamic step's energy balance (energy.COLUMNS)


OnStep = Callable[[Step], bool | None]


def workspace(scene: Scene, settings: Settings, *, mtype: int | None = None) -> Workspace:
    """The workspace of a scene: its terms' pattern and the linear solver's analysis
    (``mtype``: PARDISO's matrix type; None: as its terms call for)."""
    return Workspace(scene.net, linear=settings.linear, terms=scene.terms, mtype=mtype)


def solve(
    scene: Scene,
    settings: Settings | None = None,
    *,
    workspace: Workspace | None = None,
    start: Start | None = None,
    on_step: OnStep | None = None,
    peaks: Peaks | None = None,
    **keys: Any,  # [solver] keys, checked by Settings
) -> Result:
    """Solves ``scene`` (a ``catenet.scene.Scene``) as ``settings`` say (see the module
    docstring; None: the defaults), with any [solver] key changed by ``keys``
    (``solve(scene, method="dynamic", dt=1e-3)``). ``peaks``: where the run's peaks
    accumulate (pass one to keep them when the run fails)."""
    if settings is None:  # the keys given, the rest resolved as a case file's
        settings = Settings(**keys)
    elif keys:
        settings = dataclasses.replace(settings, **keys)
    _check_bodies(scene, settings)
    ws = workspace if workspace is not None else globals()["workspace"](scene, settings)
    start = start or Start()
    if peaks is None:
        peaks = Peaks.of(scene.net)
    if settings.method != "dynamic" and any(t.dynamic_only for t in ws.system.terms):
        raise ConfigError(
            "solver.self_contact = true: is for dynamic runs: set solver.method = "
            '"dynamic" (or self_contact = false)'
        )
    if settings.method == "dynamic":
        result = _dynamic(scene, settings, ws, start, on_step, peaks)
    else:
        result = _static(scene, settings, ws, start, on_step, peaks)
    result.peaks = peaks
    return result


def _check_bodies(scene: Scene, settings: Settings) -> None:
    """ConfigError where newmark's rho_inf cannot damp a free body's rigidity (as a case
    file's ``catenet.case.rigid``)."""
    from catenet.scene.rigid import RHO_INF_MAX

    newmark = settings.method == "dynamic" and settings.integrator == "newmark"
    if scene.rigid and newmark and settings.rho_inf > RHO_INF_MAX:
        raise ConfigError(
            f"solver.rho_inf = {settings.rho_inf!r}: must be <= {RHO_INF_MAX} with a free "
            f"body (obstacle[{scene.rigid[0].obstacle}]): its rigidity is a stiff mode the "
            "newmark scheme must damp; the default 0.8 does"
        )


class _Stop(Exception):
    """Raised from the continuation's callback when on_step asks to stop."""


def _static(
    scene: Scene,
    settings: Settings,
    ws: Workspace,
    start: Start,
    on_step: OnStep | None,
    peaks: Peaks,
) -> Result:
    begin = time.perf_counter()
    steps = settings.steps
    factors = [k / steps for k in range(1, steps + 1)]
    done: list[Result] = []

    def seen(factor: float, r: Result) -> None:
        done.append(r)
        r.time = factor
        peaks.observe(factor, r.x, r.tension)
        if on_step is not None and on_step(Step(len(done), factor, r.x, None, r)):
            raise _Stop

    nested: NestedStart | None = None

    def total(r: Result, **fields: object) -> Result:
        r.iterations = sum(q.iterations for q in done)
        r.steps = len(done)
        r.wall_time = time.perf_counter() - begin
        r.nested = nested
        for key, value in fields.items():
            setattr(r, key, value)
        return r

    def run(x0: np.ndarray | None) -> None:
        continuation(
            scene.net,
            scene.loads,
            factors,
            x0=x0,
            rtol=settings.rtol,
            max_iter=settings.static_iterations,
            on_step=seen,
            workspace=ws,
            post_collapse=settings.post_collapse,
        )

    try:
        found = _nested(scene, settings, start)
        x0, nested = (start.x, None) if found is None else found
        try:
            run(x0)
        except ConvergenceError as exc:
            if nested is None or done or isinstance(exc, Interrupted):
                raise
            # the nested start failed where the default start may not: that one, counted
            log.warning("the nested start did not converge (%s): the default start", exc)
            spent = exc.iterations + nested.iterations
            nested = None
            run(start.x)
            done[0].iterations += spent
    except _Stop:
        if len(done) < steps:
            return total(
                done[-1], converged=False, message="interrupted", outcome=Outcome.INTERRUPTED
            )
    except CatenetError as exc:
        if isinstance(exc, ConfigError):
            raise
        # The last good state: the last equilibrium (a load step's or a cut-back's
        # sub-step's), else the start at load factor 0; never an unconverged iterate.
        good = exc.last_good
        x, factor = (None, 0.0) if good is None else (good.x, good.time)
        if x is None:
            x, factor = start_state(scene.net, scene.loads, start.x, 0.0), 0.0
        spent = sum(q.iterations for q in done) + exc.iterations
        with_last_good(exc, LastGood(x, factor, len(done), spent))
        raise
    r = total(done[-1])
    if r.outcome in (Outcome.EQUILIBRIUM, Outcome.AT_FLOOR):
        r.message = str(r.outcome)  # which criterion held
    return r


def _dynamic(
    scene: Scene,
    settings: Settings,
    ws: Workspace,
    start: Start,
    on_step: OnStep | None,
    peaks: Peaks,
) -> Result:
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.energy import Ledger

    net, loads = scene.net, scene.loads
    x0 = net.nodes.copy() if start.x is None else np.array(start.x, dtype=np.float64)
    if settings.initial_state == "equilibrium" and start.x is None:
        x0 = equilibrium_start(scene, settings, ws, start.t)
    v_scene = scene.velocity  # a case's [[mass]] velocities
    v = start.v if start.v is not None else v_scene
    v0 = np.zeros_like(x0) if v is None else np.array(v, dtype=np.float64)
    x0[net.fixed] = loads.support_positions(net, time=start.t)
    last = _Last(0, start.t, x0.copy(), v0.copy())
    accel = np.zeros_like(x0) if settings.integrator == "newmark" else None
    last.a = None if start.a is None else np.array(start.a, dtype=np.float64)
    tension = ws.system.tension
    peaks.between |= settings.tolerance is not None  # peaks between steps chosen by accuracy
    peaks.observe(start.t, x0, tension(x0))

    def rest(ratio: float) -> None:
        last.rest = ratio

    ledger = Ledger(settings.energy_tolerance)

    def seen(step: int, t: float, x: np.ndarray, v: np.ndarray) -> bool:
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(v))):
            raise ConvergenceError(f"the state became non-finite at t = {t:.6g} s")
        peaks.observe(t, x, tension(x))
        a = None if accel is None else accel.copy()
        last.steps, last.t, last.x, last.v, last.a = step, t, x.copy(), v.copy(), a
        if on_step is None:
            return False
        energy = ledger.row.copy()
        return bool(on_step(Step(step, t, x, v, rest=last.rest, a=a, energy=energy)))

    try:
        result = solve_dynamic(
            net,
            loads,
            dt=settings.dt,
            damping=settings.damping,
            t_end=settings.t_end,
            rtol=settings.rtol,
            max_iter=settings.max_iter,  # (None: a time step's default budget)
            x0=x0,
            v0=v0,
            t0=start.t,
            on_step=seen,
            workspace=ws,
            on_rest=rest,
            integrator=settings.integrator,
            rho_inf=settings.rho_inf,
            reuse=settings.reuse,
            a0=start.a,
            a_out=accel,
            max_steps=settings.max_steps,
            ledger=ledger,
            tolerance=settings.tolerance,
            dt_max=settings.dt_max,
            dt_min=settings.dt_min,
        )
        _judge_rest(ws, result)
        return result
    except CatenetError as exc:
        if isinstance(exc, ConfigError):
            raise
        iterations = exc.iterations
        if last.steps == 0 and accel is not None:
            last.a = accel.copy()  # the start's state: solve_dynamic set it first
        good = LastGood(last.x, last.t, last.steps, iterations, last.v, last.a)
        with_last_good(exc, good)
        raise


def equilibrium_start(scene: Scene, settings: Settings, ws: Workspace, t0: float) -> np.ndarray:
    """solver.initial_state = "equilibrium": the static equilibrium of the scene under
    its loads, supports and water as they are at t0 (``Loads.at``), in settings.steps
    load steps; a failure raises as a static run's does (its last equilibrium kept)."""
    net = scene.net
    frozen = scene.loads.at(net, t0)
    factors = [k / settings.steps for k in range(1, settings.steps + 1)]
    log.info("the dynamic run starts from its static equilibrium at t = %.6g s", t0)
    found = continuation(
        net,
        frozen,
        factors,
        rtol=settings.rtol,
        max_iter=settings.static_iterations,
        workspace=ws,
    )
    x = np.array(found[-1].x, dtype=np.float64)
    _relocated(scene, x)
    return x


#: A free body or ball moved by the start's equilibrium more than this share of the
#: scene's size was placed elsewhere than it rests: said (its fall is no part of the run)
MOVED = 0.25


def _relocated(scene: Scene, x: np.ndarray) -> None:
    """Warns where the equilibrium start moved a free body or ball far from where it was
    given: a body given above the net to be dropped onto it now rests on it at t0."""
    net = scene.net
    if net.n_nodes == net.n_net:
        return
    moved = np.linalg.norm(x[net.n_net :] - net.nodes[net.n_net :], axis=1)
    far = float(moved.max())
    if not far > MOVED * float(scene.size):
        return
    log.warning(
        "solver.initial_state = 'equilibrium' moved a free body %.4g m from where it was "
        "given, to where it rests with the net: the run starts from there, at rest (a body "
        "given above the net to fall onto it does not fall); to drop it, start from the "
        "given geometry (initial_state = 'given')",
        far,
    )


@dataclass
class _Last:
    """A dynamic run's last accepted state (its start until a step is accepted): steps
    done, time, positions, velocities, the newmark scheme's acceleration state (else
    None), and how far it is from rest (``Step.rest``)."""

    steps: int
    t: float
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray | None = None
    rest: float = float("nan")


def _nested(
    scene: Scene, settings: Settings, start: Start
) -> tuple[np.ndarray, NestedStart] | None:
    """The nested start (``catenet.solver.nested``): the start on the fine net from the
    coarse net's equilibrium at the first load step, and what that cost; None for the
    default start (where it does not apply, or the coarse solve fails)."""
    factor = coarse_factor(scene, settings, start.x is not None)
    if factor is None:
        return None
    forced = settings.start == "nested"
    begin = time.perf_counter()
    coarse = coarse_scene(scene, factor, forced)
    if coarse is None:
        return None
    first = dataclasses.replace(settings, start="auto")  # nested again only where it pays
    try:  # the first load step's equilibrium: the continuation's first
        r = solve(coarse, first, on_step=lambda step: True)
    except CatenetError as exc:
        if isinstance(exc, Interrupted):  # the coarse net's state is no state of this net
            exc.last_good = None  # (the caller keeps this net's start)
            raise
        if isinstance(exc, ConfigError):
            raise
        log.warning("the coarse net of the nested start failed (%s): the default start", exc)
        return None
    x0 = transfer(coarse.net, r.x, scene.net)
    if x0 is None:
        log.warning("the coarse net does not match the fine net: the default start")
        return None
    spent = r.iterations + (r.nested.iterations if r.nested is not None else 0)
    took = time.perf_counter() - begin
    return x0, NestedStart(factor, free_dofs(coarse.net), spent, took)


def _judge_rest(ws: Workspace, result: Result) -> None:
    """A dynamic run that came to rest ends at a static equilibrium: its stability
    verdict (``catenet.solver.stability``), as a static run's (a net with bilateral edges
    may come to rest balanced on an unstable state); a transient is not judged."""
    if not result.equilibrium:
        return
    net = ws.system.net
    if net.bodies:
        return  # free bodies at rest: catenet.solver.modal.stable_with_bodies's to judge
    if net.law.all_tension_only:
        result.stability = "stable"  # tension-only stiffness is never negative
        return
    from catenet.solver.tangent import STABLE, UNSTABLE, tangent

    verdict = tangent(ws.system, ws.solver, result.x).verdict
    result.stable = True if verdict == STABLE else False if verdict == UNSTABLE else None
    result.stability = "unstable" if verdict == UNSTABLE else "stable"
