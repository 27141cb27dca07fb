"""Rule 6 of the static path's stability (``catenet.solver.stability``): a mechanism that
its compressed members push along.

A structure whose start is neutral (its tangent has modes without stiffness: a frame on
pinned feet whose rigid joints turn about rods that do not twist) may carry a load in a
state that leaves those modes alone (the portal swaying in its plane) when the loads are
symmetric about them, and that state is unstable as soon as a member along the mode is
compressed (the beam of such a portal turns about its column's axis like a pinned strut).
From the exact geometry Newton stays on the symmetric state and its tangent says so (rule
2); from geometry moved by round-off it may step round that state onto the branch where
the mechanism has turned as far as the load makes it (a lean that grows as the load's
cube root), an equilibrium whose tangent is neutral again. Both are the same structure,
so both must be a collapse.

The step is such a turn when, from a neutral start, it moves the nodes along the start's
zero modes by more than ``ALONG`` of the structure's size, its end is not stable (a
hammock's compressed spreaders beside its taut cables), and the members' forces at its
end give one of those modes a negative geometric stiffness (the sum over edges of N / l
times the square of the mode's move across the edge) below -``PUSH`` of the step's
largest nodal load per median edge length. The least over the modes, not the one along
the move: Newton may also turn such a frame about the line through its feet, a mode that
no force resists or pushes. A cable or net that sags from a straight start moves far
along its zero modes too, but its tension holds them (a positive geometric stiffness); a
mechanism that the loads move without stressing it (a two-bar chain whose joint swings
to leave both bars unstressed) has no forces to push it. The thresholds sit far from
both: the portal's push is about -1e-2 of its load scale, a cable's positive, an
unstressed mechanism's at the solve's accuracy (1e-8).

A step along those modes that leaves its members unstressed (|push| along the move
itself below ``PUSH``) is such a collapse too where it moved more than ``FAR`` times the
structure's elastic response with the modes held (``elastic``): a strut split in two
folds aside until it carries nothing, 0.2 m where the elastic move is 2e-6 m, while the
two-bar joint swings only as far as its neighbours move (a fiftieth of the elastic move).

The members that a step's loads compress push along such modes at once where the
modes move as a mechanism (``finite``: no self-stress of the edges resists them at
second order), whatever Newton then does: the linear response with the modes held gives
the members' forces to first order (``compressed_across``), and the same geometric
stiffness below -``PUSH`` on the mechanism's part of the modes says that the state that
carries the loads is unstable from their first share. A three-hinged arch whose crown
nothing holds across its plane: Newton found it hanging below its feet as a V, each bar
turned 43.6 degrees, at any load, pushed across its plane or not, "converged". A
bilateral rope given straight, whose weight compresses its lower part across its sway,
is no mechanism: every sway stretches its edges against its uniform self-stress, and it
bulges into tension close by.

Dense systems only (``tangent.DENSE`` free DOFs), where the start's zero modes are
computed whole.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from catenet.solver.system import System

ALONG = 1e-3  # the step moves along the start's zero modes by this share of the size ...
PUSH = 1e-3  # ... and its compressed members push that move: -PUSH x load / edge length
FAR = 100.0  # ... or nothing holds it (|push| < PUSH) and it is this many elastic moves
FIRST = 1e-6  # the first-order forces of a linear response: read on a move this share
#              of the median edge along it
STRAIGHT = 1e-3  # a compatibility matrix's singular values up to this are zero (``finite``)
HOLDS = 1e-6  # a self-stress holds a move above this share of its uncancelled stretching
NOISE = 64.0  # a tension-only edge is taut above this many round-offs of its axial force
EPS = float(np.finfo(np.float64).eps)


def zero_modes(
    system: System, x: np.ndarray, scale: np.ndarray, top: float, known: np.ndarray | None
) -> np.ndarray:
    """(free DOFs, k) an orthonormal basis of the displacements that the tangent at x
    does not resist: the eigenvectors of S K S (S = scale^(-1/2)) at or below ``top``,
    mapped back to displacements (``known``: those displacements, where the tangent's
    verdict found them all)."""
    from scipy.linalg import eigh

    if known is not None:
        return np.linalg.qr(known)[0] if known.shape[1] else known
    k = system.matrix(system.hessian(x).copy()).toarray()
    s = 1.0 / np.sqrt(scale)
    a = k * s[:, None] * s[None, :]
    a = 0.5 * (a + a.T)
    if not np.all(np.isfinite(a)):
        return np.zeros((len(a), 0))
    lam, vec = eigh(a, subset_by_value=(-np.inf, top), check_finite=False)
    if lam.size == 0:
        return np.zeros((len(a), 0))
    basis: np.ndarray = np.linalg.qr(s[:, None] * vec)[0]
    return basis


def pushed_along(
    system: System,
    modes: np.ndarray,
    prev: np.ndarray,
    x1: np.ndarray,
    *,
    size: float,
    load: float,
) -> tuple[float, float, float]:
    """(move, push, held) of the step from ``prev`` to ``x1`` along ``modes`` (the
    start's zero modes, ``zero_modes``): how far it moved the nodes along them [length],
    and the geometric stiffness that the members' forces at x1 give a unit move along
    them (the sum over edges of N / l times its move across the edge squared), as a share
    of ``load`` per median rest length: the least over the modes (negative: the forces
    push along a mode), and along the move itself. (0, 0, 0) where it did not move."""
    free = system.free_dofs
    step = (x1 - prev).reshape(-1)[free]
    along = modes @ (modes.T @ step)
    move = float(np.linalg.norm(along))
    if not move > ALONG * size or not load > 0.0:
        return 0.0, 0.0, 0.0
    geometric = _geometric(system, modes, x1, system.tension(x1))
    unit = load / float(np.median(system.net.rest_length))
    w = modes.T @ along / move  # the move in the modes' basis, unit length
    return move, float(np.linalg.eigvalsh(geometric)[0]) / unit, float(w @ geometric @ w) / unit


def compressed_across(
    system: System, modes: np.ndarray, prev: np.ndarray, g: np.ndarray, *, load: float
) -> float:
    """The least geometric stiffness that the members' forces of the step's first-order
    response give the part of ``modes`` (the zero modes at ``prev``) that moves as a
    mechanism (``finite``), as a share of ``load`` per median rest length; 0 where no
    part does. The response is the linear one with the modes held (``_response``), its
    forces to first order in the load (a tension-only edge's at least 0): a negative
    value says that the state that carries the loads is unstable from their first share,
    wherever Newton then goes (a three-hinged arch whose crown nothing holds across its
    plane: its compressed bars turn it over sideways). A mode that the edges'
    second-order stretching resists (a rope's sway, a flat net's sag) is left out: its
    own tension holds it as it moves. ``g``: the potential's gradient at prev under the
    step's end load."""
    if not modes.shape[1] or not float(np.linalg.norm(g)) > 0.0 or not load > 0.0:
        return 0.0
    u = _response(system, modes, prev, g)
    if u is None:
        return 0.0
    median = float(np.median(system.net.rest_length))
    top = float(np.max(np.abs(u), initial=0.0))
    if not top > 0.0:
        return 0.0
    # the members' forces to first order in the load, from a move FIRST of the median
    # edge (a linear response may pass through a flat arch's chord; a tiny one is
    # round-off's)
    share = FIRST * median / top
    x = prev.copy()
    x.reshape(-1)[system.free_dofs] += share * u
    start = system.tension(prev)
    tension = start + (system.tension(x) - start) / share
    only = _tension_only(system)
    tension[only] = np.maximum(tension[only], 0.0)
    unit = load / median
    geometric = _geometric(system, modes, prev, tension)
    if not float(np.linalg.eigvalsh(geometric)[0]) / unit < -PUSH:
        return 0.0  # (the common case: the cheap test first)
    moving = finite(system, modes, prev)
    if not moving.shape[1]:
        return 0.0
    return float(np.linalg.eigvalsh(moving.T @ geometric @ moving)[0]) / unit


def finite(system: System, modes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(k, p) an orthonormal basis, in the coefficients of ``modes`` (k zero modes at x),
    of the moves that no self-stress of the edges holds at second order: a move z
    stretches each edge by |z across it|^2 / (2 l) to second order, and a self-stress s
    (edge forces in balance with no load, the supports' and rollers' reactions aside)
    holds a move where the matrix Omega(s) of the sum of s / l times those squares does
    not vanish on it (the moves with Omega(s) z = 0 for every s: a subspace of those
    with z Omega(s) z = 0, so a mechanism among several modes may be missed, never a
    held move called one). No edge network holds a three-hinged arch's crown (no
    self-stress: the whole mode moves); a straight rope's uniform tension holds every
    sway of its nodes (none moves). The edges are the bilateral ones and the taut
    tension-only ones (a slack cable holds nothing; a self-stress may need compression;
    taut is above NOISE round-offs of the edge's axial force).

    Self-stresses are the null space of the edges' compatibility matrix (rows: the
    edges' unit directions at their nodes), its singular values up to ``STRAIGHT``
    counted as zero: a line whose edges kink by less than about 2e-3 rad (a rope given
    straight, its nodes moved by round-off) has no room to move that its stretch would
    notice, and is held as a straight one is. A move is held where some Omega(s) is
    above ``HOLDS`` of the sum of |s| / l times the same squares (Omega without its
    cancellations: round-off in a sum that vanishes is no hold)."""
    net = system.net
    # taut: above NOISE round-offs of its axial force, EA eps |x| / l0 (a cable given at
    # its rest length carries that much either way)
    noise = NOISE * EPS * float(np.max(np.abs(x), initial=0.0)) * net.EA / net.rest_length
    used = ~_tension_only(system) | (system.tension(x) > noise)
    across, t, length = _across(system, modes, x)
    edges, across, t, length = net.edges[used], across[:, used], t[used], length[used]
    m, k = len(edges), modes.shape[1]
    rows = np.arange(m)
    b = np.zeros((m, net.n_nodes, 3))
    b[rows, edges[:, 1]] += t
    b[rows, edges[:, 0]] -= t
    b = b.reshape(m, -1)[:, system.free_dofs]
    if system.guided is not None:  # a roller's held direction is its reaction's
        guided = system.guided
        y = b[:, guided.dofs]
        b[:, guided.dofs] = y - np.einsum("kij,mkj->mki", guided.held, y)
    stresses = _null(b.T, STRAIGHT)  # (edges, r)
    if not stresses.shape[1]:
        return np.eye(k)
    a = across.transpose(1, 2, 0).reshape(3 * m, k)  # rows: an edge's three components
    inverse = np.repeat(1.0 / np.where(length > 0.0, length, np.inf), 3)[:, None]
    omegas, reference = [], 0.0
    for s in stresses.T:
        w = np.repeat(s, 3)[:, None] * inverse
        omegas.append(a.T @ (w * a))
        reference = max(reference, float(np.trace(a.T @ (np.abs(w) * a))))
    if not reference > 0.0:
        return np.eye(k)
    return _null(np.vstack(omegas), HOLDS * reference)


def _null(a: np.ndarray, below: float) -> np.ndarray:
    """(columns, p) an orthonormal basis of the vectors that ``a`` maps to within
    ``below`` (its singular values up to it counted as zero)."""
    _, sigma, vt = np.linalg.svd(a, full_matrices=True)
    rank = int(np.count_nonzero(sigma > below))
    basis: np.ndarray = vt[rank:].T
    return basis


def _tension_only(system: System) -> np.ndarray:
    """Per edge: tension-only."""
    net = system.net
    return np.asarray(net.law.tension_only, dtype=bool) & np.ones(net.n_edges, dtype=bool)


def _geometric(system: System, modes: np.ndarray, x: np.ndarray, tension: np.ndarray) -> np.ndarray:
    """(k, k) the geometric stiffness that the edges' ``tension`` gives the ``modes`` at
    x: the sum over edges of N / l times the modes' moves across the edge."""
    across, _, length = _across(system, modes, x)
    stiffness = tension / np.where(length > 0.0, length, np.inf)
    geometric: np.ndarray = np.einsum("kij,mij,i->km", across, across, stiffness)
    return geometric


def _across(
    system: System, modes: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(across (k, edges, 3), t (edges, 3), length (edges,)): each mode's move of an edge's
    far node against its near one across the edge at x, the edges' unit directions and
    lengths."""
    net = system.net
    flat = np.zeros((modes.shape[1], net.n_nodes * 3))
    flat[:, system.free_dofs] = modes.T
    v = flat.reshape(len(flat), -1, 3)
    e = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    length = np.linalg.norm(e, axis=1)
    t = e / np.where(length > 0.0, length, 1.0)[:, None]
    dv = v[:, net.edges[:, 1]] - v[:, net.edges[:, 0]]
    across = dv - np.einsum("kij,ij->ki", dv, t)[:, :, None] * t
    return across, t, length


def elastic(system: System, modes: np.ndarray, prev: np.ndarray, g: np.ndarray) -> float:
    """The size of the step's linear response from ``prev`` with its zero ``modes`` held
    (``_response``): the move an elastic structure makes under the step's load. ``g``:
    the potential's gradient at prev at that load."""
    u = _response(system, modes, prev, g)
    return np.inf if u is None else float(np.linalg.norm(u))


def _response(
    system: System, modes: np.ndarray, prev: np.ndarray, g: np.ndarray
) -> np.ndarray | None:
    """The linear response (free DOFs) from ``prev`` to the out-of-balance force -g with
    the zero ``modes`` held by springs as stiff as the stiffest DOF across them; None
    where that solve fails."""
    k = system.matrix(system.hessian(prev).copy()).toarray()
    held = float(np.max(np.abs(np.diag(k)), initial=1.0)) * (modes @ modes.T)
    try:
        u = np.linalg.solve(k + held, -g)
    except np.linalg.LinAlgError:
        return None
    return u if np.all(np.isfinite(u)) else None
