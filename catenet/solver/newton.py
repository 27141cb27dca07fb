"""Newton's method with line search for the potentials of catenet's solvers.

Both solvers minimise a potential of the free DOFs y (supports held at given places):

    Phi(y) = E(x) - f . x + 1/2 sum_d w_d (y_d - a_d)^2

E is the stretching energy, f the external force. The static solver has w = 0; a step of
the paper's implicit Euler (Eqs. 10-13) has w = M (1/h^2 + mu/h) and
a = (M/h^2 (q_k + h v_k) + mu M/h q_k) / w, so that grad Phi is exactly Eq. 10a and the
Jacobian is Eq. 13.

Each iteration solves (J + c D) dy = -grad Phi, J = K + diag(w), D the diagonal of the
axial stiffness. c >= 0 is a Levenberg-Marquardt / pseudo-transient regularisation: it
makes a flat, unstressed net (K singular) solvable. It follows a trust-region rule on the
ratio of actual to predicted decrease of Phi and reaches zero as steps succeed, which
restores Newton's quadratic convergence. The step length comes from a line search on the
slope of Phi along the step (Armijo and curvature conditions): the full step where it
suffices, longer steps while the slope stays steep (a slack net falling freely), a secant
search inside a bracket otherwise. Where differences of Phi fall below round-off the norm
of the gradient is the merit function instead.

Convergence: |grad Phi| <= max(rtol * scale, floor), where scale is the load scale (the
larger of |f| and |internal force|, supports included) and floor the round-off level of
the gradient (which includes the strains' round-off, EA eps |x| / l0 per edge). A residual
that stalls within STALL_FLOOR times the floor is converged as well; when the floor, not
the tolerance, ended the run, one more Newton step is taken if it lowers the residual.
A run in which neither the residual nor Phi falls beyond round-off for STAGNATION
iterations stops at once ("stagnated") instead of spending the rest of max_iter; inside
``interruptible(stop)`` every iteration asks ``stop()`` first and raises Interrupted.

Modified Newton (``reuse=Reuse()``; ``solve_dynamic(reuse=True)``): each iteration solves with
the last factorised matrix, kept across iterations and solves, while it converges: its step must be
a descent direction, accepted by the line search, and cut the residual by REUSE_RATE (or be
on course to reach the tolerance within REUSE_AHEAD more steps at its rate: cheaper than a
new factorisation); else the next iteration factorises afresh (a rejected step is retried
with a fresh matrix before c grows). Kept steps leave c alone. The convergence test is on
the true residual, so the solution is the same; the first solve with each factorisation
checks its backward error, later ones (``LinearSolver.solve``) that they are finite.
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from catenet.errors import ConvergenceError, Interrupted, SingularSystemError
from catenet.kernels.sparse import dot, norm
from catenet.solver.linear import LinearSolver
from catenet.solver.linesearch import line_search
from catenet.solver.system import System
from catenet.terms import ExternalForce, Term

log = logging.getLogger(__name__)

EPS = np.finfo(float).eps
C_MIN = 1e-12  # below this relative regularisation, c is set to 0 (pure Newton)
C_MAX = 1e12
STALL_FLOOR = 10.0  # a residual stuck within this multiple of the floor has converged
FLOOR_SAFETY = 16.0  # a DOF's residual within this many eps of its forces is round-off
SHRINK = 1e-3  # c restarts at this fraction of _c_start after pure Newton stumbles
STAGNATION = 20  # iterations in which neither |grad Phi| nor Phi fell beyond round-off: stop
PROGRESS = 1e-3  # the least relative decrease of the residual that counts as progress
REUSE_RATE = 0.03  # a kept factorisation whose step cuts the residual less is refreshed
REUSE_AHEAD = 2  # ... unless this many more steps at its rate reach the tolerance

_stop: Callable[[], bool] | None = None  # asked before every iteration (see interruptible)


@contextlib.contextmanager
def interruptible(stop: Callable[[], bool] | None):
    """While inside, every Newton iteration first asks ``stop()``; True raises Interrupted
    (a signal handler's flag: a long solve stops within one iteration, not one step)."""
    global _stop
    previous, _stop = _stop, stop
    try:
        yield
    finally:
        _stop = previous


@dataclass
class NewtonResult:
    """Outcome of one Newton solve."""

    converged: bool
    iterations: int
    residual: float  # |grad Phi| at the end [N]
    tolerance: float  # the absolute tolerance it was held to [N]
    history: list[float] = field(default_factory=list)
    reason: str = ""
    factorizations: int = 0
    reused: int = 0  # iterations that solved with a kept factorisation (modified Newton)


class Reuse:
    """The factorisation modified Newton keeps across iterations and solves: which
    potential and regularisation c it belongs to and the solver's factorisation count
    when it was made (any other factorisation on the solver makes it stale). ``keep(key)``
    drops it when the key changes (a time step's h: the inertia diagonal changes)."""

    def __init__(self):
        self._owner = None  # (potential, c, solver's factorisation count)
        self._key = None

    def keep(self, key) -> None:
        if key != self._key:
            self._key = key
            self._owner = None

    def valid(self, potential: Potential, c: float) -> bool:
        own = self._owner
        return (
            own is not None
            and own[0] is potential
            and own[1] == c
            and own[2] == potential.solver.stats["factorize"]
        )

    def mark(self, potential: Potential, c: float) -> None:
        """The solver now holds the matrix of ``potential`` with regularisation c."""
        self._owner = (potential, c, potential.solver.stats["factorize"])

    def drop(self) -> None:
        self._owner = None


class Potential:
    """Phi on the free DOFs of a net: the sum of energy terms (``catenet.terms``), with
    the supports held in place. Evaluates value and gradient, fills the Jacobian.

    ``system`` sums the internal terms (stretching and whatever else the scene names),
    ``force`` (N, 3) is the external force (the linear term -f.x), ``steps`` are the
    terms of a time step (inertia and damping), whose values change from step to step.
    """

    def __init__(
        self,
        system: System,
        solver: LinearSolver,
        force: np.ndarray,
        steps: Sequence[Term] = (),
    ):
        self.system = system
        self.solver = solver
        external = ExternalForce(force)
        self.force = external.force  # (N, 3) external force
        self.f_free = external.flat[system.free_dofs].copy()
        self.f_norm = external.norm
        self.external = external if self.f_norm > 0 else None  # no loads: nothing to compute
        self.steps = tuple(steps)
        self.D = system.stiffness()  # diagonal scale of the regularisation (free DOFs)
        # Terms that bound a step (obstacles: the first contact along it).
        self._limits = [t for t in system.terms if t.bounds_step]
        self._dx = np.zeros_like(self.force) if self._limits else None
        self._g = np.empty(system.n_free)
        self._shift = np.empty(system.n_free)

    def set_force(self, force: np.ndarray) -> None:
        """Replaces the external force (N, 3) in place: a time-varying load's value at a
        time step, without rebuilding the potential (the pattern and solver stay)."""
        external = ExternalForce(force)
        self.force = external.force
        self.f_free = external.flat[self.system.free_dofs].copy()
        self.f_norm = external.norm
        self.external = external if self.f_norm > 0 else None

    def begin_step(
        self, x: np.ndarray, time: float | None = None, start: float | None = None
    ) -> None:
        """Tells every term a new load step (``time`` None) or time step (from ``start``,
        the time of x, to ``time``) starts from the accepted state x (``Term.begin_step``)."""
        for term in (*self.system.terms, *self.steps):
            term.begin_step(x, time, start)

    def with_system(self, system: System) -> Potential:
        """The same loads and step terms on other internal terms of the same pattern."""
        return Potential(system, self.solver, self.force, self.steps)

    def free(self, x: np.ndarray) -> np.ndarray:
        return x.reshape(-1)[self.system.free_dofs]

    def max_step(self, x: np.ndarray, dy: np.ndarray) -> float:
        """The largest multiple of the step dy (free DOFs) from x that keeps every node
        outside every obstacle (inf when there are none)."""
        if not self._limits:
            return math.inf
        self._dx.reshape(-1)[self.system.free_dofs] = dy
        return min(t.max_step(x, self._dx) for t in self._limits)

    def toward(self, x: np.ndarray, target: np.ndarray, share: float = 0.9) -> np.ndarray:
        """``target`` if the straight path of the free nodes from x to it keeps every node
        outside every obstacle, else their point ``share`` of the way to the first contact
        (supports stay where ``target`` puts them)."""
        if not self._limits:
            return target
        dx = target - x
        t = min(o.max_step(x, dx) for o in self._limits)
        if t > 1.0:
            return target
        out = target.copy()
        free = self.system.free.reshape(-1, 3)
        out[free] = x[free] + share * t * dx[free]
        return out

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, float, float, float]:
        """Phi, grad Phi (free DOFs), the load scale, the gradient's round-off floor and
        the round-off level of Phi.

        The load scale is the larger of |f| and |internal force| (supports included).
        The floor adds the round-off of every term: forces of size |f| and |internal|,
        and the strains' (coordinates of size |x| carry an error eps |x|, which each edge
        turns into a force error EA eps |x| / l0 at both of its nodes)."""
        energy, grad = self.system.gradient(x)
        internal = float(norm(grad.reshape(-1)))
        strains, phi_scale = self.system.roundoff(x)
        work = 0.0 if self.external is None else -self.external.energy(x)
        phi = energy - work
        floor = self.f_norm + 2.0 * internal + strains
        phi_scale += abs(work)
        for term in self.steps:
            e = term.gradient(x, grad)
            phi += e
            g_level, e_level = term.roundoff(x, e)
            floor += g_level
            phi_scale += e_level
        g = self._g
        np.subtract(grad.reshape(-1)[self.system.free_dofs], self.f_free, out=g)
        scale = max(self.f_norm, internal)
        floor *= 4.0 * EPS
        phi_scale *= 64.0 * EPS
        return phi, g, scale, floor, phi_scale

    def at_floor(self, x: np.ndarray, g: np.ndarray) -> float | None:
        """The norm of the residual's round-off floor, DOF by DOF, if the residual g (free
        DOFs) at x is within it in every free DOF: FLOOR_SAFETY eps of the forces that
        meet there (the edges' |N| + EA |x| / l0, ``Stretch.node_roundoff``; the other
        terms' and the loads' forces); else None. A state there is converged, and that
        norm is the tolerance it was held to (the caller compares it with the loads)."""
        stretch = self.system.stretch
        free = self.system.free_dofs
        level = np.repeat(stretch.node_roundoff(x), 3)[free]
        _, grad = self.system.gradient(x)
        level += 2.0 * np.abs(grad.reshape(-1)[free]) + np.abs(self.f_free)
        for term in self.steps:  # a time step's inertia
            force = np.zeros_like(x)
            term.gradient(x, force)
            level += 2.0 * np.abs(force.reshape(-1)[free])
        level *= FLOOR_SAFETY * EPS
        return float(np.linalg.norm(level)) if bool(np.all(np.abs(g) <= level)) else None

    def factorize(self, x: np.ndarray, c: float) -> None:
        """Fills J + c D at x and factorises it."""
        shift = np.multiply(c, self.D, out=self._shift) if c > 0 else None
        data = self.system.hessian(x, shift, self.steps)
        # Cholesky while no non-convex term (an obstacle out of reach) contributes.
        self.solver.factorize(data, definite=self.system.convex)


