"""Where a static solve starts: the given or reference positions with the supports in
place (the free nodes carried along by moved supports: ``HarmonicExtension``), for
an unstressed net under loads, the stretched start (``stretched_start``), for a
prestressed net among obstacles, a direct solve before any continuation
(``direct_solve``), and what the tension-only detour of a compressed start asks
(``compressed_bilateral``, ``definite``, ``turned_over``)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConfigError, SingularSystemError
from catenet.model.measures import strain
from catenet.model.net import Loads, Net
from catenet.solver.newton import NewtonResult, solve_newton
from catenet.solver.potential import Potential
from catenet.solver.stability import FLIP
from catenet.terms.stretch import Springs, Stretch


def start_state(net: Net, loads: Loads, x0: ArrayLike | None, factor: float) -> np.ndarray:
    """The starting guess: x0 (or the reference positions) with the supports put in place.
    Where supports move, the free nodes follow them by the harmonic extension of the
    support displacement, so no edge starts out stretched many times its length."""
    if x0 is None:
        x = net.nodes.copy()
    else:
        x = np.array(x0, dtype=np.float64, copy=True)
        if x.shape != net.nodes.shape or not np.all(np.isfinite(x)):
            raise ConfigError(f"x0: shape {x.shape}: must be finite with shape {net.nodes.shape}")
    target = loads.support_positions(net, factor=factor)
    if loads.moves_supports:
        x += harmonic_extension(net, target - x[net.fixed])
    x[net.fixed] = target
    if net.guides is not None:  # rollers and sliders: on their guides
        net.guides.place(x, net.nodes)
    return x


class HarmonicExtension:
    """Displacements of the free nodes that follow given support displacements: at every
    free node the average of its neighbours' (weights 1/l0), the solution of a graph-
    Laplacian system factorised once per net. Moved supports carry the net with them
    instead of running over their neighbours. A free node that no chain of edges joins
    to a support (a free body's frame, a ball, a loose piece of net) does not follow."""

    def __init__(self, net: Net):
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components
        from scipy.sparse.linalg import splu

        n = net.n_nodes
        i, j = net.edges[:, 0], net.edges[:, 1]
        w = 1.0 / net.rest_length
        lap = sp.coo_matrix(
            (
                np.concatenate([w, w, -w, -w]),
                (np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i])),
            ),
            shape=(n, n),
        ).tocsr()
        self.net = net
        _, part = connected_components(lap, directed=False)
        held = np.zeros(part.max(initial=-1) + 1, dtype=bool)
        held[part[net.fixed]] = True
        self.free = ~net.fixed & held[part]  # the free nodes a support's chain reaches
        self._coupling = lap[self.free][:, net.fixed].tocsr()
        self._lu = splu(lap[self.free][:, self.free].tocsc()) if self.free.any() else None

    def __call__(self, support_shift: np.ndarray) -> np.ndarray:
        """Displacement (N, 3): ``support_shift`` (K, 3) at the fixed nodes."""
        u = np.zeros((self.net.n_nodes, 3))
        u[self.net.fixed] = support_shift
        if self._lu is not None and np.any(support_shift):
            u[self.free] = self._lu.solve(-(self._coupling @ support_shift))
        return u


def harmonic_extension(net: Net, support_shift: np.ndarray) -> np.ndarray:
    """The displacement (N, 3) of HarmonicExtension for one support shift."""
    return HarmonicExtension(net)(support_shift)


UNSTRESSED = 1e-12  # a start whose strains are all below this carries no tension
STRETCH_RTOL = 1e-3  # the stretched start's scale is found to this relative width


def unstressed(net: Net, x: np.ndarray) -> bool:
    """Whether no edge is strained at x (a flat net, a straight cable at its rest
    length): the stiffness has no transverse part and Newton must find one."""
    return bool(np.all(np.abs(strain(net, x)) <= UNSTRESSED))


