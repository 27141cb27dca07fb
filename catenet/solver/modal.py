"""The mass and the coordinates of a modal analysis (``catenet.solver.modes``) beyond a
net's lumped point masses: free rigid bodies reduced to their six rigid motions, and the
added mass of the water around a mooring line.

**Free rigid bodies.** A free body is four nodes of an affine body (``catenet.terms.rigid``)
held rigid by a stiff orthogonality energy. Its twelve DOFs hold six that are physical
(translation and rotation) and six strains (stretch and shear of the affine map) whose
stiffness is the orthogonality energy's, about 1e6 times the loads' scale: as modes they
would be frequencies of no physical meaning (and they would set the spectrum's scale,
which the shift and the test for zero frequencies are taken from). The modal problem is
therefore solved on the rigid motions: u = Z q with q the free net DOFs as they are and,
per body, a translation t and a small rotation w of its nodes about its centre c,

    du_k = t + w x (p_k - c),

and K_r = Z^T K Z, M_r = Z^T M Z. Along such a motion the orthogonality energy is
constant (A -> (1 + W) A keeps A^T A to first order, exactly for the rotation exp(W)),
so at an equilibrium (zero gradient) Z^T K Z is the second derivative of the potential
along the body's exact rigid motions: the net's and the barrier's stiffness, and the
geometric term of the contact forces acting at their points on the turning body (the
share of the orthogonality energy's Hessian that its stress brings in, the Lagrange
multiplier's term of a rigid body). M_r is the body's true mass m 1 and its inertia tensor
about its centre at the current pose (the four masses m/4 carry the second moment J
exactly: sum m/4 [r_k]x^T [r_k]x = tr(J) 1 - J = I). The shapes are Z q: rigid on every
body.

**Added mass of water.** A line moving sideways through still water carries with it an
added mass Ca rho_w A per length (Ca the added-mass coefficient, 1 for a circular
cylinder in potential flow; rho_w the water's density, A the cross-section); moving
along itself it carries nothing. Each edge adds Ca rho_w A l0 (I - t t^T) / 2 at each of
its ends (t its unit direction at the equilibrium, l0 its rest length: the displaced
volume A l0 is the unstressed one, as the structural mass is): a 3 x 3 block per node,
symmetric positive semidefinite, which on the structural m 1 keeps M positive definite.

``Operator`` holds K and M of the modal problem (on the rigid motions where there are
free bodies) and factorises K - sigma M; ``stable_with_bodies`` counts its negative
eigenvalues for a static solve with free bodies.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError

if TYPE_CHECKING:
    from collections.abc import Sequence

    import scipy.sparse as sp
    from numpy.typing import ArrayLike

    from catenet.model.net import Net
    from catenet.model.torsion import Torsion
    from catenet.solver.linear import LinearSolver
    from catenet.solver.system import System
    from catenet.solver.workspace import Workspace
    from catenet.terms.rigid import BodyFrame, Rigidity

SHIFT = 1e-10  # sigma = -SHIFT x max(K_ii / m_i)
ZERO = 1e-12  # w^2 below ZERO x max(K_ii / m_i) is a zero-frequency mode
# w^2 below -NEGATIVE x max(K_ii / m_i) is unstable; between that and ZERO x max a zero
# mode: an equilibrium held to rtol leaves its zero modes (a frictionless body's free
# slide or turn) at w^2 of a few 1e-9 of that scale, of either sign as the processor's
# round-off falls, so the negative side gets a margin far above it.
NEGATIVE = 1e-7


def rigidities(system: System) -> list[Rigidity]:
    """The orthogonality terms (``Rigidity``) of the system's free rigid bodies."""
    if "catenet.terms.rigid" not in sys.modules:
        return []  # no Rigidity exists before its module loads: not loaded to look
    from catenet.terms.rigid import Rigidity

    return [t for t in system.terms if isinstance(t, Rigidity)]


