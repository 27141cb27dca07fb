"""The net never passes through itself: a barrier between strands that share no node.

Every pair of edges that share no node, closer than the activation distance ``dhat``,
stores kappa b(D) on their squared distance D, mollified where they are nearly parallel
(``catenet.kernels.strands`` has the distance, its exact derivatives and why they are
C1). Adjacent edges (sharing a node) are the strand's own bends and feel nothing.

Guarantee: no two strands cross, at any step size. The energy is infinite at zero
distance, and every Newton line search (and the predictor of a time step) is capped at
``max_step``:

- the candidate pairs, gathered at the start of each time step (``begin_step``) by a
  uniform grid, are the pairs within dhat + R_a + R_b, R_e the radius of the edge's
  nodes; within the step, additive continuous collision detection (Li, Kaufman and
  Jiang 2021) keeps each of them apart along every straight step the solver tries;
- every node's motion from the step's start, relative to the mean motion of the net,
  stays within its radius, so a pair that was not a candidate stays farther apart than
  dhat: the barrier, which acts on candidates only, is the whole energy, and no other
  pair can meet.

The radii follow the motion: a node's radius is ``reach`` (a tenth of the shortest
edge, at least dhat) plus twice its relative motion in the last step; a step that is
tried again (it failed) after they held its last Newton step back doubles them. The cost grows
with the close pairs, not with the square of the edges.

The Hessian's sparsity pattern holds the 12x12 blocks of the pairs that were
candidates: when a step's candidates include new pairs, the pattern grows (``grows``,
``grew``) and the time stepping rebuilds the system and the linear solver's analysis
(``catenet.solver.workspace.Workspace.refresh``); otherwise nothing is rebuilt. Past
pairs stay in it (no rebuild when they come back) until they outnumber PATTERN_SLACK
times the candidates: then the pattern starts anew from the candidates. So the
term is for dynamic runs: a static solve refuses it (``catenet.case.sections``).
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.ccd import strand_max_step
from catenet.kernels.contact import barrier
from catenet.kernels.strands import candidates, sqdist, strand_gradient, strand_hessian
from catenet.terms.base import Term, register

#: The largest multiple of a Newton step the cap checks (longer ones are refused).
STEP_CHECKED = 4.0
#: A node's smallest radius, relative to the shortest edge (at least dhat).
REACH_SHARE = 0.1
#: The pattern keeps past pairs until they outnumber this many times the candidates.
PATTERN_SLACK = 4


def default_strand_stiffness(force: float, dhat: float) -> float:
    """kappa [N/m^3] at which two strands dhat/2 apart push each other with ``force``:
    kappa |b'(D)| 2 d = force at d = dhat/2, D = d^2, on the barrier of D_hat = dhat^2."""
    d = 0.5 * dhat
    _, db, _ = barrier(d * d, dhat * dhat)
    return max(force, 1e-300) / (2.0 * d * abs(db))


