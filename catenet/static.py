"""Static equilibrium directly (beyond the paper, which reaches it by dynamic relaxation).

Newton on the total potential E(x) - f.x with the regularisation and line search of
``catenet.newton``: from a flat unstressed net or a straight zero-slack cable it starts as
a damped gradient flow and ends as pure Newton with quadratic convergence.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence

import numpy as np

from catenet.assembly import System
from catenet.errors import ConfigError
from catenet.linsolve import LinearSolver, make_solver
from catenet.net import Loads, Net
from catenet.newton import Potential, raise_unconverged, solve
from catenet.result import Result, finish

log = logging.getLogger(__name__)


class Workspace:
    """A net's system (pattern) and linear solver (symbolic analysis), built once and
    reused by every solve on that net: load steps, time steps, sweeps over loads."""

    def __init__(self, net: Net, *, linear: str = "auto", mtype: int | None = None):
        upper = mtype != 11
        self.net = net
        start = time.perf_counter()
        self.system = System(net, upper=upper)
        dof_node = np.flatnonzero(~net.fixed).repeat(3)
        self.solver: LinearSolver = make_solver(
            linear, self.system.indptr, self.system.indices, upper=upper, dof_node=dof_node,
            mtype=mtype,
        )
        self.setup_seconds = time.perf_counter() - start

    def potential(self, loads: Loads, factor: float = 1.0) -> Potential:
        return Potential(self.system, self.solver, loads.external_force(self.net, factor))

    def stats(self) -> dict:
        s = self.solver
        return {
            "backend": s.name,
            "dofs": self.system.n_free,
            "nnz": self.system.nnz,
            **{f"{k}_count": v for k, v in s.stats.items()},
            **{f"{k}_seconds": v for k, v in s.seconds.items()},
            "assembly_seconds": self.system.seconds,
            "setup_seconds": self.setup_seconds,
        }


def solve_static(
    net: Net,
    loads: Loads,
    *,
    x0: np.ndarray | None = None,
    factor: float = 1.0,
    rtol: float = 1e-8,
    max_iter: int = 200,
    linear: str = "auto",
    workspace: Workspace | None = None,
    raise_on_failure: bool = True,
) -> Result:
    """Static equilibrium of ``net`` under ``loads`` scaled by ``factor``.

    ``x0`` (N, 3) is the starting guess (default: the reference positions); supports are
    put at their prescribed places. Raises ConvergenceError when Newton fails (with the
    residual history), unless ``raise_on_failure`` is False.
    """
    _check_rtol(rtol)
    ws = workspace or Workspace(net, linear=linear)
    start = time.perf_counter()
    x = _start(net, loads, x0, factor)
    potential = ws.potential(loads, factor)
    result = solve(potential, x, rtol=rtol, max_iter=max_iter, label="static")
    if not result.converged and raise_on_failure:
        raise_unconverged(result, "static equilibrium", state=x)
    return finish(
        ws.system,
        loads,
        x,
        factor,
        converged=result.converged,
        equilibrium=result.converged,
        iterations=result.iterations,
        residual=result.residual,
        history=result.history,
        message=result.reason,
        wall_time=time.perf_counter() - start,
        stats=ws.stats(),
    )


def continuation(
    net: Net,
    loads: Loads,
    factors: Sequence[float],
    *,
    x0: np.ndarray | None = None,
    rtol: float = 1e-8,
    max_iter: int = 200,
    linear: str = "auto",
    on_step: Callable[[float, Result], None] | None = None,
    workspace: Workspace | None = None,
) -> list[Result]:
    """Equilibria at increasing load factors, each starting from the previous one (a
    force-displacement curve). ``on_step(factor, result)`` sees each as it is found.
    A failing step raises ConvergenceError whose ``state`` is the last equilibrium."""
    if len(factors) == 0:
        raise ConfigError("continuation: factors is empty: give at least one load factor")
    ws = workspace or Workspace(net, linear=linear)
    results: list[Result] = []
    x = x0
    for k, factor in enumerate(factors):
        try:
            r = solve_static(
                net, loads, x0=x, factor=float(factor), rtol=rtol, max_iter=max_iter,
                workspace=ws,
            )
        except Exception as exc:
            if results and hasattr(exc, "state"):
                exc.state = results[-1].x
            raise
        r.steps = k + 1
        results.append(r)
        x = r.x
        if on_step is not None:
            on_step(float(factor), r)
    return results


def _start(net: Net, loads: Loads, x0, factor: float) -> np.ndarray:
    if x0 is None:
        x = net.nodes.copy()
    else:
        x = np.array(x0, dtype=np.float64, copy=True)
        if x.shape != net.nodes.shape or not np.all(np.isfinite(x)):
            raise ConfigError(f"x0: shape {x.shape}: must be finite with shape {net.nodes.shape}")
    x[net.fixed] = loads.support_positions(net, factor=factor)
    return x


def _check_rtol(rtol: float) -> None:
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise ConfigError(f"solver.rtol = {rtol!r}: must be in (0, 1)")
