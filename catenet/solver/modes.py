"""Natural frequencies and mode shapes of a net about an equilibrium.

Small vibrations u about an equilibrium x obey M u'' + K u = 0 with K the tangent
stiffness at x (the Hessian of the internal terms on the free DOFs: every edge's axial
and geometric blocks, springs, contact) and M the lumped mass (``Net.mass``: rho A l0 / 2
of each edge at each of its ends, conserved as the net stretches, plus point masses and
the bodies' centres). The modes solve K phi = w^2 M phi; f = w / (2 pi).

The tangent is the one the static solver uses at x: a tension-only edge shorter than its
rest length (slack) contributes nothing; an edge at exactly zero strain counts as taut on
its loading branch, with its axial stiffness EA/l0 along itself and no geometric term
(its tension is zero): the one-sided stiffness of a cable that is just straight.

The lowest modes come from the Lanczos method (ARPACK through ``scipy.sparse.linalg.eigsh``)
in shift-invert mode: each Lanczos step applies (K - sigma M)^-1, solved with the net's
own linear solver (``catenet.solver.linear``: PARDISO's factors, else SciPy's), factorised
once and reused for every step. The shift sigma = -SHIFT x s, with s the largest ratio
K_ii / m_i of the diagonals (the scale of the spectrum from above), lies just below zero:

- K - sigma M = K + |sigma| M is positive definite whenever K is positive semidefinite
  (every tension-only net): Cholesky, and no eigenvalue sits on the shift;
- the transformation 1/(w^2 - sigma) spreads the lowest eigenvalues far apart (they
  converge first), while |sigma| M still dominates the round-off of K (eps_mach s m) in
  the directions of a mechanism, so that its zero modes are resolved, not lost in noise.

Zero-frequency modes (w^2 below ZERO x s) are mechanisms, not frequencies: a node that
hangs on slack edges only, a part held by slack edges only, untensioned straight edges.
DOFs with no stiffness at all are taken out before the solve (a stiffness that puts
their dummy modes above every real one), the others are found by the Lanczos method and
asked for again until ``count`` real modes are found; all are named
(``catenet.solver.diagnose.describe_zero_modes``), never returned as tiny frequencies. A
negative eigenvalue (an unstable equilibrium of bilateral edges) raises ConvergenceError
with the unstable nodes named.

The Ritz vectors are refined by one Rayleigh-Ritz step in the M inner product, so the
shapes are M-orthonormal to round-off; each mode's residual is checked.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NoReturn, Protocol

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConfigError, ConvergenceError
from catenet.scene import Scene
from catenet.solver.eigen import dense_modes, lanczos_modes, rayleigh_ritz
from catenet.solver.modal import Operator

if TYPE_CHECKING:
    from catenet.model.net import Loads, Net
    from catenet.model.torsion import Torsion
    from catenet.solver.result import Result
    from catenet.solver.settings import Settings
    from catenet.solver.workspace import Workspace
    from catenet.terms import Term

log = logging.getLogger(__name__)

DENSE = 240  # at most this many free DOFs: a dense eigensolver (and any count)
DENSE_MAX = 4000  # ... and up to this many where too few DOFs carry mass for Lanczos
RESIDUAL_TOL = 1e-6  # largest accepted |K phi - w^2 M phi| / (|K phi| + w^2 |M phi|) ...
#: ... unless within this many times the eigensolver's round-off, n eps (|K| + w^2 |M|)
#: |phi| (the infinity norms of K and M): a low mode of a stiff frame with a heavy mass
#: (axial stiffness 1e10 N/m beside 10 t) sits there at 1e-6 on one processor, 1.3e-6
#: on another.
ROUNDOFF_SAFETY = 100.0
AXES = "xyz"


class Cables(Protocol):
    """A case's cable index (``Scene.cables``): each cable's name and each edge's cable
    (its index in ``names``, -1: none)."""

    @property
    def names(self) -> Sequence[str]: ...

    @property
    def edge(self) -> np.ndarray: ...


@dataclass
class Modes:
    """The lowest natural modes of a net about an equilibrium x.

    frequency : (K,) f [Hz], ascending;  omega2 : (K,) w^2 [1/s^2]
    shape : (K, N, 3) mass-normalised shapes (phi^T M phi = 1) [1/sqrt(kg)], zero at
        the supports; the sign of each shape is fixed so that its largest component is
        positive
    participation : (K, 3) Gamma_kd = phi_k^T M r_d (r_d: a unit translation of every
        free node along axis d) [sqrt(kg)]
    effective_mass : (K, 3) Gamma_kd^2 [kg]: summed over all modes, the free mass
    total_mass : (3,) the mass of the free nodes that moves along each axis [kg]
    zero_modes : how many zero-frequency modes (mechanisms) were found and left out;
        ``zero_nodes`` the nodes that move in them, ``zero_message`` names them ("" if none)
    sigma : the shift [1/s^2];  x : (N, 3) the equilibrium
    stats : method ("lanczos" or "dense"), backend, seconds, solves, factorisations,
        residual (the largest relative residual of a mode)
    mass : (N,) the lumped masses of the free nodes [kg], 0 at the supports
    twist : (K, M) where the rods' twist angles are DOFs (``catenet.model.torsion``):
        each edge's twist angle in the mass-normalised mode [rad/sqrt(kg m^2)], 0 where
        no rod twists (None: no twist angles);  inertia : (M,) each edge's rotational
        inertia rho J_p l0 [kg m^2] (0 where none)
    """

    frequency: np.ndarray
    omega2: np.ndarray
    shape: np.ndarray
    participation: np.ndarray
    effective_mass: np.ndarray
    total_mass: np.ndarray
    x: np.ndarray
    sigma: float = 0.0
    zero_modes: int = 0
    zero_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    zero_message: str = ""
    stats: dict[str, Any] = field(default_factory=dict)
    equilibrium: Result | None = None  # the static Result the modes are about, if solved here
    mass: np.ndarray | None = None  # (N,) lumped masses of the free nodes [kg] (0: supports)
    added: np.ndarray | None = None  # (N, 3, 3) added mass of water of the free nodes [kg]
    twist: np.ndarray | None = None  # (K, M) twist angles [rad/sqrt(kg m^2)]
    inertia: np.ndarray | None = None  # (M,) rotational inertia of each edge [kg m^2]

    def twist_share(self) -> np.ndarray:
        """(K,) each mode's share of its kinetic energy in the rods' twist (sum J theta^2
        of the mass-normalised mode; 0 without twist angles): above 1/2 a torsional
        mode."""
        if self.twist is None or self.inertia is None:
            return np.zeros(self.count)
        share: np.ndarray = np.einsum("e,ke->k", self.inertia, self.twist**2)
        return share

    @property
    def period(self) -> np.ndarray:
        """(K,) periods 1/f [s]."""
        with np.errstate(divide="ignore"):
            return 1.0 / self.frequency

    @property
    def count(self) -> int:
        return int(self.frequency.size)

    def direction_share(self) -> np.ndarray:
        """(K, 3) each mode's kinetic energy share along x, y, z (sum m_i phi_id^2, and
        phi_id (A_i phi_i)_d with an added mass A_i)."""
        share: np.ndarray = np.einsum("n,knd->kd", self._mass(), self.shape**2)
        if self.added is not None:
            share += np.einsum("knd,nde,kne->kd", self.shape, self.added, self.shape)
        return share

    def dominant(self) -> list[str]:
        """Each mode's dominant direction: the axis with the largest kinetic energy share."""
        return [AXES[int(d)] for d in np.argmax(self.direction_share(), axis=1)]

    def node_share(self) -> np.ndarray:
        """(K, N) each node's share of each mode's kinetic energy phi_i^T M_i phi_i (sums
        to 1; M_i = m_i 1 plus any added mass)."""
        share: np.ndarray = self._mass()[None, :] * np.einsum("knd,knd->kn", self.shape, self.shape)
        if self.added is not None:
            share += np.einsum("knd,nde,kne->kn", self.shape, self.added, self.shape)
        return share

    def _mass(self) -> np.ndarray:
        assert self.mass is not None, "natural_modes gives the modes their masses"
        return self.mass


