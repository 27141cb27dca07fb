"""The paper's method: implicit (backward) Euler with mass-proportional damping.

Each step from t_k to t_k + h solves Eq. 10a,

    M ((q - q_k)/h^2 - v_k/h) + mu M (q - q_k)/h + grad E(q) - F = 0,

by Newton from the predictor q_k + h v_k (Eq. 11) with the Jacobian
M/h^2 + mu M/h + K (Eq. 13); then v_{k+1} = (q - q_k)/h. A step whose Newton iteration
fails is retried with half the step (never accepted silently); after four good steps the
step grows back towards ``dt``. With ``t_end = "rest"`` the run goes to rest in
pseudo-time, its step grown as the motion decays (catenet/solver/relax.py), at most
``max_steps`` steps. With ``reuse``, Newton keeps its factorisation across iterations
and steps (modified Newton) while h stays; a step that fails with a kept matrix is
retried once with fresh ones before its h is halved. Dynamic relaxation: the run stops
before ``t_end`` once the supports have settled and both the static residual
|grad E - F| and the inertial force |M v|/h are below rtol times the load scale.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from catenet.errors import ConfigError, ConvergenceError
from catenet.model.net import Loads, Net
from catenet.solver.adaptive import ErrorControl, watch
from catenet.solver.energy import Ledger
from catenet.solver.integrators import RHO_INF, Newmark, make
from catenet.solver.relax import MAX_STEPS, REST, RestControl
from catenet.solver.result import Outcome, Result, finish
from catenet.solver.settings import STEP_MAX_ITER
from catenet.solver.stepper import (  # noqa: F401  (TimeStepper, at_rest: here too)
    OnStep,
    TimeStepper,
    at_rest,
    mass_and_damping,
    potential_at,
    store_acceleration,
)
from catenet.solver.stepping import (  # noqa: F401  (the step control's names, here too)
    ALLOWANCE,
    FAIL_ALLOWANCE,
    GROW_AFTER,
    MAX_CUTS,
    SLOWDOWN,
    StepControl,
    _advance,
)
from catenet.solver.workspace import Workspace, check_rtol


def solve_dynamic(
    net: Net,
    loads: Loads,
    *,
    dt: float,
    damping: float,
    t_end: float | str,
    rtol: float = 1e-8,
    x0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
    t0: float = 0.0,
    max_iter: int | None = None,
    stop_at_equilibrium: bool = True,
    linear: str = "auto",
    on_step: OnStep | None = None,
    workspace: Workspace | None = None,
    on_rest: Callable[[float], None] | None = None,
    reuse: bool = False,
    integrator: str = "implicit_euler",
    rho_inf: float = RHO_INF,
    a0: np.ndarray | None = None,
    a_out: np.ndarray | None = None,
    max_steps: int = MAX_STEPS,
    ledger: Ledger | None = None,
    tolerance: float | None = None,
    dt_max: float | None = None,
    dt_min: float | None = None,
) -> Result:
    """Time integration from ``t0`` (state ``x0``, ``v0``; default: reference positions
    at rest) to ``t_end`` or to equilibrium.

    ``on_step(step, t, x, v)`` sees every accepted step; returning True stops the run
    there (an interrupted run: ``converged`` is False). Raises ConvergenceError, with the
    last accepted state in ``state``, when even the smallest step fails. ``on_rest(ratio)``
    follows dynamic relaxation (before ``on_step``, once the supports have settled):
    max(static residual, inertial force) / tolerance, at most 1 at rest.

    ``max_iter``: Newton iterations of one time step; None: STEP_MAX_ITER, and in a run
    to a time at fixed steps (no ``tolerance``: steps chosen by accuracy are planned anew
    after a cut) a step's solve still converging there goes on
    (``solve_newton(extend=)``).

    ``reuse=True``: modified Newton, the factorisation kept across iterations and steps
    (about 2x faster on the paper's relaxation; off by default: its path differs within
    the tolerance, so a run at rest stops a few steps apart and a restart does not
    repeat the uninterrupted run exactly). ``reuse=False``: a factorisation per iteration.

    ``integrator``: "implicit_euler" (the paper's), "bdf2" (second order, L-stable) or
    "newmark" (second order, its high-frequency dissipation ``rho_inf``;
    catenet/solver/integrators.py). Newmark's acceleration state (N, 3), 0 at the
    supports: ``a0`` the start's (a restart's; None: the physical one), ``a_out`` an array
    kept equal to it, and the result's ``a``; the others have none.

    Times are exact multiples of the smallest step dt / 2**MAX_CUTS after t0 (t0 + k dt
    with one rounding while the step is dt), not sums of the steps' round-off.

    ``t_end = "rest"``: dynamic relaxation to rest (``stop_at_equilibrium`` must hold),
    its steps growing as the motion decays (catenet/solver/relax.py), their time
    pseudo-time; ConvergenceError when ``damping`` is 0 (an undamped run never rests)
    or when ``max_steps`` accepted steps do not reach rest.

    ``ledger``: the run's energy balance (``catenet.solver.energy.Ledger``; a new one
    where None); EnergyError where the integrator creates energy. ``tolerance`` (a number
    for t_end): steps chosen by accuracy, ``dt`` the first, within [``dt_min``,
    ``dt_max``] (catenet/solver/adaptive.py; implicit Euler or bdf2).
    """
    _check(dt, damping, t_end, t0, rtol, max_steps)
    _check_rest(t_end, damping, stop_at_equilibrium)
    scheme = make(integrator, rho_inf)
    _check_mass(net)
    ws = workspace or Workspace(net, linear=linear)
    stepper = TimeStepper(
        net, loads, ws, scheme, damping, rtol=rtol, reuse=reuse,
        max_iter=STEP_MAX_ITER if max_iter is None else max_iter,
        extend=max_iter is None and not isinstance(t_end, str) and tolerance is None,
    )  # fmt: skip
    start = time.perf_counter()
    stepper.ledger = balance = Ledger() if ledger is None else ledger
    stepper.begin(x0, v0, t0, a0, a_out)
    control = _control(stepper, dt, t0, t_end, max_steps, (tolerance, dt_max, dt_min))
    run = stepper.run(control, rest=stop_at_equilibrium, on_step=on_step, on_rest=on_rest)
    strikes = stepper.watch.strikes if stepper.watch is not None else None
    if stepper.watch is not None:
        stepper.watch.report()
    if isinstance(control, ErrorControl) and control.strikes is not None:
        strikes = control.strikes
        strikes.landings()
    result = _result(stepper, balance, run, start)
    result.landed = "" if strikes is None else strikes.advice()  # (the integrator's advice)
    return result


def _check_rest(t_end: float | str, damping: float, stop_at_equilibrium: bool) -> None:
    """Raises where a run to rest (``t_end = "rest"``) cannot come to rest."""
    to_rest = t_end == REST
    if to_rest and not stop_at_equilibrium:
        raise ConfigError("t_end = 'rest' needs stop_at_equilibrium")
    if to_rest and damping == 0:
        raise ConvergenceError(
            "solver.t_end = 'rest' with solver.damping = 0: an undamped run never rests: "
            "give solver.t_end or damping"
        )


def _control(
    stepper: TimeStepper,
    dt: float,
    t0: float,
    t_end: float | str,
    max_steps: int,
    accuracy: tuple[float | None, float | None, float | None] = (None, None, None),
) -> RestControl | StepControl | ErrorControl:
    """The run's step control: to rest (its steps grown as the motion decays, through the
    stepper's continuation stages), or to ``t_end`` by ``dt``, or by ``accuracy``
    (tolerance, dt_max, dt_min; catenet/solver/adaptive.py) where its tolerance is given."""
    if t_end == REST:
        return RestControl(dt, t0, MAX_CUTS, max_steps, stepper.rest_stages())
    tolerance, dt_max, dt_min = accuracy
    if tolerance is None:
        stepper.watch = watch(stepper, t0, float(t_end))
        return StepControl(dt, t0, float(t_end))
    return ErrorControl.of(stepper, dt, t0, float(t_end), tolerance, dt_max, dt_min)


def _result(stepper: TimeStepper, ledger: Ledger, run: Outcome, start: float) -> Result:
    """The Result of the run that ended as ``run``, from the stepper's last state and its
    energy balance ``ledger`` (its wall time counted from ``start``)."""
    ws, scheme = stepper.ws, stepper.scheme
    x, v, t = stepper.x, stepper.v, stepper.t
    return finish(
        ws.system,
        stepper.loads,
        x,
        converged=run is not Outcome.INTERRUPTED,
        equilibrium=stepper.equilibrium,
        iterations=stepper.iterations,
        residual=stepper.residual,
        load_time=t,
        steps=stepper.steps,
        time=t,
        v=v,
        a=None if scheme.a is None else store_acceleration(scheme, np.zeros_like(x), stepper.free),
        message=str(run),
        wall_time=time.perf_counter() - start,
        stats=ws.stats(),
        outcome=run,
        energy=ledger.row.copy(),
        energy_scale=ledger.largest,
        energy_motion=ledger.internal,
    )


def start_acceleration(
    net: Net,
    loads: Loads,
    x: np.ndarray,
    v: np.ndarray,
    *,
    damping: float,
    t: float,
    workspace: Workspace,
) -> np.ndarray:
    """The physical acceleration M^-1 (f(t) - grad E(x)) - mu v (N, 3), 0 at the
    supports: the newmark scheme's state at the start of a run (solve_dynamic without
    ``a0``), for the result file's first frame."""
    x = np.asarray(x, dtype=np.float64)
    m_free, mu = mass_and_damping(net, damping)
    scheme = Newmark()
    potential = potential_at(workspace.potential(loads), loads, net, t)
    scheme.begin(potential, x, np.asarray(v, dtype=np.float64), m_free, mu)
    out = np.zeros_like(x)
    store_acceleration(scheme, out, workspace.system.free_dofs)
    return out


def _check(
    dt: float, damping: float, t_end: float | str, t0: float, rtol: float, max_steps: int
) -> None:
    problems = []
    if not (isinstance(max_steps, int) and max_steps >= 1):
        problems.append(f"solver.max_steps = {max_steps!r}: must be an integer >= 1")
    if not (math.isfinite(dt) and dt > 0):
        problems.append(f"solver.dt = {dt!r}: must be finite and > 0")
    if not (math.isfinite(damping) and damping >= 0):
        problems.append(f"solver.damping = {damping!r}: must be finite and >= 0")
    if isinstance(t_end, str):
        if t_end != REST:
            problems.append(f"solver.t_end = {t_end!r}: must be a number or {REST!r}")
    elif not (math.isfinite(t_end) and t_end > t0):
        problems.append(f"solver.t_end = {t_end!r}: must be finite and > {t0}, or {REST!r}")
    if problems:
        raise ConfigError(problems)
    check_rtol(rtol)


def _check_mass(net: Net) -> None:
    if not np.all(net.mass[~net.fixed] > 0):
        raise ConfigError(
            "material.density: the free nodes have no mass: the dynamic solver needs "
            "density > 0 (or use solver.method = 'static')"
        )
