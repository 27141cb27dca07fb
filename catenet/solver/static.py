"""Static equilibrium directly (beyond the paper, which reaches it by dynamic relaxation).

Newton on the total potential E(x) - f.x with the regularisation and line search of
``catenet.solver.newton``: from a flat unstressed net or a straight zero-slack cable it starts as
a damped gradient flow and ends as pure Newton with quadratic convergence.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError, ConvergenceError, Interrupted, SingularSystemError
from catenet.model.measures import loose_nodes, slack_strain, strain
from catenet.model.net import Loads, Net
from catenet.solver.diagnose import describe_unstable
from catenet.solver.linear import LinearSolver, make_solver
from catenet.solver.newton import Potential, _c_start, raise_unconverged, solve
from catenet.solver.result import Result, finish
from catenet.solver.system import System
from catenet.terms import Inertia, Stretch, Term
from catenet.terms.stretch import Springs

log = logging.getLogger(__name__)


class Workspace:
    """A net's system (its energy terms and their pattern) and linear solver (symbolic
    analysis), built once and reused by every solve on that net: load steps, time steps,
    sweeps over loads. ``terms``: the scene's internal terms besides the stretching of
    the edges (springs, contact, ...)."""

    def __init__(
        self,
        net: Net,
        *,
        linear: str = "auto",
        mtype: int | None = None,
        terms: Sequence[Term] = (),
    ):
        all_terms = (Stretch(net), *terms)
        if mtype is None:  # Cholesky where the matrices are positive (semi)definite
            mtype = 2 if all(t.convex for t in all_terms) else -2
        upper = mtype != 11
        self.net = net
        start = time.perf_counter()
        self.system = System(net, all_terms, upper=upper)
        dof_node = np.flatnonzero(~net.fixed).repeat(3)
        self.solver: LinearSolver = make_solver(
            linear,
            self.system.indptr,
            self.system.indices,
            upper=upper,
            dof_node=dof_node,
            mtype=mtype,
        )
        self.setup_seconds = time.perf_counter() - start

    def potential(self, loads: Loads, factor: float = 1.0, steps: Sequence[Term] = ()) -> Potential:
        """The potential of the loads at ``factor`` (and of a time step's ``steps`` terms)."""
        force = loads.external_force(self.net, factor)
        return Potential(self.system, self.solver, force, steps)

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
    accepted: np.ndarray | None = None,
    transient: bool = False,
) -> Result:
    """Static equilibrium of ``net`` under ``loads`` scaled by ``factor``.

    ``x0`` (N, 3) is the starting guess (default: the reference positions); supports are
    put at their prescribed places. ``accepted``: the last accepted state this load step
    starts from, which the terms' ``begin_step`` sees (lagged friction measures slip
    from it; default: x0, else the reference positions). Raises ConvergenceError when
    Newton fails (with the residual history and, as ``state``, the start: never an
    unconverged iterate), unless ``raise_on_failure`` is False. ``transient``: reach the
    equilibrium by a damped pseudo-transient solve (``_pseudo_transient``; the last rung
    of the cut-back's ladder) instead of Newton directly.
    """
    _check_rtol(rtol)
    ws = workspace or Workspace(net, linear=linear)
    start = time.perf_counter()
    x = _start(net, loads, x0, factor)
    begin = x.copy()  # what a failure reports: the start, never an unconverged iterate
    potential = ws.potential(loads, factor)
    if accepted is None:
        accepted = net.nodes if x0 is None else np.asarray(x0, dtype=np.float64)
    potential.begin_step(accepted)
    result = equilibrium(potential, x, rtol=rtol, max_iter=max_iter, transient=transient)
    result = _relag(potential, x, result, rtol=rtol, max_iter=max_iter)
    if result.converged and result.tolerance > potential.f_norm > 0:
        # Held only to a round-off floor above the loads: no digit of the answer is sure.
        result.converged = False
        result.reason = "the forces' round-off floor exceeds the loads"
    if not result.converged and raise_on_failure:
        hint = ""
        if result.tolerance > ROUNDOFF_HINT * potential.f_norm:
            hint = (
                ": the round-off level of this net's forces (EA eps_mach |x| / l0 per edge) "
                "is comparable to its loads, more than double precision can resolve; use "
                "fewer, longer edges or check EA"
            )
        raise_unconverged(result, "static equilibrium", state=begin, hint=hint)
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
    )
    if not net.law.all_tension_only and result.converged:
        out.stable = _stable(ws, potential, x)
        if out.stable is False:
            out.diagnosis = describe_unstable(ws.system.stretch, x, ~net.fixed)
            log.warning(
                "the equilibrium is unstable: the stiffness matrix has negative eigenvalues "
                "(compressed bilateral edges: any disturbance makes the net buckle away): %s",
                out.diagnosis,
            )
    loose = loose_nodes(net, out.tension)
    for term in ws.system.terms:  # nodes that another term (a spring, contact) holds
        pattern = term.pattern() if not isinstance(term, Stretch) else None
        if pattern is not None and loose.size:
            loose = np.setdiff1d(loose, pattern[0] // 3)
    if loose.size:
        log.warning(
            "%d free nodes hang on slack edges only (nodes %s%s): nothing fixes their "
            "position, the equilibrium there is not unique",
            loose.size,
            ", ".join(map(str, loose[:10])),
            " ..." if loose.size > 10 else "",
        )
    return out


LAG_ROUNDS = 20  # a static load step re-solved at most this often for its lagged terms
LAG_RTOL = 1e-6  # until their lagged quantities change less than this share


def _relag(potential: Potential, x: np.ndarray, result, *, rtol: float, max_iter: int):
    """A static load step has no time: terms with lagged quantities (friction: the normal
    forces of the step's start) have them updated at the equilibrium found (``relag``,
    returning the relative change) and the step is solved again from there, until they
    change less than LAG_RTOL (fixed-point iteration; what is left after LAG_ROUNDS stays
    lagged, as in a dynamic step)."""
    lagged = [t for t in potential.system.terms if hasattr(t, "relag")]
    for _ in range(LAG_ROUNDS if lagged else 0):
        if not result.converged or max(t.relag(x) for t in lagged) <= LAG_RTOL:
            return result
        again = solve(potential, x, rtol=rtol, max_iter=max_iter, label="static (lagged terms)")
        again.iterations += result.iterations
        again.history = result.history + again.history
        result = again
    if lagged and result.converged:
        log.info("lagged terms still change after %d re-solves of a load step", LAG_ROUNDS)
    return result


def _stable(ws: Workspace, potential: Potential, x: np.ndarray) -> bool | None:
    """Whether the stiffness matrix at x is positive definite (None: cannot tell here).
    Only bilateral nets can lose stability: tension-only stiffness is never negative."""
    if ws.solver.name == "pardiso" and getattr(ws.solver, "mtype", None) != -2:
        return None
    try:
        potential.factorize(x, 0.0)
    except SingularSystemError:
        return False  # singular at equilibrium: neutral at best
    negative = ws.solver.negative_eigenvalues()
    return None if negative is None else negative == 0


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
):
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

    Intermediate stages are solved loosely (SMOOTH_RTOL of the load scale). ``max_iter``
    bounds each Newton solve (every stage and the last), not their sum.
    """
    system = potential.system
    net = system.net
    stretch = system.stretch
    others = tuple(t for t in system.terms if t is not stretch)
    history: list[float] = []
    iterations = 0
    stretched = not others and potential.f_norm > 0 and _unstressed(net, x)
    if stretched:
        _stretched_start(potential, x)
    if _compressed_bilateral(stretch, x) and not _definite(potential, x):
        # Bilateral edges in compression: the straight compressed state is an unstable
        # equilibrium beside the sagging one, and the Hessian is indefinite around it, so
        # Newton from the start stalls near it. Where the sagging state has every edge in
        # tension it is the tension-only equilibrium: that one first (its smoothing
        # continuation handles the compressed edges as slack), then the exact law from
        # there (converged at once where no edge ends in compression). A compressed strut
        # that other edges hold (a guyed mast: the Hessian at the start is positive
        # definite) is solved directly: the detour would let it fall over.
        taut = stretch.with_law(stretch.law.with_tension_only(True))
        first = equilibrium(
            potential.with_system(system.with_terms((taut, *others))),
            x,
            rtol=rtol,
            max_iter=max_iter,
        )
        iterations += first.iterations
        history += first.history
    # Stages are held to the load scale: smoothing and scaling change the internal forces.
    atol = SMOOTH_RTOL * max(potential.f_norm, float(np.linalg.norm(system.gradient(x)[1])))
    scale = _strain_scale(net, potential)
    factors = []
    # With contact the soft start matters more: a stiff chain pressed onto an obstacle
    # takes Newton steps its barrier cannot follow; it starts at strains of CONTACT_STRAIN.
    contact = any(hasattr(t, "max_step") for t in system.terms)
    start, below = (CONTACT_STRAIN, CONTACT_STRAIN) if contact else (1e-3, STIFF_STRAIN)
    if 0.0 < scale < below:
        factor = scale / start
        while factor < 1.0:
            factors.append(factor)
            factor *= STIFF_STEP
    mu = slack_strain(net, x) if stretch.law.any_tension_only else 0.0

    barriers = _Barriers(others)

    def stage(term: Stretch, label: str, level: int = 0) -> bool:
        """One loose solve with the stretching ``term`` in place of the exact one and the
        obstacles' barriers of continuation ``level`` (0: the widest)."""
        nonlocal iterations, history
        result = solve(
            potential.with_system(system.with_terms((term, *barriers(level)))),
            x,
            rtol=SMOOTH_RTOL,
            atol=atol,
            max_iter=max_iter,
            label=f"static ({label})",
        )
        iterations += result.iterations
        history += result.history
        return result.converged and result.iterations > 0

    for k, factor in enumerate(factors + [1.0]):
        scaled = stretch.scaled(factor)
        if k == 0:  # the smoothing continuation, at the first stiffness
            for _ in range(SMOOTH_STAGES if mu > 0.0 else 0):
                smooth = scaled.with_law(stretch.law.smoothed(mu))
                if not stage(smooth, f"EA x {factor:.1e}, mu {mu:.1e}"):
                    break
                strains = strain(net, x)
                taut = strains[strains > 0]
                if taut.size and mu < SMOOTH_END * float(np.min(taut)):
                    break
                mu /= SMOOTH_REDUCTION
        if factor < 1.0:
            stage(scaled, f"EA x {factor:.1e}")
    for level in range(barriers.count):  # the obstacles' barriers, narrower each stage
        stage(stretch, f"barrier stage {level + 1} of {barriers.count}", level)
    if transient:
        result = _pseudo_transient(potential, x, rtol=rtol, max_iter=max_iter)
    else:
        result = solve(
            potential, x, rtol=rtol, max_iter=max_iter, label="static", shifted=stretched
        )
    result.iterations += iterations
    result.history = history + result.history
    return result