def natural_modes(
    workspace: Workspace,
    x: ArrayLike,
    count: int,
    *,
    mass: ArrayLike | None = None,
    method: str = "auto",
    cables: Cables | None = None,
    added: ArrayLike | None = None,
    torsion: Torsion | None = None,
) -> Modes:
    """The ``count`` lowest natural modes of the workspace's net about the equilibrium x
    (see the module docstring); ``torsion`` (``catenet.model.torsion.Torsion``, a
    scene's): the rods' twist angles as DOFs with their rotational inertia, so that
    torsional modes come out with the others (None: the twist eliminated). ``mass`` (N,)
    [kg] defaults to ``Net.mass``; ``method``: "auto" (dense up to DENSE free DOFs,
    else Lanczos), "dense" or "lanczos";
    ``cables`` (``names``, ``edge``: a case's cable index) names cables in messages;
    ``added`` (E,) [kg]: each edge's added mass of water Ca rho_w A l0, moving with its
    ends sideways only, or (E, 2): sideways and along the edge (ca_n and ca_t's)
    (``catenet.solver.modal.added_mass_blocks``), or None."""
    begin = time.perf_counter()
    system = workspace.system
    net = system.net
    masses = net.mass if mass is None else np.asarray(mass, dtype=np.float64)
    from catenet.solver.modal import body_frames

    bodies = len(body_frames(system))
    held = 0 if net.guides is None else net.guides.held_count  # rollers and sliders
    angles = 0 if torsion is None else torsion.count  # the rods' twist angles
    _check_count(count, system.n_free - 6 * bodies - held + angles)
    if not float(np.sum(masses[~net.fixed])) > 0.0:
        raise ConfigError(
            "modes: the net has no mass (material.density = 0 and no [[mass]]): give "
            "material.density [kg/m^3] or point masses to find its frequencies"
        )
    at = np.asarray(x, dtype=np.float64)
    blocks = None if added is None else _added_blocks(net, at, added)
    op = Operator(system, at, masses, blocks, torsion)
    lam, vec, stats = _solve(op, workspace, at, count, method)
    real = lam < op.bound * (1 + 1e-9)  # dummy modes of DOFs without stiffness: out
    lam, vec = lam[real], vec[:, real]
    if lam.size and lam[0] < -op.negative:
        _unstable(f"omega^2 = {lam[0]:.3g} 1/s^2 < 0", workspace, at)
    zero = _zero_modes(lam, op)
    found = _assemble(net, op, lam[~zero][:count], vec[:, ~zero][:, :count], masses, at, op.sigma)
    found.added = None if blocks is None else np.where(net.fixed[:, None, None], 0.0, blocks)
    _name_zero_modes(found, op, vec[:, zero], workspace, at, cables)
    found.stats = {
        **stats,
        "seconds": time.perf_counter() - begin,
        **_residual(op, found.omega2, vec[:, ~zero][:, :count]),
        "dofs": op.n,
        "bodies": bodies,
    }
    _check_found(found, count)
    return found


