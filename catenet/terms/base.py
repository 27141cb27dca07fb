"""The interface every energy term implements, and the registry of terms by name.

A term is one physical contribution E(x) to the potential a solver minimises, as a
function of the node positions x (N, 3):

- ``pattern()``: the global DOF indices (rows, cols) of its Hessian values (dof = 3 node
  + axis), asked once, when a workspace builds the sparsity pattern; None when it has no
  Hessian (a linear term).
- ``gradient(x, grad)``: adds dE/dx into ``grad`` (N, 3) and returns E.
- ``energy(x)``: E alone.
- ``hessian(x, values)``: writes its Hessian values, in the order of ``pattern()``, into
  ``values`` (a preallocated slice of the assembled values).
- ``roundoff(x, energy)``: the round-off levels of its gradient norm and of its energy,
  which set the floor below which Newton's residual and decrease cannot be resolved.
- ``node_roundoff(x, energy)``: per node (N,), the round-off level of its forces there (or
  None: none); convergence at round-off is decided DOF by DOF with it, so that a stiff
  term's round-off (a free body's) counts on its own nodes only. Default: the gradient's
  level of ``roundoff`` on every node where ``stiffness()`` is positive (on every node
  for a term without stiffness). A contact ``barrier`` adds what its stiffness makes of
  the positions' round-off (``stiff_roundoff``).
- ``stiffness()``: per node (N,), the scale of its Hessian diagonal (the regularisation of
  a singular start scales with it), or None.

Optional capabilities, declared so that solvers ask no term what it has:

- ``bounds_step`` (with ``max_step(x, dx)``: the largest multiple of the step dx that
  keeps every node outside, inf when it never touches): obstacles and balls; line
  searches, predictors and polishing steps are capped there.
- ``lagged`` (with ``relag(x)``: updates lagged quantities at an equilibrium, returns
  their relative change): friction; a static load step is re-solved until they settle.
- ``moving`` (with ``set_pose(t)``): an obstacle on a prescribed motion.
- ``stages``: wider copies of an obstacle a static solve goes through first;
  ``rides_on``: the obstacle whose barrier a term rides on (friction's normal force).
- ``grows`` (with ``grew``): a term whose pattern may change at ``begin_step`` (the
  candidate pairs of self-contact); it sets ``grew`` then, and the time stepping
  rebuilds the system with the new pattern (``Workspace.refresh``), which clears it.
- ``loadlike`` (with ``set_factor(factor)``): a load-like term (water's buoyancy and
  drag) that a static run's load factor scales as it scales the applied loads; one that
  ``weighs`` (buoyancy, with ``unit_energy``) follows gravity's history as well.
- ``medium`` (with ``begin_run``, ``set_motion``, ``kinetic`` and ``losses``): a term of
  the step's velocity (water's drag and added mass, ``catenet.terms.water``; the cables'
  axial damping, ``catenet.terms.axial``): the
  stepper gives it the scheme's velocity and acceleration maps every step, the energy
  balance its kinetic energy and losses.
- ``driven`` (with ``begin_run``, ``driven_work(x_old, x_new, commit)`` and ``settle_time()``): a
  term whose energy a prescribed history of its own changes (a rod end turned along a
  history, ``catenet.terms.twist``): a dynamic run starts it at its start time, runs at
  least to where its history ends before it stops at rest, and the energy balance counts
  the work that history does in each accepted step.
- ``edge_net``: a net whose edges' row-major 6x6 blocks are the term's Hessian values, edge
  by edge (the stretching, the stretched start's springs): the system shares one map
  into its pattern between all such terms of a net.
- ``holds``: a support's term (the elastic supports' springs,
  ``catenet.terms.supports``): its force counts in the reactions, not the contact forces.

``role`` says how a solver uses the term: "internal" terms belong to the structure
(stretching, springs, contact; support reactions balance them), "external" ones are the
linear potential -f.x of applied loads (their force sets the load scale), "step" terms
belong to one time step (inertia and damping). ``convex`` terms have a positive
semidefinite Hessian everywhere, which lets the linear solver use Cholesky.

The values are computed by ``@njit(cache=True)`` kernels (``catenet.kernels``) over flat
arrays; the classes hold the arrays and call them. ``check_derivatives`` is the finite
difference check that every term passes in the tests.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from catenet.model.net import Net

#: Terms by name: a new term is one module that defines it plus one ``register`` call.
TERMS: dict[str, type[Term]] = {}


def register(name: str) -> Callable[[type[Term]], type[Term]]:
    """Class decorator: make a term known by ``name``."""

    def add(cls: type[Term]) -> type[Term]:
        old = TERMS.get(name)
        same = old is not None and (old.__module__, old.__qualname__) == (
            cls.__module__,
            cls.__qualname__,
        )  # the same class defined again (a module or notebook cell run twice)
        if old is not None and not same:
            raise ValueError(f"a term named {name!r} is registered already: {old}")
        cls.name = name
        TERMS[name] = cls
        return cls

    return add


#: The attributes (points, (3,) or (K, 3)) a barrier computes its gaps from besides the
#: nodes (``Term.frame_scale``).
FRAME_POINTS = ("center", "origin", "c0", "point", "points", "vertices")


class Term:
    """Base class of energy terms (see the module docstring)."""

    name = "term"
    role = "internal"
    bounds_step = False  # has max_step(x, dx)
    lagged = False  # has relag(x)
    horizon = False  # max_step(x, dx, upto) looks no farther than upto (its cost grows)
    moving = False  # has set_pose(t)
    loadlike = False  # has set_factor(factor): a static run's load factor scales it
    weighs = False  # loadlike and a weight (buoyancy): gravity's history scales it too
    factor = 1.0  # (loadlike terms) the factor set_factor gave
    medium = False  # has begin_run, set_motion, kinetic, losses (water, axial damping)
    driven = False  # has begin_run, driven_work (catenet.terms.twist)
    grows = False  # its pattern may grow at begin_step (then ``grew`` is True)
    grew = False
    dynamic_only = False  # only in time steps (self-contact: its candidates need them)
    widens = False  # a failed step its candidate radii held back (its ``held``) is tried
    #                 again at its length, the radii widened (``TimeStepper.widened``)
    stages: tuple = ()  # wider barriers of the same obstacle (static continuation)
    rides_on: Term | None = None  # the term whose barrier it rides on (friction's)
    edge_net: Net | None = None  # the Hessian is its edges' 6x6 blocks, edge by edge
    structural = False  # the structure's own energy (rods' bending, a body's rigidity): no contact
    holds = False  # a support's term (springs): its force is a reaction, not a contact
    owner: int | None = None  # the obstacle, ball or free body (its index k) it is part of
    barrier = False  # a contact barrier: its stiffness turns positions' round-off into force's
    struck_by: Any = None  # a solid's own barrier: catenet.scene.movers.StruckBy (its bounces)
    label = ""  # the obstacle, ball or body it is, in messages ("obstacle[0] (kind 'box')")
    key = ""  # the case key of its activation distance ("obstacle[0].distance"), if it has one

    @property
    def convex(self) -> bool:
        """Whether its Hessian is positive semidefinite everywhere (a subclass says it
        with a class attribute, or a property where it depends on the term's data)."""
        return True

    def pattern(self) -> tuple[np.ndarray, np.ndarray] | None:
        return None

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        raise NotImplementedError

    def energy(self, x: np.ndarray) -> float:
        return self.gradient(x, np.zeros_like(x))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> bool | None:
        """Writes the Hessian values (only terms with a pattern have any); False says
        they are all zero (an obstacle out of reach: nothing to add)."""
        return None

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        return 0.0, abs(energy)

    def node_roundoff(self, x: np.ndarray, energy: float) -> np.ndarray | None:
        """Per node (N,), the round-off level of the term's forces there, in the units of
        ``roundoff`` (without eps); None where it has none."""
        level, _ = self.roundoff(x, energy)
        out = None
        if level != 0.0:
            out = np.full(x.shape[0], level)
            stiffness = self.stiffness()
            if stiffness is not None:
                out[stiffness <= 0.0] = 0.0
        return out

    def stiff_roundoff(self, x: np.ndarray) -> np.ndarray | None:
        """Per node (N,), the round-off its positions' round-off brings to the term's
        forces: sum_j |H_ij| (|x_j| + s) over the node's rows (the largest of its
        three), s the size of the obstacle's own coordinates (``frame_scale``), in the
        units of ``roundoff``; None where the Hessian is zero (the convergence test
        adds it for a ``barrier``, within a share of the structure's forces:
        ``Potential.floor_levels``). A barrier's stiffness,
        its force over its gap, grows without bound as the gap closes: a cord pressed on
        a paddle's corner at a gap of nanometres has forces uncertain to 1e-6 N where
        eps times the forces meeting there is 2e-9 N, and Newton's residual cannot go
        below that (the step was called stagnated, then the run failed)."""
        pattern = None if self.grows else self.__dict__.get("_stiff_pattern")
        if pattern is None:  # kept where it cannot change (a growing one asked each time)
            pattern = self.pattern()
            if pattern is None:
                return None
            self._stiff_pattern = pattern
        rows, cols = pattern
        values = np.zeros(len(rows))
        if not self.hessian(x, values):
            return None
        scale = np.abs(np.asarray(x, dtype=np.float64)).reshape(-1) + self.frame_scale()
        weights = np.abs(values) * scale[cols]
        per_dof = np.bincount(rows, weights=weights, minlength=x.size)
        out: np.ndarray = per_dof.reshape(-1, 3).max(axis=1)
        return out

    def frame_scale(self) -> float:
        """The size of the coordinates the term computes its gaps in besides the nodes'
        (an obstacle's centre, a moving obstacle's reference point) [m]."""
        sizes = [0.0]
        for name in FRAME_POINTS:
            value = getattr(self, name, None)
            if isinstance(value, np.ndarray) and value.shape[-1:] == (3,):
                sizes.append(float(np.max(np.abs(value), initial=0.0)))
        return max(sizes)

    def stiffness(self) -> np.ndarray | None:
        return None

    def max_step(self, x: np.ndarray, dx: np.ndarray) -> float:
        """(``bounds_step`` terms) The largest multiple of the step dx from x that keeps
        every node outside; inf when it never touches."""
        return math.inf

    def max_step_within(self, x: np.ndarray, dx: np.ndarray, upto: float) -> float:
        """``max_step`` where no multiple beyond ``upto`` is asked for: a term whose
        search grows with the distance (``horizon``) stops there (inf then means no
        contact up to ``upto``); the others give their ``max_step``."""
        return self.max_step(x, dx)

    def relag(self, x: np.ndarray) -> float:
        """(``lagged`` terms) Updates the lagged quantities at the equilibrium x; returns
        their relative change."""
        raise NotImplementedError(f"{type(self).__name__} lags nothing")

    def set_factor(self, factor: float) -> None:
        """(``loadlike`` terms) The load factor of a static load step (1: in full)."""
        raise NotImplementedError(f"{type(self).__name__} is no load")

    def unit_energy(self, x: np.ndarray) -> float:
        """(``weighs`` terms) The energy at x per unit factor (the energy balance books a
        change of the factor as work)."""
        raise NotImplementedError(f"{type(self).__name__} is no weight")

    def begin_run(self, x: np.ndarray, t: float) -> None:
        """(``medium`` and ``driven`` terms) A dynamic run's start state x at time t."""
        raise NotImplementedError(f"{type(self).__name__} is no medium")

    def settle_time(self) -> float:
        """(``driven`` terms) The time after which its history no longer changes."""
        raise NotImplementedError(f"{type(self).__name__} is not driven")

    def driven_work(self, x_old: np.ndarray, x_new: np.ndarray, commit: bool = True) -> float:
        """(``driven`` terms) The work [J] its own history did in the step from x_old to
        x_new (the step of the last ``begin_step``); ``commit``: the step is accepted (else
        nothing of it is kept: a step judged before it is taken)."""
        raise NotImplementedError(f"{type(self).__name__} is not driven")

    def drive(self, x_old: np.ndarray, x_new: np.ndarray) -> np.ndarray | None:
        """(``moving`` terms) (N, 3) the displacement of the obstacle's surface where the
        nodes are over the last step (None: none): its friction's work is f . drive."""
        return None

    def set_motion(self, kv: float, centre: np.ndarray, ka: float, centre_a: np.ndarray) -> None:
        """(``medium`` terms) The step's velocity kv (x - centre) and acceleration
        ka (x - centre_a) as maps of its positions x (N, 3) (``Scheme.motion``)."""
        raise NotImplementedError(f"{type(self).__name__} is no medium")

    def kinetic(self, v: np.ndarray) -> float:
        """(``medium`` terms) The kinetic energy it carries at velocities v (N, 3)."""
        raise NotImplementedError(f"{type(self).__name__} is no medium")

    def mass_blocks(self) -> np.ndarray:
        """(``medium`` terms) (N, 3, 3) the mass it adds at each node [kg]."""
        raise NotImplementedError(f"{type(self).__name__} is no medium")

    def relagged(self, v: np.ndarray, commit: bool = True) -> float:
        """(``medium`` terms) The kinetic energy that this step's mass blocks, lagged at
        its start, give the velocities v (N, 3) of its start beyond the blocks the last
        accepted step was booked with: the lagged model's own work, no integrator's
        (``commit``: the step is accepted). 0 for a medium whose mass never changes."""
        return 0.0

    def losses(
        self,
        x_old: np.ndarray,
        x_new: np.ndarray,
        h: float,
        mean: bool = False,
        commit: bool = True,
    ) -> tuple[float, float]:
        """(``medium`` terms) (dissipated, work) of the step x_old -> x_new; ``commit``:
        the step is accepted (its end force is the next step's start)."""
        raise NotImplementedError(f"{type(self).__name__} is no medium")

    def held_force(self, x: np.ndarray, out: np.ndarray) -> None:
        """(``holds`` terms) Adds to ``out`` (N, 3) the force the support exerts on the
        net as the reactions count it: minus its gradient (a rod end's 6x6 spring: the
        wrench's force at its node, ``catenet.terms.rodends``)."""
        grad = np.zeros_like(out)
        self.gradient(x, grad)
        out -= grad

    def safeguard(self, on: bool) -> None:
        """Newton's safeguarded mode (``catenet.solver.newton``: after a line search cut a step
        short): a term whose exact Hessian lets Newton overshoot gives a safer matrix while
        on (a free body's contact: projected blocks). Gradient and energy never change."""

    def periods(self) -> tuple[float, ...]:
        """The periods [s] of the term's own sines (the water's waves): steps chosen by
        accuracy follow them as a support's sine (catenet/solver/adaptive.py)."""
        return ()

    def corners(self) -> tuple[float, ...]:
        """The times at which a prescribed motion of the term turns a corner (its history's
        points): steps chosen by accuracy end on them (catenet/solver/adaptive.py)."""
        return ()

    def begin_step(self, x: np.ndarray, time: float | None, start: float | None = None) -> None:
        """Called before every static load step (``time`` None) and every dynamic time
        step (``time``: the step's end, ``start``: its start, the time of x) with the
        last accepted state x (N, 3). A term whose energy depends on the step (lagged
        friction, an obstacle on a prescribed path) updates itself here; the pattern
        must not change, but for ``grows`` terms (which set ``grew``). Default: nothing."""


def node_block_pattern(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the 3x3 blocks of the given nodes, row-major per block: the
    pattern of a term acting on each node by itself (springs, ground contact)."""
    dofs = 3 * np.asarray(nodes, dtype=np.int64)[:, None] + np.arange(3)  # (K, 3)
    rows = np.repeat(dofs, 3, axis=1).ravel()
    cols = np.tile(dofs, (1, 3)).ravel()
    return rows, cols


def check_derivatives(term: Term, x: np.ndarray, *, step: float = 1e-6) -> tuple[float, float]:
    """Largest relative errors of the term's gradient against central differences of its
    energy, and of its Hessian against central differences of its gradient, at x (N, 3).
    Both are O(step^2) plus round-off: about 1e-8 for smooth terms with step = 1e-6."""
    x = np.array(x, dtype=np.float64)
    n = x.size
    grad = np.zeros_like(x)
    term.gradient(x, grad)
    fd = np.zeros(n)
    flat = x.reshape(-1)
    h = step * max(1.0, float(np.max(np.abs(x))))
    for d in range(n):
        keep = flat[d]
        flat[d] = keep + h
        up = term.energy(x)
        flat[d] = keep - h
        down = term.energy(x)
        flat[d] = keep
        fd[d] = (up - down) / (2 * h)
    g = grad.reshape(-1)
    grad_err = float(np.max(np.abs(g - fd))) / max(float(np.max(np.abs(g))), 1e-300)

    pattern = term.pattern()
    dense = np.zeros((n, n))
    if pattern is not None:
        rows, cols = pattern
        values = np.zeros(len(rows))
        term.hessian(x, values)
        np.add.at(dense, (rows, cols), values)
    fd_h = np.zeros((n, n))
    for d in range(n):
        keep = flat[d]
        g_up, g_down = np.zeros_like(x), np.zeros_like(x)
        flat[d] = keep + h
        term.gradient(x, g_up)
        flat[d] = keep - h
        term.gradient(x, g_down)
        flat[d] = keep
        fd_h[:, d] = (g_up - g_down).reshape(-1) / (2 * h)
    scale = max(float(np.max(np.abs(dense))), float(np.max(np.abs(fd_h))), 1e-300)
    hess_err = float(np.max(np.abs(dense - fd_h))) / scale
    return grad_err, hess_err