PT_STEPS = 200  # pseudo-time steps of the damped pseudo-transient solve at most
PT_GROW = 4.0  # its step grows (c shrinks) this much after each converged step
PT_END = 1e-8  # ... until c is this share of its start: then Newton on the true potential


def _pseudo_transient(potential: Potential, x: np.ndarray, *, rtol: float, max_iter: int):
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
    _, g, scale, floor, _ = potential.evaluate(x)
    c = c_first = _c_start(potential, g)
    iterations, history = 0, []
    for _ in range(PT_STEPS):
        if c < PT_END * c_first or float(np.linalg.norm(g)) <= max(rtol * scale, floor):
            break
        y = x.reshape(-1)[free].copy()
        inertia.set_step(c * potential.D, y)
        step = Potential(system, potential.solver, potential.force, (inertia,))
        r = solve(step, x, rtol=rtol, max_iter=max_iter, label=f"static (pseudo-time, c {c:.1e})")
        iterations += r.iterations
        history += r.history
        if r.converged:
            c /= PT_GROW
        else:
            x.reshape(-1)[free] = y
            c *= PT_GROW**2
        _, g, scale, floor, _ = potential.evaluate(x)
    result = solve(potential, x, rtol=rtol, max_iter=max_iter, label="static")
    result.iterations += iterations
    result.history = history + result.history
    return result


