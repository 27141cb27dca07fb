"""The tangent stiffness of a system at a state and its verdict, decided the same way on
every machine (``catenet.solver.stability``'s module docstring says how): "stable",
"unstable" or "neutral" against the margins MARGIN and POSITIVE on the eigenvalues of
S K S (S = D^(-1/2), D the diagonal's scale), dense up to DENSE free DOFs, else by the
inertia of the symmetric-indefinite factorisation.

``kept_tangent`` keeps it for the last two states asked while no term's state changed
(``catenet.solver.potential.generation``): a load step's end is judged by its static
solve (``endstate._stable``) and again by the load path (``PathJudge``), and one dense
eigen-decomposition serves both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import SingularSystemError
from catenet.solver.potential import generation

if TYPE_CHECKING:
    from catenet.solver.linear import LinearSolver
    from catenet.solver.system import System

STABLE, UNSTABLE, NEUTRAL = "stable", "unstable", "neutral"

MARGIN = 1e-11  # eigenvalues of S K S below -MARGIN are unstable (S = D^(-1/2)) ...
POSITIVE = 1e-13  # ... above +POSITIVE stable, between them neutral
DENSE = 900  # free DOFs up to which the verdict takes the dense eigenvalues
SUBSET_FROM = 300  # free DOFs from which it computes the least eigenpairs alone ...
ZERO_MODES = 8  # ... this many (the zero modes of a neutral state among them)


@dataclass
class Tangent:
    """The tangent stiffness of a system at x on its free DOFs, and what it says."""

    verdict: str  # STABLE, UNSTABLE or NEUTRAL
    least: float  # the least eigenvalue of S K S (nan where the inertia decided)
    mode: np.ndarray | None  # (N, 3) the least mode (dense only), else None
    # the least eigenvalues of S K S (dense only: all, or the ZERO_MODES least) and their
    # displacements (free DOFs, k)
    lam: np.ndarray | None = None
    vecs: np.ndarray | None = None

    def low(self, cut: float) -> tuple[np.ndarray | None, bool]:
        """The displacements of the eigenvalues at or below ``cut`` (None: not known),
        and whether they are all of them (else only those among the least computed)."""
        if self.lam is None or self.vecs is None:
            return None, True
        below = self.lam <= cut
        return self.vecs[:, below], not (below.all() and len(self.lam) < self.vecs.shape[0])

    @property
    def zero(self) -> np.ndarray | None:
        return self.low(POSITIVE)[0]

    @property
    def all_zero(self) -> bool:
        return self.low(POSITIVE)[1]


def _scale(system: System) -> np.ndarray:
    d = np.abs(system.stiffness())
    top = float(d.max()) if d.size else 1.0
    scale: np.ndarray = np.maximum(d, 1e-12 * max(top, 1e-300))
    return scale


def tangent(system: System, solver: LinearSolver, x: np.ndarray) -> Tangent:
    """The tangent of ``system`` at x (``solver``: the workspace's linear solver, for the
    inertia of large systems)."""
    x = np.asarray(x, dtype=np.float64)
    d = _scale(system)
    n = system.n_free
    if n == 0:
        return Tangent(STABLE, math.inf, None)
    if n <= DENSE:
        return _dense(system, x, d)
    return _sparse(system, solver, x, d)


def kept_tangent(system: System, solver: LinearSolver, x: np.ndarray) -> Tangent:
    """``tangent``, the same one for the same state while no term's state changed through
    a potential (module docstring); for the load path's solves, whose terms change only
    so (a caller that sets a term's state itself asks ``tangent``)."""
    x = np.asarray(x, dtype=np.float64)
    key = (id(system), generation())
    for seen, at, found in _KEPT:
        if seen == key and np.array_equal(at, x):
            return found
    found = tangent(system, solver, x)
    _KEPT[:] = [(key, x.copy(), found), *_KEPT[:1]]
    return found


_KEPT: list[tuple[tuple[int, int], np.ndarray, Tangent]] = []  # the last two (``kept_tangent``)


def definite(system: System, x: np.ndarray, solver: LinearSolver | None = None) -> bool:
    """Whether the tangent at x is STABLE (S K S - POSITIVE I positive definite), by one
    Cholesky factorisation: the band's where ``solver`` is the bordered band (a fraction
    of a millisecond), else dense (up to DENSE free DOFs; 13 ms at 615 DOF, the
    eigenvalues' 36). For a net whose stiffness cannot be negative: its end state is
    checked for a mode without stiffness, whose eigenvalues are computed only where this
    fails."""
    d = _scale(system)
    s = 1.0 / np.sqrt(d)
    data = system.hessian(np.asarray(x, dtype=np.float64)).copy()
    rows = np.repeat(np.arange(system.n_free), np.diff(system.indptr))
    data *= s[rows] * s[system.indices]
    data[system.diag_pos] -= POSITIVE
    if not np.all(np.isfinite(data)):
        return False
    band = getattr(solver, "positive_definite", None)  # (the bordered band's own test)
    if band is not None:
        return bool(band(data))
    a = system.dense(data)
    try:
        np.linalg.cholesky(a)
    except np.linalg.LinAlgError:
        return False
    return True


def _dense(system: System, x: np.ndarray, d: np.ndarray) -> Tangent:
    k = system.dense(system.hessian(x).copy())
    s = 1.0 / np.sqrt(d)
    a = k * s[:, None] * s[None, :]
    a = 0.5 * (a + a.T)
    if not np.all(np.isfinite(a)):
        return Tangent(NEUTRAL, math.nan, None)
    if len(a) >= SUBSET_FROM:
        # The least eigenpairs alone (LAPACK's MRRR, dsyevr): a third of the full
        # decomposition's time, the same pairs to round-off.
        from scipy.linalg import eigh

        last = min(ZERO_MODES, len(a)) - 1
        lam, vec = eigh(a, subset_by_index=[0, last], driver="evr", check_finite=False)
    else:  # (below, importing scipy.linalg costs more than it saves)
        lam, vec = np.linalg.eigh(a)
    least = float(lam[0])
    verdict = STABLE if least > POSITIVE else UNSTABLE if least < -MARGIN else NEUTRAL
    mode = np.zeros(system.net.n_nodes * 3)
    mode[system.free_dofs] = s * vec[:, 0]
    return Tangent(verdict, least, mode.reshape(-1, 3), lam, s[:, None] * vec)


def _sparse(system: System, solver: LinearSolver, x: np.ndarray, d: np.ndarray) -> Tangent:
    """The inertia of K + MARGIN D (negative: unstable) and of K - POSITIVE D (none
    negative: stable), where the factorisation tells; else NEUTRAL (cannot say)."""
    if solver.mtype != -2:  # only PARDISO's symmetric indefinite factors tell here
        return Tangent(NEUTRAL, math.nan, None)

    def negatives(shift: float) -> int | None:
        data = system.hessian(x, shift * d)
        try:
            solver.factorize(data, definite=False)
        except SingularSystemError:
            return None
        return solver.negative_eigenvalues()

    above = negatives(+MARGIN)
    if above is None:
        return Tangent(NEUTRAL, math.nan, None)
    if above > 0:
        return Tangent(UNSTABLE, math.nan, None)
    below = negatives(-POSITIVE)
    if below != 0:
        return Tangent(NEUTRAL, math.nan, None)
    return Tangent(STABLE, math.nan, None)