def body_frames(system: System) -> list[BodyFrame]:
    """The ``BodyFrame`` of every free rigid body among the system's terms (its rigidity)."""
    return [t.frame for t in rigidities(system)]


class Reduction:
    """u = Z q on a system's free DOFs: the free net DOFs as they are, then six per free
    body (translation, rotation about its centre at x). ``node``: each q's node (a body's
    first node for its six); ``bodies``: (frame, first q index) per body."""

    def __init__(self, system: System, x: np.ndarray, frames: Sequence[BodyFrame]):
        import scipy.sparse as sp

        x = np.asarray(x, dtype=np.float64)
        n = system.n_free
        free_node = system.free_dofs // 3
        body_dof = np.zeros(n, dtype=bool)
        reduced = system._reduced
        for frame in frames:
            body_dof[reduced[frame.dofs()]] = True
        guides = system.guides
        if guides is not None:  # rollers and sliders: their free directions only
            body_dof[reduced[3 * guides.nodes[:, None] + np.arange(3)].ravel()] = True
        keep = np.flatnonzero(~body_dof)
        rows, cols, vals = [keep], [np.arange(keep.size)], [np.ones(keep.size)]
        node = [free_node[keep]]
        self.bodies: list[tuple[BodyFrame, int]] = []
        q = keep.size
        for frame in frames:
            c = x[frame.nodes].mean(axis=0)
            r = x[frame.nodes] - c  # (4, 3)
            self.bodies.append((frame, q))
            for k in range(4):
                dof = reduced[3 * frame.nodes[k] + np.arange(3)]
                for d in range(3):  # translation along d
                    rows.append(dof[d : d + 1])
                    cols.append(np.array([q + d]))
                    vals.append(np.ones(1))
                for d in range(3):  # rotation about axis d: e_d x r_k
                    rows.append(dof)
                    cols.append(np.full(3, q + 3 + d))
                    vals.append(np.cross(np.eye(3)[d], r[k]))
            node.append(np.full(6, frame.nodes[0]))
            q += 6
        groups = [np.arange(q) // 3]  # M's blocks: each node's, each body's two triples
        if guides is not None:
            for g, basis in zip(guides.nodes, guides.basis(), strict=True):
                k = basis.shape[1]
                rows.append(np.tile(reduced[3 * g + np.arange(3)], k))
                cols.append(np.repeat(q + np.arange(k), 3))
                vals.append(basis.T.ravel())
                node.append(np.full(k, g))
                groups.append(np.full(k, q))  # a group id past every triple's
                q += k
        self.groups = np.concatenate(groups)
        self.n = q
        self.node = np.concatenate(node).astype(np.int64)
        self.z = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, q)
        )

    def rigidity(self, terms: Sequence[Rigidity], x: np.ndarray) -> sp.csr_matrix:
        """Z^T H Z of the bodies' orthogonality energies ``terms``, exactly: on a rigid
        motion dA = W A (W skew: a turn; 0: a translation) dC = dA^T A + A^T dA = 0,
        so of the Hessian k (dC1 : dC2 + C : (dA1^T dA2 + dA2^T dA1)) only the stress
        term is left, between turns (made from the full Hessian, whose entries are
        1e6 times the loads' scale, it would be lost in their round-off)."""
        import scipy.sparse as sp

        rows, cols, vals = [], [], []
        skew = [np.cross(np.eye(3), e) for e in np.eye(3)]  # W_i v = e_i x v
        first = {id(frame): q for frame, q in self.bodies}
        for term in terms:
            A, C = term._C(x)
            q = first[id(term.frame)] + 3
            dA = [W @ A for W in skew]
            for i in range(3):
                for j in range(3):
                    v = term.k * float(np.sum(C * (dA[i].T @ dA[j] + dA[j].T @ dA[i])))
                    rows.append(q + i)
                    cols.append(q + j)
                    vals.append(v)
        return sp.csr_matrix((vals, (rows, cols)), shape=(self.n, self.n))

    def reduce(self, a: sp.spmatrix) -> sp.csr_matrix:
        """Z^T A Z (symmetrised), CSR."""
        r = (self.z.T @ a @ self.z).tocsr()
        return ((r + r.T) * 0.5).tocsr()

    def expand(self, q: np.ndarray) -> np.ndarray:
        """The free DOFs u = Z q of reduced vectors (columns)."""
        u: np.ndarray = self.z @ q
        return u