class _Barriers:
    """The internal terms besides the stretching at each stage of the obstacles' barrier
    continuation (``Obstacle.stages``): ``self(level)`` for level 0 (the widest) up to
    ``count`` (the exact terms). Obstacles with fewer stages reach their own barrier
    earlier, so all arrive together; friction rides on the exact barriers only."""

    def __init__(self, others: tuple):
        self.others = others
        self.count = max((len(getattr(t, "stages", ())) for t in others), default=0)

    def __call__(self, level: int) -> tuple:
        if level >= self.count:
            return self.others
        out = []
        for term in self.others:
            stages = getattr(term, "stages", ())
            if stages:
                k = level - (self.count - len(stages))
                out.append(stages[max(k, 0)])
            elif not getattr(getattr(term, "obstacle", None), "stages", ()):
                out.append(term)  # friction on a staged barrier waits for the exact one
        return tuple(out)


UNSTRESSED = 1e-12  # a start whose strains are all below this carries no tension
STRETCH_RTOL = 1e-3  # the stretched start's scale is found to this relative width


def _unstressed(net: Net, x: np.ndarray) -> bool:
    """Whether no edge is strained at x (a flat net, a straight cable at its rest
    length): the stiffness has no transverse part and Newton must find one."""
    return bool(np.all(np.abs(strain(net, x)) <= UNSTRESSED))


