"""The energy balance of a dynamic run, step by step: what the net holds (kinetic,
elastic, contact), what was put in (the work of loads, gravity and moving supports), what
left it (damping and friction), and the remainder, which is the integrator's own:

    numerical = (K + U + C) - (K + U + C)_0 - W + D

K = 1/2 sum m v^2 over the free DOFs; U the structure's elastic energy (the edges'
stretching, the rods' bending: ``structural`` terms) and the elastic supports' springs
(``holds``); C every other conservative term's energy (barriers of obstacles, bodies and
strands, a free body's rigidity); W the work of the applied forces, sum over steps of
1/2 (f_n + f_{n+1}) . (x_{n+1} - x_n), and of the supports, 1/2 (R_n + R_{n+1}) . (their
move) (the part of R that holds a dashpot or the water at the media's own rule, as their
losses: ``_through_media``), and of a rod end turned along a history, 1/2 (M_n +
M_{n+1}) (Phi_{n+1} - Phi_n) (``driven`` terms); D the work done against the
mass-proportional damping, mu m v . (x_{n+1} - x_n) with v the scheme's own: v_{n+1}
for implicit Euler (its discrete energy identity), the step's mean (v_n + v_{n+1}) / 2
for newmark and bdf2 (the trapezoidal rule's), against
friction, g_f(x_{n+1}) . (x_{n+1} - x_n) (lagged friction's force; on an obstacle on a
prescribed motion, g_f . (dx - D) with D its surface's displacement where the nodes
are, ``Moving.drive``, and its work through friction -g_f . D booked in W), and against the
cables' axial dashpots (``catenet.terms.axial``, their ``losses``).

In water (``catenet.terms.water``) K also holds the added mass's 1/2 v^T M_a v, D the
drag's work against the motion relative to the water, -F_d . (dx - h U), and W the
water's work on the net: the current's F_d . h U and the flow's inertia force's, and
buoyancy's change with gravity's history, (f_{n+1} - f_n) (u_b(x_n) + u_b(x_{n+1})) / 2
with u_b its energy per unit factor f (its mechanical part then at the mean factor, as
the trapezoidal work of a load that follows a history).

Implicit Euler's remainder is never positive on a convex energy where the supports'
work is taken at the step's end, R_{n+1} . (their move), the rule of its own energy
identity: the step adds -1/2 m |v_{n+1} - v_n|^2 to it (its numerical dissipation). The
remainder reported takes the trapezoid, the closer estimate of that work; its verdict
takes the step's end (``_ends``: the sum of 1/2 (R_{n+1} - R_n) . (their move)). By the
trapezoid, a fairlead moved 2 m in a 1 s step while its pull rose by 100 kN booked 1e5 J
that implicit Euler never made, and a chain's run stopped as "creating energy". An integrator whose
remainder grows beyond ``tolerance`` x the largest energy seen creates energy: the run
stops with EnergyError (exit 1), never ending as an answer. An obstacle on a prescribed
motion (``catenet.terms.moving``) is ``driven``: its work on the net is booked in W, and
such runs are judged like any other; so is a ball on a prescribed path
(``catenet.terms.body.Guide``, ``driven``): its path's work through the spring that
holds it there, the trapezoid of the spring's force times the path's displacement, is
booked in W.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConvergenceError

if TYPE_CHECKING:
    from catenet.solver.stepper import TimeStepper
    from catenet.solver.system import System

COLUMNS = ("kinetic", "elastic", "contact", "external_work", "dissipated", "numerical")
TOLERANCE = 1e-2  # solver.energy_tolerance's default: a share of the largest energy
ROUNDOFF = 1e-9  # ... never below this share (the energies' own round-off, summed over steps)
FLOOR_EPS = 16.0  # ... nor below the energy of a state known to 16 eps of its size (``_floor``)
GRACE = 4  # the run's first steps are not judged alone (``check``)


#: What an EnergyError advises, by integrator (steps chosen by accuracy: ADAPTIVE_REMEDY).
REMEDIES = {
    "newmark": 'solver.integrator = "bdf2" (or "implicit_euler"), a smaller solver.dt, or a '
    "smaller solver.rho_inf (<= 0.5 in contact)",
    "": "a smaller solver.dt",
}
ADAPTIVE_REMEDY = "a smaller solver.tolerance or solver.dt_max"


class EnergyError(ConvergenceError):
    """A dynamic run whose energy balance shows the integrator creating energy."""


class Ledger:
    """The energy balance of one dynamic run (see the module docstring)."""

    def __init__(self, tolerance: float = TOLERANCE):
        self.tolerance = float(tolerance)
        self.row = np.zeros(len(COLUMNS))
        self.judged = True
        self.largest = 0.0
        self.motion = 0.0  # the largest kinetic energy (steps chosen by accuracy)
        # ... in the centre of mass's frame where nothing outside the net and its bodies
        # holds them (a thrown net: its flight's energy no step can lose is not counted;
        # ``catenet.run.integrator_advice``'s share of the motion's energy)
        self.internal = 0.0
        self._axes: np.ndarray | None = None  # each free DOF's axis, where that frame is
        self.remedy = REMEDIES[""]  # what an EnergyError advises (``begin``)
        self.weak = ""  # ... first: a barrier too weak for a landing (fixed steps' Watch)
        self.steps = 0  # the accepted steps so far (``check``'s GRACE)
        self._start = 0.0
        self._work = 0.0
        self._dissipated = 0.0
        self.floor = 0.0  # the energy a state known to round-off holds (``_floor``)

    # --- what the stepper calls ------------------------------------------------------
    def begin(self, stepper: TimeStepper) -> None:
        """The run's start state (``stepper``: a ``TimeStepper`` after ``begin``)."""
        system = stepper.system
        self.judged = True
        self._friction = [t for t in system.terms if t.lagged and not t.medium]
        self._media = [t for t in system.terms if t.medium]  # water: its own losses
        loads = stepper.loads  # their supports' part only where a support can move
        moving = loads.moves_supports or bool(loads.vessels)
        self._pulled = self._media if moving and stepper.net.fixed.any() else []
        self._weighs = [t for t in system.terms if t.weighs]  # buoyancy under gravity's history
        self._factors = [t.factor for t in self._weighs]
        self._driven = [t for t in system.terms if t.driven]  # a turned rod end's work
        self._force = self._applied(stepper).copy()
        k, u, c, reaction = self._state(stepper, stepper.x, stepper.v)
        self._held = self._through_media(stepper, stepper.x)
        self._reaction = reaction - self._held
        self._start = k + u + c
        self._work = self._dissipated = self._ends = 0.0
        self.floor = 0.0
        self.row[:] = (k, u, c, 0.0, 0.0, 0.0)
        self.largest = max(abs(k), abs(u), abs(c))
        self.motion = k
        self._axes = stepper.free % 3 if _held_by_nothing(stepper) else None
        self.internal = self._internal(stepper, stepper.v, k)
        self.steps = 0
        self.remedy = REMEDIES.get(stepper.scheme.name, REMEDIES[""])

    def step(
        self,
        stepper: TimeStepper,
        x_old: np.ndarray,
        x_new: np.ndarray,
        v_new: np.ndarray,
        h: float,
    ) -> None:
        """The accepted step from x_old to x_new (velocities v_new after it) of length h."""
        k, u, c, work, dissipated = self._balance(stepper, x_old, x_new, v_new, h, True)
        self._work, self._dissipated = work, dissipated
        self.row[:] = (k, u, c, work, dissipated, self._remainder(k + u + c, work, dissipated))
        self.floor = max(self.floor, _floor(stepper, x_new, h))
        self.largest = max(self.largest, abs(k), abs(u), abs(c), abs(work))
        self.motion = max(self.motion, k)
        self.internal = max(self.internal, self._internal(stepper, v_new, k))
        self.steps += 1

    def change(
        self,
        stepper: TimeStepper,
        x_old: np.ndarray,
        x_new: np.ndarray,
        v_new: np.ndarray,
        h: float,
    ) -> tuple[float, float]:
        """What the step from x_old to x_new would do, nothing booked (steps chosen by
        accuracy, catenet/solver/adaptive.py): the change of the remainder (the energy
        the integrator would create, < 0 where it removes some) and the motion's energy
        after it (the largest kinetic energy and what damping, drag and friction took)."""
        k, u, c, work, dissipated = self._balance(stepper, x_old, x_new, v_new, h, False)
        remainder = self._remainder(k + u + c, work, dissipated)
        return remainder - float(self.row[-1]), max(self.motion, k) + max(dissipated, 0.0)

    def _internal(self, stepper: TimeStepper, v: np.ndarray, kinetic: float) -> float:
        """The kinetic energy in the centre of mass's frame (``kinetic`` itself where
        something outside holds the net): less sum over the axes of P^2 / 2 M."""
        if self._axes is None:
            return kinetic
        m, vel = stepper.m_free, v.reshape(-1)[stepper.free]
        flight = 0.0
        for axis in range(3):
            on = self._axes == axis
            mass = float(np.sum(m[on]))
            if mass > 0.0:
                flight += 0.5 * float(np.dot(m[on], vel[on])) ** 2 / mass
        return kinetic - flight

    def _remainder(self, held: float, work: float, dissipated: float) -> float:
        """The integrator's own energy: what the net and bodies hold (``held``, kinetic,
        elastic and contact) beyond the start's, less the work done on them, plus what
        damping, drag and friction took."""
        return held - self._start - work + dissipated

    def _balance(
        self,
        stepper: TimeStepper,
        x_old: np.ndarray,
        x_new: np.ndarray,
        v_new: np.ndarray,
        h: float,
        commit: bool,
    ) -> tuple[float, float, float, float, float]:
        """(kinetic, elastic, contact, work, dissipated) after the step from x_old to
        x_new; ``commit``: the step is accepted, and the ledger and the media keep what
        the next step's trapezoids start from."""
        net = stepper.net
        dx = x_new - x_old
        free = ~net.fixed
        force = self._applied(stepper)  # its work at a moving support too: the node's
        work = self._work + 0.5 * float(np.sum((self._force + force) * dx))  # own load
        k, u, c, reaction = self._state(stepper, x_new, v_new)
        fixed = net.fixed
        trapezoid = stepper.scheme.name != "implicit_euler"  # the media's rule (``losses``)
        held = self._through_media(stepper, x_new)  # what holds the media at a support
        reaction -= held  # works by their rule, as the losses it enters: the rest by the
        through = 0.5 * (held + self._held) if trapezoid else held  # trapezoid
        pull = 0.5 * (self._reaction + reaction) + through
        work += float(np.sum(pull[fixed] * dx[fixed]))
        if commit and not trapezoid:  # implicit Euler's own rule, R_n+1, for its verdict
            self._ends += 0.5 * float(np.sum((reaction - self._reaction)[fixed] * dx[fixed]))
        if commit:
            self._force[:] = force
            self._reaction[:] = reaction
            self._held = held
        flat = dx.reshape(-1)[stepper.free]
        vel = v_new.reshape(-1)[stepper.free]
        if stepper.scheme.name != "implicit_euler":  # the step's mean velocity
            vel = 0.5 * (vel + stepper.v.reshape(-1)[stepper.free])
        damping = stepper.damping * stepper.m_free * vel
        dissipated = self._dissipated + float(np.dot(damping, flat))
        for term in self._friction:
            g = np.zeros_like(x_new)
            term.gradient(x_new, g)
            on = term.rides_on
            drive = on.drive(x_old, x_new) if on is not None and on.moving else None
            if drive is None:
                dissipated += float(np.sum(g[free] * dx[free]))
            else:  # on a moving obstacle: its work through friction, the rest the slip's
                dissipated += float(np.sum(g[free] * (dx - drive)[free]))
                work -= float(np.sum(g[free] * drive[free]))
        for i, term in enumerate(self._weighs):  # its energy's change with gravity, at
            if term.factor != self._factors[i]:  # the step's mean (as gravity's work)
                mean = 0.5 * (term.unit_energy(x_old) + term.unit_energy(x_new))
                work += (term.factor - self._factors[i]) * mean
                if commit:
                    self._factors[i] = term.factor
        for term in self._driven:
            work += term.driven_work(x_old, x_new, commit)
        for term in self._media:
            lost, put = term.losses(x_old, x_new, h, trapezoid, commit)
            dissipated += lost
            work += put + term.relagged(stepper.v, commit)  # (stepper.v: the step's start)
        return k, u, c, work, dissipated

    @property
    def headroom(self) -> float:
        """The energy the integrator may still create before ``check`` stops the run."""
        allowed = max(max(self.tolerance, ROUNDOFF) * self.largest, self.floor)
        return allowed - (float(self.row[-1]) - self._ends)

    def check(self, t: float) -> None:
        """EnergyError where the remainder shows energy created beyond the tolerance. The
        first GRACE steps of a run are not judged alone: their energies are a
        few steps' work, and a scheme's start-up (newmark's first step under a load
        rising from zero overshoots by 9 % of it, 6e-11 J against 7e-10) stopped runs
        that then keep their energy to 1e-4; what a start creates for good is judged
        from the next step on, against the energies the run has by then."""
        if not self.judged or self.steps < GRACE:
            return
        remainder = float(self.row[-1]) - self._ends  # (implicit Euler: its own rule)
        allowed = max(max(self.tolerance, ROUNDOFF) * self.largest, self.floor)
        if remainder > allowed and remainder > 0.0:
            k, u, c, w, d, _ = self.row
            raise EnergyError(
                f"the integrator creates energy: by t = {t:.6g} s the net and bodies hold "
                f"{k + u + c:.4g} J (kinetic {k:.4g}, elastic {u:.4g}, contact {c:.4g}) "
                f"where the start's {self._start:.4g} J, the work of loads and supports "
                f"({w:.4g} J) and the losses to damping and friction ({d:.4g} J) allow "
                f"{k + u + c - remainder:.4g} J: {remainder:.4g} J appeared from nothing, "
                f"more than solver.energy_tolerance = {self.tolerance:g} of the largest "
                f"energy ({self.largest:.4g} J). Not an answer: use "
                f"{self.weak + ', or ' if self.weak else ''}{self.remedy}"
            )

    # --- the parts -------------------------------------------------------------------
    def _through_media(self, stepper: TimeStepper, x: np.ndarray) -> np.ndarray:
        """The part of the supports' force on the net at x (N, 3; 0 at free nodes) that
        holds the media (a dashpot, the water): its work is booked by the media's own
        rule, as their losses are (implicit Euler's: at the step's end; a support that
        starts at once pulls its dashpot at once), the rest's by the trapezoid."""
        out = np.zeros_like(x)
        if not self._pulled:  # no support moves: no work through them (one gradient less)
            return out
        force = np.zeros_like(x)
        for term in self._pulled:
            term.held_force(x, force)
        fixed = stepper.net.fixed
        out[fixed] = -force[fixed]
        return out

    def _applied(self, stepper: TimeStepper) -> np.ndarray:
        return np.asarray(stepper.potential.force, dtype=np.float64)

    def _state(
        self, stepper: TimeStepper, x: np.ndarray, v: np.ndarray
    ) -> tuple[float, float, float, np.ndarray]:
        """Kinetic, elastic and contact energy at (x, v), and the force the supports
        exert on the net there (0 at free nodes): one evaluation of the terms."""
        vel = v.reshape(-1)[stepper.free]
        kinetic = 0.5 * float(np.dot(stepper.m_free * vel, vel))
        kinetic += sum(t.kinetic(v) for t in stepper.media)
        system, potential = stepper.system, stepper.potential
        if potential.system is system:  # the step's last evaluation's, where at this x
            grad, energies = potential.internal(x)
        else:  # a run to rest on a stage's wider barrier: the run's own terms
            grad, energies = system.gradient(x)[1], system.energies
        reaction = np.zeros_like(x)
        fixed = stepper.net.fixed
        reaction[fixed] = grad[fixed] - potential.force[fixed]
        return (kinetic, *_stored(system, energies), reaction)


