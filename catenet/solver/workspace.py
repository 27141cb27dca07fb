"""A net's workspace: its energy terms' system (pattern once) and its linear solver
(symbolic analysis once), shared by every solve on that net."""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import Loads, Net
from catenet.solver.linear import LinearSolver, PardisoSolver, make_solver
from catenet.solver.potential import Potential
from catenet.solver.result import SolverStats
from catenet.solver.system import System
from catenet.terms import Stretch, Term


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
        all_terms = (Stretch(net), *support_terms(net), *terms)
        self._small = mtype is None  # a PARDISO type asked for: PARDISO, never the band
        if mtype is None:  # Cholesky where the matrices are positive (semi)definite
            mtype = 2 if all(t.convex for t in all_terms) else -2
        upper = mtype != 11
        self.net = net
        start = time.perf_counter()
        self.system = System(net, all_terms, upper=upper)
        self._linear = (linear, upper, np.flatnonzero(~net.fixed).repeat(3), mtype)
        self.solver: LinearSolver = self._make_solver()
        self.setup_seconds = time.perf_counter() - start

    def _make_solver(self) -> LinearSolver:
        linear, upper, dof_node, mtype = self._linear
        system = self.system
        solver = make_solver(
            linear, system.indptr, system.indices, upper=upper, dof_node=dof_node, mtype=mtype
        )
        if linear != "auto" or not self._small or not isinstance(solver, PardisoSolver):
            return solver
        from catenet.solver.banded import small_solver  # below a measured size, a band

        return small_solver(
            system.indptr, system.indices, upper=upper, dof_node=dof_node, fallback=solver
        )

    def refresh(self, *potentials: Potential) -> bool:
        """After a time step's ``begin_step``: when a term's pattern grew (``Term.grows``:
        self-contact's new candidate pairs), rebuilds the system's pattern and the linear
        solver (a new symbolic analysis), and points the ``potentials`` at the new
        solver; whether it did, or changed a potential. The solver's counts and times go
        on from the old one's. A potential on a view of the system (a run to rest's
        continuation stage: ``System.with_terms``) built before the last rebuild gets a
        view of the new pattern: its Hessian did not fit (a run to rest of two crossing
        wires with self-contact stopped with an internal error)."""
        rebuilt = self.system.refresh()
        if rebuilt:
            old = self.solver
            start = time.perf_counter()
            self.solver = self._make_solver()
            self.setup_seconds += time.perf_counter() - start
            for name, count in old.stats.items():
                self.solver.stats[name] = self.solver.stats.get(name, 0) + count
            for name, seconds in old.seconds.items():
                self.solver.seconds[name] = self.solver.seconds.get(name, 0.0) + seconds
            old.release()
        changed = rebuilt
        for potential in potentials:
            if potential.system.builds != self.system.builds:  # a view of an older pattern
                potential.system = self.system.with_terms(potential.system.terms)
                changed = True
            if potential.solver is not self.solver:
                potential.solver = self.solver
                changed = True
        return changed

    def potential(self, loads: Loads, factor: float = 1.0, steps: Sequence[Term] = ()) -> Potential:
        """The potential of the loads at ``factor`` (and of a time step's ``steps`` terms)."""
        force = loads.external_force(self.net, factor)
        for term in self.system.terms:
            if term.loadlike:  # load-like terms (water) follow the load factor
                term.set_factor(factor * (loads.weight_scale() if term.weighs else 1.0))
        return Potential(self.system, self.solver, force, steps)

    def stats(self) -> SolverStats:
        """What the solves on this workspace have cost so far."""
        s = self.solver
        return SolverStats(
            backend=s.name,
            dofs=self.system.n_free,
            nnz=self.system.nnz,
            analyse_count=s.stats["analyse"],
            factorize_count=s.stats["factorize"],
            solve_count=s.stats["solve"],
            refine_count=s.stats.get("refine", 0),
            analyse_seconds=s.seconds["analyse"],
            factorize_seconds=s.seconds["factorize"],
            solve_seconds=s.seconds["solve"],
            assembly_seconds=self.system.seconds,
            setup_seconds=self.setup_seconds,
        )


def support_terms(net: Net) -> tuple[Term, ...]:
    """The terms of a net's elastic supports (``Net.springs``: translational springs, rod
    ends on 6x6 springs), every solve's."""
    springs = net.springs
    if springs is None:
        return ()
    out: list[Term] = []
    if springs.nodes.size:
        from catenet.terms.supports import ElasticSupport

        out.append(ElasticSupport(net))
    if springs.ends is not None:
        from catenet.terms.rodends import RodEndSupport

        out.append(RodEndSupport(springs.ends, net.nodes, net.n_nodes))
    return tuple(out)


def check_rtol(rtol: float) -> None:
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise ConfigError(f"solver.rtol = {rtol!r}: must be in (0, 1)")