def _added_blocks(net: Net, x: np.ndarray, added: ArrayLike) -> np.ndarray:
    """The (N, 3, 3) added-mass blocks of the edges' added masses ``added`` (E,) or
    (E, 2) [kg] (``catenet.solver.modal.added_mass_blocks``); ConfigError where they are
    not finite masses >= 0, one (sideways) or two (sideways, along) per edge."""
    from catenet.solver.modal import added_mass_blocks

    line = np.asarray(added, dtype=np.float64)
    shaped = line.shape in ((net.n_edges,), (net.n_edges, 2))
    if not shaped or not np.all(np.isfinite(line) & (line >= 0)):
        raise ConfigError(
            f"modes: added mass of shape {line.shape}: must be {net.n_edges} finite "
            "masses >= 0 [kg], one per edge (or two: sideways and along it)"
        )
    if line.ndim == 1:
        return added_mass_blocks(net, x, line)
    return added_mass_blocks(net, x, line[:, 0], line[:, 1])


def _solve(
    op: Operator, workspace: Workspace, x: np.ndarray, count: int, method: str
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """(eigenvalues, M-orthonormal vectors, stats) of the operator by the dense solver or
    the Lanczos method as ``method`` and the operator's size say, refined by Rayleigh-Ritz."""
    if method not in ("auto", "dense", "lanczos"):
        raise ConfigError(f"modes method = {method!r}: must be 'auto', 'dense' or 'lanczos'")
    solver = workspace.solver
    # every mode asked for (ARPACK finds at most n - 1): the dense solver whatever n
    dense = method == "dense" or (method == "auto" and op.n <= DENSE) or count >= op.n - 1
    dense = dense or _few_masses(op, count)
    sigma = op.sigma
    stats: dict[str, Any] = {"method": "dense" if dense else "lanczos", "backend": solver.name}
    if dense:
        lam, vec = dense_modes(op, sigma)
    else:
        lam, vec = lanczos_modes(
            op, solver, sigma, count, stats, lambda why: _unstable(why, workspace, x)
        )
    lam, vec = rayleigh_ritz(op, vec)
    return lam, vec, stats


def _check_found(found: Modes, count: int) -> None:
    """ConvergenceError where the modes found are inaccurate; a warning where fewer than
    ``count`` have a frequency."""
    stats = found.stats
    if stats["residual"] > RESIDUAL_TOL and stats["roundoff_ratio"] > ROUNDOFF_SAFETY:
        raise ConvergenceError(
            f"modes: the eigensolver's modes are inaccurate (relative residual "
            f"{stats['residual']:.1e} > {RESIDUAL_TOL:g}, {stats['roundoff_ratio']:.3g} "
            f"times its round-off)"
        )
    if found.count < count:
        log.warning(
            "modes: %d modes asked for, the net has %d with a frequency%s",
            count,
            found.count,
            f" ({found.zero_modes} more of zero frequency)" if found.zero_modes else "",
        )


def _few_masses(op: Operator, count: int) -> bool:
    """Whether so few DOFs carry mass (point masses on massless cables) that the Lanczos
    vectors, which live in the range of M, cannot fill its basis: then the dense solver
    (up to DENSE_MAX DOFs), else ConvergenceError."""
    massive = int(np.count_nonzero((op.m > 0) & ~op.dead))
    if massive > 2 * count + 20:
        return False
    if op.n <= DENSE_MAX:
        return True
    raise ConvergenceError(
        f"modes: only {massive} of the {op.n} free DOFs carry mass: too few for the Lanczos "
        f"method on a net this large; give the cables a density (material.density)"
    )


GAP = 1e4  # zero modes in the margin band lie this far below the first real mode


def _zero_modes(lam: np.ndarray, op: Operator) -> np.ndarray:
    """(len(lam),) bool: the zero-frequency modes of the ascending omega^2 ``lam``: those
    below ``op.zero``, and where something slides freely (``op.slides``: a free body, a
    barrier) the lowest j within the margin band |omega^2| < ``op.negative`` that a gap of
    GAP separates from the next (a frictionless body's free slide or turn at an
    equilibrium held to rtol: its omega^2 is round-off of either sign, 1e-9 of the
    stiffness scale, where the lowest real mode is orders of magnitude above it). Without
    one, a near-rigid member on springs keeps its modes on them (at 5e-12 of the scale,
    their band's gap to the member's own modes 1e4 and more)."""
    zero = lam < op.zero
    band = int(np.count_nonzero(lam < op.negative)) if op.slides else 0
    for j in range(band, 0, -1):
        low = max(float(np.max(np.abs(lam[:j]))), op.zero)
        if j < lam.size and lam[j] > GAP * low:
            zero[:j] = True
            break
    return zero


def _check_count(count: int, n_free: int) -> None:
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ConfigError(f"--count = {count!r}: must be a positive integer")
    if count > n_free:
        raise ConfigError(
            f"--count = {count}: the net has {n_free} free DOFs (3 per free node, 6 per "
            f"free body): ask for at most {n_free} modes"
        )


def _unstable(how: str, workspace: Workspace, x: np.ndarray) -> NoReturn:
    """Raises ConvergenceError: the equilibrium is unstable (``how``), its nodes named."""
    from catenet.solver.diagnose import describe_unstable, describe_unstable_bodies, has_twist

    system = workspace.system
    why = describe_unstable_bodies(system, x)
    if not why:
        why = describe_unstable(system.stretch, x, ~system.net.fixed, twisted=has_twist(system))
    raise ConvergenceError(f"modes: the equilibrium is unstable ({how}): {why}")


def _assemble(
    net: Net,
    op: Operator,
    lam: np.ndarray,
    vec: np.ndarray,
    mass: np.ndarray,
    x: np.ndarray,
    sigma: float,
) -> Modes:
    """Modes of the net: shapes on every node (a free body's four nodes moving rigidly),
    signs fixed, participation phi^T M r_d with the whole M (added mass too)."""
    k = lam.size
    shape = np.zeros((k, net.n_nodes, 3))
    free = np.flatnonzero(~net.fixed)
    if k:
        vec = vec / np.sqrt(np.einsum("ik,ik->k", vec, op.mm @ vec))[None, :]
    u = op.full(vec)
    turn = op.twist(vec).T.copy()  # (k, twist angles)
    weight = np.sqrt(op.m_free.diagonal())  # the sign by the largest kinetic share
    for j in range(k):
        v = u[:, j]
        shares = np.concatenate([v * weight, turn[j] * np.sqrt(op.m[op.n_x :])])
        if shares[np.argmax(np.abs(shares))] < 0:
            v, turn[j] = -v, -turn[j]
        shape[j, free] = v.reshape(-1, 3)
    m_free = np.where(net.fixed, 0.0, mass)
    rigid = np.zeros((op.m_free.shape[0], 3))
    for d in range(3):
        rigid[d::3, d] = 1.0  # a unit translation of every free node along axis d
    moved = op.m_free @ rigid  # (n_free, 3): M r_d
    participation = np.einsum("kn,nd->kd", shape[:, free].reshape(k, -1), moved)
    out = Modes(
        frequency=np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi),
        omega2=lam.copy(),
        shape=shape,
        participation=participation,
        effective_mass=participation**2,
        total_mass=np.einsum("nd,nd->d", rigid, moved),
        x=np.array(x, dtype=np.float64),
        sigma=float(sigma),
        mass=m_free,
    )
    if op.torsion is not None:
        out.twist = np.zeros((k, net.n_edges))
        out.twist[:, op.torsion.edges] = turn
        out.inertia = np.zeros(net.n_edges)
        out.inertia[op.torsion.edges] = op.torsion.inertia
    return out


