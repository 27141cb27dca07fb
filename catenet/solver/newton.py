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

Convergence: |grad Phi| <= rtol * scale, where scale is the load scale (the larger of |f|
and |internal force|, supports included), or every DOF at its own round-off floor but for a
part within rtol * scale (``Potential.at_floor``: eps of the forces that meet at that DOF,
the strains' EA eps |x| / l0 per edge included, and each term's round-off on its own nodes).
That test is made once the residual is within the global floor (the round-off of all
forces together), or stalls within STALL_FLOOR times it (then allowed STALL_FLOOR times
each DOF's floor). When the floor, not the tolerance, ended the run, one more Newton
step is taken if it lowers the residual.
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

Safeguards (``solve_newton(safeguard=True)``, every time step's solve): once a line search
has cut a step below SAFEGUARD_ALPHA of its length, the rest of the solve takes its steps
from a safer model (``Potential.safeguard``): the tension-only edges slack by less than
``HOLD_REACH`` are held in it as if taut (their axial stiffness, their pull to the rest
length: ``Stretch.hold``), released for the rest of the solve where the model's step
leaves them slack (``Stretch.release``), and a free body's contact blocks enter the
matrix projected to positive semidefinite (``BodyContact.safeguard``). A light net of
stiff cords at a step far above its axial period (a 41 x 41 Dyneema net meeting a box
at 10 ms: inertia 1e-5 of the axial stiffness) otherwise moves the nodes of its slack
edges as if free, far past the edges' lengths, and the line search cuts every such step
to a few percent: one ring of edges taken up per iteration. Phi, its gradient, the line
search and the convergence test stay exact, so the solve reaches the same state (a
model's step that does not descend on Phi is replaced by Phi's own Newton step).
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from catenet.errors import ConvergenceError, Interrupted, SingularSystemError
from catenet.kernels.sparse import dot
from catenet.solver.linesearch import LineSearch, Searched
from catenet.solver.potential import Potential
from catenet.terms import Term

log = logging.getLogger(__name__)

C_MIN = 1e-12  # below this relative regularisation, c is set to 0 (pure Newton)
C_MAX = 1e12
STALL_FLOOR = 10.0  # a residual stuck within this multiple of the floor has converged
SHRINK = 1e-3  # c restarts at this fraction of _c_start after pure Newton stumbles
STAGNATION = 20  # iterations in which neither |grad Phi| nor Phi fell beyond round-off: stop
PROGRESS = 1e-3  # the least relative decrease of the residual that counts as progress
REUSE_RATE = 0.03  # a kept factorisation whose step cuts the residual less is refreshed
REUSE_AHEAD = 2  # ... unless this many more steps at its rate reach the tolerance
SAFEGUARD_ALPHA = 0.5  # a line search cutting a step below this share: safeguards on
EXTEND = 4  # a solve still converging at its budget goes on up to this many times it ...
COURSE = 5  # ... while its best residual of this many last accepted steps is below ...
FALL = 0.03  # ... its best before them by this share at least

_stop: Callable[[], bool] | None = None  # asked before every iteration (see interruptible)


@contextlib.contextmanager
def interruptible(stop: Callable[[], bool] | None) -> Iterator[None]:
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
    safeguarded: bool = False  # whether the safeguards came on (``solve_newton``)
    #: per term, the iterations whose full step would have reached its contact (cut short)
    capped: dict[Term, int] = field(default_factory=dict)

    def contact_note(self) -> str:
        """Where most iterations of an unconverged solve were cut short at one obstacle's
        contact (its barriers of nodes and of edges together): a sentence naming it, its
        activation distance and the key that sets it (a barrier far narrower than the
        motion Newton's steps want is approached a share of the way per iteration), else
        ''. Terms without a key (a continuation's stages, self-contact) give none."""
        if self.converged:
            return ""
        counts: dict[str, tuple[int, float, str]] = {}  # key: (count, dhat, label)
        for term, count in self.capped.items():
            dhat = getattr(term, "dhat", None)
            if term.key and dhat is not None:
                before = counts.get(term.key, (0, 0.0, term.label))
                counts[term.key] = (before[0] + count, max(before[1], dhat), before[2])
        if not counts:
            return ""
        key, (count, dhat, label) = max(counts.items(), key=lambda item: item[1][0])
        if 2 * count < self.iterations:
            return ""
        return (
            f"; {count} of its {self.iterations} Newton iterations were cut short where a full "
            f"step would have reached {label}, whose barrier acts within {dhat:.3g} m "
            f"({key}): Newton's steps then approach it a share of the way at a time. A "
            f"longer distance may let them converge (e.g. {key} = {100.0 * dhat:.3g}, 100x; "
            "it is also the largest gap the contact leaves)"
        )


class Reuse:
    """The factorisation modified Newton keeps across iterations and solves: which
    potential and regularisation c it belongs to and the solver's factorisation count
    when it was made (any other factorisation on the solver makes it stale). ``keep(key)``
    drops it when the key changes (a time step's h: the inertia diagonal changes)."""

    def __init__(self) -> None:
        # (potential, c, the solver's factorisation count) of the kept factorisation
        self._owner: tuple[Potential, float, int] | None = None
        self._key: object = None

    def keep(self, key: object) -> None:
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


def solve_newton(
    potential: Potential,
    x: np.ndarray,
    *,
    rtol: float,
    max_iter: int,
    atol: float | None = None,
    label: str = "newton",
    reuse: Reuse | None = None,
    shifted: bool = False,
    polish: bool = True,
    safeguard: bool = False,
    extend: bool = False,
) -> NewtonResult:
    """Minimises ``potential`` from x (N, 3), updated in place. Never raises for slow
    convergence: the result says whether it converged; a singular system with c > 0 is
    met by raising c, with c = 0 it raises SingularSystemError only if raising c fails.
    ``atol`` replaces rtol * scale by a fixed tolerance [N] (never below the floor).
    ``reuse``: modified Newton with the factorisation it keeps (module docstring).
    ``shifted``: start with the regularisation a rejected first step would bring
    (SHRINK x ``_c_start``), for a start known to be stiff in some directions only.
    ``polish``: where the round-off floor ended the solve, one more Newton step (its
    factorisation) to land below it; a time step that no rest test reads (its
    truncation error far above the floor) goes without (``TimeStepper.run``).
    ``safeguard``: once a line search has cut a step below SAFEGUARD_ALPHA of its
    length, the rest of the solve is safeguarded (``Potential.safeguard``; the module
    docstring; the result's ``safeguarded`` says whether it was).
    ``extend``: at ``max_iter`` iterations a solve still converging goes on
    (``_Newton.on_course``), as a fixed time step of a run to a time does by default."""
    run = _Newton(potential, x, rtol=rtol, atol=atol, max_iter=max_iter, label=label, reuse=reuse)
    run.extend = extend
    try:
        _iterate(run, shifted, safeguard)
    finally:
        if safeguard and potential.safeguarded:
            run.safeguarded = True
            potential.safeguard(False)
    if polish:
        run.polish()
    return run.result()


def _iterate(run: _Newton, shifted: bool, safeguard: bool) -> None:
    """Newton's iterations of ``solve_newton`` until a verdict (``run.reason``)."""
    potential, x = run.potential, run.x
    if shifted:
        run.c = SHRINK * _c_start(potential, run.ev.g)
    while (reason := run.verdict()) is None:
        run.it += 1
        step = run.direction()
        if step is None:  # no regularisation made the matrix regular and the step descend
            return
        dy, slope, kept = step
        # Decrease of Phi that the quadratic model predicts for the full step (the model's
        # Hessian excludes c D): with (J + c D) dy = -g, dy.J.dy = -g.dy - c dy.D.dy.
        predicted = -0.5 * slope + 0.5 * run.c * float(dot(potential.D * dy, dy))
        search = LineSearch(
            potential,
            x,
            dy,
            start=run.ev,
            slope=slope,
            tol=run.tol,
            predicted=predicted,
            y_trial=run.y_trial,
        ).run()
        if safeguard and search.alpha < SAFEGUARD_ALPHA and not potential.safeguarded:
            potential.safeguard(True)
        if search.capped_by is not None:
            run.capped[search.capped_by] = run.capped.get(search.capped_by, 0) + 1
        if search.accepted:
            run.accept(search, kept)
        elif (reason := run.reject(kept)) is not None:
            break
    run.reason = reason


class _Newton:
    """The state of one Newton solve between iterations: the evaluation at x, the
    tolerance, the regularisation c and the counts that judge progress."""

    def __init__(
        self,
        potential: Potential,
        x: np.ndarray,
        *,
        rtol: float,
        atol: float | None,
        max_iter: int,
        label: str,
        reuse: Reuse | None,
    ):
        self.potential = potential
        self.x = x
        self.rtol, self.atol, self.max_iter = rtol, atol, max_iter
        self.label = label
        self.reuse: Reuse | None = reuse
        self.ev = potential.evaluate(x)
        self.gnorm = self.ev.gnorm
        self.tol = max(self.target(), self.ev.floor)
        self.history = [self.gnorm]
        self.c = 0.0  # raised when singular or a step fails
        self.factorizations = 0
        self.reused = 0
        self.stall = 0
        self.good = 0  # consecutive well-predicted full steps
        self.extend = False  # on course at max_iter: go on (``on_course``)
        # the iteration of the last progress (stagnation)
        self.best, self.best_phi, self.moved = self.gnorm, self.ev.phi, 0
        self.it = 0
        self.reason = ""
        self.y_trial = np.empty_like(self.ev.g)
        self.safeguarded = False
        self.capped: dict[Term, int] = {}  # iterations cut short at a term's contact

    def target(self) -> float:
        """The tolerance the loads ask for [N] (the floor aside)."""
        return self.rtol * self.ev.scale if self.atol is None else self.atol

    def at_floor(self, reason: str | None, factor: float = 1.0) -> str | None:
        """Convergence at round-off if every DOF's residual is within its own floor (times
        ``factor``) but for a part within the tolerance the loads ask for
        (``Potential.at_floor``; the tolerance is then that bound), else ``reason``."""
        level = self.potential.at_floor(self.x, self.ev.g, target=self.target(), factor=factor)
        if level is not None:
            self.tol = level
            return "converged (round-off floor)"
        return reason

    def verdict(self) -> str | None:
        """Why the iteration ends before the next step (None: it goes on)."""
        gnorm, floor = self.gnorm, self.ev.floor
        if not math.isfinite(gnorm):
            return "non-finite residual"
        scale = self.ev.scale
        if not (math.isfinite(self.tol) and math.isfinite(scale)):  # never "converged" vs inf
            return f"non-finite tolerance (load scale {scale:.3g} N): the arithmetic overflows"
        if gnorm <= self.target():
            return "converged"
        # Near the global floor, the floor DOF by DOF decides: a stiff term's round-off
        # (a free body's) must not excuse the residual of a cable beside it.
        stuck = self.stall >= 3 and gnorm <= STALL_FLOOR * floor
        if gnorm <= floor or stuck:
            if (reason := self.at_floor(None, STALL_FLOOR if stuck else 1.0)) is not None:
                return reason
        if self.it >= self.max_iter and not (self.extend and self.on_course()):
            return self.at_floor(f"no convergence in {self.it} iterations")
        if _stop is not None and _stop():
            raise Interrupted(
                f"{self.label}: interrupted after {self.it} Newton iterations",
                iterations=self.it,
                history=self.history,
            )
        if self.it - self.moved >= STAGNATION:
            return self.at_floor(
                f"stagnated: neither the residual nor the energy has decreased beyond round-off "
                f"in {STAGNATION} iterations (best residual {self.best:.3e} N, round-off floor "
                f"{floor:.1e} N)"
            )
        return None

    def on_course(self) -> bool:
        """Whether, past its budget (and below EXTEND times it), the solve's best residual
        of its last COURSE accepted steps is FALL below its best before them (the best: a
        minimiser of Phi may raise |grad Phi| on one step): a light net's stiff cords taken
        up at an impact, that a cut would only start again; not a solve that creeps."""
        h = self.history
        if self.it >= EXTEND * self.max_iter or len(h) <= COURSE:
            return False
        return min(h[-COURSE:]) < (1.0 - FALL) * min(h[:-COURSE])

    def direction(self) -> tuple[np.ndarray, float, bool] | None:
        """The step dy, the slope g.dy < 0 and whether it came from a kept factorisation;
        None (with the reason) if no regularisation c <= C_MAX gives a descent direction."""
        potential, g, reuse = self.potential, self.ev.g, self.reuse
        if reuse is not None and reuse.valid(potential, self.c):
            # modified Newton: the kept matrix, if it gives a descent direction
            try:
                dy = potential.solve(-g)
                slope = float(dot(g, dy))
            except SingularSystemError:
                slope = math.nan
            if slope < 0.0:
                self.reused += 1
                return dy, slope, True
            reuse.drop()
        # Newton direction, raising c until the matrix is regular and dy a descent direction.
        while True:
            try:
                potential.factorize(self.x, self.c)
                self.factorizations += 1
                dy = potential.solve(potential.model_rhs(self.x, g))
                slope = float(dot(g, dy))
                if potential.safeguarded:
                    if not slope < 0.0:  # the held edges' pull turned it: Phi's own step
                        dy = potential.solve(-g)
                        slope = float(dot(g, dy))
                    potential.release(self.x, dy)
                if slope < 0.0:
                    if reuse is not None:
                        reuse.mark(potential, self.c)
                    return dy, slope, False
                why = "not a descent direction"
            except SingularSystemError as exc:
                if self.c >= C_MAX:
                    raise
                why = str(exc)
            self.c = max(10.0 * self.c, _c_start(potential, g))
            log.debug("%s: %s; regularisation c -> %.3g", self.label, why, self.c)
            if self.c > C_MAX:
                self.reason = "regularisation failed (" + why + ")"
                return None

    def reject(self, kept: bool) -> str | None:
        """After a step the line search refused (x back at its start): why the iteration
        ends, or None to try again (a fresh matrix, or a larger c)."""
        self.ev = self.potential.evaluate(self.x)
        near = self.gnorm <= STALL_FLOOR * self.ev.floor
        if (reason := self.at_floor(None, STALL_FLOOR if near else 1.0)) is not None:
            return reason
        if kept and self.reuse is not None:  # a fresh matrix before a larger c
            self.reuse.drop()
            return None
        self.c = max(4.0 * self.c, SHRINK * _c_start(self.potential, self.ev.g))
        log.debug("%s: step rejected; regularisation c -> %.3g", self.label, self.c)
        if self.c > C_MAX:
            return self.at_floor("line search failed")
        self.stall += 1
        return None

    def accept(self, search: Searched, kept: bool) -> None:
        """Moves on to the state the line search reached; adapts c (or the kept matrix)."""
        prev = self.gnorm
        ev = search.trial
        assert ev is not None  # the step was accepted
        self.ev = ev
        self.gnorm = gnorm = ev.gnorm
        self.tol = max(self.target(), ev.floor)
        self.history.append(gnorm)
        self.stall = self.stall + 1 if gnorm > 0.5 * prev else 0
        if gnorm < self.best * (1.0 - PROGRESS) and self.best - gnorm > ev.floor:
            self.best, self.moved = gnorm, self.it
        if ev.phi < self.best_phi - ev.phi_tol:
            self.best_phi, self.moved = ev.phi, self.it
        log.debug(
            "%s %3d: |r| = %.3e (tol %.1e)  step %.3g  rho %.2f  c = %.2g",
            self.label,
            self.it,
            gnorm,
            self.tol,
            search.alpha,
            search.rho,
            self.c,
        )
        if kept and self.reuse is not None:  # c stays; a slow step refreshes the matrix
            if gnorm > REUSE_RATE * prev and not _converges_soon(gnorm, prev, self.tol):
                self.reuse.drop()
            return
        self.good = self.good + 1 if (search.alpha >= 1.0 and search.rho > 0.75) else 0
        self.c = _update_regularisation(
            self.c, search.alpha, search.rho, self.good, self.potential, ev.g
        )

    def polish(self) -> None:
        """When the round-off floor, not the tolerance, ended a converged run: one more
        Newton step often lands far below the floor (the iteration was still quadratic)."""
        if not (
            self.reason.startswith("converged")
            and self.gnorm > self.target()
            and math.isfinite(self.gnorm)
        ):
            return
        potential, reuse = self.potential, self.reuse
        count = potential.solver.stats["factorize"]
        better = _polish(potential, self.x, self.ev.g, self.gnorm)
        if reuse is not None and potential.solver.stats["factorize"] > count:
            reuse.mark(potential, 0.0)  # J at a point next to the solution: worth keeping
        if better is not None:
            self.gnorm = better
            self.history.append(better)
            self.it += 1
            self.factorizations += 1

    def result(self) -> NewtonResult:
        converged = (
            self.reason.startswith("converged")
            and math.isfinite(self.gnorm)
            and math.isfinite(self.tol)
        )
        return NewtonResult(
            converged,
            self.it,
            self.gnorm,
            self.tol,
            self.history,
            self.reason,
            self.factorizations,
            self.reused,
            self.safeguarded,
            self.capped,
        )


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
        dy = potential.solve(-g)
    except SingularSystemError:
        return None
    if potential.max_step(x, dy, 2.0) <= 1.0:
        return None  # the full step would touch an obstacle
    xf[free] = y0 + dy
    new = potential.evaluate(x).gnorm
    if math.isfinite(new) and new < gnorm:
        return new
    xf[free] = y0
    return None


def _update_regularisation(
    c: float, alpha: float, rho: float, good: int, potential: Potential, g: np.ndarray
) -> float:
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


def raise_unconverged(
    result: NewtonResult, what: str, state: np.ndarray | None = None, hint: str = ""
) -> None:
    count = "" if "iterations" in result.reason else f" after {result.iterations} Newton iterations"
    raise ConvergenceError(
        f"{what}: {result.reason}{count} (residual {result.residual:.3e} N, tolerance "
        f"{result.tolerance:.1e} N){hint}",
        iterations=result.iterations,
        history=result.history,
        state=state,
    )