def _stretched_start(potential: Potential, x: np.ndarray) -> None:
    """Moves the free nodes of an unstressed net (x, in place) along the displacement u
    of a net of linear springs q = 1/l0 under the loads (the force density method's; one
    solve with the net's own factorisation, ``terms.stretch.Springs``), to the point
    x + s u where the potential is least along that ray (a convex function of s for a
    tension-only net: bisection on its slope). Every edge the move lengthens is taut
    there, so Newton starts with a transverse stiffness it would otherwise grow step by
    step from the flat start, and takes a number of iterations that hardly grows with
    refinement (the paper's n = 34 net: 7, 10 and 12 at 1 cm, 1 mm and 0.2 mm edges,
    where the flat start took 11, 14 and more than 600). Edges the move hardly
    lengthened (near the supports) are still soft across, so that Newton begins with a
    small Levenberg-Marquardt shift (``newton.solve(shifted=True)``)."""
    net = potential.system.net
    u = np.zeros_like(x)
    springs = potential.with_system(
        potential.system.with_terms([Springs(net, 1.0 / net.rest_length)])
    )
    try:
        springs.factorize(x, 0.0)
        u.reshape(-1)[potential.system.free_dofs] = potential.solver.solve(springs.f_free)
    except SingularSystemError:
        return  # a part without support: the usual path says so
    if not np.all(np.isfinite(u)):
        return
    largest = float(np.max(np.abs(u), initial=0.0))  # no squares: no overflow
    extent = float(np.max(np.ptp(net.nodes, axis=0)))
    if not (largest > 0.0 and math.isfinite(extent) and extent > 0.0):
        return
    u *= extent / largest  # s = 1 moves the farthest node by the net's extent
    u_free = u.reshape(-1)[potential.system.free_dofs]
    x0 = x.copy()

    def slope(s: float) -> float:
        np.add(x0, s * u, out=x)
        g = potential.evaluate(x)[1]
        return float(np.dot(g, u_free))

    lo, hi = 0.0, 1e-6
    for _ in range(60):  # the slope is negative at 0 (the loads pull along u)
        if not slope(hi) < 0.0:
            break
        lo, hi = hi, 4.0 * hi
    else:
        x[:] = x0
        return
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if slope(mid) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= STRETCH_RTOL * hi:
            break
    np.add(x0, hi * u, out=x)


def _definite(potential: Potential, x: np.ndarray) -> bool:
    """Whether the stiffness at x is positive definite (False where the solver cannot
    tell: then the caller takes the safe path)."""
    if getattr(potential.solver, "mtype", -2) != -2:
        return False
    try:
        potential.factorize(x, 0.0)
    except SingularSystemError:
        return False
    return potential.solver.negative_eigenvalues() == 0