def _residual(op: Operator, lam: np.ndarray, vec: np.ndarray) -> dict[str, float]:
    """The modes' largest relative residual |K phi - w^2 M phi| / (|K phi| + w^2 |M phi|)
    ("residual") and the largest residual over the eigensolver's round-off, n eps
    (|K| + w^2 |M|) |phi| ("roundoff_ratio", module constant ROUNDOFF_SAFETY)."""
    if vec.shape[1] == 0:
        return {"residual": 0.0, "roundoff_ratio": 0.0}
    kv = op.k @ vec
    mv = op.mm @ vec
    r = np.linalg.norm(kv - mv * lam[None, :], axis=0)
    scale = np.linalg.norm(kv, axis=0) + np.abs(lam) * np.linalg.norm(mv, axis=0)
    k_norm = float(np.max(np.asarray(abs(op.k).sum(axis=1)), initial=0.0))  # infinity norms
    m_norm = float(np.max(np.asarray(abs(op.mm).sum(axis=1)), initial=0.0))
    eps = float(np.finfo(np.float64).eps)
    floor = op.n * eps * (k_norm + np.abs(lam) * m_norm) * np.linalg.norm(vec, axis=0)
    return {
        "residual": float(np.max(r / np.maximum(scale, 1e-300))),
        "roundoff_ratio": float(np.max(r / np.maximum(floor, 1e-300))),
    }


