"""What a solve returns: the final state, tensions, reactions and how it got there."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.model.net import Loads
from catenet.model.peaks import Peaks

if TYPE_CHECKING:  # the solvers (and Numba) load only when a solve runs
    from catenet.run.cases import CaseRun
    from catenet.solver.nested import NestedStart
    from catenet.solver.system import System


class Outcome(StrEnum):
    """How a solve ended (its value is the summary's word for it)."""

    EQUILIBRIUM = "equilibrium"  # every free DOF within rtol of the force scale
    AT_FLOOR = "equilibrium at the round-off floor of its forces"  # above rtol, at round-off
    REACHED_T_END = "reached t_end"  # a dynamic run that ran its time, not yet at rest
    INTERRUPTED = "interrupted"  # stopped on request (a signal, a callback)
    FAILED = "failed"  # did not converge: the state is the last good one


@dataclass
class SolverStats:
    """What a solve cost: the linear solver's backend, the size of the system, and the
    count and seconds of each phase (the linear solver's symbolic analysis, numerical
    factorisation, solves and refinements; the assembly of values; the workspace's set-up)."""

    backend: str = ""
    dofs: int = 0
    nnz: int = 0  # stored entries of the system matrix (one triangle)
    analyse_count: int = 0
    factorize_count: int = 0
    solve_count: int = 0
    refine_count: int = 0  # solves whose backward error needed iterative refinement
    analyse_seconds: float = 0.0
    factorize_seconds: float = 0.0
    solve_seconds: float = 0.0
    assembly_seconds: float = 0.0
    setup_seconds: float = 0.0

    def as_dict(self) -> dict[str, str | int | float]:
        return asdict(self)


@dataclass(frozen=True)
class Timing:
    """Where a whole run's time went (``catenet run``: ``catenet.run.clock.Clock``): the
    solve (the engine) and the start-up before it (the interpreter, imports, the case,
    the JIT cache) [s]; /result ``solve_time`` and ``startup_time``."""

    solve: float
    startup: float


@dataclass
class Result:
    """A solved state of a net.

    x : (N, 3) positions [m];  v : (N, 3) velocities [m/s] (dynamic runs) or None
    a : (N, 3) the integrator's acceleration state [m/s^2] (newmark runs; 0 at the
        supports), which a restart goes on from, or None
    tension : (M,) axial forces EA*eps [N], 0 when slack
    reaction : (N, 3) force each support exerts on the net [N] (0 at free nodes)
    contact_force : (N, 3) force that obstacles, bodies and friction (every internal
        term besides the edges' stretching) exert on each node [N]; at equilibrium
        reactions, contact forces and applied loads sum to zero
    converged : the solve met its tolerance (dynamic: every step did, and the run reached
        t_end or equilibrium);  equilibrium : the state is a static equilibrium
    iterations : Newton iterations in all;  residual : final |grad| [N]
    steps : time steps (dynamic) or load steps (static);  time : simulated time [s]
    max_strain : largest edge strain (|e|/l0 - 1; 0 when none is stretched)
    stable : for bilateral nets, whether the stiffness at the equilibrium is positive
        definite (False: an unstable equilibrium, e.g. a straight cable in compression);
        None where not checked (tension-only nets are never unstable)
    stats : counts and seconds per phase (``SolverStats``)
    timing : a whole run's solve and start-up seconds (``Timing``; None outside a run)
    diagnosis : what makes an unstable equilibrium unstable (``catenet.solver.diagnose``), or ""
    outcome : how the solve ended (``Outcome``); None where not known
    peaks : each edge's largest tension and each node's largest displacement over every
        time step or load step (``catenet.model.peaks.Peaks``); None where not followed
    cases : the load cases and combinations solved from this (base) state, each a
        ``catenet.run.cases.CaseRun`` (name, Result, summary numbers, error)
    nested : a static run's nested start (``catenet.solver.nested.NestedStart``: the
        coarse net's solve, whose iterations ``iterations`` does not count), or None
    stability : the verdict on the state and the path to it (``catenet.solver.stability``):
        "stable", "unstable", "collapsed" (a failed path: the last stable state),
        "post-collapse" (``solver.post_collapse``), or "" where not judged (a transient)
    energy : a dynamic run's energy balance at its end [J], in the order of
        ``catenet.solver.energy.COLUMNS`` (kinetic, elastic, contact, external_work,
        dissipated, numerical), or None; energy_scale : the largest of the run's kinetic,
        elastic, contact energies and work [J] (what the energy verdict measures against);
        energy_motion : its largest kinetic energy [J]
    """

    x: np.ndarray
    tension: np.ndarray
    reaction: np.ndarray
    converged: bool
    iterations: int
    residual: float
    steps: int = 1
    time: float = 0.0
    v: np.ndarray | None = None
    equilibrium: bool = False
    wall_time: float = 0.0
    message: str = ""
    max_strain: float = float("nan")
    stable: bool | None = None
    history: list[float] = field(default_factory=list)
    stats: SolverStats = field(default_factory=SolverStats)
    a: np.ndarray | None = None
    contact_force: np.ndarray | None = None
    diagnosis: str = ""
    outcome: Outcome | None = None
    timing: Timing | None = None
    peaks: Peaks | None = None
    cases: list[CaseRun] = field(default_factory=list)
    nested: NestedStart | None = None
    stability: str = ""
    energy: np.ndarray | None = None
    energy_scale: float = float("nan")
    energy_motion: float = float("nan")
    landed: str = ""  # a fixed obstacle's barrier too weak for a landing: the stiffness


def finish(
    system: System,
    loads: Loads,
    x: np.ndarray,
    factor: float = 1.0,
    *,
    load_time: float | None = None,
    **fields: Any,
) -> Result:
    """Tension and reactions at x (``catenet.model.measures``), and the Result around them;
    ``load_time``: the time of a dynamic state (loads with a history at their value then)."""
    from catenet.model import measures

    net = system.net
    _, grad = system.gradient(x)
    f = loads.external_force(net, factor, time=load_time)
    reaction = measures.reaction(net, grad, f, measures.support_force(system, x))
    return Result(
        x=x.copy(),
        tension=system.tension(x),
        reaction=reaction,
        contact_force=measures.contact_force(system, x),
        max_strain=measures.max_strain(net, x),
        **fields,
    )
