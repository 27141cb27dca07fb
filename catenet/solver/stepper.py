"""A dynamic run's state (t, x, v) and the time steps that advance it (``TimeStepper``,
which ``catenet.solver.dynamic.solve_dynamic`` drives): each step's predictor, its
Newton solve with the scheme's inertia and damping, the retry with fresh factorisations,
the acceptance and the rest test of dynamic relaxation (``at_rest``)."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, NoReturn

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConfigError, ConvergenceError, SingularSystemError
from catenet.kernels.sparse import norm
from catenet.model.measures import slack_strain
from catenet.model.net import Loads, Net
from catenet.solver.adaptive import ErrorControl
from catenet.solver.energy import Ledger
from catenet.solver.events import deep_contact
from catenet.solver.integrators import Scheme
from catenet.solver.newton import EXTEND, NewtonResult, Reuse, solve_newton
from catenet.solver.relax import RestControl, rest_stages
from catenet.solver.result import Outcome
from catenet.solver.start import HarmonicExtension
from catenet.solver.stepping import StepControl
from catenet.solver.workspace import Workspace
from catenet.terms import Inertia
from catenet.terms.moving import carry, moves
from catenet.terms.pinch import Pinched, pinch_note

if TYPE_CHECKING:
    from catenet.model.guides import Guides
    from catenet.solver.potential import Potential
    from catenet.solver.strikes import Watch
    from catenet.solver.system import System

EPS = float(np.finfo(np.float64).eps)
SEEN = 64.0  # a load below this many round-offs of the largest one so far is none

log = logging.getLogger("catenet.solver.dynamic")  # the dynamic run's messages, as ever

WIDEN = 4  # a step candidate radii held back is tried again at its length this many times

#: ``on_step(step, t, x, v)``: sees every accepted step; True stops the run there.
OnStep = Callable[[int, float, np.ndarray, np.ndarray], bool | None]


class TimeStepper:
    """The state (t, x, v) of a dynamic run and the steps that advance it: each step's
    predictor (the scheme's, carried along by moving supports and obstacles), its Newton
    solve with the scheme's inertia and damping, the retry with fresh factorisations of a
    step that failed with a kept one (modified Newton, ``reuse``), and the rest test of
    dynamic relaxation. ``iterations`` counts every Newton iteration, failed steps' too."""

    def __init__(
        self,
        net: Net,
        loads: Loads,
        ws: Workspace,
        scheme: Scheme,
        damping: float,
        *,
        rtol: float,
        max_iter: int,
        reuse: bool,
        extend: bool = False,
    ):
        self.net, self.loads, self.scheme = net, loads, scheme
        self.ws = ws
        self.system = ws.system
        self.free = self.system.free_dofs
        self.m_free, self.damping = mass_and_damping(net, damping)
        self.inertia = Inertia(self.free)  # the step's inertia and damping, refilled every step
        self.potential = ws.potential(loads, steps=(self.inertia,))
        self.rtol, self.max_iter, self.extend = rtol, max_iter, extend
        self.polish = True  # Newton polishes below its floor (``run``: only toward rest)
        self.kept = Reuse() if reuse else None  # the factorisation modified Newton keeps
        self.fresh = False  # this step's retry with fresh factorisations (its kept one failed)
        self.load_peak = 0.0  # the largest load scale of the accepted steps (``accept``)
        self.widens = 0  # this step's retries with wider candidate radii (``widened``)
        self.iterations = 0
        self.steps = 0
        self.residual = 0.0  # the last step's Newton residual; at rest the static one
        self.equilibrium = False
        self.pseudo = False  # a run to rest through its stages: the path is only a path
        self.ledger: Ledger | None = None  # the energy balance (catenet.solver.energy)
        self.media = [t for t in self.system.terms if t.medium]  # water (terms/water.py)
        self.watch: Watch | None = None  # strikes fixed steps step over (solver/strikes.py)

    def begin(
        self,
        x0: ArrayLike | None,
        v0: ArrayLike | None,
        t0: float,
        a0: ArrayLike | None,
        a_out: np.ndarray | None,
    ) -> None:
        """The start state at t0: ``x0``, ``v0`` (default: reference positions at rest)
        with the supports where they are at t0; the scheme's acceleration state from
        ``a0`` (None: the physical one), copied into ``a_out`` after every step."""
        net, loads = self.net, self.loads
        x = net.nodes.copy() if x0 is None else np.array(x0, dtype=np.float64, copy=True)
        v = np.zeros_like(x) if v0 is None else np.array(v0, dtype=np.float64, copy=True)
        if x.shape != net.nodes.shape or v.shape != net.nodes.shape:
            raise ConfigError(f"x0, v0: must have shape {net.nodes.shape}")
        x[net.fixed] = loads.support_positions(net, time=t0)
        if net.guides is not None:  # rollers and sliders: on their guides, moving along
            net.guides.place(x, net.nodes)
            _along_guides(net.guides, v)
        driven = [term.settle_time() for term in self.system.terms if term.driven]
        self.settle = max([loads.settle_time(), *driven])  # every history at its end
        # an obstacle on a prescribed motion, at its t0 pose
        self.moving = moves(self.potential, t0)
        moving_supports = loads.moves_supports and self.settle > t0
        self.follow = HarmonicExtension(net) if moving_supports else None
        self.t, self.x, self.v = t0, x, v
        self.x0_free = x.reshape(-1)[self.free].copy()  # adaptive steps' displacements
        self.x_trial = np.empty_like(x)
        if a0 is not None and np.shape(a0) != net.nodes.shape:
            raise ConfigError(f"a0: must have shape {net.nodes.shape}")
        a_free = None if a0 is None else np.asarray(a0, dtype=np.float64).reshape(-1)[self.free]
        potential = potential_at(self.potential, loads, net, t0)
        for term in self.system.terms:
            if term.medium or term.driven:
                term.begin_run(x, t0)
        self.scheme.begin(potential, x, v, self.m_free, self.damping, a_free)
        self.a_out = a_out
        store_acceleration(self.scheme, a_out, self.free)
        if self.ledger is not None:
            self.ledger.begin(self)

    def _on_guides(self, v: np.ndarray) -> None:
        """The step's end state exactly on the rollers and sliders: positions on the
        guides, velocities and the scheme's acceleration in their free directions."""
        guides = self.net.guides
        assert guides is not None
        guides.place(self.x_trial, self.net.nodes)
        v[guides.nodes] = guides.project(v[guides.nodes])
        a = self.scheme.a  # (None: a scheme without an acceleration state)
        if a is not None and self.system.guided is not None:
            self.system.guided.project(a)

    def run(
        self,
        control: StepControl | RestControl | ErrorControl,
        *,
        rest: bool,
        on_step: OnStep | None,
        on_rest: Callable[[float], None] | None,
    ) -> Outcome:
        """Steps to ``control.t_end``, to rest (``rest``: dynamic relaxation, once the
        supports have settled and no obstacle moves) or until ``on_step`` says stop.
        ``control``: a StepControl, or a RestControl (a run to rest: its steps grow as the
        static residual decays; ConvergenceError after its ``max_steps`` steps)."""
        to_rest = control if isinstance(control, RestControl) else None
        # a run that may end at rest (damped) tests the static residual: its steps polished
        self.polish = rest and bool(np.any(np.asarray(self.damping) > 0.0))
        if self.pseudo and self.ledger is not None:
            self.ledger.judged = False  # stages change the potential: pseudo-time only
        while self.t < control.t_end * (1 - 1e-12) and not self.equilibrium:
            h_step = control.step(self.t)
            newton, why = self.solve_step(h_step)
            if newton is None or not newton.converged:
                if not (self.widened(h_step, why) or self.refresh(h_step, why)):
                    self.cut(control, h_step, why, newton)
                continue
            if isinstance(control, ErrorControl) and not control.within(self, h_step, newton):
                continue  # its error beyond the tolerance: tried again, shorter
            self.accept(control, h_step, newton)
            if rest and self.t >= self.settle and not self.moving:  # else it runs to t_end
                self.rest_test(to_rest, h_step, newton, on_rest)
            if on_step is not None and on_step(self.steps, self.t, self.x, self.v):
                return Outcome.INTERRUPTED
            if to_rest and not self.equilibrium and self.steps >= to_rest.max_steps:
                self.no_rest(to_rest)
        log.info(
            "%d steps tried (%d failed); dt plans %d", control.tries, control.fails, control.planned
        )
        return Outcome.EQUILIBRIUM if self.equilibrium else Outcome.REACHED_T_END

    def rest_test(
        self,
        to_rest: RestControl | None,
        h_step: float,
        newton: NewtonResult,
        on_rest: Callable[[float], None] | None,
    ) -> None:
        """After an accepted step of ``h_step`` (Newton's ``newton``): whether the state
        is at rest (``at_rest``; a run to rest ``to_rest`` then goes on to its next stage,
        if any, else its control hears the residual), and ``on_rest`` its ratio."""
        tol = to_rest.rtol(self.rtol) if to_rest else self.rtol
        self.equilibrium, residual_static, ratio = at_rest(
            self.potential.system, self.potential, self.x, self.v, self.m_free, h_step, tol
        )
        if self.equilibrium and to_rest and to_rest.stages:
            self.potential = to_rest.next_stage()  # at rest on a wider barrier
            self.equilibrium = False
        elif self.equilibrium:
            self.residual = residual_static
        elif to_rest:
            to_rest.settled(residual_static, newton.iterations)
        if on_rest is not None:
            on_rest(ratio)

    def predict(self, h_step: float) -> np.ndarray:
        """The step's start for Newton: the scheme's predictor (Eq. 11 for implicit Euler)
        with the supports at t + h, the free nodes following their motion, carried by a
        moving obstacle and cut at the obstacles."""
        net, loads, potential = self.net, self.loads, self.potential
        x, v, t, x_trial = self.x, self.v, self.t, self.x_trial
        x_trial[:] = x
        self.scheme.predict(x_trial, v, self.free, h_step)
        supports = loads.support_positions(net, time=t + h_step)
        if self.follow is not None and t < self.settle:
            # The free nodes follow what Eq. 11 does not foresee of the supports' motion
            # (a start, a stop, a change of speed): the net is carried along instead of
            # being run over by a support.
            x_trial += self.follow(supports - x[net.fixed] - h_step * v[net.fixed])
        x_trial[net.fixed] = supports
        potential_at(potential, loads, net, t + h_step)  # loads with a history: at t + h
        potential.begin_step(x, t + h_step, t)
        if self.ws.refresh(potential) and self.kept is not None:
            self.kept.drop()  # the pattern grew (self-contact): a new matrix
        try:  # nodes a moving obstacle may reach ride with it (catenet/terms/moving.py)
            base = carry(potential, x, x_trial, t, t + h_step, net.fixed)
        except Pinched:
            raise  # too long a step for two obstacles closing on the net: a shorter one
        except ConvergenceError as exc:
            raise ConvergenceError(str(exc), iterations=self.iterations, state=x.copy()) from None
        x_trial[:] = potential.toward(base, x_trial)  # a predictor inside an obstacle is cut
        if net.guides is not None:  # rollers and sliders: Newton's steps keep them there
            net.guides.place(x_trial, net.nodes)
        return x_trial

    def solve_step(self, h_step: float) -> tuple[NewtonResult | None, str]:
        """Newton for the step of ``h_step`` from the predictor: its result (None when the
        system was singular) and why it failed."""
        try:
            x_trial = self.predict(h_step)
        except Pinched as exc:
            return None, str(exc)
        y_k = self.x.reshape(-1)[self.free]
        v_k = self.v.reshape(-1)[self.free]
        self.inertia.set_step(*self.scheme.weights(self.m_free, y_k, v_k, h_step, self.damping))
        if self.media:
            self.set_motion(y_k, v_k, h_step)
        if self.pseudo:
            self.start_still(x_trial)
        if self.kept is not None:
            self.kept.keep(h_step)  # a new h changes the inertia diagonal: factorise afresh
        try:
            newton = solve_newton(
                self.potential,
                x_trial,
                rtol=self.rtol * self.scheme.step_rtol,
                max_iter=self.max_iter,
                label="step",
                reuse=None if self.fresh else self.kept,
                polish=self.polish,
                safeguard=True,
                extend=self.extend,
            )
        except SingularSystemError as exc:
            return None, str(exc)
        self.iterations += newton.iterations
        return newton, newton.reason

    def set_motion(self, y_k: np.ndarray, v_k: np.ndarray, h_step: float) -> None:
        """Gives the water's terms the step's velocity and acceleration as affine maps of
        its positions (``Scheme.motion``)."""
        kv, c, ka, c_a = self.scheme.motion(y_k, v_k, h_step)
        fixed = self.net.fixed  # the supports: the scheme's velocity on their own path
        end = self.x_trial[fixed].reshape(-1)  # (``Scheme.held``), as the maps give it
        start, speed = self.x[fixed].reshape(-1), self.v[fixed].reshape(-1)
        v_end, a_end = self.scheme.held(end, start, speed, h_step)
        centre, centre_a = self.x.copy(), self.x.copy()
        centre[fixed] = (end - v_end / kv).reshape(-1, 3)
        centre_a[fixed] = (end - a_end / ka).reshape(-1, 3)
        centre.reshape(-1)[self.free] = c
        centre_a.reshape(-1)[self.free] = c_a
        for term in self.media:
            term.set_motion(kv, centre, ka, centre_a)

    def start_still(self, x_trial: np.ndarray) -> None:
        """In pseudo-time (a run to rest through its stages), Newton starts the step from
        the last state instead of the scheme's predictor where the step's potential is
        lower there: the step's equilibrium is the same, only Newton's start differs (the
        predictor extrapolates a recoil after a stage change: catenet/solver/relax.py)."""
        still = self.x.copy()
        still[self.net.fixed] = x_trial[self.net.fixed]
        if self.potential.evaluate(still).phi < self.potential.evaluate(x_trial).phi:
            x_trial[:] = still

    def widened(self, h_step: float, why: str) -> bool:
        """After a failed step: whether to retry it at the same h because a contact's
        candidate radii held it back (``Term.widens``: a free body's contact, whose
        radii from the last step's motion missed a sudden one, another body striking it);
        its ``begin_step`` widens them for the retry. At most WIDEN times a step."""
        terms = self.potential.system.terms
        held = any(t.widens and t.grows and getattr(t, "held", False) for t in terms)
        if not held or self.widens >= WIDEN:
            self.widens = 0
            return False
        self.widens += 1
        log.info("t = %.6g: step %.3g failed (%s) with nodes held near a body by their "
                 "candidate radii; retrying with wider radii", self.t, h_step, why)  # fmt: skip
        return True

    def refresh(self, h_step: float, why: str) -> bool:
        """After a failed step: whether to retry it at the same h with fresh
        factorisations (it failed with a kept one)."""
        if self.kept is None or self.fresh:
            self.fresh = False
            return False
        self.fresh = True
        self.kept.drop()
        log.info(
            "t = %.6g: step %.3g failed (%s); retrying with fresh factorisations",
            self.t,
            h_step,
            why,
        )
        return True

    def cut(
        self,
        control: StepControl | RestControl | ErrorControl,
        h_step: float,
        why: str,
        newton: NewtonResult | None,
    ) -> None:
        """After a failed step: the next try has half its length; raises ConvergenceError
        (the last accepted state) below the smallest step."""
        again = control.failed(h_step)
        log.info(
            "t = %.6g: step %.3g failed (%s); retrying with %.3g", self.t, h_step, why, control.h
        )
        if not again:
            message = f"dynamic step at t = {self.t:.6g} s failed even with h = {h_step:.3g} s"
            if why.startswith("no convergence in") and self.extend:
                why += (
                    f" (a time step's Newton takes {self.max_iter} iterations, at fixed "
                    f"steps up to {EXTEND * self.max_iter} while its residual falls; a "
                    "solver.max_iter you give is a hard budget: a larger one may let it "
                    "converge)"
                )
            elif why.startswith("no convergence in"):
                why += (
                    f" (solver.max_iter = {self.max_iter} bounds each time step's Newton "
                    "iterations: a larger one may let it converge)"
                )
        elif control.spent():
            assert not isinstance(control, RestControl)  # a run to rest ends by max_steps
            message = control.spent_message(self.t)
        else:
            return
        note = ""
        if self.moving:  # two obstacles closing on the net (catenet/terms/pinch.py): first
            ahead = self.t + max(h_step, control.dt)  # the step it plans, not the cut one
            note = pinch_note(self.potential.system.terms, self.x, self.t, ahead)
        if note:  # (the budget's message already ends "the last failed step")
            step = (
                why if message.endswith("the last failed step") else f"the last failed step: {why}"
            )
            why = f"{note.removeprefix('; ')} ({step})"
        elif newton is not None:  # most of its iterations cut short at one contact: which
            why += newton.contact_note()
        raise ConvergenceError(
            f"{message}: {why}",
            iterations=self.iterations,
            history=newton.history if newton else [],
            state=self.x.copy(),
        )

    def rest_stages(self) -> list[Potential]:
        """The continuation stages of a run to rest after the first (whose potential this
        stepper takes): catenet/solver/relax.py; none where something moves."""
        from catenet.solver.static import _Barriers, stiffness_factors

        fixed = not (self.loads.varies or self.moving or self.follow or self.net.bodies)
        if not fixed:
            return []
        system = self.system
        barriers = _Barriers(tuple(t for t in system.terms if t is not system.stretch))
        factors = stiffness_factors(self.potential)
        law = system.stretch.law
        smooth = slack_strain(self.net, self.x) if law.any_tension_only else 0.0
        first, *rest = rest_stages(self.potential, barriers, factors, smooth)
        self.potential = first
        self.pseudo = True
        return rest

    def no_rest(self, control: RestControl) -> NoReturn:
        """A run to rest that spent its steps: ConvergenceError (the last step's state)."""
        raise ConvergenceError(
            f"not at rest after solver.max_steps = {control.max_steps} time steps "
            f"(pseudo-time t = {self.t:.6g} s): the motion does not die out: give "
            "solver.t_end, more solver.damping or a larger solver.max_steps",
            iterations=self.iterations,
            state=self.x.copy(),
        )

    def accept(
        self, control: StepControl | RestControl | ErrorControl, h_step: float, newton: NewtonResult
    ) -> None:
        """The converged step becomes the state (Eq. 10c for implicit Euler)."""
        self.fresh = False
        self.widens = 0
        loads = self.potential.f_norm
        self.load_peak = max(self.load_peak, loads)  # a history's zero is no load at all
        if SEEN * EPS * self.load_peak < loads < newton.residual:  # what the step leaves
            # is its forces' round-off (a gust's history landed on its end, 1e-14 N of
            # 100 N left by the time's round-off, stopped a run at fixed steps)
            raise ConvergenceError(
                f"the time step of {h_step:.3g} s to t = {self.t + h_step:.6g} s ends with "
                f"a force imbalance of {newton.residual:.3g} N, the round-off of its "
                f"forces, above the loads ({loads:.3g} N): no digit of this answer is "
                f"sure; {deep_contact(self.system.terms, self.x_trial) or _why_roundoff(control)}",
                iterations=self.iterations,
                state=self.x.copy(),
            )
        v = self.scheme.accept(self.x_trial, self.x, self.v, self.free, h_step)
        if self.net.guides is not None:  # round-off kept off the guides (no drift)
            self._on_guides(v)
        if self.watch is not None:  # strikes that fixed steps step over; a weak barrier
            self.watch.step(self.x, self.v, self.x_trial, v, h_step, self.t)
            if self.ledger is not None:  # (what its EnergyError advises first)
                self.ledger.weak = self.watch.strikes.advice()
        if self.ledger is not None:  # judged before the step becomes the state
            self.ledger.step(self, self.x, self.x_trial, v, h_step)
            try:
                self.ledger.check(self.t + h_step)
            except ConvergenceError as exc:
                exc.iterations = self.iterations
                exc.state = self.x.copy()
                raise
        self.v = v
        store_acceleration(self.scheme, self.a_out, self.free)
        self.x[:] = self.x_trial
        self.t = control.advance(self.t, h_step)
        self.steps += 1
        self.residual = newton.residual
        control.accepted()
        if isinstance(control, ErrorControl):
            moved = self.x.reshape(-1)[self.free] - self.x0_free
            control.saw(self.x, moved, self.v.reshape(-1)[self.free], self.m_free)
            control.ahead(self.x, self.v)


def mass_and_damping(net: Net, damping: float) -> tuple[np.ndarray, float | np.ndarray]:
    """The free DOFs' masses and mass-proportional damping (mu damps the net, not a rigid
    body's flight: catenet/terms/body.py)."""
    m_free = np.repeat(net.mass[~net.fixed], 3)
    if net.bodies:
        body = np.repeat(np.flatnonzero(~net.fixed) >= net.n_net, 3)
        return m_free, np.where(body, 0.0, damping)
    return m_free, damping


def store_acceleration(
    scheme: Scheme, out: np.ndarray | None, free: np.ndarray
) -> np.ndarray | None:
    """The scheme's acceleration state into ``out`` (N, 3) on the free DOFs (if both
    exist); returns ``out``."""
    if out is not None and scheme.a is not None:
        out.reshape(-1)[free] = scheme.a
    return out


def at_rest(
    system: System,
    potential: Potential,
    x: np.ndarray,
    v: np.ndarray,
    m_free: np.ndarray,
    h: float,
    rtol: float,
) -> tuple[bool, float, float]:
    """The rest test of dynamic relaxation after a step of length h to (x, v): whether the
    static residual |grad E - f| and the inertial force |M v| / h are both below rtol
    times the load scale (the larger of |f| and |grad E|), the residual's tolerance
    raised to its round-off floor where every DOF's residual is within it (as a static
    solve's: ``Potential.at_floor``; a long stiff chain's rtol is below that floor); the
    residual and the larger of the two over that tolerance (at most 1 at rest)."""
    grad, _ = potential.internal(x)  # (the step's last evaluation's, where at this x)
    r = system.restrict(grad.reshape(-1)) - potential.f_free
    scale = max(potential.f_norm, float(norm(grad.reshape(-1))))
    tol = rtol * scale
    residual = float(norm(r.reshape(-1)))
    inertia = float(norm(m_free * v.reshape(-1)[system.free_dofs])) / h
    if not (math.isfinite(tol) and tol > 0 and math.isfinite(residual + inertia)):
        return False, residual, math.inf  # never at rest against a non-finite tolerance
    level = tol
    moving = inertia > tol and residual <= inertia  # no floor changes the answer: skipped
    if residual > tol and not moving:
        floor = potential.at_floor(x, r, steps=False)
        level = level if floor is None else floor
    ratio = max(residual / level, inertia / tol)
    return (residual <= level and inertia <= tol), residual, ratio


def potential_at(potential: Potential, loads: Loads, net: Net, t: float) -> Potential:
    """The potential with the loads' value at time t (a time history's, else as built),
    weight-like terms (buoyancy) with gravity's factor then."""
    if loads.varies:
        potential.set_force(loads.external_force(net, time=t))
        if loads.gravity_history is not None:
            for term in potential.system.terms:
                if term.weighs:
                    term.set_factor(loads.weight_scale(t))
    return potential


def _along_guides(guides: Guides, v: np.ndarray) -> None:
    """A start's velocities (in place) at the rollers and sliders in their free
    directions, with a warning where a given velocity had a held part."""
    given = v[guides.nodes]
    free = guides.project(given)
    lost = np.linalg.norm(given - free, axis=1)
    if np.any(lost > 1e-9 * (np.linalg.norm(given, axis=1) + 1e-300)):
        k = int(guides.nodes[np.argmax(lost)])
        log.warning(
            "the initial velocity of node %d (and %d more) has a part along the direction "
            "its roller or slider holds: left out (%.3g m/s)",
            k, int(np.count_nonzero(lost > 0)) - 1, float(lost.max()),
        )  # fmt: skip
    v[guides.nodes] = free


def _why_roundoff(control: StepControl | RestControl | ErrorControl) -> str:
    """What a step whose forces' round-off exceeds its loads most likely means: steps
    chosen by accuracy that shrank until a step's inertia (m / h^2) turned the positions'
    round-off into forces beyond the loads (a tolerance tighter than the model allows,
    at a corner of a prescribed motion), or a motion far faster than a step (a body spun
    beyond what dt resolves)."""
    if isinstance(control, ErrorControl):
        return (
            "the steps chosen by accuracy shrank until a step's inertia turned the "
            "positions' round-off into forces beyond the loads (a solver.tolerance tighter "
            "than this model allows, or a motion far faster than the steps: a body spun "
            "beyond them): use a larger solver.tolerance or solver.dt_min, or check the "
            "initial velocities and angular velocities"
        )
    return (
        "a motion far faster than the step (a body spun beyond what dt resolves): use a "
        "smaller solver.dt or check the initial velocities and angular velocities"
    )