def _name_zero_modes(
    found: Modes,
    op: Operator,
    zero_vec: np.ndarray,
    workspace: Workspace,
    x: np.ndarray,
    cables: Cables | None,
) -> None:
    """Counts and names the zero-frequency modes: the DOFs without stiffness and the
    mechanisms the Lanczos method found."""
    from catenet.solver.diagnose import describe_zero_modes

    net = workspace.system.net
    dead_nodes = np.unique(op.node[op.dead & (op.m > 0)])
    moving = np.zeros(0, dtype=np.int64)
    spins = _spins(op, zero_vec)  # rods turning about their own axes
    zero_vec = zero_vec[:, ~spins]
    if zero_vec.shape[1]:
        energy = np.einsum("d,dk->d", op.m, zero_vec**2)
        per_node = np.bincount(op.node, energy, minlength=net.n_nodes)
        moving = np.flatnonzero(per_node > 1e-3 * per_node.max())
    others = int(np.count_nonzero(op.dead & (op.m > 0))) + zero_vec.shape[1]
    found.zero_modes = others + int(spins.sum())
    nodes = np.union1d(dead_nodes, moving).astype(np.int64)
    found.zero_nodes = nodes
    if others:
        found.zero_message = describe_zero_modes(
            workspace.system,
            x,
            nodes,
            others,
            None if cables is None else cables.names,
            None if cables is None else cables.edge,
        )
    if spins.any():
        n = int(spins.sum())
        spin = (
            f"{n} zero-frequency mode{'s' if n > 1 else ''} (left out): rods turning about "
            "their own axes (a ring, or a rod whose twist no clamp holds, spins freely)"
        )
        found.zero_message = "; ".join(m for m in (found.zero_message, spin) if m)