def added_mass_blocks(
    net: Net, x: np.ndarray, line: ArrayLike, axial: ArrayLike | None = None
) -> np.ndarray:
    """(N, 3, 3) the added mass at each node [kg]: each edge's ``line`` (E,) [kg]
    (Ca rho_w A l0) times (I - t t^T) / 2 and ``axial`` (E,) (ca_t rho_w A l0; None: 0)
    times t t^T / 2 at each of its ends, t its direction at x
    (``catenet.model.water.added_mass_blocks``, the dynamic runs' too)."""
    from catenet.model.water import added_mass_blocks as blocks

    x = np.asarray(x, dtype=np.float64)
    if not net.n_edges:
        return np.zeros((net.n_nodes, 3, 3))
    d = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    length = np.linalg.norm(d, axis=1)
    t = d / np.where(length > 0, length, 1.0)[:, None]
    half = 0.5 * np.asarray(line, dtype=np.float64)
    along = np.zeros_like(half) if axial is None else 0.5 * np.asarray(axial, dtype=np.float64)
    ends = np.concatenate([net.edges[:, 0], net.edges[:, 1]])
    return blocks(net.n_nodes, ends, np.concatenate([t, t]), np.tile(half, 2), np.tile(along, 2))


def mass_data(system: System, mass: np.ndarray, blocks: np.ndarray | None) -> np.ndarray:
    """The CSR data, in the system's own pattern, of the mass matrix: the lumped ``mass``
    (N,) on the diagonal plus the 3 x 3 ``blocks`` (N, 3, 3) (or None) of each free node
    (every free node's own block is in the pattern: its edges put it there)."""
    net = system.net
    data = np.zeros(system.nnz)
    data[system.diag_pos] = np.repeat(np.asarray(mass, dtype=np.float64)[~net.fixed], 3)
    if blocks is None:
        return data
    free = np.flatnonzero(~net.fixed)
    reduced = system._reduced
    a, b = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    rows = reduced[3 * free[:, None, None] + a[None]].ravel()
    cols = reduced[3 * free[:, None, None] + b[None]].ravel()
    vals = blocks[free].ravel()
    if system.upper:
        upper = cols >= rows
        rows, cols, vals = rows[upper], cols[upper], vals[upper]
    pos = _locate(system, rows, cols)
    np.add.at(data, pos, vals)
    return data


