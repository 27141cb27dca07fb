"""Whether anything in a case depends on time: the default of ``solver.t_end``.

A dynamic run of a case where nothing depends on time is dynamic relaxation: its motion
is only the path to the static equilibrium, so by default it runs to rest
(``t_end = "rest"``: catenet/solver/relax.py). Anything that makes the motion itself the
answer keeps the fixed default end time (10 s): a time history of a load or support
motion, a support that moves over a duration, an obstacle that moves (a ball with mass,
a path, a turning shape) or is a free body, an initial velocity, or no damping
(an undamped motion does not die out).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

from catenet.case.obstacles import SphereObstacle
from catenet.case.sections import LoadConfig, SolverConfig, SupportsConfig
from catenet.solver.adaptive import ADAPTIVE, TOLERANCE
from catenet.solver.relax import REST
from catenet.solver.settings import steps_given

#: solver.t_end's default where something depends on time [s].
T_END = 10.0


def time_dependence(load: Any, supports: Any, solver: Any, obstacles: Any, masses: Any) -> str:
    """The first key of the case (its path as the user writes it) that makes the motion
    depend on time, or "" when none does. Sections that failed their checks are skipped."""
    for path, history in load_histories(load):
        if history is not None:
            return f"{path}.history"
    moves = supports.moves if isinstance(supports, SupportsConfig) else ()
    for k, move in enumerate(moves):
        if move.history is not None:
            return f"supports.move[{k}].history"
        if move.sine is not None:
            return f"supports.move[{k}].sine"
        if move.duration > 0:
            return f"supports.move[{k}].duration"
    if isinstance(supports, SupportsConfig) and supports.vessels:
        return "supports.vessel[0]"
    for k, obs in enumerate(obstacles if isinstance(obstacles, tuple) else ()):
        if obs.free:
            return f"obstacle[{k}] (a free body)"
        if (isinstance(obs, SphereObstacle) and obs.moves) or obs.rigid_motion:
            return f"obstacle[{k}] (it moves)"
    for k, m in enumerate(masses if isinstance(masses, tuple) else ()):
        if m.velocity is not None:
            return f"mass[{k}].velocity"
    if isinstance(solver, SolverConfig) and solver.damping == 0:
        return "solver.damping = 0"
    return ""


def default_t_end(load: Any, supports: Any, solver: Any, obstacles: Any, masses: Any):
    """solver.t_end when the case does not give it: "rest" where nothing depends on time
    (``time_dependence``), else T_END."""
    return T_END if time_dependence(load, supports, solver, obstacles, masses) else REST


def resolve_steps(solver: SolverConfig, transient: bool = False) -> SolverConfig:
    """A dynamic case's steps as the run takes them (its t_end decided): a run with a
    number for t_end and a ``tolerance`` adapts its steps to it (``dt``: the first step,
    else FIRST_SHARE of t_end, at most ``dt_max``) with bdf2 unless ``integrator`` says
    otherwise (``catenet.solver.adaptive``); any other run steps by ``dt`` (default
    0.01 s) with implicit Euler unless ``integrator`` says otherwise
    (``catenet.solver.settings.steps_given``, as a Settings made in Python).

    A ``transient`` run to a time (one with contact: an obstacle, a ball, a free body or
    self-contact; or whose motion is the answer: ``time_dependence``) that gives neither
    ``dt`` nor ``tolerance`` takes the default tolerance
    (``catenet.solver.adaptive.TOLERANCE``): its impacts and peaks are what it is run
    for, and fixed steps of a guessed size step over them or damp them
    (docs/howto/dynamic-runs.md). Dynamic relaxation (nothing depends on time) keeps
    the paper's implicit Euler at 0.01 s."""
    if (
        transient
        and solver.method == "dynamic"
        and isinstance(solver.t_end, (int, float))
        and solver.dt is None
        and solver.tolerance is None
        and solver.integrator in (None, *ADAPTIVE)
    ):
        solver = dataclasses.replace(solver, tolerance=TOLERANCE)
    dt, integrator = steps_given(solver.dt, solver.integrator, solver)
    dynamic = solver.method == "dynamic"  # (a static case keeps its integrator unset)
    return dataclasses.replace(
        solver, dt=dt, integrator=integrator if dynamic else solver.integrator
    )


def newmark_refused(obstacles: Any) -> str:
    """The problem of a dynamic case with contact that asks for newmark: at its default
    rho_inf it gains momentum in impacts and does not converge with the step, and below
    it its steps fail at first contact (docs/howto/dynamic-runs.md)."""
    what = f"obstacle[0] ({obstacles[0].kind})" if obstacles else "solver.self_contact"
    return (
        f"solver.integrator = 'newmark': not for a run with contact ({what}): newmark "
        "gains momentum in impacts (a box dropped onto a net leaves it faster than it "
        "came) or fails at first contact; use 'bdf2' (second order and right in contact, "
        "the default there) or 'implicit_euler' (docs/howto/dynamic-runs.md)"
    )


def load_histories(load: Any, prefix: str = "load") -> Iterator[tuple[str, tuple | None]]:
    """(key path, history) of the load (its path ``prefix``: a load case's
    ``load_case[k]``) and each of its point, line and area loads (none for a load that
    failed its checks)."""
    if not isinstance(load, LoadConfig):
        return
    yield prefix, load.history
    parts = (
        ("point", [point.history for point in load.points]),
        ("line", [line.history for line in load.lines]),
        ("area", [area.history for area in load.areas]),
    )
    for name, histories in parts:
        for k, history in enumerate(histories):
            yield f"{prefix}.{name}[{k}]", history
