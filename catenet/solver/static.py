"""Static equilibrium directly (beyond the paper, which reaches it by dynamic relaxation).

Newton on the total potential E(x) - f.x with the regularisation and line search of
``catenet.solver.newton``: from a flat unstressed net or a straight zero-slack cable it starts as
a damped gradient flow and ends as pure Newton with quadratic convergence.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from catenet.model.measures import slack_strain, strain
from catenet.model.net import Loads, Net
from catenet.solver.endstate import judge_stability, warn_state
from catenet.solver.newton import NewtonResult, _c_start, raise_unconverged, solve_newton
from catenet.solver.potential import Potential
from catenet.solver.result import Outcome, Result, finish
from catenet.solver.start import (
    compressed_bilateral,
    definite,
    direct_solve,
    start_state,
    strain_scale,
    stretched_start,
    turned_over,
    unstressed,
)
from catenet.solver.workspace import Workspace, check_rtol
from catenet.terms import Inertia, Stretch, Term

log = logging.getLogger(__name__)


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
    accepted: np.ndarray | None = None,
    transient: bool = False,
    relaxed: bool = False,
    warn: bool = True,
) -> Result:
    """Static equilibrium of ``net`` under ``loads`` scaled by ``factor``.

    ``x0`` (N, 3) is the starting guess (default: the reference positions); supports are
    put at their prescribed places, the free nodes following moved supports
    (``start_state``). ``accepted``: the last accepted state this load step starts from,
    which the terms' ``begin_step`` sees (lagged friction measures slip from it;
    default: x0, else the reference positions); where the straight way from it to the
    start meets an obstacle, the free nodes start 0.9 of the way to the first contact
    (``Potential.toward``): a cord whose supports move down past a block starts above
    it, not in it or beyond. Raises ConvergenceError when
    Newton fails (with the residual history and, as ``state``, the start: never an
    unconverged iterate), unless ``raise_on_failure`` is False. ``transient``: reach the
    equilibrium by a damped pseudo-transient solve (``_pseudo_transient``; the last rung
    of the cut-back's ladder) instead of Newton directly. ``relaxed``: x0 is at rest
    already (dynamic relaxation's, the ladder's last rung): Newton on the exact potential
    from it, without the continuation stages (they would move it away). ``warn``: log
    what the equilibrium found is (unstable, nodes on slack edges only; ``warn_state``);
    False: only the result says it (a load path's solves: the path says it once).
    """
    check_rtol(rtol)
    ws = workspace or Workspace(net, linear=linear)
    start = time.perf_counter()
    x = start_state(net, loads, x0, factor)
    potential = ws.potential(loads, factor)
    if accepted is None:
        accepted = net.nodes if x0 is None else np.asarray(x0, dtype=np.float64)
    potential.begin_step(accepted)
    ws.refresh(potential)  # a free body's contact takes every node again (after a dynamic run)
    # a start that moved supports or a predictor carry into an obstacle (or through it)
    # is cut short on its straight way from the accepted state
    x = potential.toward(np.asarray(accepted, dtype=np.float64), x)
    begin = x.copy()  # what a failure reports: the start, never an unconverged iterate
    if relaxed:
        result = solve_newton(
            potential, x, rtol=rtol, max_iter=max_iter, label="static (from rest)"
        )
    else:
        result = equilibrium(potential, x, rtol=rtol, max_iter=max_iter, transient=transient)
    result = _relag(potential, x, result, rtol=rtol, max_iter=max_iter)
    _check_converged(result, potential, begin, raise_on_failure, _past_peak(net, x))
    out = finish(
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
        outcome=_outcome(result),
    )
    if result.converged:
        judge_stability(ws, net, x, out)
    if warn:
        warn_state(ws, net, out)
    return out


def _past_peak(net: Net, x: np.ndarray) -> str:
    """Why a solve that failed with edges stretched past their law's peak force failed
    ("" when none is): the loads ask more than those edges can carry."""
    eps = strain(net, x)
    past = net.law.past_peak(eps)
    if not past.any():
        return ""
    k = int(np.flatnonzero(past)[np.argmax(eps[past])])
    return (
        f"edge {k} is stretched past the peak of its {net.law.name(k)} law (its force "
        f"peaks at EA / e = {float(net.EA[k]) / math.e:.6g} N at strain e - 1 and falls "
        f"beyond; strain {float(eps[k]):.4g} here): most likely the loads ask more than such "
        "edges can carry, and no equilibrium holds them; lower the loads, or use a law "
        "without a peak (material.law = 'neo_hookean')"
    )


def _check_converged(
    result: NewtonResult,
    potential: Potential,
    begin: np.ndarray,
    raise_on_failure: bool,
    past_peak: str = "",
) -> None:
    """A converged result held only to a round-off floor above the loads is not converged
    (no digit of the answer is sure); an unconverged one raises ConvergenceError (its
    ``state`` the start ``begin``), unless not ``raise_on_failure``. ``past_peak``: why
    a failed one failed, where its edges passed their law's peak (``_past_peak``)."""
    if result.converged and result.tolerance > potential.f_norm > 0:
        # Held only to a round-off floor above the loads: no digit of the answer is sure.
        result.converged = False
        result.reason = "the forces' round-off floor exceeds the loads"
    if not result.converged and past_peak:
        result.reason = past_peak
    if not result.converged and raise_on_failure:
        hint = ""
        if not past_peak and result.tolerance > ROUNDOFF_HINT * potential.f_norm:
            hint = (
                ": the round-off level of this net's forces (EA eps_mach |x| / l0 per edge) "
                "is comparable to its loads, more than double precision can resolve; use "
                "fewer, longer edges or check EA"
            )
        raise_unconverged(result, "static equilibrium", state=begin, hint=hint)


def _outcome(result: NewtonResult) -> Outcome:
    """The Outcome of a load step's Newton result: which criterion held, or failed."""
    if not result.converged:
        return Outcome.FAILED
    return Outcome.AT_FLOOR if "round-off floor" in result.reason else Outcome.EQUILIBRIUM


LAG_ROUNDS = 20  # a static load step re-solved at most this often for its lagged terms
LAG_RTOL = 1e-6  # until their lagged quantities change less than this share


def _relag(
    potential: Potential, x: np.ndarray, result: NewtonResult, *, rtol: float, max_iter: int
) -> NewtonResult:
    """A static load step has no time: terms with lagged quantities (friction: the normal
    forces of the step's start) have them updated at the equilibrium found (``relag``,
    returning the relative change) and the step is solved again from there, until they
    change less than LAG_RTOL (fixed-point iteration; what is left after LAG_ROUNDS stays
    lagged, as in a dynamic step)."""
    lagged = [t for t in potential.system.terms if t.lagged]
    for _ in range(LAG_ROUNDS if lagged else 0):
        if not result.converged or max(t.relag(x) for t in lagged) <= LAG_RTOL:
            return result
        again = solve_newton(
            potential, x, rtol=rtol, max_iter=max_iter, label="static (lagged terms)"
        )
        again.iterations += result.iterations
        again.history = result.history + again.history
        result = again
    if lagged and result.converged:
        log.info("lagged terms still change after %d re-solves of a load step", LAG_ROUNDS)
    return result


ROUNDOFF_HINT = 1e-2  # a failure held to a tolerance above this share of |f| is round-off
SMOOTH_REDUCTION = 10.0  # mu shrinks tenfold per stage
SMOOTH_RTOL = 1e-3  # stages before the last are solved loosely
SMOOTH_STAGES = 30  # at most this many smoothing stages (mu down by 1e30)
SMOOTH_END = 1e-3  # smoothing stops once mu is this fraction of the smallest |strain|
STIFF_STRAIN = 1e-6  # nets strained less than this by their loads: stiffness continuation
STIFF_STEP = 100.0  # EA grows a hundredfold per stage
CONTACT_STRAIN = 3e-2  # nets that touch obstacles start the stiffness continuation here


def equilibrium(
    potential: Potential, x: np.ndarray, *, rtol: float, max_iter: int, transient: bool = False
) -> NewtonResult:
    """Newton to equilibrium from x (updated in place), through two continuations when
    the start calls for them; the last solve always uses the exact law and stiffness to
    the full tolerance.

    - Nearly inextensible nets (strain scale |f| / EA below STIFF_STRAIN): Newton's
      quadratic model holds only for rotations below sqrt(strain), so the net is solved
      first with EA scaled down to strains of about 1e-3, then with EA raised a hundred-
      fold per stage, each stage from the last (the shape hardly changes between them).
    - Tension-only nets that start with slack edges (a cable whose supports moved inward,
      a loose net) have no stiffness where slack, and Newton steps there are erratic: the
      law max(eps, 0) is replaced by (eps + sqrt(eps^2 + mu^2))/2, which keeps every edge
      slightly taut, with mu from the largest slack strain down tenfold per stage until
      it is negligible against the strains.

    - Obstacles whose barrier is narrower than the scene calls for at the start (the
      default: accurate to 1e-4 of an edge) are met first with wider barriers, tenfold
      narrower per stage (``Obstacle.stages``), down to their own.
    - A prestressed net among obstacles is first solved directly (``direct_solve``), the
      continuations only where that does not converge.

    Intermediate stages are solved loosely (SMOOTH_RTOL of the load scale). ``max_iter``
    bounds each Newton solve (every stage and the last), not their sum.
    """
    system = potential.system
    net = system.net
    stretch = system.stretch
    others = tuple(t for t in system.terms if t is not stretch)
    stretched = not others and potential.f_norm > 0 and unstressed(net, x)
    if stretched:
        stretched_start(potential, x)
    first = _taut_first(potential, x, rtol=rtol, max_iter=max_iter)
    # Stages are held to the load scale: smoothing and scaling change the internal forces.
    atol = SMOOTH_RTOL * max(potential.f_norm, float(np.linalg.norm(system.gradient(x)[1])))
    factors = stiffness_factors(potential)
    mu = slack_strain(net, x) if stretch.law.any_tension_only else 0.0
    stages = _Stages(potential, x, _Barriers(others), atol=atol, max_iter=max_iter)
    if first is not None:
        stages.count(first)
    result = (
        direct_solve(potential, x, rtol=rtol, max_iter=max_iter)
        if factors and not transient
        else None
    )
    if result is None or not result.converged:
        if result is not None:
            stages.count(result)
        stages.continue_stiffness(factors, mu)
        stages.narrow_barriers()
        if transient:
            result = _pseudo_transient(potential, x, rtol=rtol, max_iter=max_iter)
        else:
            result = solve_newton(
                potential, x, rtol=rtol, max_iter=max_iter, label="static", shifted=stretched
            )
    result.iterations += stages.iterations
    result.history = stages.history + result.history
    return result


def _taut_first(
    potential: Potential, x: np.ndarray, *, rtol: float, max_iter: int
) -> NewtonResult | None:
    """The tension-only equilibrium first (x updated), for bilateral edges compressed at
    x where the stiffness there is not positive definite: its result (its iterations
    count; x back at the start where it folded a strut), else None."""
    system = potential.system
    stretch = system.stretch
    others = tuple(t for t in system.terms if t is not stretch)
    if not (compressed_bilateral(stretch, x) and not definite(potential, x)):
        return None
    # Bilateral edges in compression: the straight compressed state is an unstable
    # equilibrium beside the sagging one, and the Hessian is indefinite around it, so
    # Newton from the start stalls near it. Where the sagging state has every edge in
    # tension it is the tension-only equilibrium: that one first (its smoothing
    # continuation handles the compressed edges as slack), then the exact law from
    # there (converged at once where no edge ends in compression). A compressed strut
    # that other edges hold (a guyed mast: the Hessian at the start is positive
    # definite) is solved directly: the detour would let it fall over. It is a start only:
    # where its end holds more of the exact potential than the start by more than the
    # loads' work over the structure's size, a strut folded through its slack (a wall
    # bracket's, hung 80 % short beside its tie), and the start is solved directly (a
    # rope's lower part, slack in it, holds a little more). Unloaded, no load folds one.
    # Where a bilateral edge turned beyond FLIP, a strut turned over its pin into tension
    # (a braced panel's posts hung upside down under their slack braces): no sag either.
    start, before = x.copy(), potential.evaluate(x)
    taut = stretch.with_law(stretch.law.with_tension_only(True))
    detour = equilibrium(
        potential.with_system(system.with_terms((taut, *others))), x, rtol=rtol, max_iter=max_iter
    )
    after = potential.evaluate(x)
    work = potential.f_norm * float(np.max(np.ptp(start, axis=0)))
    higher = after.phi > before.phi + max(before.phi_tol, after.phi_tol, work)
    if work > 0.0 and (higher or turned_over(stretch, start, x)):
        log.info("static: the tension-only detour folded a strut: solved from the start")
        x[:] = start
    return detour


class _Stages:
    """The loose solves of ``equilibrium``'s continuations from x (updated in place), held
    to ``atol``, with the obstacles' ``barriers``; ``iterations`` and ``history`` count
    every solve's."""

    def __init__(
        self,
        potential: Potential,
        x: np.ndarray,
        barriers: _Barriers,
        *,
        atol: float,
        max_iter: int,
    ):
        self.potential, self.x, self.barriers = potential, x, barriers
        self.atol, self.max_iter = atol, max_iter
        self.iterations = 0
        self.history: list[float] = []

    def count(self, result: NewtonResult) -> None:
        """Adds a solve's iterations and residual history."""
        self.iterations += result.iterations
        self.history += result.history

    def __call__(self, term: Stretch, label: str, level: int = 0) -> bool:
        """One loose solve with the stretching ``term`` in place of the exact one and the
        obstacles' barriers of continuation ``level`` (0: the widest): whether it
        converged and moved."""
        system = self.potential.system
        result = solve_newton(
            self.potential.with_system(system.with_terms((term, *self.barriers(level)))),
            self.x,
            rtol=SMOOTH_RTOL,
            atol=self.atol,
            max_iter=self.max_iter,
            label=f"static ({label})",
        )
        self.count(result)
        return result.converged and result.iterations > 0

    def continue_stiffness(self, factors: list[float], mu: float) -> None:
        """The stiffness continuation (EA scaled by each of ``factors``, then the exact
        EA), with the smoothing continuation from ``mu`` at the first stiffness."""
        stretch = self.potential.system.stretch
        for k, factor in enumerate(factors + [1.0]):
            scaled = stretch.scaled(factor)
            if k == 0:  # the smoothing continuation, at the first stiffness
                self.smooth(scaled, factor, mu)
            if factor < 1.0:
                self(scaled, f"EA x {factor:.1e}")

    def smooth(self, scaled: Stretch, factor: float, mu: float) -> None:
        """The smoothing continuation of the stretching ``scaled`` (EA x ``factor``): its
        law smoothed by ``mu``, tenfold less per stage, until it is negligible against the
        strains (none for ``mu`` 0)."""
        system = self.potential.system
        stretch, net = system.stretch, system.net
        for _ in range(SMOOTH_STAGES if mu > 0.0 else 0):
            smooth = scaled.with_law(stretch.law.smoothed(mu))
            if not self(smooth, f"EA x {factor:.1e}, mu {mu:.1e}"):
                break
            strains = strain(net, self.x)
            positive = strains[strains > 0]
            if positive.size and mu < SMOOTH_END * float(np.min(positive)):
                break
            mu /= SMOOTH_REDUCTION

    def narrow_barriers(self) -> None:
        """The obstacles' barrier continuation: narrower each stage, to their own."""
        stretch = self.potential.system.stretch
        count = self.barriers.count
        for level in range(count):
            self(stretch, f"barrier stage {level + 1} of {count}", level)


def stiffness_factors(potential: Potential) -> list[float]:
    """The factors (each below 1, rising STIFF_STEP-fold) of the stiffness continuation
    of ``equilibrium`` for a nearly inextensible net; [] for the others."""
    system = potential.system
    scale = strain_scale(system.net, potential)
    factors = []
    # With contact the soft start matters more: a stiff chain pressed onto an obstacle
    # takes Newton steps its barrier cannot follow; it starts at strains of CONTACT_STRAIN.
    contact = any(t.bounds_step for t in system.terms)
    start, below = (CONTACT_STRAIN, CONTACT_STRAIN) if contact else (1e-3, STIFF_STRAIN)
    if 0.0 < scale < below:
        factor = scale / start
        while factor < 1.0:
            factors.append(factor)
            factor *= STIFF_STEP
    return factors


PT_STEPS = 200  # pseudo-time steps of the damped pseudo-transient solve at most
PT_GROW = 4.0  # its step grows (c shrinks) this much after each converged step
PT_END = 1e-8  # ... until c is this share of its start: then Newton on the true potential


def _pseudo_transient(
    potential: Potential, x: np.ndarray, *, rtol: float, max_iter: int
) -> NewtonResult:
    """The equilibrium by a damped pseudo-transient solve: implicit Euler steps of the
    gradient flow D dy/dt = -grad Phi (D the axial stiffness diagonal; pseudo-time, no
    inertia), each the minimum of Phi + (c/2) |y - y_k|_D^2 by Newton (an ``Inertia``
    term of weight c D anchored at the step's start: a well-conditioned problem however
    ill-conditioned Phi is), its step growing (c / PT_GROW) while they converge and
    shrinking (c x PT_GROW^2) when one does not; from c below PT_END of its start (or a
    state already within tolerance), Newton on the true potential ends it. Returns that
    last solve's NewtonResult with the iterations of every step added."""
    system = potential.system
    free = system.free_dofs
    inertia = Inertia(free)
    ev = potential.evaluate(x)
    c = c_first = _c_start(potential, ev.g)
    iterations = 0
    history: list[float] = []
    for _ in range(PT_STEPS):
        if c < PT_END * c_first or float(np.linalg.norm(ev.g)) <= max(rtol * ev.scale, ev.floor):
            break
        y = x.reshape(-1)[free].copy()
        inertia.set_step(c * potential.D, y)
        step = Potential(system, potential.solver, potential.force, (inertia,))
        label = f"static (pseudo-time, c {c:.1e})"  # a way there: solved loosely, as stages
        r = solve_newton(step, x, rtol=max(rtol, SMOOTH_RTOL), max_iter=max_iter, label=label)
        iterations += r.iterations
        history += r.history
        if r.converged:
            c /= PT_GROW
        else:
            x.reshape(-1)[free] = y
            c *= PT_GROW**2
        ev = potential.evaluate(x)
    result = solve_newton(potential, x, rtol=rtol, max_iter=max_iter, label="static")
    result.iterations += iterations
    result.history = history + result.history
    return result


class _Barriers:
    """The internal terms besides the stretching at each stage of the obstacles' barrier
    continuation (``Obstacle.stages``): ``self(level)`` for level 0 (the widest) up to
    ``count`` (the exact terms). Obstacles with fewer stages reach their own barrier
    earlier, so all arrive together; friction rides on the exact barriers only."""

    def __init__(self, others: tuple[Term, ...]):
        self.others = others
        self.count = max((len(t.stages) for t in others), default=0)

    def __call__(self, level: int) -> tuple[Term, ...]:
        if level >= self.count:
            return self.others
        out: list[Term] = []
        for term in self.others:
            stages = term.stages
            if stages:
                k = level - (self.count - len(stages))
                out.append(stages[max(k, 0)])
            elif term.rides_on is None or not term.rides_on.stages:
                out.append(term)  # friction on a staged barrier waits for the exact one
        return tuple(out)
