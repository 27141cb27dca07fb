"""A case's balls and free bodies (``[[obstacle]]`` tables that move) as the scene
builder's ``Mover``s (``catenet.scene.bodies``, ``catenet.scene.rigid``), and what the
case's ``[solver]`` asks of them:

- a sphere with ``mass`` alone is a ball (the exact torque-free case: a frictionless ball
  never spins up); a sphere with ``velocity`` and no mass is a ball on a prescribed path,
  which moves in dynamic runs only;
- a box, capsule, cylinder, mesh or sphere with ``mass`` or ``density`` (a sphere: with
  ``density``, ``inertia`` or ``angular_velocity``) is a free body, whose initial motion
  acts in dynamic runs only, and which newmark runs must damp
  (``catenet.scene.rigid.RHO_INF_MAX``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from catenet.errors import ConfigError
from catenet.scene.movers import Mover
from catenet.scene.rigid import RHO_INF_MAX


def movers(case: Any) -> tuple[Mover, ...]:
    """The case's balls and free bodies, in the order of its ``[[obstacle]]`` tables.
    Raises ConfigError for what its ``[solver]`` cannot run (module docstring)."""
    out = []
    for k, obs in enumerate(case.obstacles):
        if obs.moves:
            _check_ball(case, k, obs)
        elif obs.free:
            _check_free(case, k, obs)
        else:
            continue
        inertia = None if obs.inertia is None else np.array(obs.inertia, float)
        shape = obs.shape()
        mover = Mover(
            k, shape, obs.contact(), free=obs.free, mass=obs.mass, density=obs.density,
            inertia=inertia, velocity=obs.velocity, angular_velocity=obs.angular_velocity,
            history=obs.history, placed=obs.given(shape.origin_key),
        )  # fmt: skip
        out.append(mover)
    return tuple(out)


def _check_ball(case: Any, k: int, obs: Any) -> None:
    if case.solver.method == "dynamic":
        return
    if obs.mass is None:
        raise ConfigError(
            f"obstacle[{k}].velocity = {list(obs.velocity)}: a sphere on a prescribed path "
            "moves in dynamic runs only: set solver.method = 'dynamic', or drop velocity"
        )
    if any(obs.velocity or ()):  # a free ball's initial motion, as a free body's
        raise ConfigError(
            f"obstacle[{k}].velocity = {list(obs.velocity)}: a free ball's initial motion "
            "acts in dynamic runs only: set solver.method = 'dynamic', or drop it"
        )


def _check_free(case: Any, k: int, obs: Any) -> None:
    solver = case.solver
    if solver.method == "dynamic" and solver.integrator == "newmark":
        if solver.rho_inf > RHO_INF_MAX:
            raise ConfigError(
                f"solver.rho_inf = {solver.rho_inf!r}: must be <= {RHO_INF_MAX} with a free "
                f"body (obstacle[{k}]): its rigidity is a stiff mode the newmark "
                "scheme must damp; the default 0.8 does"
            )
    given = (("velocity", obs.velocity), ("angular_velocity", obs.angular_velocity))
    moving = [(key, value) for key, value in given if any(value or ())]
    if solver.method != "dynamic" and moving:
        key, value = moving[0]
        raise ConfigError(
            f"obstacle[{k}].{key} = {list(value)}: a free body's initial motion "
            "acts in dynamic runs only: set solver.method = 'dynamic', or drop it"
        )
