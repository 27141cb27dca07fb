"""The time integrators of dynamic runs, each a step of one incremental potential.

Every scheme turns a time step from (x_n, v_n) over h into the minimisation of

    Phi(x) = 1/2 sum_d w_d (x_d - a_d)^2 + E(x) - f(t_{n+1}) . x

over the free DOFs (``terms.Inertia`` holds w and a), so that the same Newton iteration,
line search, step halving, obstacle cap and predictor cut serve every scheme. A scheme
says w and a (``weights``), where Newton starts (``predict``) and the new velocities
from the solution (``accept``).

``implicit_euler`` (the default, the paper's Eqs. 10-13): w = M (1/h^2 + mu/h),
v_{n+1} = (x_{n+1} - x_n)/h. First order; it damps every mode numerically, by a ratio
of about h omega / 2 of critical (Fig. A.9's runs at dt = 0.01 s settle in about the
same time whatever mu).

``newmark``: Newmark's method in the Bossak (WBZ-alpha) form of the generalized-alpha
family (Wood, Bossak & Zienkiewicz 1980; Chung & Hulbert 1993 with alpha_f = 0):

    M ((1 - alpha_m) a_{n+1} + alpha_m a_n) + mu M v_{n+1} + grad E(x_{n+1}) = f(t_{n+1})
    x_{n+1} = x_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})
    v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})

with alpha_m = (rho_inf - 1)/(rho_inf + 1), gamma = 1/2 - alpha_m,
beta = (1 - alpha_m)^2 / 4. It is second order (damped or not), unconditionally stable
for linear systems, and ``rho_inf`` (solver.rho_inf, in [0, 1]) is its spectral radius at
h omega -> infinity: rho_inf = 1 is the plain average-acceleration (trapezoidal) rule,
which conserves the energy of a linear system and damps nothing; below 1 the modes that
the step cannot resolve (the axial modes of a cable net, h omega ~ 10-100 at the paper's
dt) lose a factor of about rho_inf per step while the resolved ones keep their amplitude
to O((h omega)^3) per period. Why this form:

- Eliminating a_{n+1} and v_{n+1} leaves the equation of motion as the gradient of the
  incremental potential above with w = M ((1 - alpha_m)/(beta h^2) + mu gamma/(beta h)):
  the stretching, contact and loads are evaluated at x_{n+1} itself (alpha_f = 0), so an
  obstacle's barrier and its line-search cap keep every accepted state, not an
  intermediate point, outside it. HHT-alpha and the full generalized-alpha method put the
  internal forces at a mean of x_n and x_{n+1}, and the state x_{n+1} would be an
  extrapolation past the point the barrier guards.
- The mass-proportional damping mu M v_{n+1} enters with the same Newmark velocity, so
  the damped scheme is second order too (tests/solver/test_integrators.py checks the order).
- Plain average acceleration (rho_inf = 1) is energy conserving only for linear systems:
  on the paper's tension-only net (a kink in the stiffness at zero strain, axial modes
  far beyond 1/h) its undamped high modes ring for ever, since mass-proportional
  damping gives mode omega only the ratio mu / (2 omega), and the net never comes to
  rest. High-frequency dissipation removes them in a few dozen steps.
- The default rho_inf = 0.8 is measured, not guessed: the paper's n = 10 net relaxed
  with mu = 1 comes to rest at every step from 0.01 s to 1 s with rho_inf <= 0.8, while
  with 0.9 it falls into a limit cycle (slack and taut edges trading energy, about
  0.13 m from equilibrium, for ever) once the lowest mode is unresolved (h = 0.1 s,
  h omega_1 = 4). At h omega = 0.42 (the damping study's lowest mode at dt = 0.01 s) it
  damps by 0.11 % of critical against implicit Euler's 20 %. Where the lowest modes are
  well resolved, rho_inf = 0.9 to 1 damps them less still (configs/dynamics/).

``bdf2``: the two-step backward differentiation formula on variable steps (``BDF2``):
second order, damped or not, and L-stable, so that what the step cannot resolve (axial
modes, a barrier's stiffness) is damped out as implicit Euler damps it while the resolved
motion keeps its energy to O((h omega)^3) per period. It is the scheme for contact and
bodies: on the drop of benchmarks/peers/mujoco_drop.toml it throws the box back with the
fine-step momentum to 1 % at 10 ms steps (implicit Euler: 47 % short), and on the
capture scene it only loses energy (8.6 % in 1 s), where newmark above rho_inf 0.25
creates it.

In contact keep rho_inf <= 0.5 (a case file with contact refuses newmark:
``catenet.case.timing.newmark_refused``): at 0.8 a box or ball dropped onto a net leaves
it faster than it came and the rebound does not converge with h; at 0.5 it does
(docs/howto/dynamic-runs.md). Likely mechanism: the barrier is a mode far beyond 1/h
that a_n carries from step to step, losing only a factor rho_inf per step, and the one-
sided barrier pushes back on each swing toward the obstacle and lets the swings away go.

The scheme's acceleration a_n is part of its state. A run starts with the physical
acceleration M^-1 (f - grad E - mu M v); with rho_inf < 1 later a_n are filtered, so a
newmark run's file stores them (/trajectory/a, /result/a) and a restart goes on from
them, repeating the uninterrupted run to round-off. A file without them restarts from
the physical acceleration (the scheme's own at rho_inf = 1; else a transient of the
size of the discretisation error).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

import numpy as np

from catenet.errors import ConfigError

if TYPE_CHECKING:
    from catenet.solver.potential import Potential

INTEGRATORS = ("implicit_euler", "newmark", "bdf2")
RHO_INF = 0.8  # solver.rho_inf's default (module docstring)


class Scheme(Protocol):
    """A time integrator as the stepper (catenet/solver/stepper.py) uses it: ``a`` its
    acceleration state on the free DOFs (None: it has none); ``damping`` is mu, one
    number or per free DOF."""

    name: str
    order: int
    step_rtol: float

    @property
    def a(self) -> np.ndarray | None: ...

    def begin(
        self,
        potential: Potential,
        x: np.ndarray,
        v: np.ndarray,
        m_free: np.ndarray,
        damping: float | np.ndarray,
        a0: np.ndarray | None = None,
    ) -> None: ...

    def predict(self, x_trial: np.ndarray, v: np.ndarray, free: np.ndarray, h: float) -> None: ...

    def weights(
        self,
        m_free: np.ndarray,
        y_k: np.ndarray,
        v_k: np.ndarray,
        h: float,
        damping: float | np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]: ...

    def motion(
        self, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[float, np.ndarray, float, np.ndarray]: ...

    def held(
        self, x_end: np.ndarray, x: np.ndarray, v: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray]: ...

    def corner(self) -> None: ...

    def accept(
        self, x_new: np.ndarray, x: np.ndarray, v: np.ndarray, free: np.ndarray, h: float
    ) -> np.ndarray: ...


class ImplicitEuler:
    """The paper's backward Euler (Eqs. 10-13); its state is (x, v)."""

    name = "implicit_euler"
    order = 1
    step_rtol = 1.0  # Newton's tolerance per step, in units of the run's rtol
    a = None  # no acceleration state

    def begin(
        self,
        potential: Potential,
        x: np.ndarray,
        v: np.ndarray,
        m_free: np.ndarray,
        damping: float | np.ndarray,
        a0: np.ndarray | None = None,
    ) -> None:
        """Nothing to derive at the start of a run (no last step)."""
        self._prev = None

    def predict(self, x_trial: np.ndarray, v: np.ndarray, free: np.ndarray, h: float) -> None:
        """Newton's start (Eq. 11): x_trial (a copy of x_n) += h v_n on the free DOFs."""
        x_trial.reshape(-1)[free] += h * v.reshape(-1)[free]

    def weights(
        self,
        m_free: np.ndarray,
        y_k: np.ndarray,
        v_k: np.ndarray,
        h: float,
        damping: float | np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """w and a of the step's inertia term (Eq. 10a as a gradient)."""
        self.b = h
        w = m_free * (1.0 / h**2 + damping / h)
        a = (m_free / h**2 * (y_k + h * v_k) + damping * m_free / h * y_k) / w
        return w, a

    def motion(
        self, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[float, np.ndarray, float, np.ndarray]:
        """The step's velocity k (y - c) and acceleration k_a (y - c_a) as affine maps of
        its free DOFs y: (k, c, k_a, c_a) (after ``weights``; water's drag and added
        mass, catenet/terms/water.py)."""
        return 1.0 / h, y_k, 1.0 / h**2, y_k + h * v_k

    def held(
        self, x_end: np.ndarray, x: np.ndarray, v: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The velocity and acceleration at the step's end of DOFs on a prescribed path
        (the supports: at x_end there, (x, v) at the start) by the scheme's own formula
        (``_stepped``): a support and the free node beside it moving as one have no
        relative velocity (an edge's dashpot, catenet/terms/axial.py)."""
        return _stepped(x_end, x, v, h)

    def corner(self) -> None:
        """A corner of a prescribed motion at the state's time (``BDF2.corner``): nothing
        to restart (its supports' velocity is the step's own)."""

    keep = False  # keep the last state for ``estimate`` (steps chosen by accuracy)
    _prev: tuple[np.ndarray, np.ndarray, float] | None = None  # y, v, h of the last step
    b = 0.0  # the step's b: v_{n+1} = (x_{n+1} - x_n) / b (``weights``)

    def velocities(
        self, x_new: np.ndarray, x: np.ndarray, v: np.ndarray, free: np.ndarray, h: float
    ) -> np.ndarray:
        """The velocities at the end of the step from x to x_new (Eq. 10c), nothing kept."""
        v_new: np.ndarray = (x_new - x) / h
        return v_new

    def accept(
        self, x_new: np.ndarray, x: np.ndarray, v: np.ndarray, free: np.ndarray, h: float
    ) -> np.ndarray:
        """The velocities of the accepted step (Eq. 10c)."""
        if self.keep:
            self._prev = (x.reshape(-1)[free].copy(), v.reshape(-1)[free].copy(), float(h))
        return self.velocities(x_new, x, v, free, h)

    def estimate(
        self, y_new: np.ndarray, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The local error of the step of ``h`` from (y_k, v_k) to y_new (free DOFs), in x
        and in v: -R / (P - R) times the difference between the step's solution and the
        line through the last two states extrapolated to t + h (R = -h^2/2 the residual
        of the scheme's formula on y = t^2/2, P = h (h + h1) / 2 the line's error there:
        the solution is off by -R y'', the line by -P y''); None on the first step."""
        if self._prev is None:
            return None
        y1, v1, h1 = self._prev
        v_new = (y_new - y_k) / h
        share = h / (2.0 * h + h1)  # -R / (P - R)
        ex = share * (y_new - (y_k + (h / h1) * (y_k - y1)))
        ev = share * (v_new - (v_k + (h / h1) * (v_k - v1)))
        return ex, ev


class Newmark:
    """Newmark's method with Bossak's high-frequency dissipation (module docstring); its
    state is (x, v, a), a on the free DOFs."""

    name = "newmark"
    order = 2
    # Each step's Newton leaves a force error up to its tolerance times the load scale. A
    # scheme that damps nothing itself lets these errors add up where the physical
    # damping is light (mu h = 1e-3 per step): at rtol they hold the inertial force of a
    # net at rest near the rest test's own tolerance (rtol), so the run never stops. Steps
    # are solved 100 times tighter than the rest test asks (one more Newton iteration).
    step_rtol = 0.01

    def __init__(self, rho_inf: float = RHO_INF):
        if not (isinstance(rho_inf, (int, float)) and math.isfinite(rho_inf)):
            raise ConfigError(f"solver.rho_inf = {rho_inf!r}: must be a number in [0, 1]")
        if not 0.0 <= rho_inf <= 1.0:
            raise ConfigError(f"solver.rho_inf = {rho_inf!r}: must be in [0, 1]")
        self.rho_inf = float(rho_inf)
        self.alpha_m = (self.rho_inf - 1.0) / (self.rho_inf + 1.0)
        self.gamma = 0.5 - self.alpha_m
        self.beta = 0.25 * (1.0 - self.alpha_m) ** 2
        self.a: np.ndarray | None = None  # the scheme's acceleration, free DOFs
        self._p: np.ndarray | None = None  # this step's x_n + h v_n + h^2 (1/2 - beta) a_n

    def begin(
        self,
        potential: Potential,
        x: np.ndarray,
        v: np.ndarray,
        m_free: np.ndarray,
        damping: float | np.ndarray,
        a0: np.ndarray | None = None,
    ) -> None:
        """The acceleration state at the start: ``a0`` (free DOFs, a restart's stored
        state), else the physical acceleration M^-1 (f - grad E - mu M v) (M with the
        water's added mass, ``Term.mass_blocks``)."""
        if a0 is not None:
            self.a = np.array(a0, dtype=np.float64)
            return
        system = potential.system
        _, grad = system.gradient(x)
        force = potential.f_free - system.restrict(grad.reshape(-1))
        media = [t for t in system.terms if t.medium]  # water: its added mass moves too
        if not media:
            self.a = force / m_free - damping * v.reshape(-1)[system.free_dofs]
            return
        free = ~system.net.fixed
        blocks = sum(t.mass_blocks()[free] for t in media) + np.einsum(
            "n,ij->nij", m_free[::3], np.eye(3)
        )
        a = np.linalg.solve(blocks, force.reshape(-1, 3)[..., None])[..., 0].reshape(-1)
        self.a = a - damping * v.reshape(-1)[system.free_dofs]

    @property
    def _a(self) -> np.ndarray:
        if self.a is None:
            raise RuntimeError("Newmark: begin() sets the acceleration state first")
        return self.a

    def predict(self, x_trial: np.ndarray, v: np.ndarray, free: np.ndarray, h: float) -> None:
        """Newton's start: x_n + h v_n + h^2/2 a_n (constant acceleration over the step)."""
        x_trial.reshape(-1)[free] += h * v.reshape(-1)[free] + (0.5 * h * h) * self._a

    def weights(
        self,
        m_free: np.ndarray,
        y_k: np.ndarray,
        v_k: np.ndarray,
        h: float,
        damping: float | np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """w and a of the step's inertia term: the equation of motion above with
        a_{n+1} = (x - p)/(beta h^2), p = x_n + h v_n + h^2 (1/2 - beta) a_n."""
        a_n, beta, gamma, am = self._a, self.beta, self.gamma, self.alpha_m
        p = y_k + h * v_k + (h * h * (0.5 - beta)) * a_n
        self._p = p
        w = m_free * ((1.0 - am) / (beta * h * h) + damping * gamma / (beta * h))
        rest = m_free * (am * a_n + damping * (v_k + h * (1.0 - gamma) * a_n))
        return w, p - rest / w

    def motion(
        self, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[float, np.ndarray, float, np.ndarray]:
        """(k, c, k_a, c_a) as ``ImplicitEuler.motion``: v_{n+1} = k (y - c) and the
        acceleration of the equation of motion, (1 - alpha_m) a_{n+1} + alpha_m a_n =
        k_a (y - c_a) (after ``weights``)."""
        a_n, beta, gamma, am = self._a, self.beta, self.gamma, self.alpha_m
        assert self._p is not None  # weights() came first
        k = gamma / (beta * h)
        ka = (1.0 - am) / (beta * h * h)
        c = self._p - (v_k + h * (1.0 - gamma) * a_n) / k
        return k, c, ka, self._p - am * a_n / ka

    def held(
        self, x_end: np.ndarray, x: np.ndarray, v: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """A support's velocity and acceleration as ``ImplicitEuler.held``: its mean
        velocity over the step (first order: the scheme keeps no acceleration of the
        supports, and its recurrence on a prescribed path is not damped at rho_inf = 1)."""
        return _stepped(x_end, x, v, h)

    def corner(self) -> None:
        """Nothing to restart (no error estimate; the supports' velocity is the step's)."""

    def accept(
        self, x_new: np.ndarray, x: np.ndarray, v: np.ndarray, free: np.ndarray, h: float
    ) -> np.ndarray:
        """The new velocities (and acceleration) of the accepted step; supports'
        velocities are their mean over the step."""
        y_new = x_new.reshape(-1)[free]
        assert self._p is not None  # weights() came first
        a_new = (y_new - self._p) / (self.beta * h * h)
        out: np.ndarray = (x_new - x) / h
        v_k = v.reshape(-1)[free]
        out.reshape(-1)[free] = v_k + h * ((1.0 - self.gamma) * self._a + self.gamma * a_new)
        self.a = a_new
        return out


class BDF2:
    """The two-step backward differentiation formula (Gear's), on variable steps: with
    omega = h / h_prev, c1 = (1 + omega)^2 / (1 + 2 omega), c2 = omega^2 / (1 + 2 omega),
    b = h (1 + omega) / (1 + 2 omega),

        x_{n+1} - c1 x_n + c2 x_{n-1} = b v_{n+1}
        v_{n+1} - c1 v_n + c2 v_{n-1} = b a_{n+1},   M a_{n+1} + mu M v_{n+1} + grad E = f

    which is implicit Euler's incremental potential with h -> b, x_n -> c1 x_n - c2 x_{n-1}
    and v_n -> c1 v_n - c2 v_{n-1}: the same Newton, line search, obstacle cap and step
    halving, with every force at x_{n+1} itself (the state the barriers guard). Second
    order (damped or not), A- and L-stable: the modes the step resolves keep their energy
    to O((h omega)^3) per period, those it cannot resolve (axial modes, a barrier's) are
    removed within a few steps, as implicit Euler removes them, and nothing rings on in a
    state the next step carries (newmark's acceleration). Zero-stable for step ratios
    omega < 1 + sqrt 2; a step after a longer ratio (or the first of a run, or of a
    restart: the state is (x_n, v_n, x_{n-1}, v_{n-1})) is an implicit Euler step."""

    name = "bdf2"
    order = 2
    step_rtol = 0.01  # as newmark: little damping of its own to absorb Newton's errors
    a = None  # no acceleration state
    keep = True  # its last two states are its own: always kept (``estimate``)
    MAX_RATIO = 2.4  # the largest step ratio taken as a BDF2 step (zero-stable below 2.414)

    def __init__(self) -> None:
        self._prev: tuple[np.ndarray, np.ndarray, float] | None = None  # y, v, h of step n-1
        self._older: tuple[np.ndarray, np.ndarray, float] | None = None  # ... of step n-2
        self._bar: tuple[np.ndarray, np.ndarray, float] | None = None  # this step's x, v, b
        self._bdf = False  # this step is a BDF2 step (not implicit Euler's)
        self._c = (1.0, 0.0)  # this step's (c1, c2)
        self._held: tuple[np.ndarray, np.ndarray] | None = None  # supports' x, v at n-1
        self.b = 0.0  # the step's b: v_{n+1} = (x_{n+1} - x_bar) / b (``weights``)

    def begin(
        self,
        potential: Potential,
        x: np.ndarray,
        v: np.ndarray,
        m_free: np.ndarray,
        damping: float | np.ndarray,
        a0: np.ndarray | None = None,
    ) -> None:
        """A run starts with one implicit Euler step."""
        self._prev = self._older = self._held = None

    def _coefficients(
        self, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """(c1 x_n - c2 x_{n-1}, c1 v_n - c2 v_{n-1}, b) of a step h from (y_k, v_k)."""
        prev = self._prev
        self._bdf = prev is not None and h / prev[2] <= self.MAX_RATIO
        if prev is None or not self._bdf:
            return y_k, v_k, h  # implicit Euler
        y_p, v_p, h_p = prev
        omega = h / h_p
        c2 = omega * omega / (1.0 + 2.0 * omega)
        c1 = 1.0 + c2  # = (1 + omega)^2 / (1 + 2 omega)
        b = h * (1.0 + omega) / (1.0 + 2.0 * omega)
        self._c = (c1, c2)
        return c1 * y_k - c2 * y_p, c1 * v_k - c2 * v_p, b

    def predict(self, x_trial: np.ndarray, v: np.ndarray, free: np.ndarray, h: float) -> None:
        """Newton's start: where the free DOFs go without force, x_bar + b v_bar (Eq. 11
        for the first step)."""
        flat = x_trial.reshape(-1)
        y_bar, v_bar, b = self._coefficients(flat[free], v.reshape(-1)[free], h)
        flat[free] = y_bar + b * v_bar

    def weights(
        self,
        m_free: np.ndarray,
        y_k: np.ndarray,
        v_k: np.ndarray,
        h: float,
        damping: float | np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """w and a of the step's inertia term: implicit Euler's with (b, x_bar, v_bar)."""
        y_bar, v_bar, b = self._coefficients(y_k, v_k, h)
        self._bar = (y_bar, v_bar, b)
        self.b = b
        w = m_free * (1.0 / b**2 + damping / b)
        a = (m_free / b**2 * (y_bar + b * v_bar) + damping * m_free / b * y_bar) / w
        return w, a

    def motion(
        self, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[float, np.ndarray, float, np.ndarray]:
        """(k, c, k_a, c_a) as ``ImplicitEuler.motion``, with (b, x_bar, v_bar)."""
        assert self._bar is not None  # weights() came first
        y_bar, v_bar, b = self._bar
        return 1.0 / b, y_bar, 1.0 / b**2, y_bar + b * v_bar

    def held(
        self, x_end: np.ndarray, x: np.ndarray, v: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The velocity and acceleration at the step's end of DOFs on a prescribed path
        (``ImplicitEuler.held``) by this step's formula, (x_end - x_bar) / b and (v_end -
        v_bar) / b with x_bar, v_bar from their own last two states: a support's velocity
        is second order, as the free nodes' are (its mean over the step lags by h / 2, and
        (x_end - x_n) / b, 1.5 times its velocity on equal steps, made the dashpot of a
        surged chain's last edge pull 2 % too hard); an implicit Euler step's otherwise."""
        if not self._bdf or self._held is None:
            return _stepped(x_end, x, v, h)
        (x_p, v_p), (c1, c2), b = self._held, self._c, self.b
        v_end = (x_end - (c1 * x - c2 * x_p)) / b
        return v_end, (v_end - (c1 * v - c2 * v_p)) / b

    def velocities(
        self, x_new: np.ndarray, x: np.ndarray, v: np.ndarray, free: np.ndarray, h: float
    ) -> np.ndarray:
        """The velocities at the step's end, (x_{n+1} - x_bar) / b on the free DOFs, the
        supports' by the same formula (``held``), nothing kept."""
        assert self._bar is not None  # weights() came first
        y_bar, _, b = self._bar
        flat, start, speed = x_new.reshape(-1), x.reshape(-1), v.reshape(-1)
        out = np.empty_like(flat)
        out[free] = (flat[free] - y_bar) / b
        self._fixed = fixed = np.ones(len(flat), dtype=bool)  # the supports (``accept``)
        fixed[free] = False
        out[fixed] = self.held(flat[fixed], start[fixed], speed[fixed], h)[0]
        return out.reshape(x_new.shape)

    def accept(
        self, x_new: np.ndarray, x: np.ndarray, v: np.ndarray, free: np.ndarray, h: float
    ) -> np.ndarray:
        """The new velocities (``velocities``). Step n becomes the scheme's previous step."""
        out = self.velocities(x_new, x, v, free, h)
        start, speed = x.reshape(-1), v.reshape(-1)
        fixed = self._fixed  # (``velocities``' mask of this very step)
        self._older = self._prev
        self._prev = (start[free].copy(), speed[free].copy(), float(h))
        self._held = (start[fixed].copy(), speed[fixed].copy())
        return out

    def corner(self) -> None:
        """A corner of a prescribed motion at the state's time (a support that stops or
        starts, a load's history that turns): the supports' velocities restart from it,
        (x_end - x) / h on the first step after it, exact on a linear piece (the formula
        through states on both sides gave a support that had stopped a third of its
        speed, and its edge's dashpot pulled). The free nodes' formula and error estimate
        go on through it: their estimate is what shortens the steps where the motion
        turns (a weight struck by a force pulse gained 1.5 % of its energy in the step
        after the pulse where it was left out for two steps)."""
        self._held = None

    def estimate(
        self, y_new: np.ndarray, y_k: np.ndarray, v_k: np.ndarray, h: float
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The local error of the step of ``h`` from (y_k, v_k) to y_new (free DOFs), in x
        and in v: -R / (P - R) times the difference between the step's solution and the
        parabola through the last three states extrapolated to t + h, R the residual of
        the scheme's formula on y = t^3/6 (-2 h^3 / 9 on equal steps) and P the
        parabola's error there (the solution is off by -R y3, the parabola by -P y3, y3
        the third derivative: 2/11 of the difference on equal steps); None before the
        scheme has those states, or for an implicit Euler step."""
        if not self._bdf or self._older is None or self._prev is None or self._bar is None:
            return None
        y_bar, _, b = self._bar
        v_new = (y_new - y_bar) / b
        (y1, v1, h1), (y2, v2, h2) = self._prev, self._older
        omega = h / h1
        c2 = omega * omega / (1.0 + 2.0 * omega)
        err_c = ((1.0 + c2) * h**3 - c2 * (h + h1) ** 3) / 6.0
        err_p = h * (h + h1) * (h + h1 + h2) / 6.0
        w0 = (h + h1) * (h + h1 + h2) / (h1 * (h1 + h2))  # the parabola's weights at t + h
        w1 = -h * (h + h1 + h2) / (h1 * h2)
        w2 = h * (h + h1) / ((h1 + h2) * h2)
        share = -err_c / (err_p - err_c)
        ex = share * (y_new - (w0 * y_k + w1 * y1 + w2 * y2))
        ev = share * (v_new - (w0 * v_k + w1 * v1 + w2 * v2))
        return ex, ev


def _stepped(
    x_end: np.ndarray, x: np.ndarray, v: np.ndarray, h: float
) -> tuple[np.ndarray, np.ndarray]:
    """Implicit Euler's velocity and acceleration at the end of a step of h on a prescribed
    path from x (velocity v) to x_end: (x_end - x) / h and its change over h."""
    v_end = (x_end - x) / h
    return v_end, (v_end - v) / h


def make(name: str = "implicit_euler", rho_inf: float = RHO_INF) -> Scheme:
    """The scheme called ``name`` (solver.integrator)."""
    if name == "implicit_euler":
        return ImplicitEuler()
    if name == "newmark":
        return Newmark(rho_inf)
    if name == "bdf2":
        return BDF2()
    raise ConfigError(f"solver.integrator = {name!r}: must be one of {', '.join(INTEGRATORS)}")