def solve(
    potential: Potential,
    x: np.ndarray,
    *,
    rtol: float,
    max_iter: int,
    atol: float | None = None,
    label: str = "newton",
    reuse: Reuse | None = None,
    shifted: bool = False,
) -> NewtonResult:
    """Minimises ``potential`` from x (N, 3), updated in place. Never raises for slow
    convergence: the result says whether it converged; a singular system with c > 0 is
    met by raising c, with c = 0 it raises SingularSystemError only if raising c fails.
    ``atol`` replaces rtol * scale by a fixed tolerance [N] (never below the floor).
    ``reuse``: modified Newton with the factorisation it keeps (module docstring).
    ``shifted``: start with the regularisation a rejected first step would bring
    (SHRINK x ``_c_start``), for a start known to be stiff in some directions only."""
    free = potential.system.free_dofs
    xf = x.reshape(-1)
    phi, g, scale, floor, phi_tol = potential.evaluate(x)
    gnorm = float(norm(g.reshape(-1)))
    tol = max(rtol * scale if atol is None else atol, floor)
    history = [gnorm]
    c = SHRINK * _c_start(potential, g) if shifted else 0.0  # raised when singular or a step fails
    factorizations = 0
    reused = 0
    stall = 0
    good = 0  # consecutive well-predicted full steps
    best, best_phi, moved = gnorm, phi, 0  # the iteration of the last progress: stagnation
    it = 0
    reason = ""
    y_trial = np.empty_like(g)
    while True:
        if not math.isfinite(gnorm):
            reason = "non-finite residual"
            break
        if not (math.isfinite(tol) and math.isfinite(scale)):  # never "converged" against inf
            reason = f"non-finite tolerance (load scale {scale:.3g} N): the arithmetic overflows"
            break
        if gnorm <= tol:  # which criterion held: the tolerance, or the floor above it
            target = rtol * scale if atol is None else atol
            reason = "converged" if gnorm <= target else "converged (round-off floor)"
            break
        if stall >= 3 and gnorm <= STALL_FLOOR * floor:
            reason, tol = "converged (round-off floor)", max(tol, STALL_FLOOR * floor)
            break
        if it >= max_iter:
            reason = f"no convergence in {max_iter} iterations"
            if (level := potential.at_floor(x, g)) is not None:
                reason, tol = "converged (round-off floor)", max(tol, level)
            break
        if _stop is not None and _stop():
            raise Interrupted(
                f"{label}: interrupted after {it} Newton iterations", iterations=it, history=history
            )
        if it - moved >= STAGNATION:
            if (level := potential.at_floor(x, g)) is not None:
                reason, tol = "converged (round-off floor)", max(tol, level)
                break
            reason = (
                f"stagnated: neither the residual nor the energy has decreased beyond round-off "
                f"in {STAGNATION} iterations (best residual {best:.3e} N, round-off floor "
                f"{floor:.1e} N)"
            )
            break
        it += 1
        kept = reuse is not None and reuse.valid(potential, c)
        if kept:  # modified Newton: the kept matrix, if it gives a descent direction
            try:
                dy = potential.solver.solve(-g)
                slope = float(dot(g, dy))
            except SingularSystemError:
                slope = math.nan
            if not slope < 0.0:
                kept = False
                reuse.drop()
            else:
                reused += 1
        # Newton direction, raising c until the matrix is regular and dy a descent direction.
        while not kept:
            try:
                potential.factorize(x, c)
                factorizations += 1
                dy = potential.solver.solve(-g)
                slope = float(dot(g, dy))
                if slope < 0.0:
                    if reuse is not None:
                        reuse.mark(potential, c)
                    break
                why = "not a descent direction"
            except SingularSystemError as exc:
                if c >= C_MAX:
                    raise
                why = str(exc)
            c = max(10.0 * c, _c_start(potential, g))
            log.debug("%s: %s; regularisation c -> %.3g", label, why, c)
            if c > C_MAX:
                reason = "regularisation failed (" + why + ")"
                return NewtonResult(False, it, gnorm, tol, history, reason, factorizations, reused)
        # Decrease of Phi that the quadratic model predicts for the full step (the model's
        # Hessian excludes c D): with (J + c D) dy = -g, dy.J.dy = -g.dy - c dy.D.dy.
        predicted = -0.5 * slope + 0.5 * c * float(dot(potential.D * dy, dy))
        y0 = xf[free].copy()
        alpha, accepted, rho, trial = line_search(
            potential, x, y0, dy, phi, slope, gnorm, phi_tol, tol, predicted, y_trial
        )
        if not accepted:
            xf[free] = y0
            phi, g, scale, floor, phi_tol = potential.evaluate(x)
            if gnorm <= STALL_FLOOR * floor:
                reason, tol = "converged (round-off floor)", max(tol, STALL_FLOOR * floor)
                break
            if (level := potential.at_floor(x, g)) is not None:
                reason, tol = "converged (round-off floor)", max(tol, level)
                break
            if kept:  # a fresh matrix before a larger c
                reuse.drop()
                continue
            c = max(4.0 * c, SHRINK * _c_start(potential, g))
            log.debug("%s: step rejected; regularisation c -> %.3g", label, c)
            if c > C_MAX:
                reason = "line search failed"
                if (level := potential.at_floor(x, g)) is not None:
                    reason, tol = "converged (round-off floor)", max(tol, level)
                break
            stall += 1
            continue
        prev = gnorm
        phi, g, scale, floor, phi_tol, gnorm = trial
        tol = max(rtol * scale if atol is None else atol, floor)
        history.append(gnorm)
        stall = stall + 1 if gnorm > 0.5 * prev else 0
        if gnorm < best * (1.0 - PROGRESS) and best - gnorm > floor:
            best, moved = gnorm, it
        if phi < best_phi - phi_tol:
            best_phi, moved = phi, it
        log.debug(
            "%s %3d: |r| = %.3e (tol %.1e)  step %.3g  rho %.2f  c = %.2g",
            label,
            it,
            gnorm,
            tol,
            alpha,
            rho,
            c,
        )
        if kept:  # c stays; a slow step refreshes the matrix
            if gnorm > REUSE_RATE * prev and not _converges_soon(gnorm, prev, tol):
                reuse.drop()
            continue
        good = good + 1 if (alpha >= 1.0 and rho > 0.75) else 0
        c = _update_regularisation(c, alpha, rho, good, potential, g)
    converged = reason.startswith("converged") and math.isfinite(gnorm) and math.isfinite(tol)
    target = rtol * scale if atol is None else atol
    if converged and gnorm > target and math.isfinite(gnorm):
        # The round-off floor, not the tolerance, ended the run: one more Newton step
        # often lands far below the floor (the iteration was still quadratic).
        count = potential.solver.stats["factorize"]
        better = _polish(potential, x, g, gnorm)
        if reuse is not None and potential.solver.stats["factorize"] > count:
            reuse.mark(potential, 0.0)  # J at a point next to the solution: worth keeping
        if better is not None:
            gnorm = better
            history.append(gnorm)
            it += 1
            factorizations += 1
    return NewtonResult(converged, it, gnorm, tol, history, reason, factorizations, reused)