def _spins(op: Operator, vec: np.ndarray) -> np.ndarray:
    """(k,) bool: which of the modes ``vec`` carry most of their kinetic energy in the
    rods' twist."""
    if op.torsion is None or not vec.shape[1]:
        return np.zeros(vec.shape[1], dtype=bool)
    total = np.einsum("d,dk->k", op.m, vec**2)
    twist = np.einsum("d,dk->k", op.m[op.n_x :], op.twist(vec) ** 2)
    spins: np.ndarray = twist > 0.5 * total
    return spins


def modes(
    net: Net | Scene,
    loads: Loads | None = None,
    k: int = 10,
    *,
    x: np.ndarray | None = None,
    settings: Settings | None = None,
    terms: Sequence[Term] = (),
    workspace: Workspace | None = None,
    mass: ArrayLike | None = None,
    method: str = "auto",
    added: ArrayLike | None = None,
) -> Modes:
    """The ``k`` lowest natural modes of ``net`` (a ``Net``, or a ``catenet.scene.Scene``)
    under ``loads`` about its equilibrium, found by the one solve path (``settings``: a
    ``catenet.solver.path.Settings``; default: static) unless ``x`` (N, 3) gives the
    equilibrium. ``terms``: further internal terms (with a ``Net``); ``added`` (E,)
    [kg]: each edge's added mass of water (``natural_modes``). Raises
    ConvergenceError where the equilibrium is not found (or a dynamic run ends before
    rest) and ConfigError for bad input (no mass, ``k`` out of range). The static
    Result is ``Modes.equilibrium``."""
    from catenet.model.net import Loads
    from catenet.solver import path

    scene = (
        net
        if isinstance(net, Scene)
        else Scene(net, Loads() if loads is None else loads, tuple(terms))
    )
    if settings is None:
        settings = path.Settings()
    ws = workspace if workspace is not None else path.workspace(scene, settings)
    result = None
    if x is None:
        result = path.solve(scene, settings, workspace=ws)
        if not (result.converged and result.equilibrium):
            raise ConvergenceError(
                f"modes: no equilibrium to take the modes about: {result.message or 'not at rest'}"
            )
        x = result.x
    found = natural_modes(
        ws, x, k, mass=mass, method=method, cables=scene.cables, added=added,
        torsion=scene.torsion,
    )  # fmt: skip
    found.equilibrium = result
    return found
