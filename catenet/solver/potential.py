"""The potential Newton minimises: Phi on the free DOFs of a net, the sum of its energy
terms with the supports held in place (``Potential``), and its value, gradient and
round-off levels at a state (``Evaluation``). ``catenet.solver.newton`` has the method."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from catenet.kernels.sparse import norm
from catenet.solver.linear import LinearSolver
from catenet.solver.system import System
from catenet.terms import ExternalForce, Term

EPS = np.finfo(float).eps
FLOOR_SAFETY = 16.0  # a DOF's residual within this many eps of its forces is round-off
#: A contact barrier's share of a DOF's floor (its stiffness times the positions'
#: round-off, ``Term.stiff_roundoff``) is at most this share of the structure's largest
#: force: a cord held round a paddle's corners at 0.36 nm (its floor there 1e-7 to 1e-6 N
#: of 486 N) is at its round-off; a rope squeezed between a plate and a ball with 6 MN
#: (floors of 10 N of the rope's 600 N) is pinched.
STIFF_SHARE = 1e-6
_generation = 0  # counts what may change a term's state at a given x (``Potential.internal``)


@dataclass(frozen=True)
class Evaluation:
    """Phi and its gradient at a state, with the scales Newton's tests compare them with.
    ``g`` is the potential's own buffer, overwritten by its next evaluation: ``kept()``
    is the same evaluation with a copy of it."""

    phi: float  # Phi [J]
    g: np.ndarray  # grad Phi on the free DOFs [N]
    scale: float  # the load scale: the larger of |f| and |internal force| [N]
    floor: float  # the gradient's round-off floor [N]
    phi_tol: float  # the round-off level of Phi [J]
    gnorm: float  # |g| [N]

    def kept(self) -> Evaluation:
        return replace(self, g=self.g.copy())


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
        self.f_free = system.restrict(external.flat)
        self.f_norm = external.norm
        self.external = external if self.f_norm > 0 else None  # no loads: nothing to compute
        self.steps = tuple(steps)
        self.D = system.stiffness()  # diagonal scale of the regularisation (free DOFs)
        self.safeguarded = False  # Newton's safeguarded mode (``safeguard``)
        # Terms that bound a step (obstacles: the first contact along it).
        self._limits = [t for t in system.terms if t.bounds_step]
        self.capped_by: Term | None = None  # the term whose first contact ended max_step's
        self._dx = np.zeros_like(self.force)  # a step of the free DOFs as (N, 3)
        self._g = np.empty(system.n_free)
        self._shift = np.empty(system.n_free)
        # A time step's potential keeps the internal terms' gradient and energies of its
        # last evaluation (``internal``: its floor test, rest test and energy balance read
        # them at the state Newton ended on); a static one, whose tests come rarely, does
        # not copy them at every evaluation.
        self._keeps = bool(self.steps)
        size = self.force.shape if self._keeps else (0, 3)
        self._seen: tuple[np.ndarray, np.ndarray, list[float], int] = (
            np.full(size, np.nan),
            np.zeros(size),
            [],
            -1,
        )
        _new_generation()

    def set_force(self, force: np.ndarray) -> None:
        """Replaces the external force (N, 3) in place: a time-varying load's value at a
        time step, without rebuilding the potential (the pattern and solver stay)."""
        _new_generation()  # (its callers set the load-like terms' factor with it)
        external = ExternalForce(force)
        self.force = external.force
        self.f_free = self.system.restrict(external.flat)
        self.f_norm = external.norm
        self.external = external if self.f_norm > 0 else None

    def begin_step(
        self, x: np.ndarray, time: float | None = None, start: float | None = None
    ) -> None:
        """Tells every term a new load step (``time`` None) or time step (from ``start``,
        the time of x, to ``time``) starts from the accepted state x (``Term.begin_step``)."""
        _new_generation()
        for term in (*self.system.terms, *self.steps):
            term.begin_step(x, time, start)

    def with_system(self, system: System) -> Potential:
        """The same loads and step terms on other internal terms of the same pattern."""
        return Potential(system, self.solver, self.force, self.steps)

    def free(self, x: np.ndarray) -> np.ndarray:
        return x.reshape(-1)[self.system.free_dofs]

    def max_step(self, x: np.ndarray, dy: np.ndarray, upto: float = math.inf) -> float:
        """The largest multiple of the step dy (free DOFs) from x that keeps every node
        outside every obstacle (inf when there are none); ``upto``: no multiple beyond it
        is asked for, so terms whose search grows with the distance (``horizon``) stop
        there (inf: no contact up to ``upto``). ``capped_by``: the term that gave it."""
        self.capped_by = None
        if not self._limits:
            return math.inf
        self._dx.reshape(-1)[self.system.free_dofs] = dy
        cap = math.inf
        for term in self._limits:
            step = term.max_step_within(x, self._dx, upto)
            if step < cap:
                cap, self.capped_by = step, term
        return cap

    def toward(self, x: np.ndarray, target: np.ndarray, share: float = 0.9) -> np.ndarray:
        """``target`` if the straight path of the free nodes from x to it keeps every node
        outside every obstacle, else their point ``share`` of the way to the first contact
        (supports stay where ``target`` puts them)."""
        if not self._limits:
            return target
        dx = target - x
        t = min(o.max_step_within(x, dx, 2.0) for o in self._limits)
        if t > 1.0:
            return target
        out = target.copy()
        free = self.system.free.reshape(-1, 3)
        out[free] = x[free] + share * t * dx[free]
        return out

    def evaluate(self, x: np.ndarray) -> Evaluation:
        """Phi, grad Phi (free DOFs), the load scale, the gradient's round-off floor and
        the round-off level of Phi at x (``Evaluation``).

        The load scale is the larger of |f| and |internal force| (supports included).
        The floor adds the round-off of every term: forces of size |f| and |internal|,
        and the strains' (coordinates of size |x| carry an error eps |x|, which each edge
        turns into a force error EA eps |x| / l0 at both of its nodes)."""
        energy, grad = self.system.gradient(x)
        if self._keeps:
            seen_x, seen_grad, seen_energies, _ = self._seen
            np.copyto(seen_x, x)
            np.copyto(seen_grad, grad)
            seen_energies[:] = self.system.energies
            self._seen = (seen_x, seen_grad, seen_energies, _generation)
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
        if self.system.guided is not None:  # rollers, sliders: their free directions
            self.system.guided.project(g)
        scale = max(self.f_norm, internal)
        floor *= 4.0 * EPS
        phi_scale *= 64.0 * EPS
        return Evaluation(phi, g, scale, floor, phi_scale, float(norm(g)))

    def internal(self, x: np.ndarray) -> tuple[np.ndarray, list[float]]:
        """The internal terms' gradient (N, 3) at x and their energies: a time step's
        last evaluation's where it was at this very x and no term has begun a step or been
        given a factor since (the same numbers), else computed (arrays to read, not keep)."""
        seen_x, seen_grad, seen_energies, generation = self._seen
        if generation == _generation and seen_x.shape == x.shape and np.array_equal(seen_x, x):
            return seen_grad, seen_energies
        _, grad = self.system.gradient(x)
        return grad, self.system.energies

    def floor_levels(self, x: np.ndarray, steps: bool = True) -> np.ndarray:
        """Per free DOF, the round-off floor of the residual at x [N]: FLOOR_SAFETY eps of
        the forces that meet there: the edges' |N| + EA |x| / l0 (``Stretch.node_roundoff``),
        every other term's round-off on its own nodes (``Term.node_roundoff``: a free
        body's stiff rigidity counts on the body alone), the net internal force and the
        load. ``steps=False``: the static residual's floor (a time step's inertia left out)."""
        system = self.system
        free = system.free_dofs
        grad, energies = self.internal(x)
        nodes = np.zeros(x.shape[0])
        stiff = np.zeros(x.shape[0])
        for term, e in zip(system.terms, energies, strict=True):
            if (level := term.node_roundoff(x, e)) is not None:
                nodes += level
            if term.barrier and (level := term.stiff_roundoff(x)) is not None:
                stiff += level
        if stiff.any():  # within STIFF_SHARE of the structure's largest force
            cap = STIFF_SHARE / (FLOOR_SAFETY * EPS) * self._structure_force(x)
            nodes += np.minimum(stiff, cap)
        forces = 2.0 * np.abs(grad.reshape(-1)[free]) + np.abs(self.f_free)
        for term in self.steps if steps else ():  # a time step's inertia
            force = np.zeros_like(x)
            e = term.gradient(x, force)
            forces += 2.0 * np.abs(force.reshape(-1)[free])
            if (level := term.node_roundoff(x, e)) is not None:
                nodes += level
        floor: np.ndarray = np.repeat(nodes, 3)[free] + forces
        floor *= FLOOR_SAFETY * EPS
        return floor

    def _structure_force(self, x: np.ndarray) -> float:
        """The largest force the structure itself carries [N]: an edge's axial force or
        a node's applied load."""
        load = float(np.max(np.abs(self.f_free), initial=0.0))
        if not self.system.net.n_edges:
            return load
        return max(load, float(np.max(np.abs(self.system.stretch.tension(x)))))

    def at_floor(
        self,
        x: np.ndarray,
        g: np.ndarray,
        steps: bool = True,
        target: float = 0.0,
        factor: float = 1.0,
    ) -> float | None:
        """Whether the residual g (free DOFs) at x is converged DOF by DOF: the part of
        each DOF's residual above its round-off floor (``floor_levels``, times ``factor``),
        in norm, is within ``target`` (the tolerance the loads ask for; 0: every DOF
        within its floor). Returns the tolerance the state then meets, ``target`` + the
        floor's norm (|g| is below it), or None."""
        floor = self.floor_levels(x, steps) * factor
        excess = np.maximum(np.abs(g) - floor, 0.0)
        if float(np.linalg.norm(excess)) > target:
            return None
        return target + float(np.linalg.norm(floor))

    # --- Newton's safeguarded mode (catenet.solver.newton) ---------------------------------
    def safeguard(self, on: bool) -> None:
        """Turns the terms' safeguarded mode on or off (``Term.safeguard``: the stretching holds
        near-slack edges in Newton's model, a free body's contact projects its blocks)."""
        self.safeguarded = on
        for term in self.system.terms:
            term.safeguard(on)

    def model_rhs(self, x: np.ndarray, g: np.ndarray) -> np.ndarray:
        """The right-hand side of Newton's model at x, whose gradient is g: -g, and while
        safeguarded the held edges' pull (``Stretch.model_gradient``)."""
        if not self.safeguarded:
            return -g
        pull = np.zeros_like(x)
        if self.system.stretch.model_gradient(x, pull) == 0:
            return -g
        rhs: np.ndarray = -(g + self.system.restrict(pull.reshape(-1)))
        return rhs

    def release(self, x: np.ndarray, dy: np.ndarray) -> int:
        """While safeguarded: releases the held edges Newton's step dy shortens."""
        if not self.safeguarded:
            return 0
        self._dx.reshape(-1)[self.system.free_dofs] = dy
        return self.system.stretch.release(x, self._dx)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """The factorised matrix's solution for ``rhs`` (free DOFs), a guided node's in
        its free directions (``catenet.solver.guided``: the held part is zero but for
        round-off, which no step then carries into the constraint)."""
        dy: np.ndarray = self.solver.solve(rhs)
        if self.system.guided is not None:
            self.system.guided.project(dy)
        return dy

    def factorize(self, x: np.ndarray, c: float) -> None:
        """Fills J + c D at x and factorises it (safeguarded: with the edges held at x)."""
        if self.safeguarded:
            self.system.stretch.hold(x)
        shift = np.multiply(c, self.D, out=self._shift) if c > 0 else None
        data = self.system.hessian(x, shift, self.steps)
        # Cholesky while no non-convex term (an obstacle out of reach) contributes.
        self.solver.factorize(data, definite=self.system.convex)


def generation() -> int:
    """The present generation (``_new_generation``): results at a given x computed in it
    stand while it lasts."""
    return _generation


def _new_generation() -> None:
    """A term's state may change (a new step begins, a new potential sets the load-like
    terms' factor): evaluations cached before it no longer stand (``Potential.internal``)."""
    global _generation
    _generation += 1