@register("self_contact")
class SelfContact(Term):
    """The barrier between the net's edges that share no node (see the module
    docstring): stiffness ``kappa`` [N/m^3] on squared distances, activation distance
    ``dhat`` [m]; the candidate pairs at the positions ``x`` (default: the net's). With a
    contact ``radius`` r > 0 (``solver.edge_contact``) each edge is a capsule: the barrier
    acts on the gap d - 2 r (kappa then in N/m, ``default_stiffness``)."""

    bounds_step = True
    barrier = True  # its stiffness in the round-off floor (Term.stiff_roundoff)
    grows = True
    dynamic_only = True
    convex = False
    role = "internal"

    def __init__(
        self, net, *, kappa: float, dhat: float, x: np.ndarray | None = None, radius: float = 0.0
    ):
        if not (math.isfinite(kappa) and kappa > 0 and math.isfinite(dhat) and dhat > 0):
            raise ValueError(f"self_contact: kappa = {kappa!r}, dhat = {dhat!r}: must be > 0")
        if not (math.isfinite(radius) and radius >= 0):
            raise ValueError(f"self_contact: radius = {radius!r}: must be >= 0")
        self.kappa, self.dhat = float(kappa), float(dhat)
        self.gap_r = 2.0 * float(radius)  # > 0: on the gap d - 2 radius (capsules)
        self._r = self.gap_r if radius > 0 else -1.0  # the kernels' r (< 0: squared distance)
        self.edges = np.ascontiguousarray(net.edges, dtype=np.int64)
        self.rest = np.ascontiguousarray(net.rest_length, dtype=np.float64)
        self.nodes = np.unique(self.edges)
        self.reach = max(REACH_SHARE * float(self.rest.min()), self.dhat)
        self.radius = np.zeros(net.n_nodes)
        self.radius[self.nodes] = self.reach
        self.known = np.zeros((0, 2), dtype=np.int64)  # the pattern's pairs, never fewer
        self._slot: dict[tuple[int, int], int] = {}
        self.pairs = self.known  # this step's candidates
        self.slots = np.zeros(0, dtype=np.int64)
        self.base: np.ndarray | None = None  # the positions the candidates were found at
        self.grew = False
        self.held = False  # the radii cut the last step asked about short
        self._gather(net.nodes if x is None else np.asarray(x, dtype=np.float64))
        self.base = None

    # --- candidates --------------------------------------------------------------------
    def begin_step(self, x, time, start=None) -> None:
        """The candidates of the step from x: radii from the last step's motion (doubled
        when the same step is tried again)."""
        if self.base is not None:
            if np.array_equal(x, self.base):
                if self.held:  # the step failed where the radii held it back: wider
                    self.radius[self.nodes] *= 2.0
            else:
                moved = x[self.nodes] - self.base[self.nodes]
                moved -= moved.mean(axis=0)
                self.radius[self.nodes] = self.reach + 2.0 * np.linalg.norm(moved, axis=1)
        self.held = False
        self._gather(x)

    def _gather(self, x: np.ndarray) -> None:
        edge_radius = np.maximum(self.radius[self.edges[:, 0]], self.radius[self.edges[:, 1]])
        pairs = candidates(x, self.edges, edge_radius, self.dhat + self.gap_r)
        if len(self.known) > PATTERN_SLACK * max(len(pairs), 32):  # mostly stale: start anew
            self.known = np.zeros((0, 2), dtype=np.int64)
            self._slot = {}
            self.grew = True  # changed: the system is rebuilt all the same
        slots = np.empty(len(pairs), dtype=np.int64)
        new: list = []
        for k, (a, b) in enumerate(pairs.tolist()):
            slot = self._slot.get((a, b))
            if slot is None:
                slot = self._slot[(a, b)] = len(self.known) + len(new)
                new.append((a, b))
            slots[k] = slot
        if new:
            self.known = np.concatenate([self.known, np.array(new, dtype=np.int64)])
            self.grew = True
        self.pairs, self.slots = pairs, slots
        self.base = np.array(x, dtype=np.float64, copy=True)

    # --- energy ------------------------------------------------------------------------
    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """The 12x12 blocks (points a0 a1 b0 b1, row-major) of every known pair."""
        quad = np.concatenate([self.edges[self.known[:, 0]], self.edges[self.known[:, 1]]], axis=1)
        dofs = (3 * quad[:, :, None] + np.arange(3)).reshape(len(quad), 12)
        rows = np.repeat(dofs, 12, axis=1).ravel()
        cols = np.tile(dofs, (1, 12)).ravel()
        return rows, cols

    def gradient(self, x, grad) -> float:
        args = (x, self.edges, self.rest, self.pairs, self.dhat, self.kappa, grad, self._r)
        return strand_gradient(*args)

    def hessian(self, x, values) -> bool:
        if values.size != 144 * len(self.known):
            raise RuntimeError(
                "self_contact: the pattern grew since the system was built: "
                "Workspace.refresh() rebuilds it"
            )
        args = (x, self.edges, self.rest, self.pairs, self.slots, self.dhat, self.kappa, values)
        return strand_hessian(*args, self._r) > 0

    def max_step(self, x, dx) -> float:
        base = x if self.base is None else self.base
        args = (x, dx, base, self.nodes, self.radius, self.edges, self.pairs, STEP_CHECKED)
        t, moved = strand_max_step(*args, self.gap_r)
        self.held = moved < 1.0  # the last step asked about (as a free body's contact)
        return t

    def distances(self, x: np.ndarray, reach: float | None = None) -> np.ndarray:
        """The distances [m] of the strands closer than ``reach`` (default: dhat) at x
        (N, 3), pairs of edges that share no node, ascending (found by the grid)."""
        reach = self.dhat if reach is None else float(reach)
        x = np.ascontiguousarray(x, dtype=np.float64)
        pairs = candidates(x, self.edges, np.zeros(len(self.edges)), reach)
        out = np.empty(len(pairs))
        g, h = np.empty(12), np.empty((12, 12))
        for k, (a, b) in enumerate(pairs.tolist()):
            p = x[[*self.edges[a], *self.edges[b]]].ravel()
            out[k] = math.sqrt(sqdist(p, 0, g, h, False))
        return np.sort(out)