def at_roundoff(remainder: float, scale: float) -> bool:
    """Whether a balance's remainder is within the energies' round-off of ``scale`` (a
    net at rest: 3e-15 J is no loss of the integrator's)."""
    return abs(remainder) <= ROUNDOFF * scale


def _held_by_nothing(stepper: TimeStepper) -> bool:
    """No fixed node, no moving support, and no term that ties the net to the world (an
    obstacle, fixed or moving, a body's plane, a roller, a spring or support term, the
    water): the net and its bodies fly free, and a uniform motion of them all is no
    motion an integrator can lose."""
    from catenet.terms.axial import AxialDamping
    from catenet.terms.body import Guide
    from catenet.terms.body_plane import BodyPlane
    from catenet.terms.contact import Obstacle

    if stepper.net.fixed.any() or stepper.loads.moves_supports or stepper.loads.vessels:
        return False
    for term in stepper.system.terms:
        if isinstance(term, (Obstacle, BodyPlane, Guide)) or term.holds or term.moving:
            return False
        if term.medium and not isinstance(term, AxialDamping):
            return False
    return True


def _floor(stepper: TimeStepper, x: np.ndarray, h: float) -> float:
    """The energy [J] of a state known to FLOOR_EPS round-offs of its size, d = FLOOR_EPS
    eps max |x|: the edges' 1/2 EA / l0 d^2 and 1/2 m (d / h)^2 of the free DOFs. A
    remainder below it is no energy created (a net at rest, nothing yet touched, whose
    nodes move by round-off: 1e-46 J appeared "from nothing" against a largest energy of
    the same size)."""
    net = stepper.net
    d = FLOOR_EPS * float(np.finfo(np.float64).eps) * max(float(np.max(np.abs(x))), 1e-300)
    stiffness = float(np.sum(net.EA / net.rest_length))
    mass = float(np.sum(stepper.m_free))
    return 0.5 * stiffness * d**2 + 0.5 * mass * (d / h) ** 2 if h > 0.0 else 0.0


