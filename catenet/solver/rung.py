"""The static ladder's last rung: dynamic relaxation to rest (``relaxed``), the paper's
method, which follows the net's motion where Newton's load steps fail; where it applies
(``can_relax``), the loads as a run to rest takes them (``held``), and the starts that
need it first (``hangs_slack``: a cable given straight and longer than its chord)."""

from __future__ import annotations

import dataclasses
import logging
from typing import TypedDict

import numpy as np

from catenet.errors import ConvergenceError, Interrupted, LastGood, with_last_good
from catenet.model.measures import strain, tension
from catenet.model.net import Loads, Net
from catenet.solver.relax import REST
from catenet.solver.result import Outcome, Result
from catenet.solver.settings import Settings
from catenet.solver.static import solve_static
from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)


class StepSettings(TypedDict):
    """What every static solve of a load path shares (``solve_static``'s keywords)."""

    rtol: float
    max_iter: int
    workspace: Workspace
    warn: bool  # False: the path, not each of its solves, warns about its end state


DR_MAX_ITER = 25  # the last rung's Newton iterations per time step
#: A strain below -SLACK is slack, a tension below SLACK EA none: far above the strains
#: a start's round-off gives (a flat net perturbed by 1e-12 m stays "unstressed", not
#: slack), far below any cable given longer than its chord.
SLACK = 1e-8


def hangs_slack(net: Net, good: LastGood) -> bool:
    """Whether the failed step starts from the unloaded start (load factor 0) of a net
    that carries no tension there and has slack edges (a cable given straight and longer
    than its chord): its equilibrium hangs far from the start whatever the load's size,
    so smaller load steps do not help where following its motion to rest does."""
    if good.time != 0.0:
        return False
    strains = strain(net, good.x)
    if not np.any(strains < -SLACK):
        return False
    return bool(np.all(np.abs(tension(net, good.x)) <= SLACK * np.max(net.EA, initial=0.0)))


def can_relax(net: Net, target: float, settings: StepSettings) -> bool:
    """Whether the last rung applies: a step to the full loads (``target`` 1) of a net
    whose free nodes have mass, with a Newton budget ``max_iter`` of at least a time
    step's DR_MAX_ITER (the rung would not keep a smaller one)."""
    if target != 1.0 or settings["max_iter"] < DR_MAX_ITER:
        return False
    return bool(np.all(net.mass[~net.fixed] > 0.0))


def relax_to_rest(
    net: Net, loads: Loads, target: float, good: LastGood, settings: StepSettings
) -> Result | None:
    """The ladder's last rung: the equilibrium under the loads at load factor ``target``
    (the full loads, 1, but for ``_by_motion``) by dynamic relaxation to rest from the
    last equilibrium ``good`` (the paper's method,
    ``solver.t_end = "rest"`` at the default dt and damping: it follows the net's motion,
    which needs no continuation stage), then Newton on the exact potential from its rest
    state to the static tolerance (``solve_static(relaxed=True)``). The result, its
    iterations those of both (``good`` updated), or None when either fails."""
    # (imported here, as in path.py: a plain static run loads no dynamic module)
    from catenet.solver.dynamic import solve_dynamic

    default = Settings()
    log.info("load step from load factor %.6g: dynamic relaxation to rest", good.time)
    try:
        rest = solve_dynamic(
            net,
            held(loads, net, target),
            dt=default.dt,
            damping=default.damping,
            t_end=REST,
            rtol=settings["rtol"],
            max_iter=DR_MAX_ITER,
            x0=good.x,
            workspace=settings["workspace"],
        )
        if rest.outcome not in (Outcome.EQUILIBRIUM, Outcome.AT_FLOOR):
            return None
        r = solve_static(net, loads, x0=rest.x, factor=target, relaxed=True, **settings)
    except ConvergenceError as exc:
        if isinstance(exc, Interrupted):  # the last equilibrium is kept, not the motion's
            raise with_last_good(exc, LastGood(good.x, good.time)) from None
        log.info("dynamic relaxation to rest did not help: %s", exc)
        return None
    r.iterations += rest.iterations
    good.x, good.time = r.x, target
    return r


def held(loads: Loads, net: Net | None = None, factor: float = 1.0) -> Loads:
    """``loads`` as a static run takes them at load ``factor`` (the net's, where not 1),
    for a run to rest: every load and support displacement at its value from the start
    (no history, no ramp)."""
    if factor != 1.0:  # the full loads, scaled: forces, gravity, the supports' moves
        assert net is not None
        full = held(loads)
        move = None
        if full.support_displacement is not None:
            move = np.zeros((net.n_nodes, 3))
            move[net.fixed] = full.support_positions(net, factor=factor) - net.nodes[net.fixed]
        return dataclasses.replace(
            full,
            force=None if full.force is None else factor * full.force,
            gravity=None if full.gravity is None else factor * np.asarray(full.gravity),
            gravity_factor=factor * full.gravity_factor,
            support_displacement=move,
        )
    if not (loads.parts or loads.gravity_history or loads.support_history or loads.vessels):
        if loads.ramp_time is None:
            return loads
    force = None if loads.force is None else loads.force.copy()
    for f, _ in loads.parts:
        force = np.array(f, dtype=np.float64) if force is None else force + f
    vessels = tuple((nodes, vessel.frozen()) for nodes, vessel in loads.vessels)
    return dataclasses.replace(
        loads,
        force=force,
        parts=(),
        gravity_history=None,
        ramp_time=None,
        support_history=(),
        vessels=vessels,
    )
