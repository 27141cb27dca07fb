"""Gradient and Hessian of a net's energy terms on its free DOFs.

The sparsity pattern of the reduced system (supports eliminated) is the union of the
patterns of the terms (``catenet.terms``) and the diagonal, built once from the topology;
every Newton iteration only refills the values. For a symmetric solver only the upper
triangle is stored. Entries that are zero at the moment (slack edges) keep their place:
the pattern never changes, so the symbolic analysis of the linear solver stays valid for
the whole run.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from catenet.kernels.pattern import (
    block_pattern,
    pattern_csr,
    pattern_entries,
    pattern_locate,
)
from catenet.kernels.sparse import add_diagonal, scatter_add
from catenet.model.net import Net
from catenet.solver.guided import Guided, guided_blocks
from catenet.terms import Stretch, Term

if TYPE_CHECKING:  # SciPy is imported where a matrix is asked for: not on a run's path
    import scipy.sparse as sp

_NO_ELEMS = np.zeros((0, 2), dtype=np.int64)
_NO_DOFS = np.zeros(0, dtype=np.int64)


#: A sparsity pattern: (indptr, indices, each term's targets, the diagonal's positions).
Pattern = tuple[np.ndarray, np.ndarray, list[np.ndarray], np.ndarray]

#: Below this many Hessian values (about 1e5 edges), the pattern is made by one np.unique
#: (milliseconds, nothing to compile); above it, at node level by a kernel (linear time).
SMALL_PATTERN = 4_000_000


class System:
    """The internal energy terms of a net (default: its stretching) on its free DOFs.

    Parameters
    ----------
    net : the net
    terms : the internal terms (stretching, springs, contact, ...); their patterns,
        and the diagonal, make the sparsity pattern of every matrix this system fills
    upper : store only the upper triangle (for symmetric solvers)
    """

    def __init__(self, net: Net, terms: Sequence[Term] | None = None, *, upper: bool = True):
        self.net = net
        self.upper = upper
        self.terms = (Stretch(net),) if terms is None else tuple(terms)
        n = net.n_nodes
        self.free = np.repeat(~net.fixed, 3)  # (3N,) mask of free DOFs
        self.free_dofs = np.flatnonzero(self.free)
        self.n_free = int(self.free_dofs.size)
        self._reduced = np.full(3 * n, -1, dtype=np.int64)
        self._reduced[self.free_dofs] = np.arange(self.n_free)
        self.guides = net.guides  # rollers and sliders: projected rows (``catenet.solver.guided``)
        self.guided: Guided | None = None

        self._build()
        self._grad = np.zeros((n, 3))
        self._energies = [0.0] * len(self.terms)
        self.seconds = 0.0  # spent filling gradients and Hessians
        self.convex = all(t.convex for t in self.terms)  # of the last ``hessian`` (see there)

    # --- pattern -----------------------------------------------------------------------
    def _build(self) -> None:
        """The pattern: every term's entries on free DOFs, and the diagonal (a grown
        term's entries too: it has not grown since)."""
        for term in self.terms:
            if term.grows:
                term.grew = False
        self.builds = getattr(self, "builds", 0) + 1  # (views keep the count they saw)
        self._targets: dict[int, tuple[object, np.ndarray]] = {}
        if self.guides is not None or self._entry_count() <= SMALL_PATTERN:
            found = self._unique_pattern()
        else:
            found = self._block_pattern() or self._entry_pattern()
        self.indptr, self.indices, targets, self.diag_pos = found
        self.nnz = int(self.indices.size)
        for term, target in zip(self.terms, targets, strict=True):
            self._remember(term, target)
        self._values: dict[int, np.ndarray] = {}
        self.data = np.zeros(self.nnz)

    def refresh(self) -> bool:
        """Rebuilds the pattern in place if a term's grew since it was built (``grows``
        terms: self-contact's new candidate pairs); whether it did. Nothing happens (and
        nothing is computed) otherwise."""
        if not any(t.grows and t.grew for t in self.terms):
            return False
        start = time.perf_counter()
        self._build()
        self.seconds += time.perf_counter() - start
        return True

    def _block_pattern(self) -> Pattern | None:
        """The pattern at node level (catenet.kernels.pattern.block_pattern): the edges'
        node adjacency as 3x3 blocks, when every free node has an edge and the other
        terms' entries fall into it (node-local terms do); else None."""
        net = self.net
        stretch = [t for t in self.terms if t.edge_net is net]
        if not stretch or self.n_free == 0:
            return None
        edges = np.ascontiguousarray(net.edges, dtype=np.int64)
        touched = np.bincount(edges.ravel(), minlength=net.n_nodes) > 0
        if not touched[~net.fixed].all():
            return None
        rank = np.full(net.n_nodes, -1, dtype=np.int64)
        rank[~net.fixed] = np.arange(self.n_free // 3)
        indptr, indices, edge_target, diag = block_pattern(
            edges, rank, self.n_free // 3, self.upper
        )
        targets = []
        for term in self.terms:
            if term.edge_net is net:
                targets.append(edge_target)
                continue
            _, rows, cols, count = self._entries(term)
            target = np.empty(count, dtype=np.int64)
            args = (indptr, indices, rows, cols, self._reduced, self.upper, target)
            if count and pattern_locate(*args):
                return None  # the term couples DOFs the edges do not
            targets.append(target)
        return indptr, indices, targets, diag

    def _entry_count(self) -> int:
        """How many Hessian values the terms have (36 per edge for the stretching)."""
        return sum(self._entries(term)[3] for term in self.terms)

    def _unique_pattern(self) -> Pattern:
        """The pattern by one np.unique over the keys row * n + col of every kept entry:
        for small systems, where it takes milliseconds and the kernels of the other two
        ways would first have to compile (seconds on a first run; the same arrays)."""
        width = max(self.n_free, 1)
        parts, kept = [], []
        for term in self.terms:
            pattern = term.pattern()
            if pattern is None:
                kept.append(np.zeros(0, bool))
                continue
            rows, cols = self._reduced[pattern[0]], self._reduced[pattern[1]]
            keep = (rows >= 0) & (cols >= 0)
            if self.upper:
                keep &= rows <= cols
            parts.append((rows * width + cols)[keep])
            kept.append(keep)
        diag = np.arange(self.n_free, dtype=np.int64)
        if self.guides is not None:  # a guided node's blocks whole: its rows mix
            dofs = self._guided_dofs()
            parts.append(guided_blocks(np.concatenate(parts), dofs, width, self.upper))
        parts.append(diag * width + diag)
        unique, inverse = np.unique(np.concatenate(parts), return_inverse=True)
        if self.guides is not None:
            self.guided = Guided(self.guides, self._guided_dofs(), unique, width, self.upper)
        indptr = np.zeros(self.n_free + 1, dtype=np.int32)
        np.cumsum(np.bincount(unique // width, minlength=self.n_free), out=indptr[1:])
        targets, start = [], 0
        for keep in kept:
            target = np.full(keep.size, -1, dtype=np.int64)
            count = int(keep.sum())
            target[np.flatnonzero(keep)] = inverse[start : start + count]
            start += count
            targets.append(target)
        return (
            indptr,
            (unique % width).astype(np.int32),
            targets,
            inverse[inverse.size - diag.size :],
        )

    def _entry_pattern(self) -> Pattern:
        """The pattern from every entry of every term (catenet.kernels.pattern): bucketed
        by row and made unique per row, no global sort."""
        upper = self.upper
        sources = [self._entries(term) for term in self.terms]
        sources.append((_NO_ELEMS, self.free_dofs, self.free_dofs, self.n_free))
        offsets = np.cumsum([0] + [s[3] for s in sources])
        start = np.zeros(self.n_free + 1, dtype=np.int64)
        empty_i32, empty_i64 = np.zeros(0, np.int32), np.zeros(0, np.int64)
        for elems, rows, cols, _ in sources:
            pattern_entries(
                elems, rows, cols, self._reduced, upper, start, empty_i32, empty_i64, 0, False
            )
        np.cumsum(start, out=start)
        cursor = start[:-1].copy()
        colbuf = np.empty(int(start[-1]), dtype=np.int32)
        srcbuf = np.empty(int(start[-1]), dtype=np.int64)
        for (elems, rows, cols, _), offset in zip(sources, offsets, strict=False):
            pattern_entries(
                elems, rows, cols, self._reduced, upper, cursor, colbuf, srcbuf, offset, True
            )
        del cursor
        indptr, indices, pos = pattern_csr(start, colbuf, srcbuf, int(offsets[-1]))
        targets = [pos[offsets[k] : offsets[k + 1]] for k in range(len(self.terms))]
        return indptr, indices, targets, pos[offsets[-2] :]

    @staticmethod
    def _entries(term: Term) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """A term's entries (elements, rows, cols, count of values): a term of a net's
        edges (``edge_net``: the stretching) gives them (row-major 6x6 blocks of their two
        nodes), every other term its pattern."""
        if term.edge_net is not None:
            edges = np.ascontiguousarray(term.edge_net.edges, dtype=np.int64)
            return edges, _NO_DOFS, _NO_DOFS, 36 * edges.shape[0]
        pattern = term.pattern()
        if pattern is None:
            return _NO_ELEMS, _NO_DOFS, _NO_DOFS, 0
        rows = np.ascontiguousarray(pattern[0], dtype=np.int64)
        cols = np.ascontiguousarray(pattern[1], dtype=np.int64)
        return _NO_ELEMS, rows, cols, rows.size

    @staticmethod
    def _pattern_key(term: Term) -> object:
        """Terms that share a pattern (variants of one stretch term) share its map."""
        return term.edge_net if term.edge_net is not None else term

    def _remember(self, term: Term, target: np.ndarray) -> None:
        key = self._pattern_key(term)
        self._targets[id(key)] = (key, target)

    def target(self, term: Term) -> np.ndarray:
        """Position in the CSR data of each of a term's Hessian values (-1: dropped, on a
        support or below the diagonal). A term not seen when the pattern was built must
        fit into it (node-local terms always do: every node's block is there)."""
        key = self._pattern_key(term)
        hit = self._targets.get(id(key))
        if hit is not None and hit[0] is key:
            return hit[1]
        pattern = term.pattern()
        if pattern is None:
            target = np.zeros(0, dtype=np.int64)
        else:
            rows = np.ascontiguousarray(pattern[0], dtype=np.int64)
            cols = np.ascontiguousarray(pattern[1], dtype=np.int64)
            target = np.empty(rows.size, dtype=np.int64)
            args = (self.indptr, self.indices, rows, cols, self._reduced, self.upper, target)
            if pattern_locate(*args):
                raise ValueError(
                    f"term {term.name!r} couples DOFs outside the workspace's sparsity "
                    "pattern: build the workspace with it"
                )
        self._remember(term, target)
        return target

    def with_terms(self, terms: Sequence[Term]) -> System:
        """The same pattern and buffers with other terms (e.g. the stretching under a
        smoothed law, for a continuation stage); they must fit into the pattern."""
        view = copy.copy(self)
        view.terms = tuple(terms)
        view._energies = [0.0] * len(view.terms)
        for term in view.terms:
            view.target(term)
        return view

    @property
    def stretch(self) -> Stretch:
        """The stretching term (every net has one)."""
        return next(t for t in self.terms if isinstance(t, Stretch))

    def _guided_dofs(self) -> np.ndarray:
        """(K, 3) the reduced DOFs of the guided nodes (none without guides)."""
        nodes = np.zeros(0, np.int64) if self.guides is None else self.guides.nodes
        dofs: np.ndarray = self._reduced[3 * nodes[:, None] + np.arange(3)]
        return dofs

    def restrict(self, flat: np.ndarray) -> np.ndarray:
        """A force or gradient (3N,) on the free DOFs: the free DOFs' entries, a guided
        node's projected on its free directions (a new array)."""
        out: np.ndarray = flat[self.free_dofs]
        if self.guided is not None:
            self.guided.project(out)
        return out

    # --- scalar and vector terms -------------------------------------------------------
    def energy(self, x: np.ndarray) -> float:
        return float(sum(term.energy(x) for term in self.terms))

    def gradient(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        """Energy of the terms and its gradient (N, 3) on all nodes (supports included:
        there it is minus the reaction needed to hold the net). The array is reused: copy
        to keep."""
        start = time.perf_counter()
        g = self._grad
        g.fill(0.0)
        energy = 0.0
        for k, term in enumerate(self.terms):
            self._energies[k] = term.gradient(x, g)
            energy += self._energies[k]
        self.seconds += time.perf_counter() - start
        return energy, g

    @property
    def energies(self) -> list[float]:
        """Each term's energy at the x of the last ``gradient`` call."""
        return self._energies

    def roundoff(self, x: np.ndarray) -> tuple[float, float]:
        """Round-off levels of the terms' gradient norm and energy (see Term.roundoff) at
        the x of the last ``gradient`` call."""
        grad = level = 0.0
        for term, energy in zip(self.terms, self._energies, strict=True):
            g, e = term.roundoff(x, energy)
            grad += g
            level += e
        return grad, level

    def stiffness(self) -> np.ndarray:
        """Per free DOF, the scale of the Hessian's diagonal (for the regularisation)."""
        total = np.zeros(self.net.n_nodes)
        for term in self.terms:
            k = term.stiffness()
            if k is not None:
                total += k
        return np.repeat(total[~self.net.fixed], 3)

    def tension(self, x: np.ndarray) -> np.ndarray:
        return self.stretch.tension(x)

    # --- matrix ------------------------------------------------------------------------
    def hessian(
        self,
        x: np.ndarray,
        shift: np.ndarray | None = None,
        extra: Sequence[Term] = (),
        skip: Sequence[Term] = (),
    ) -> np.ndarray:
        """Fills and returns the CSR data of the Hessian of the terms (and of ``extra``
        terms, such as a time step's inertia) plus diag(shift) on the free DOFs, without
        the ``skip`` terms.
        Afterwards ``convex`` says whether only convex terms contributed (a non-convex
        obstacle out of reach writes nothing): then the matrix is positive semidefinite
        and the linear solver may use Cholesky for it."""
        start = time.perf_counter()
        data = self.data
        data.fill(0.0)
        definite = True  # every term that wrote values is convex (see ``convex``)
        for term in (*self.terms, *extra):
            if skip and any(term is t for t in skip):
                continue
            target = self.target(term)
            if not target.size:
                continue
            values = self._values.get(target.size)
            if values is None:
                values = self._values[target.size] = np.empty(target.size)
            if term.hessian(x, values) is False:
                continue  # the term says its values are all zero (no contact)
            definite = definite and term.convex
            scatter_add(values, target, data)
        if shift is not None:
            add_diagonal(self.diag_pos, shift, data)
        if self.guided is not None:
            self.guided.project_matrix(data)
        self.convex = definite
        self.seconds += time.perf_counter() - start
        return data

    def matrix(self, data: np.ndarray | None = None) -> sp.csr_matrix:
        """The (reduced) matrix as SciPy CSR, full (both triangles) even when stored upper."""
        import scipy.sparse as sp

        data = self.data if data is None else data
        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_free, self.n_free))
        if self.upper:
            a = a + sp.triu(a, k=1, format="csr").T
        return a.tocsr()

    def dense(self, data: np.ndarray | None = None) -> np.ndarray:
        """The (reduced) matrix as a dense array, both triangles (without SciPy's sparse
        module: a small static run's verdict needs it, and its start-up does not)."""
        data = self.data if data is None else data
        n = self.n_free
        out = np.zeros((n, n))
        rows = np.repeat(np.arange(n), np.diff(self.indptr))
        out[rows, self.indices] = data  # (a CSR pattern holds each entry once)
        if self.upper:
            out += np.triu(out, k=1).T
        return out

    def diagonal(self, data: np.ndarray | None = None) -> np.ndarray:
        data = self.data if data is None else data
        return data[self.diag_pos]
