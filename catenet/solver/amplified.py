"""A static equilibrium far beyond the loads' linear response at the start: a buckling
(limit) load passed on the way, or come close to.

A strut bowed by L/100000 and loaded at 1.006 times its Euler load has a stable
equilibrium, the post-buckled elastica, bowed 200 mm: Newton finds it, and its stiffness
there is positive. So does a portal 1 mm out of plumb at 1.06 times its sway buckling
load, swayed 1.62 m. Nothing in that state says that the loads passed a buckling load
on the way, but its displacement does: it is about 200 times Newton's first,
linear step from the start, -K0^-1 g0, where a structure that stiffens as it moves (a
cable, a net, a cantilever bending far) stays within that step or near it and an
imperfect strut below 0.9 of its Euler load within twice it (its bow's amplification
1 / (1 - P / Pcr) on a small share of its motion). ``amplification`` is that ratio
where the start's stiffness is positive definite (where it is not, as for a slack or
unstressed net, the linear step says nothing) and some edge ends in compression (a
structure in tension does not buckle); the load path warns above AMPLIFIED.
Scenes with contact or free bodies are left out: their barriers' stiffness at the
start is not the structure's.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import SingularSystemError

if TYPE_CHECKING:
    from catenet.model.net import Loads, Net
    from catenet.solver.result import Result
    from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)

AMPLIFIED = 10.0  # a displacement this many times the linear step's is warned


def amplification(
    ws: Workspace, net: Net, loads: Loads, x0: np.ndarray, out: Result
) -> float | None:
    """|x - x0| / |K0^-1 g0| over the free DOFs, the equilibrium ``out`` against the
    linear step from the start x0 (N, 3) under the full loads (module docstring); None
    where it says nothing."""
    from catenet.solver.tangent import STABLE, kept_tangent

    if not out.converged or not np.any(np.asarray(out.tension) < 0.0):
        return None
    if any(t.barrier for t in ws.system.terms) or net.bodies:
        return None
    x0 = np.asarray(x0, dtype=np.float64)
    potential = ws.potential(loads, 1.0)
    if kept_tangent(ws.system, ws.solver, x0).verdict != STABLE:
        return None
    try:
        g = potential.evaluate(x0).g
        potential.factorize(x0, 0.0)
        step = potential.solve(g)
    except (SingularSystemError, FloatingPointError):
        return None
    free = ws.system.free_dofs
    moved = float(np.linalg.norm((np.asarray(out.x) - x0).reshape(-1)[free]))
    linear = float(np.linalg.norm(step))
    if not (np.isfinite(linear) and linear > 0.0 and np.isfinite(moved)):
        return None
    return moved / linear


def warn_amplified(ws: Workspace, net: Net, loads: Loads, x0: np.ndarray, out: Result) -> bool:
    """The load path's warning where its end state moved AMPLIFIED times or more its
    linear step from the start (``amplification``); whether it warned."""
    ratio = amplification(ws, net, loads, x0, out)
    if ratio is None or not ratio > AMPLIFIED:
        return False
    log.warning(
        "the equilibrium moved %.3g times as far as the loads' linear response at the "
        "start: on the way they passed a buckling (limit) load of the structure as "
        "modelled, or came close to one (a strut beyond its Euler load bows far, a frame "
        "sways), and this state is post-buckled or near it; compare the loads with the "
        "buckling load (catenet modes, docs/guide/stability.md), or follow the path "
        "with more solver.steps",
        ratio,
    )
    return True
