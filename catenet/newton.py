"""Newton's method with line search for the potentials of catenet's solvers.

Both solvers minimise a potential of the free DOFs y (supports held at given places):

    Phi(y) = E(x) - f . x + 1/2 sum_d w_d (y_d - a_d)^2

E is the stretching energy, f the external force. The static solver has w = 0; a step of
the paper's implicit Euler (Eqs. 10-13) has w = M (1/h^2 + mu/h) and
a = (M/h^2 (q_k + h v_k) + mu M/h q_k) / w, so that grad Phi is exactly Eq. 10a and the
Jacobian is Eq. 13.

Each iteration solves (J + c D) dy = -grad Phi, J = K + diag(w), D the diagonal of the
axial stiffness. c >= 0 is a Levenberg-Marquardt / pseudo-transient regularisation: it
makes a flat, unstressed net (K singular) solvable and shrinks to zero as steps succeed,
which restores Newton's quadratic convergence. The step length comes from a backtracking
(Armijo) line search on Phi; where differences of Phi fall below round-off the norm of the
gradient serves as the merit function instead.

Convergence: |grad Phi| <= max(rtol * scale, floor), where scale is the load scale (the
larger of |f| and |internal force|, supports included) and floor the round-off level of
the gradient. A residual that stalls near the floor is converged as well.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from catenet.assembly import System
from catenet.errors import ConvergenceError, SingularSystemError
from catenet.linsolve import LinearSolver

log = logging.getLogger(__name__)

EPS = np.finfo(float).eps
ARMIJO = 1e-4
MAX_HALVINGS = 30
C_MIN = 1e-12  # below this relative regularisation, c is set to 0 (pure Newton)
C_MAX = 1e12


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


class Potential:
    """Phi on the free DOFs of a net; evaluates value and gradient, fills the Jacobian."""

    def __init__(self, system: System, solver: LinearSolver, force: np.ndarray):
        self.system = system
        self.solver = solver
        self.force = force  # (N, 3) external force
        self.f_free = force.reshape(-1)[system.free_dofs].copy()
        self.f_norm = float(np.linalg.norm(force))
        self.w: np.ndarray | None = None  # inertia weights on the free DOFs
        self.a: np.ndarray | None = None
        self.D = np.repeat(system.net.axial_stiffness[~system.net.fixed], 3)
        # Round-off of the strains: coordinates of size |x| carry an error eps |x|, which
        # each edge turns into a force error EA eps |x| / l0 at both of its nodes.
        net = system.net
        self._k_norm = float(np.sqrt(2.0 * np.sum((net.EA / net.rest_length) ** 2)))
        self._g = np.empty(system.n_free)
        self._shift = np.empty(system.n_free)

    def set_inertia(self, w: np.ndarray | None, a: np.ndarray | None) -> None:
        self.w, self.a = w, a

    def free(self, x: np.ndarray) -> np.ndarray:
        return x.reshape(-1)[self.system.free_dofs]

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, float, float, float]:
        """Phi, grad Phi (free DOFs), the load scale, the gradient's round-off floor and
        the round-off level of Phi."""
        energy, grad = self.system.gradient(x)
        work = float(np.dot(self.force.reshape(-1), x.reshape(-1)))
        y = self.free(x)
        g = self._g
        np.subtract(grad.reshape(-1)[self.system.free_dofs], self.f_free, out=g)
        phi = energy - work
        internal = float(np.linalg.norm(grad))
        scale = max(self.f_norm, internal)
        floor = self.f_norm + 2.0 * internal + self._k_norm * float(np.max(np.abs(x)))
        phi_scale = abs(energy) + abs(work)
        if self.w is not None:
            r = y - self.a
            wr = self.w * r
            g += wr
            phi += 0.5 * float(np.dot(wr, r))
            floor += float(np.linalg.norm(self.w * (np.abs(y) + np.abs(self.a))))
            phi_scale += float(np.dot(self.w, y * y + self.a * self.a))
        floor *= 4.0 * EPS
        phi_scale *= 64.0 * EPS
        return phi, g, scale, floor, phi_scale

    def factorize(self, x: np.ndarray, c: float) -> None:
        """Fills J + c D at x and factorises it."""
        shift = self._shift
        if self.w is not None:
            np.multiply(c, self.D, out=shift)
            shift += self.w
        else:
            np.multiply(c, self.D, out=shift)
        data = self.system.hessian(x, shift if (c > 0 or self.w is not None) else None)
        self.solver.factorize(data)


def solve(
    potential: Potential,
    x: np.ndarray,
    *,
    rtol: float,
    max_iter: int,
    c0: float = 0.0,
    label: str = "newton",
) -> NewtonResult:
    """Minimises ``potential`` from x (N, 3), updated in place. Never raises for slow
    convergence: the result says whether it converged; a singular system with c > 0 is
    met by raising c, with c = 0 it raises SingularSystemError only if raising c fails."""
    free = potential.system.free_dofs
    xf = x.reshape(-1)
    phi, g, scale, floor, phi_tol = potential.evaluate(x)
    gnorm = float(np.linalg.norm(g))
    tol = max(rtol * scale, floor)
    history = [gnorm]
    c = c0
    factorizations = 0
    stall = 0
    it = 0
    reason = ""
    y_trial = np.empty_like(g)
    while True:
        if not math.isfinite(gnorm):
            reason = "non-finite residual"
            break
        if gnorm <= tol:
            reason = "converged"
            break
        if stall >= 3 and gnorm <= 1e3 * floor:
            reason = "converged (round-off floor)"
            break
        if it >= max_iter:
            reason = f"no convergence in {max_iter} iterations"
            break
        it += 1
        # Newton direction, raising c until the matrix is regular and dy a descent direction.
        while True:
            try:
                potential.factorize(x, c)
                factorizations += 1
                dy = potential.solver.solve(-g)
                slope = float(np.dot(g, dy))
                if slope < 0.0:
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
                return NewtonResult(False, it, gnorm, tol, history, reason, factorizations)
        # Backtracking line search on Phi (or on |grad Phi| below Phi's round-off).
        y0 = xf[free].copy()
        alpha = 1.0
        accepted = False
        for _ in range(MAX_HALVINGS):
            np.add(y0, alpha * dy, out=y_trial)
            xf[free] = y_trial
            phi_t, g_t, scale_t, floor_t, phi_tol_t = potential.evaluate(x)
            gnorm_t = float(np.linalg.norm(g_t))
            if math.isfinite(phi_t) and math.isfinite(gnorm_t):
                if abs(phi_t - phi) > phi_tol:
                    accepted = phi_t <= phi + ARMIJO * alpha * slope
                else:
                    accepted = gnorm_t <= (1.0 - ARMIJO * alpha) * gnorm or gnorm_t <= tol
            if accepted:
                break
            alpha *= 0.5
        if not accepted:
            xf[free] = y0
            phi, g, scale, floor, phi_tol = potential.evaluate(x)
            if gnorm <= 1e3 * floor:
                reason = "converged (round-off floor)"
                break
            c = max(10.0 * c, _c_start(potential, g))
            log.debug("%s: line search failed; regularisation c -> %.3g", label, c)
            if c > C_MAX:
                reason = "line search failed"
                break
            stall += 1
            continue
        prev = gnorm
        phi, g, scale, floor, phi_tol, gnorm = phi_t, g_t, scale_t, floor_t, phi_tol_t, gnorm_t
        tol = max(rtol * scale, floor)
        history.append(gnorm)
        stall = stall + 1 if gnorm > 0.5 * prev else 0
        log.debug(
            "%s %3d: |r| = %.3e (tol %.1e)  step %.3g  c = %.2g", label, it, gnorm, tol, alpha, c
        )
        # Regularisation update: full steps shrink it, cut steps grow it.
        if alpha == 1.0:
            c = 0.0 if c * 0.1 < C_MIN else c * 0.1
        elif alpha < 0.25:
            c = max(4.0 * c, _c_start(potential, g) if c == 0.0 else 0.0)
    converged = reason.startswith("converged")
    return NewtonResult(converged, it, gnorm, tol, history, reason, factorizations)


def _c_start(potential: Potential, g: np.ndarray) -> float:
    """A regularisation under which the first step moves a node by about a tenth of its
    shortest edge: c D dy ~ g."""
    net = potential.system.net
    l_min = float(np.min(net.rest_length))
    per_dof = np.abs(g) / (potential.D * 0.1 * l_min)
    return float(min(max(np.max(per_dof, initial=0.0), C_MIN * 10), C_MAX))


def raise_unconverged(result: NewtonResult, what: str, state=None) -> None:
    raise ConvergenceError(
        f"{what}: {result.reason} after {result.iterations} Newton iterations "
        f"(residual {result.residual:.3e} N, tolerance {result.tolerance:.1e} N)",
        iterations=result.iterations,
        history=result.history,
        state=state,
    )
