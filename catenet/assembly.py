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

from catenet.kernels.sparse import add_diagonal, scatter_add
from catenet.net import Net
from catenet.terms import Stretch, Term

if TYPE_CHECKING:  # SciPy is imported where a matrix is asked for: not on a run's path
    import scipy.sparse as sp


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

        # The pattern: every term's entries on free DOFs, and the diagonal.
        width = max(self.n_free, 1)
        parts, kept = [], []
        for term in self.terms:
            keys, keep = self._keys(term)
            parts.append(keys[keep])
            kept.append(keep)
        diag = np.arange(self.n_free, dtype=np.int64)
        parts.append(diag * width + diag)
        unique, inverse = np.unique(np.concatenate(parts), return_inverse=True)
        self._unique = unique
        urows = unique // width
        self.indices = (unique % width).astype(np.int32)
        self.indptr = np.zeros(self.n_free + 1, dtype=np.int32)
        np.cumsum(np.bincount(urows, minlength=self.n_free), out=self.indptr[1:])
        self.nnz = int(unique.size)
        self._targets: dict[int, tuple[object, np.ndarray]] = {}
        start = 0
        for term, keep in zip(self.terms, kept, strict=True):
            target = np.full(keep.size, -1, dtype=np.int64)
            count = int(keep.sum())
            target[np.flatnonzero(keep)] = inverse[start : start + count]
            start += count
            self._remember(term, target)
        self.diag_pos = inverse[start:].astype(np.int64)

        self._values: dict[int, np.ndarray] = {}
        self._grad = np.zeros((n, 3))
        self._energies = [0.0] * len(self.terms)
        self.data = np.zeros(self.nnz)
        self.seconds = 0.0  # spent filling gradients and Hessians

    # --- pattern -----------------------------------------------------------------------
    def _keys(self, term: Term) -> tuple[np.ndarray, np.ndarray]:
        """Keys row * n_free + col of a term's entries on free DOFs, and which count."""
        pattern = term.pattern()
        if pattern is None:
            return np.zeros(0, np.int64), np.zeros(0, bool)
        rows = self._reduced[pattern[0]]
        cols = self._reduced[pattern[1]]
        keep = (rows >= 0) & (cols >= 0)
        if self.upper:
            keep &= rows <= cols
        return rows * max(self.n_free, 1) + cols, keep

    @staticmethod
    def _pattern_key(term: Term) -> object:
        """Terms that share a pattern (variants of one stretch term) share its map."""
        return term.net if isinstance(term, Stretch) else term

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
        keys, keep = self._keys(term)
        pos = np.searchsorted(self._unique, keys[keep])
        pos = np.minimum(pos, max(self.nnz - 1, 0))
        if keep.any() and not np.array_equal(self._unique[pos], keys[keep]):
            raise ValueError(
                f"term {term.name!r} couples DOFs outside the workspace's sparsity pattern: "
                "build the workspace with it"
            )
        target = np.full(keep.size, -1, dtype=np.int64)
        target[np.flatnonzero(keep)] = pos
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
        self, x: np.ndarray, shift: np.ndarray | None = None, extra: Sequence[Term] = ()
    ) -> np.ndarray:
        """Fills and returns the CSR data of the Hessian of the terms (and of ``extra``
        terms, such as a time step's inertia) plus diag(shift) on the free DOFs."""
        start = time.perf_counter()
        data = self.data
        data.fill(0.0)
        for term in (*self.terms, *extra):
            target = self.target(term)
            if not target.size:
                continue
            values = self._values.get(target.size)
            if values is None:
                values = self._values[target.size] = np.empty(target.size)
            if term.hessian(x, values) is False:
                continue  # the term says its values are all zero (no contact)
            scatter_add(values, target, data)
        if shift is not None:
            add_diagonal(self.diag_pos, shift, data)
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

    def diagonal(self, data: np.ndarray | None = None) -> np.ndarray:
        data = self.data if data is None else data
        return data[self.diag_pos]