def _compressed_bilateral(stretch: Stretch, x: np.ndarray) -> bool:
    """Whether some bilateral edge (not tension-only) is compressed at x."""
    law = stretch.law
    if law.all_tension_only:
        return False
    return bool(np.any((strain(stretch.net, x) < 0.0) & ~law.tension_only))


def _strain_scale(net: Net, potential: Potential) -> float:
    """The strain the loads can cause at most, |f|_1 / min EA (0 without loads): an
    estimate of how stiff the net is against what acts on it."""
    return float(np.abs(potential.force).sum() / np.min(net.EA))


CUTBACKS = 5  # a failing load step is re-solved in sub-steps down to 1/2**CUTBACKS of it


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

    A load step that fails is cut back: re-solved from the last equilibrium in sub-steps
    of half its load increment, halved again while one fails (``CUTBACKS`` times at
    most); the sub-steps' equilibria are not reported, their iterations count. A step
    that still fails raises ConvergenceError whose ``state`` is the last equilibrium
    found (a step's or a sub-step's; None before the first) and ``factor`` its load
    factor (0: the start)."""
    if len(factors) == 0:
        raise ConfigError("continuation: factors is empty: give at least one load factor")
    ws = workspace or Workspace(net, linear=linear)
    results: list[Result] = []
    x = x0
    good = Equilibrium(None, 0.0)  # the last equilibrium (None: the start)
    for k, factor in enumerate(factors):
        if k >= 2:  # secant predictor through the last two equilibria
            x = predict([r.x for r in results[-2:]], factors[k - 2 : k], factor)
        settings = dict(rtol=rtol, max_iter=max_iter, workspace=ws)
        try:
            r = solve_static(
                net,
                loads,
                x0=x,
                factor=float(factor),
                accepted=results[-1].x if results else x0,
                **settings,
            )
        except ConvergenceError as exc:
            if isinstance(exc, Interrupted) or not _worth_cutting(exc):
                exc.state, exc.factor = good.x, good.factor
                raise
            origin = good if good.x is not None else Equilibrium(x0, 0.0)
            r = _cut_back(net, loads, origin, float(factor), exc, good, settings)
        r.steps = k + 1
        results.append(r)
        good = Equilibrium(r.x, float(factor))
        x = r.x
        if on_step is not None:
            on_step(float(factor), r)
    return results


@dataclass
class Equilibrium:
    """A converged state ``x`` (N, 3) of a static run and its load factor (x None: the
    run's start, load factor 0)."""

    x: np.ndarray | None
    factor: float


def _worth_cutting(exc: ConvergenceError) -> bool:
    """Whether smaller load steps can help: not for a mechanism (singular at any load)
    nor for loads below the forces' round-off."""
    if isinstance(exc, SingularSystemError):
        return False
    return "round-off floor exceeds" not in str(exc)


def _advice(exc: ConvergenceError, max_iter: int) -> str:
    """The one setting most likely to help a static run that failed after cut-back."""
    if f"no convergence in {max_iter} iterations" in str(exc):
        return f"most likely to help: a larger solver.max_iter (now {max_iter})"
    return (
        "most likely to help: solver.method = 'dynamic' (dynamic relaxation, the paper's "
        "method, which follows the net's motion to rest), or more solver.steps"
    )


def _cut_back(net, loads, origin: Equilibrium, target: float, failure, good, settings) -> Result:
    """The load step from ``origin`` to ``target`` in sub-steps (see ``continuation``);
    ``good`` (updated) holds the last equilibrium. Raises the last failure, its message
    saying what was tried, when sub-steps of 1/2**CUTBACKS still fail."""
    x, f = origin.x, origin.factor
    increment = 0.5 * (target - f)
    spent = int(getattr(failure, "iterations", 0))
    cuts = 1
    transient = False
    while True:
        level = target if f + increment >= target - 1e-12 * abs(target) else f + increment
        log.info("load step cut back: load factor %.6g from %.6g", level, f)
        try:
            r = solve_static(
                net, loads, x0=x, factor=float(level), accepted=x, transient=transient, **settings
            )
        except ConvergenceError as exc:
            spent += int(getattr(exc, "iterations", 0))
            if cuts >= CUTBACKS and _worth_cutting(exc) and not transient:
                transient = True  # the last rung: a damped pseudo-transient solve
                continue
            if cuts >= CUTBACKS or not _worth_cutting(exc):
                tried = f"load-step cut-back down to 1/{2**cuts} of the step"
                if transient:
                    tried += " and a damped pseudo-transient solve"
                exc.args = (
                    f"{exc}; tried: line search, a Levenberg-Marquardt shift, {tried} (the "
                    f"last equilibrium: load factor {good.factor:.6g}); "
                    f"{_advice(exc, settings['max_iter'])}",
                )
                exc.iterations = spent
                exc.state, exc.factor = good.x, good.factor
                raise
            increment *= 0.5
            cuts += 1
            continue
        spent += r.iterations
        x, f = r.x, float(level)
        good.x, good.factor = x, f
        if level == target:
            r.iterations = spent
            return r


def predict(states: Sequence[np.ndarray], levels: Sequence[float], level: float) -> np.ndarray:
    """The equilibrium at load level ``level`` extrapolated by the Lagrange polynomial
    through the given equilibria (two: a secant, three: a parabola) at their levels.
    Levels must be distinct; with one state it is returned as it is."""
    if len(states) != len(levels):
        raise ValueError("predict: one level per state")
    if len(set(levels)) != len(levels):
        return np.array(states[-1], copy=True)
    x = np.zeros_like(states[-1])
    for i, (xi, si) in enumerate(zip(states, levels, strict=True)):
        w = 1.0
        for j, sj in enumerate(levels):
            if j != i:
                w *= (level - sj) / (si - sj)
        x += w * xi
    return x


def _start(net: Net, loads: Loads, x0, factor: float) -> np.ndarray:
    """The starting guess: x0 (or the reference positions) with the supports put in place.
    Where supports move, the free nodes follow them by the harmonic extension of the
    support displacement, so no edge starts out stretched many times its length."""
    if x0 is None:
        x = net.nodes.copy()
    else:
        x = np.array(x0, dtype=np.float64, copy=True)
        if x.shape != net.nodes.shape or not np.all(np.isfinite(x)):
            raise ConfigError(f"x0: shape {x.shape}: must be finite with shape {net.nodes.shape}")
    target = loads.support_positions(net, factor=factor)
    if loads.moves_supports:
        x += harmonic_extension(net, target - x[net.fixed])
    x[net.fixed] = target
    return x


class HarmonicExtension:
    """Displacements of the free nodes that follow given support displacements: at every
    free node the average of its neighbours' (weights 1/l0), the solution of a graph-
    Laplacian system factorised once per net. Moved supports carry the net with them
    instead of running over their neighbours."""

    def __init__(self, net: Net):
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        n = net.n_nodes
        i, j = net.edges[:, 0], net.edges[:, 1]
        w = 1.0 / net.rest_length
        lap = sp.coo_matrix(
            (
                np.concatenate([w, w, -w, -w]),
                (np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i])),
            ),
            shape=(n, n),
        ).tocsr()
        self.net = net
        self.free = ~net.fixed
        self._coupling = lap[self.free][:, net.fixed].tocsr()
        self._lu = splu(lap[self.free][:, self.free].tocsc())

    def __call__(self, support_shift: np.ndarray) -> np.ndarray:
        """Displacement (N, 3): ``support_shift`` (K, 3) at the fixed nodes."""
        u = np.zeros((self.net.n_nodes, 3))
        u[self.net.fixed] = support_shift
        if np.any(support_shift):
            u[self.free] = self._lu.solve(-(self._coupling @ support_shift))
        return u


def harmonic_extension(net: Net, support_shift: np.ndarray) -> np.ndarray:
    """The displacement (N, 3) of HarmonicExtension for one support shift."""
    return HarmonicExtension(net)(support_shift)


def _check_rtol(rtol: float) -> None:
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise ConfigError(f"solver.rtol = {rtol!r}: must be in (0, 1)")
