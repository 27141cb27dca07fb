"""Static runs in load steps: equilibria at increasing load factors, each from the last
(``continuation``), a failing step cut back, then solved by a damped pseudo-transient
solve and, as the ladder's last rung, by dynamic relaxation to rest (``rung.relax_to_rest``);
``predict`` extrapolates a step's start."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

import numpy as np

from catenet.errors import (
    ConfigError,
    ConvergenceError,
    Interrupted,
    LastGood,
    SingularSystemError,
    with_last_good,
)
from catenet.model.net import Loads, Net
from catenet.solver.amplified import warn_amplified
from catenet.solver.endstate import warn_state
from catenet.solver.result import Result, finish
from catenet.solver.rung import StepSettings, can_relax, hangs_slack, relax_to_rest
from catenet.solver.stability import (
    COLLAPSED,
    DRIVEN,
    POST_COLLAPSE,
    REFINE,
    STABLE,
    UNSTABLE,
    CollapseError,
    PathJudge,
    describe_collapse,
)
from catenet.solver.start import predict, start_state
from catenet.solver.static import solve_static
from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)

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
    post_collapse: bool = False,
) -> list[Result]:
    """Equilibria at the given load factors, each starting from the previous one (a
    force-displacement curve). ``on_step(factor, result)`` sees each as it is found.

    A load step that fails is cut back: re-solved from the last equilibrium in sub-steps
    of half its load increment, halved again while one fails (``CUTBACKS`` times at most,
    doubled again after two that succeed), then a damped pseudo-transient solve, the last
    rung dynamic relaxation to rest (``rung.relax_to_rest``; a step to the full loads); the
    sub-steps' equilibria are not reported, their iterations count. A step that
    still fails (or is interrupted) raises its ConvergenceError with ``last_good`` the
    last equilibrium found (a step's or a sub-step's, with its load factor; the start,
    supports in place, at load factor 0 before the first).

    The path's stability is followed (``catenet.solver.stability.PathJudge``): a path that
    collapses raises CollapseError with ``last_good`` its last stable state, unless
    ``post_collapse``, where it goes on and its results' ``stability`` says
    "post-collapse". What the end state is (unstable, nodes on slack edges only) is
    logged once, at the end; the solves on the way (steps, cut-backs, the halved steps
    that judge the path) log none of it."""
    if len(factors) == 0:
        raise ConfigError("continuation: factors is empty: give at least one load factor")
    ws = workspace or Workspace(net, linear=linear)
    results: list[Result] = []
    x = x0
    good = LastGood(start_state(net, loads, x0, 0.0), 0.0)
    judge = PathJudge(ws, loads, post_collapse=post_collapse, rtol=rtol)
    loaded = bool(np.any(loads.external_force(net, 1.0))) or loads.moves_supports
    judge.begin(good.x, loaded)
    settings = StepSettings(rtol=rtol, max_iter=max_iter, workspace=ws, warn=False)
    if judge.start_unstable and not judge.balanced(good.x, rtol):
        settled = _settled(judge, net, loads, good.x, settings)
        if settled is not None:  # the path starts at the equilibrium the given geometry
            good = LastGood(settled, 0.0)  # only approximates
            x = settled
            judge.begin(settled, loaded)
    for k, factor in enumerate(factors):
        if k >= 2:  # secant predictor through the last two equilibria
            x = predict([r.x for r in results[-2:]], factors[k - 2 : k], factor)
        before = LastGood(good.x, good.time)  # the path's last judged equilibrium
        trail: list[tuple[float, Result]] = []  # a cut-back's sub-steps, each judged
        try:
            step: Result | ConvergenceError = solve_static(
                net,
                loads,
                x0=x,
                factor=float(factor),
                accepted=results[-1].x if results else x0,
                **settings,
            )
        except ConvergenceError as exc:
            if judge.start_unstable and not isinstance(exc, Interrupted):
                # from an unstable start, a failure is the collapse (no cut-back helps)
                _collapse(judge, judge.why_start(), 0.0, LastGood(judge.start_x, 0.0), x, exc)
            step = _cut_back(net, loads, float(factor), exc, good, settings, trail)
        if isinstance(step, ConvergenceError):  # it fails: the last equilibrium found is kept
            for level, sub in trail:  # unless the sub-steps found on the way collapsed
                sub = _judged(judge, net, loads, before, level, sub, False, settings)
                before = LastGood(sub.x, level)
            if step.ladder is not None:  # what was tried is said: the advice follows
                step.args = (f"{step}; {_advice(step, max_iter, step.ladder, judge, good)}",)
            raise with_last_good(step, LastGood(good.x, good.time))
        last = k == len(factors) - 1
        for level, sub in trail[:-1]:  # the path to the step's end, as it was found
            sub = _judged(judge, net, loads, before, level, sub, False, settings)
            before = LastGood(sub.x, level)
        r = _judged(judge, net, loads, before, float(factor), step, last, settings)
        r.steps = k + 1
        r.stability = _verdict(judge, r)
        results.append(r)
        good = LastGood(r.x, float(factor))
        x = r.x
        if on_step is not None:
            on_step(float(factor), r)
    # a buckling load passed on the way (amplified.py): its state is no neutral one
    far = judge.start_x is not None and warn_amplified(ws, net, loads, judge.start_x, results[-1])
    warn_state(ws, net, results[-1], neutral=not far)  # once, where the path ends
    return results


#: A given geometry that is no equilibrium is judged at the stable one Newton finds from
#: it under its prestress where no bilateral edge turns more than this between them [rad]
SETTLE_TURN = 0.1


def _settled(
    judge: PathJudge, net: Net, loads: Loads, x: np.ndarray, settings: StepSettings
) -> np.ndarray | None:
    """The stable equilibrium under the prestress alone (load factor 0) that Newton
    finds from a given geometry x that is unstable and no equilibrium, else None. Such
    a geometry is no state of the structure, and its tangent's verdict says nothing of
    the structure's stability: a guyed mast whose guys' nodes were moved by 6 mm (one
    guy's top edge slack there) was called a mechanism at its strut's top, where the
    equilibrium an iteration away is stable. A mechanism keeps its verdict: Newton finds
    no equilibrium, or an unstable one, or one whose bilateral edges turned beyond
    SETTLE_TURN from the geometry given (a mechanism's drift: a frame on pinned feet
    turned over them; the nodes of slack tension-only edges may move as they please)."""
    try:
        found = solve_static(net, loads, x0=x, factor=0.0, accepted=x, **settings).x
    except ConvergenceError:
        return None
    turned = judge.turned(x, found)
    if turned > SETTLE_TURN or judge.tangent(found).verdict != STABLE:
        return None
    return found


def _verdict(judge: PathJudge, r: Result) -> str:
    if judge.collapsed:
        return POST_COLLAPSE
    return UNSTABLE if r.stable is False else STABLE


def _judged(
    judge: PathJudge,
    net: Net,
    loads: Loads,
    good: LastGood,
    target: float,
    r: Result,
    last: bool,
    settings: StepSettings,
) -> Result:
    """The load step from the equilibrium ``good`` to ``r`` at ``target``, judged by the
    path's ``judge``: a step that jumps is halved (down to 1/2**REFINE of itself) to
    tell a limit point from a large step; a collapse raises CollapseError (or, with
    post-collapse, is noted and the path goes on). The step's result (a refined path's
    end where the step was halved)."""
    if not judge.active or judge.collapsed:
        return r
    start, f0 = good.x, float(good.time)
    if f0 == 0.0 and not judge.start_unstable and not judge.balanced(start, settings["rtol"]):
        # the given geometry is no equilibrium at load factor 0 (a strut given unstressed
        # beside prestressed guys): the path starts at the one Newton finds from it
        try:
            found = solve_static(net, loads, x0=start, factor=0.0, accepted=start, **settings).x
        except ConvergenceError:  # none found: the path is judged from the geometry given
            found = start
        start = start if judge.drifts(start, found) else found  # (a mechanism's drift)
        judge.start_tangent(start)
    why, at, before, r = _follow(judge, net, loads, start, f0, target, r, last, settings, 0)
    if why and judge.start_unstable and not judge.loaded:
        return _unstable_start(judge, loads, r, why)
    if why:
        _collapse(judge, why, at, LastGood(before, at), r.x)
        # followed through (solver.post_collapse): on from where the bracket ended
        # (Newton on the exact potential from there: no continuation stage moves it off)
        try:
            r = _beyond(judge, net, loads, r, target, at, settings)
        except ConvergenceError as exc:  # the last equilibrium before this step is kept
            raise with_last_good(exc, LastGood(good.x, good.time)) from None
    return r


def _beyond(
    judge: PathJudge,
    net: Net,
    loads: Loads,
    r: Result,
    target: float,
    at: float,
    settings: StepSettings,
) -> Result:
    """A collapse followed through: the equilibrium at ``target`` on from the bracket's
    end r; from an unstable one (straight by symmetry, which neither Newton nor the
    motion leaves) moved along its unstable mode (``PathJudge.beyond``), by the motion
    where the nodes have mass, else by the pseudo-transient solve."""
    x0 = judge.beyond(r.x)
    if x0 is r.x:
        return solve_static(net, loads, x0=x0, factor=target, accepted=x0, relaxed=True, **settings)
    if can_relax(net, 1.0, settings):
        fell = relax_to_rest(net, loads, target, LastGood(x0, at), settings)
        if fell is not None:
            return fell
    return solve_static(net, loads, x0=x0, factor=target, accepted=x0, transient=True, **settings)


def _unstable_start(judge: PathJudge, loads: Loads, r: Result, why: str) -> Result:
    """The verdict on an unloaded run from an unstable given geometry: the geometry
    itself, an unstable equilibrium (``stable`` False), wherever Newton went from it (a
    round-off's push decides that, differently on each processor)."""
    ws = judge.ws
    x = judge.start_x if judge.start_x is not None else r.x
    g = ws.potential(loads, 1.0).evaluate(x).gnorm
    out = finish(
        ws.system,
        loads,
        x,
        1.0,
        converged=True,
        equilibrium=True,
        iterations=r.iterations,
        residual=float(g),
        history=r.history,
        message=r.message,
        wall_time=r.wall_time,
        stats=ws.stats(),
        outcome=r.outcome,
    )
    out.stable = False
    out.diagnosis = why
    return out


def _follow(
    judge: PathJudge,
    net: Net,
    loads: Loads,
    x0: np.ndarray,
    f0: float,
    f1: float,
    r: Result,
    last: bool,
    settings: StepSettings,
    depth: int,
    unload: bool | None = None,
) -> tuple[str, float, np.ndarray | None, Result]:
    """(why, load factor, last stable state, result) of the step from x0 at f0 to r at
    f1, halving a step that loses stability (an unstable end, a member that fell, a
    mechanism driven, no way back when unloaded) to bracket where (see ``_judged``);
    why is "" where the path holds. ``unload``: whether the step is unloaded to test
    it (decided at its start, ``reversible_from``, for the step and the halves it is cut
    into: those of a step from a neutral start, which has no state to come back to,
    are judged as it is)."""
    why = judge.step(x0, f0, f1, r.x, last)
    if why and judge.start_unstable:
        return why, 0.0, judge.start_x, r
    if (why.startswith(DRIVEN) or why.endswith("a member fell")) and depth == 0:
        moved = _by_motion(judge, net, loads, x0, f0, f1, last, settings)
        if moved is not None:  # the motion stays near: Newton's jump, not the structure's
            moved.iterations += r.iterations
            return "", f0, x0, moved
    if unload is None:  # the step as taken (not one of its halves)
        unload = judge.reversible_from(x0)
    if not why and unload:
        try:
            back = solve_static(net, loads, x0=r.x, factor=f0, accepted=r.x, **settings).x
        except ConvergenceError:  # no way back found: this test cannot tell
            log.info("load step to %.6g: not unloaded (no equilibrium found)", f1)
            back = x0
        if not judge.returns(x0, back, r.x) and not judge.flat(x0, back, r.x, f0, f1):
            why = judge.why_jump(f0, f1, x0, back)
    if not why or depth >= REFINE:  # held, or bracketed to 1/2**REFINE of the step
        return why, f0, x0, r
    mid = 0.5 * (f0 + f1)
    try:
        half = solve_static(net, loads, x0=x0, factor=mid, accepted=x0, **settings)
    except ConvergenceError:
        return why, f0, x0, r  # no equilibrium halfway: the step stands as judged
    half.iterations += r.iterations
    deeper = depth + 1
    args = (settings, deeper, unload)
    why, at, before, half = _follow(judge, net, loads, x0, f0, mid, half, False, *args)
    if why:
        return why, at, before, half
    try:
        rest = solve_static(net, loads, x0=half.x, factor=f1, accepted=half.x, **settings)
    except ConvergenceError:
        return judge.why_jump(mid, f1, half.x, r.x), mid, half.x, r
    rest.iterations += half.iterations
    return _follow(judge, net, loads, half.x, mid, f1, rest, last, *args)


def _by_motion(
    judge: PathJudge,
    net: Net,
    loads: Loads,
    x0: np.ndarray,
    f0: float,
    f1: float,
    last: bool,
    settings: StepSettings,
) -> Result | None:
    """The step from x0 whose Newton end drove a mechanism (rules 4-6), taken again
    by the net's motion: dynamic relaxation to rest under the step's loads, at its load
    factor f1 (``can_relax`` but for the factor: the first of several load steps too).
    From a neutral state Newton can jump where the motion never goes (a mast on guys
    given straight found mirrored through its pinned foot); where the motion's rest
    passes the judge, it is the step's end, else None (the collapse stands)."""
    if not can_relax(net, 1.0, settings):
        return None
    rest = relax_to_rest(net, loads, f1, LastGood(x0, f0), settings)
    if rest is None or judge.step(x0, f0, f1, rest.x, last):
        return None
    log.info("load step to %.6g: Newton's far equilibrium left for the motion's rest", f1)
    return rest


def _collapse(
    judge: PathJudge,
    why: str,
    at: float,
    good: LastGood,
    x1: np.ndarray | None,
    exc: ConvergenceError | None = None,
) -> None:
    """Raises CollapseError from the last stable state ``good`` (or notes the collapse
    where the judge follows it through)."""
    if judge.start_unstable or x1 is None:
        nodes = judge.unstable_nodes(good.x)
    elif why.endswith(" is unstable"):  # (rule 2) what its unstable end's mode moves
        nodes = judge.unstable_nodes(x1)
    else:
        nodes = judge.moving_nodes(good.x, x1)
    if nodes.size == 0:
        nodes = judge.unstable_nodes(good.x)
    message = describe_collapse(judge, why, at, nodes, x1)
    if judge.post_collapse and judge.loaded:
        judge.collapsed = message
        log.warning("%s", message.split(". ")[0] + ": followed through (solver.post_collapse)")
        return
    verdict = COLLAPSED if judge.loaded else UNSTABLE
    raise CollapseError(
        message,
        factor=at,
        nodes=nodes,
        verdict=verdict,
        iterations=0 if exc is None else exc.iterations,
        last_good=LastGood(good.x, good.time),
    )


def _worth_cutting(exc: ConvergenceError) -> bool:
    """Whether smaller load steps can help: not for a mechanism (singular at any load)
    nor for loads below the forces' round-off."""
    if isinstance(exc, SingularSystemError):
        return False
    return "round-off floor exceeds" not in str(exc)


def _advice(
    exc: ConvergenceError, max_iter: int, relaxed: bool, judge: PathJudge, good: LastGood
) -> str:
    """The one setting most likely to help a static run that failed after cut-back
    (``relaxed``: and after dynamic relaxation to rest) from the equilibrium ``good``:
    none where that equilibrium is neutral (Newton does not settle along a mode without
    stiffness: hold it)."""
    if "past the peak of its" in str(exc):  # no setting helps (catenet.solver.static)
        return "the last equilibrium's load factor is about the most the structure carries"
    neutral = judge.neutral_mode(good.x)
    if neutral:
        return f"the last equilibrium is neutral: {neutral}"
    if f"no convergence in {max_iter} iterations" in str(exc):
        return f"most likely to help: a larger solver.max_iter (now {max_iter})"
    if relaxed:
        return "most likely to help: more solver.steps (smaller load steps)"
    return (
        "most likely to help: solver.method = 'dynamic' (dynamic relaxation, the paper's "
        "method, which follows the net's motion to rest), or more solver.steps"
    )


def _cut_back(
    net: Net,
    loads: Loads,
    target: float,
    failure: ConvergenceError,
    good: LastGood,
    settings: StepSettings,
    trail: list[tuple[float, Result]],
) -> Result | ConvergenceError:
    """The load step from the equilibrium ``good`` (updated: it holds the last one) to
    load factor ``target`` in sub-steps (see ``continuation``), in either direction of
    the load, after its ``failure``; each equilibrium found on the way, with its load
    factor, is appended to ``trail`` (for the path's judge). The step's result, or the
    failure for the caller to raise: ``failure`` itself where sub-steps cannot help (an
    interrupt, a mechanism, loads below round-off), a sub-step's interrupt at once, else
    the last failure, its message saying what was tried, when sub-steps of 1/2**CUTBACKS,
    the pseudo-transient solve and dynamic relaxation to rest (where ``can_relax``)
    still fail."""
    if isinstance(failure, Interrupted) or not _worth_cutting(failure):
        return failure
    x, f = good.x, good.time
    increment = 0.5 * (target - f)
    spent = failure.iterations
    cuts, done = 1, 0
    transient = False
    relax_first = hangs_slack(net, good) and can_relax(net, target, settings)
    if relax_first:  # a slack cable from its slack start: the load's size is not what
        relaxed = relax_to_rest(net, loads, target, good, settings)  # fails, its motion is
        if relaxed is not None:
            relaxed.iterations += spent
            trail.append((target, relaxed))
            return relaxed
    while True:
        rest = target - f
        level = target if abs(increment) >= abs(rest) * (1.0 - 1e-12) else f + increment
        log.info("load step cut back: load factor %.6g from %.6g", level, f)
        try:
            r = solve_static(
                net, loads, x0=x, factor=float(level), accepted=x, transient=transient, **settings
            )
        except ConvergenceError as exc:
            spent += exc.iterations
            if isinstance(exc, Interrupted):
                exc.iterations = spent
                return exc
            if cuts >= CUTBACKS and _worth_cutting(exc) and not transient:
                transient = True  # the last rung: a damped pseudo-transient solve
                continue
            if cuts >= CUTBACKS or not _worth_cutting(exc):
                tried = f"load-step cut-back down to 1/{2**cuts} of the step"
                if transient and can_relax(net, target, settings) and not relax_first:
                    relaxed = relax_to_rest(net, loads, target, good, settings)
                    if relaxed is not None:
                        relaxed.iterations += spent
                        trail.append((target, relaxed))
                        return relaxed
                    tried += ", a damped pseudo-transient solve and dynamic relaxation to rest"
                elif transient and relax_first:
                    tried = f"dynamic relaxation to rest, {tried}"
                    tried += " and a damped pseudo-transient solve"
                elif transient:
                    tried += " and a damped pseudo-transient solve"
                exc.args = (
                    f"{exc}; tried: line search, a Levenberg-Marquardt shift, {tried} (the "
                    f"last equilibrium: load factor {good.time:.6g})",
                )
                exc.ladder = "dynamic relaxation" in tried  # for the advice (``_advice``)
                exc.iterations = spent
                return exc
            increment *= 0.5
            cuts, done = cuts + 1, 0
            continue
        spent += r.iterations
        x, f = r.x, float(level)
        good.x, good.time = x, f
        trail.append((f, r))
        if level == target:
            r.iterations = spent
            return r
        done += 1
        if done >= 2 and cuts > 1:  # two in a row: the step grows back
            increment *= 2.0
            cuts, done = cuts - 1, 0