def held_energy(system: System, x: np.ndarray, v: np.ndarray | None) -> np.ndarray:
    """The balance's row of a start state (x, v): kinetic, elastic and contact energy,
    nothing yet put in or taken out (the first frame of a dynamic run's file)."""
    net = system.net
    free = ~net.fixed
    kinetic = 0.0
    if v is not None:
        kinetic = 0.5 * float(np.sum(net.mass[free] * np.sum(v[free] ** 2, axis=1)))
        kinetic += sum(t.kinetic(v) for t in system.terms if t.medium)
    system.gradient(x)
    return np.array([kinetic, *_stored(system, system.energies), 0.0, 0.0, 0.0])


def _stored(system: System, energies: list[float]) -> tuple[float, float]:
    """(elastic, contact) energy of the system's terms' ``energies`` (at one x): the
    edges' stretching and the rods' bending, and every other term's that is neither
    lagged (friction dissipates) nor a medium (the water's drag and added mass, an
    axial dashpot: their step's potential is the scheme's, not energy the net holds;
    their kinetic energy and losses are booked by themselves)."""
    elastic = contact = 0.0
    for term, e in zip(system.terms, energies, strict=True):
        if term.lagged or term.medium:
            continue
        if term is system.stretch or term.structural or term.holds:  # springs: elastic
            elastic += float(e)
        else:
            contact += float(e)
    return elastic, contact