def _converges_soon(gnorm: float, prev: float, tol: float) -> bool:
    """Whether REUSE_AHEAD more steps that cut the residual as the last did (from prev to
    gnorm, by less than half) reach tol: cheaper than a new factorisation."""
    rate = gnorm / prev
    return rate < 0.5 and gnorm * rate**REUSE_AHEAD <= tol


def _polish(potential: Potential, x: np.ndarray, g: np.ndarray, gnorm: float) -> float | None:
    """One unregularised Newton step, kept only if it lowers the residual norm."""
    free = potential.system.free_dofs
    xf = x.reshape(-1)
    y0 = xf[free].copy()
    try:
        potential.factorize(x, 0.0)
        dy = potential.solver.solve(-g)
    except SingularSystemError:
        return None
    if potential.max_step(x, dy) <= 1.0:
        return None  # the full step would touch an obstacle
    xf[free] = y0 + dy
    g_new = potential.evaluate(x)[1]
    new = float(norm(g_new.reshape(-1)))
    if math.isfinite(new) and new < gnorm:
        return new
    xf[free] = y0
    return None


def _update_regularisation(c, alpha, rho, good, potential, g) -> float:
    """Trust-region rule: well-predicted full steps (rho near 1) let c shrink, by 2, 4,
    8, ... for a run of them; a poorly predicted or shortened step makes it grow; a
    lengthened one shrinks it."""
    if alpha > 1.0:
        c = c / (2.0 * alpha)
        return 0.0 if c < C_MIN else c
    if alpha < 1.0:
        return max(4.0 * c, SHRINK * _c_start(potential, g)) if c == 0.0 else 4.0 * c
    if rho > 0.75:
        c = c / 2.0 ** min(good, 6)
        return 0.0 if c < C_MIN else c
    if rho < 0.25:
        return max(2.0 * c, SHRINK * _c_start(potential, g)) if c == 0.0 else 2.0 * c
    return c


def _c_start(potential: Potential, g: np.ndarray) -> float:
    """A regularisation under which the first step moves a node by about a tenth of its
    shortest edge: c D dy ~ g."""
    net = potential.system.net
    l_min = float(np.min(net.rest_length))
    per_dof = np.abs(g) / (potential.D * 0.1 * l_min)
    return float(min(max(np.max(per_dof, initial=0.0), C_MIN * 10), C_MAX))


def raise_unconverged(result: NewtonResult, what: str, state=None, hint: str = "") -> None:
    count = "" if "iterations" in result.reason else f" after {result.iterations} Newton iterations"
    raise ConvergenceError(
        f"{what}: {result.reason}{count} (residual {result.residual:.3e} N, tolerance "
        f"{result.tolerance:.1e} N){hint}",
        iterations=result.iterations,
        history=result.history,
        state=state,
    )
