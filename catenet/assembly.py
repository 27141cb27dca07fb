"""Gradient and Hessian of the stretching energy on the free DOFs of a net.

The sparsity pattern of the reduced system (supports eliminated) comes from the topology
once; every Newton iteration only refills the values. For a symmetric solver only the
upper triangle is stored. Slack edges keep their (zero) entries: the pattern never changes,
so the symbolic analysis of the linear solver stays valid for the whole run.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from catenet.kernels.sparse import add_diagonal, scatter
from catenet.kernels.stretch import (
    stretch_energy,
    stretch_gradient,
    stretch_hessian,
    stretch_tension,
)
from catenet.net import Net


class System:
    """Energy, gradient and Hessian of a net's stretching energy on its free DOFs.

    Parameters
    ----------
    net : the net
    upper : store only the upper triangle (for symmetric solvers)
    """

    def __init__(self, net: Net, *, upper: bool = True):
        self.net = net
        self.upper = upper
        n = net.n_nodes
        free_node = ~net.fixed
        self.free = np.repeat(free_node, 3)  # (3N,) mask of free DOFs
        self.free_dofs = np.flatnonzero(self.free)
        self.n_free = int(self.free_dofs.size)
        reduced = np.full(3 * n, -1, dtype=np.int64)
        reduced[self.free_dofs] = np.arange(self.n_free)

        # Local DOFs of every edge: (M, 6) global DOF indices (x_i, y_i, z_i, x_j, y_j, z_j).
        e = net.edges
        local = np.concatenate([3 * e[:, :1] + np.arange(3), 3 * e[:, 1:] + np.arange(3)], axis=1)
        rows = np.repeat(reduced[local], 6, axis=1).ravel()  # value 6a+b has row local[a]
        cols = np.tile(reduced[local], (1, 6)).ravel()  #               and col local[b]
        keep = (rows >= 0) & (cols >= 0)
        if upper:
            keep &= rows <= cols
        diag = np.arange(self.n_free)
        all_rows = np.concatenate([rows[keep], diag])
        all_cols = np.concatenate([cols[keep], diag])
        keys = all_rows * max(self.n_free, 1) + all_cols
        unique, inverse = np.unique(keys, return_inverse=True)
        urows = unique // max(self.n_free, 1)
        self.indices = (unique % max(self.n_free, 1)).astype(np.int32)
        self.indptr = np.zeros(self.n_free + 1, dtype=np.int32)
        np.cumsum(np.bincount(urows, minlength=self.n_free), out=self.indptr[1:])
        self.target = np.full(rows.size, -1, dtype=np.int64)
        self.target[np.flatnonzero(keep)] = inverse[: int(keep.sum())]
        self.diag_pos = inverse[int(keep.sum()) :].astype(np.int64)
        self.nnz = int(unique.size)

        # Preallocated buffers, refilled every call.
        self._values = np.empty(36 * net.n_edges)
        self._grad = np.zeros((n, 3))
        self.data = np.zeros(self.nnz)
        self.seconds = 0.0  # spent filling gradients and Hessians
        self.smooth = 0.0  # smoothing mu of the tension-only law (0: exact)
        self.EA = net.EA  # the stiffness the kernels use (scaled during continuation)
        self.stiffness_factor = 1.0

    # --- scalar and vector terms -------------------------------------------------------
    def energy(self, x: np.ndarray) -> float:
        net = self.net
        return stretch_energy(
            x, net.edges, net.rest_length, self.EA, net.tension_only, self.smooth
        )

    def gradient(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        """Stretching energy and its gradient (N, 3) on all nodes (supports included: there
        it is minus the reaction needed to hold the net). The array is reused: copy to keep."""
        net = self.net
        start = time.perf_counter()
        g = self._grad
        g.fill(0.0)
        energy = stretch_gradient(
            x, net.edges, net.rest_length, self.EA, net.tension_only, self.smooth, g
        )
        self.seconds += time.perf_counter() - start
        return energy, g

    def scale_stiffness(self, factor: float) -> None:
        """Let the kernels use factor * EA (1: the net's own), for the static solver's
        stiffness continuation of nearly inextensible nets."""
        self.stiffness_factor = float(factor)
        self.EA = self.net.EA if factor == 1.0 else self.net.EA * factor

    def tension(self, x: np.ndarray) -> np.ndarray:
        net = self.net
        out = np.empty(net.n_edges)
        stretch_tension(x, net.edges, net.rest_length, net.EA, net.tension_only, out)
        return out

    # --- matrix ------------------------------------------------------------------------
    def hessian(self, x: np.ndarray, shift: np.ndarray | None = None) -> np.ndarray:
        """Fills and returns the CSR data of K + diag(shift) on the free DOFs."""
        start = time.perf_counter()
        net = self.net
        stretch_hessian(
            x,
            net.edges,
            net.rest_length,
            self.EA,
            net.tension_only,
            self.smooth,
            self._values,
        )
        scatter(self._values, self.target, self.data)
        if shift is not None:
            add_diagonal(self.diag_pos, shift, self.data)
        self.seconds += time.perf_counter() - start
        return self.data

    def matrix(self, data: np.ndarray | None = None) -> sp.csr_matrix:
        """The (reduced) matrix as SciPy CSR, full (both triangles) even when stored upper."""
        data = self.data if data is None else data
        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_free, self.n_free))
        if self.upper:
            a = a + sp.triu(a, k=1, format="csr").T
        return a.tocsr()

    def diagonal(self, data: np.ndarray | None = None) -> np.ndarray:
        data = self.data if data is None else data
        return data[self.diag_pos]