def stretched_start(potential: Potential, x: np.ndarray) -> None:
    """Moves the free nodes of an unstressed net (x, in place) along the displacement u
    of a net of linear springs q = 1/l0 under the loads (the force density method's; one
    solve with the net's own factorisation, ``terms.stretch.Springs``), to the point
    x + s u where the potential is least along that ray (a convex function of s for a
    tension-only net: bisection on its slope). Every edge the move lengthens is taut
    there, so Newton starts with a transverse stiffness it would otherwise grow step by
    step from the flat start, and takes a number of iterations that hardly grows with
    refinement (the paper's n = 34 net: 7, 10 and 12 at 1 cm, 1 mm and 0.2 mm edges,
    where the flat start took 11, 14 and more than 600). Edges the move hardly
    lengthened (near the supports) are still soft across, so that Newton begins with a
    small Levenberg-Marquardt shift (``newton.solve_newton(shifted=True)``)."""
    net = potential.system.net
    u = np.zeros_like(x)
    springs = potential.with_system(
        potential.system.with_terms(
            [Springs(net, 1.0 / net.rest_length), *(t for t in potential.system.terms if t.holds)]
        )
    )
    try:
        springs.factorize(x, 0.0)
        u.reshape(-1)[potential.system.free_dofs] = springs.solve(springs.f_free)
    except SingularSystemError:
        return  # a part without support: the usual path says so
    if not np.all(np.isfinite(u)):
        return
    largest = float(np.max(np.abs(u), initial=0.0))  # no squares: no overflow
    extent = float(np.max(np.ptp(net.nodes, axis=0)))
    if not (largest > 0.0 and math.isfinite(extent) and extent > 0.0):
        return
    u *= extent / largest  # s = 1 moves the farthest node by the net's extent
    u_free = u.reshape(-1)[potential.system.free_dofs]
    x0 = x.copy()

    def slope(s: float) -> float:
        np.add(x0, s * u, out=x)
        g = potential.evaluate(x).g
        return float(np.dot(g, u_free))

    lo, hi = 0.0, 1e-6
    for _ in range(60):  # the slope is negative at 0 (the loads pull along u)
        if not slope(hi) < 0.0:
            break
        lo, hi = hi, 4.0 * hi
    else:
        x[:] = x0
        return
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if slope(mid) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= STRETCH_RTOL * hi:
            break
    np.add(x0, hi * u, out=x)


def strain_scale(net: Net, potential: Potential) -> float:
    """The strain the loads can cause at most, |f|_1 / min EA (0 without loads): an
    estimate of how stiff the net is against what acts on it."""
    return float(np.abs(potential.force).sum() / np.min(net.EA))


DIRECT_ITER = 50  # a prestressed net among obstacles is first solved directly, this long


def direct_solve(
    potential: Potential, x: np.ndarray, *, rtol: float, max_iter: int
) -> NewtonResult | None:
    """A prestressed net among obstacles (every edge at x stretched by more than the loads'
    strain scale) solved by Newton from x to the full tolerance in at most DIRECT_ITER
    iterations (x moves there only where it converged); None for other nets, or where
    the system turned singular. Its tension, not its axial stiffness, holds its
    rotations, so Newton's model holds without the stiffness continuation
    (``catenet.solver.static.equilibrium``), whose soft stages would let it sag (the
    prestress scaled with EA) onto obstacles it never reaches."""
    system = potential.system
    strains = strain(system.net, x)
    if not any(t.bounds_step for t in system.terms) or not (
        strains.size and float(np.min(strains)) > strain_scale(system.net, potential)
    ):
        return None
    y = x.copy()
    limit = min(max_iter, DIRECT_ITER)
    try:
        result = solve_newton(potential, y, rtol=rtol, max_iter=limit, label="static (direct)")
    except SingularSystemError:
        return None
    if result.converged:
        x[:] = y
    return result


def predict(states: Sequence[np.ndarray], levels: Sequence[float], level: float) -> np.ndarray:
    """The equilibrium at load level ``level`` extrapolated by the Lagrange polynomial
    through the given equilibria (two: a secant, three: a parabola) at their levels.
    Levels must be distinct; with one state it is returned as it is."""
    if len(states) != len(levels):
        raise ValueError("predict: one level per state")
    if len(set(levels)) != len(levels):
        return np.array(states[-1], copy=True)
    x = np.zeros_like(states[-1])
    for i, (xi, si) in enumerate(zip(states, levels, strict=True)):
        w = 1.0
        for j, sj in enumerate(levels):
            if j != i:
                w *= (level - sj) / (si - sj)
        x += w * xi
    return x


def definite(potential: Potential, x: np.ndarray) -> bool:
    """Whether the stiffness at x is positive definite (False where the solver cannot
    tell: then the caller takes the safe path)."""
    if potential.solver.mtype not in (-2, None):  # PARDISO's Cholesky or LU: cannot tell
        return False
    try:
        potential.factorize(x, 0.0)
    except SingularSystemError:
        return False
    return potential.solver.negative_eigenvalues() == 0


def turned_over(stretch: Stretch, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether some bilateral edge turned beyond FLIP from a to b (over its pin)."""
    edges, bilateral = stretch.net.edges, ~stretch.law.tension_only
    da, db = (np.diff(x[edges[bilateral]], axis=1)[:, 0] for x in (a, b))
    cos = np.einsum("ij,ij->i", da, db) / np.maximum(
        np.linalg.norm(da, axis=1) * np.linalg.norm(db, axis=1), 1e-300
    )
    return bool(np.any(cos < math.cos(FLIP)))


def compressed_bilateral(stretch: Stretch, x: np.ndarray) -> bool:
    """Whether some bilateral edge (not tension-only) is compressed at x."""
    law = stretch.law
    if law.all_tension_only:
        return False
    return bool(np.any((strain(stretch.net, x) < 0.0) & ~law.tension_only))