def _locate(system: System, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Positions of the entries (rows, cols) in the system's CSR pattern (each present)."""
    n = system.n_free
    keys = np.repeat(np.arange(n, dtype=np.int64), np.diff(system.indptr)) * n
    keys += system.indices
    order = np.argsort(keys, kind="stable")
    want = rows.astype(np.int64) * n + cols
    k = np.searchsorted(keys, want, sorter=order)
    pos: np.ndarray = order[np.minimum(k, keys.size - 1)]
    if not np.array_equal(keys[pos], want):
        raise ValueError("a mass block's entry is not in the system's pattern")
    return pos


class Operator:
    """K and M of a net at x on its modal coordinates: its free DOFs, or with free rigid
    bodies each body's six rigid motions in place of its twelve DOFs (``Reduction``);
    ``k``, ``mm`` as SciPy CSR (both triangles), ``m`` M's diagonal, ``node`` each
    coordinate's node, and the DOFs taken out (``dead``: no stiffness)."""

    def __init__(
        self,
        system: System,
        x: np.ndarray,
        mass: np.ndarray,
        blocks: np.ndarray | None = None,
        torsion: Torsion | None = None,
    ):
        import scipy.sparse as sp

        net = system.net
        self.system = system
        rigid = rigidities(system)
        self.k_data = system.hessian(x, skip=rigid).copy()
        self.convex = system.convex
        # something slides freely (a body, a node on a barrier): zero modes at round-off
        self.slides = bool(rigid) or any(t.barrier for t in system.terms)
        self.m_data = mass_data(system, mass, blocks)
        self.m_free = system.matrix(self.m_data)  # M on the free DOFs (participation)
        reduce = rigid or system.guides is not None  # bodies, rollers and sliders
        self.reduction = Reduction(system, x, [t.frame for t in rigid]) if reduce else None
        if self.reduction is None:
            self.node = np.flatnonzero(~net.fixed).repeat(3)
            k, self.mm = system.matrix(self.k_data), self.m_free
            groups = np.arange(k.shape[0]) // 3
        else:
            self.node = self.reduction.node
            k = self.reduction.reduce(system.matrix(self.k_data))
            if rigid:
                k = (k + self.reduction.rigidity(rigid, x)).tocsr()
            self.mm = self.reduction.reduce(self.m_free)
            self.convex = self.convex and not rigid
            groups = self.reduction.groups
        self.n_x = k.shape[0]  # the net's coordinates; then the twist angles
        self.torsion = torsion if torsion is not None and torsion.count else None
        if self.torsion is not None:
            k, self.mm = with_twist(system, x, self.torsion, self.reduction, k, self.mm)
            self.node = np.concatenate([self.node, self.torsion.edge_nodes(net)])
            groups = np.concatenate([groups, groups.max(initial=-1) + 1 + np.arange(
                self.torsion.count)])  # fmt: skip
            self.convex = False
        self.own = self.reduction is not None or self.torsion is not None  # own solver
        self.n = k.shape[0]
        self.m = self.mm.diagonal()
        rowsum = np.asarray(abs(k).sum(axis=1)).ravel()
        self.rowsum = rowsum
        self.dead = rowsum <= 1e-14 * max(float(rowsum.max(initial=0.0)), 1e-300)
        live = ~self.dead & (self.m > 0)
        if not live.any():
            raise ConfigError(
                "modes: no free node has both mass and stiffness: give the net a mass "
                "(material.density, [[mass]]) and a tension"
            )
        self.scale = float(np.max(k.diagonal()[live] / self.m[live]))  # max K_ii / m_i
        self.sigma = -SHIFT * self.scale  # the shift
        self.zero = ZERO * self.scale  # w^2 below: zero-frequency modes
        self.negative = NEGATIVE * self.scale  # w^2 below -negative: unstable
        # Gershgorin on D^-1 K, D <= M the smallest eigenvalue of each 3 x 3 block of M
        # (block diagonal): w^2 <= bound. The DOFs without stiffness get a dummy w^2 of
        # 2 x bound: above every real mode.
        low = _block_low(self.mm, self.m, groups)
        self.bound = float(np.max(rowsum[live] / low[live]))
        self.dummy = 2.0 * self.bound
        ref = np.where(self.m > 0, self.m, float(np.median(self.m[self.m > 0])))
        fix = np.where(self.dead, self.dummy * ref, 0.0)
        if not self.own:
            self.k_data[system.diag_pos[self.dead]] = fix[self.dead]
        self.k = (k + sp.diags(fix)).tocsr()

    def factorized(self, solver: LinearSolver, sigma: float) -> LinearSolver:
        """A linear solver holding the factors of K - sigma M: the workspace's own
        ``solver`` on the system's pattern, or (with free bodies) a new one of the same
        backend on the reduced pattern."""
        import scipy.sparse as sp

        from catenet.solver.linear import make_solver

        if not self.own:
            solver.factorize(self.k_data - sigma * self.m_data, definite=self.convex)
            return solver
        a = (self.k - sigma * self.mm).tocsr()
        upper = self.system.upper
        if upper:
            a = sp.triu(a, format="csr")
        a.sort_indices()
        own = make_solver(
            getattr(solver, "backend", solver.name),
            a.indptr,
            a.indices,
            upper=upper,
            dof_node=self.node,
        )
        own.factorize(a.data)
        return own

    def full(self, vec: np.ndarray) -> np.ndarray:
        """Free-DOF vectors (columns) of modal coordinates (their twist angles left out)."""
        vec = vec[: self.n_x]
        return vec if self.reduction is None else self.reduction.expand(vec)

    def twist(self, vec: np.ndarray) -> np.ndarray:
        """The twist angles (rows: ``Torsion``'s chain edges) of modal coordinates."""
        return vec[self.n_x :]


def with_twist(
    system: System,
    x: np.ndarray,
    torsion: Torsion,
    reduction: Reduction | None,
    k: sp.csr_matrix,
    mm: sp.csr_matrix,
) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """K and M of the net's modal coordinates ``k``, ``mm`` with the rods' twist angles
    after them (``catenet.model.torsion``): the twist term's eliminated Hessian replaced
    by the un-eliminated blocks, and the angles' rotational inertia."""
    import scipy.sparse as sp

    from catenet.terms.twist import Twist

    twists = next((t.twists for t in system.terms if isinstance(t, Twist)), None)
    dk, kxt, ktt = torsion.blocks(x, twists)
    free = system.free_dofs
    dk, kxt = dk.tocsr()[free][:, free], kxt.tocsr()[free]
    if reduction is not None:
        dk, kxt = reduction.reduce(dk), (reduction.z.T @ kxt).tocsr()
    else:
        dk = ((dk + dk.T) * 0.5).tocsr()
    full = sp.bmat([[k + dk, kxt], [kxt.T, ktt]], format="csr")
    inertia = sp.diags(torsion.inertia)
    return full, sp.block_diag([mm, inertia], format="csr")


def _block_low(mm: sp.csr_matrix, m: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Each coordinate's lower bound of M's eigenvalues: the smallest eigenvalue of its
    diagonal block (M is block diagonal in the coordinates' ``groups``, each of at most
    three consecutive coordinates: a node's triple, a guided node's free directions)."""
    ids, first, group = np.unique(groups, return_index=True, return_inverse=True)
    slot = np.arange(m.size) - first[group]  # each coordinate's place in its group
    coo = mm.tocoo()
    own = group[coo.row] == group[coo.col]
    blocks = np.zeros((ids.size, 3, 3))
    np.add.at(blocks, (group[coo.row[own]], slot[coo.row[own]], slot[coo.col[own]]), coo.data[own])
    size = np.bincount(group, minlength=ids.size)
    big = 4.0 * float(np.max(np.abs(m), initial=0.0)) + 1.0  # above every block's eigenvalues
    for k in (1, 2):  # the unused places of a smaller group: out of the minimum
        blocks[size <= k, k, k] = big
    low: np.ndarray = np.linalg.eigvalsh(blocks)[:, 0][group]
    return low


def stable_with_bodies(workspace: Workspace, x: np.ndarray) -> bool | None:
    """Whether the equilibrium x of a net with free bodies is stable: no omega^2 below
    the shift of ``natural_modes`` (just below zero) on the bodies' rigid motions (a
    frictionless body's free sliding or turning has no stiffness: it is neutral, not
    unstable); None where it cannot tell (no mass, a backend without the inertia)."""
    from catenet.errors import SingularSystemError

    try:
        op = Operator(workspace.system, np.asarray(x, dtype=np.float64), workspace.system.net.mass)
        solver = op.factorized(workspace.solver, -op.negative)
    except (SingularSystemError, ConfigError):
        return None
    negative = solver.negative_eigenvalues()
    return None if negative is None else negative == 0
