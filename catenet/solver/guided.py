"""Rollers and sliders in the Newton system (``catenet.model.guides``): exact, no penalty.

A guided node keeps its three DOFs in the system, but its residual is projected on its
free directions (T g, T = 1 - Q) and its rows and columns of the matrix too; its held
directions get d Q on the diagonal block (d its block's mean diagonal):

    A' = P A P + D_Q,   P = diag(T at guided nodes, 1 elsewhere).

A Newton step solves A' dx = -P g. Its held part b = Q dx meets d b = 0 (the held rows
are decoupled and their right-hand side is zero), so b = 0: every step lies in the free
directions, and on them it is the Newton step of the potential restricted to the guide
(T A T on the free directions), the step a basis x = X + B q of the free directions
would give. The constraint therefore holds exactly, to the round-off of the projection;
the held part of the residual is the reaction. The pattern of a guided node's blocks is
taken whole (its rows mix), and a guided node's scaling, inertia and regularisation
(isotropic per node) commute with P.
"""

from __future__ import annotations

import numpy as np

from catenet.model.guides import Guides


def guided_blocks(keys: np.ndarray, dofs: np.ndarray, width: int, upper: bool) -> np.ndarray:
    """Keys (row * width + col) of every entry of the 3 x 3 node blocks that the
    entries ``keys`` touch at a guided node (``dofs`` (K, 3): their reduced DOFs), both
    ways round (only row <= col where ``upper``): a guided node's blocks whole."""
    guided = np.zeros(max(width // 3, 1), dtype=bool)
    guided[dofs[:, 0] // 3] = True
    r, c = keys // width // 3, keys % width // 3
    touch = guided[r] | guided[c]
    pairs = np.unique(np.concatenate([r[touch] * width + c[touch], c[touch] * width + r[touch]]))
    pr, pc = pairs // width, pairs % width
    a = np.repeat(np.arange(3), 3)
    b = np.tile(np.arange(3), 3)
    rows = (3 * pr[:, None] + a[None]).ravel()
    cols = (3 * pc[:, None] + b[None]).ravel()
    keep = rows <= cols if upper else np.ones(rows.size, bool)
    out: np.ndarray = rows[keep] * width + cols[keep]
    return out


class Guided:
    """The projection of the guided nodes' rows and columns in a system's pattern:
    ``unique`` the sorted keys row * width + col of its CSR entries (their order in the
    CSR data), ``dofs`` (K, 3) the guided nodes' reduced DOFs."""

    def __init__(
        self, guides: Guides, dofs: np.ndarray, unique: np.ndarray, width: int, upper: bool
    ):
        self.dofs = dofs
        self.held = guides.held
        tangent = guides.tangent
        index = np.full(max(width // 3, 1), -1, dtype=np.int64)
        index[dofs[:, 0] // 3] = np.arange(len(dofs))
        r, c = unique // width // 3, unique % width // 3
        touch = (index[r] >= 0) | (index[c] >= 0)
        pairs = np.unique(r[touch] * width + c[touch])
        br, bc = pairs // width, pairs % width
        a = np.repeat(np.arange(3), 3)[None]
        b = np.tile(np.arange(3), 3)[None]
        rows, cols = 3 * br[:, None] + a, 3 * bc[:, None] + b
        if upper:  # a diagonal block's lower entries are its upper ones
            rows, cols = np.minimum(rows, cols), np.maximum(rows, cols)
        want = rows * width + cols
        pos = np.searchsorted(unique, want)
        if not np.array_equal(unique[np.minimum(pos, unique.size - 1)], want):
            raise ValueError("a guided node's block is not whole in the pattern")
        self.pos = pos  # (B, 9) each block's entries in the CSR data
        eye = np.eye(3)
        self.row_t = np.where((index[br] >= 0)[:, None, None], tangent[index[br]], eye)
        self.col_t = np.where((index[bc] >= 0)[:, None, None], tangent[index[bc]], eye)
        own = br == bc
        self.own = np.flatnonzero(own)  # the guided nodes' own blocks
        self.own_guide = index[br[own]]

    def project(self, v: np.ndarray) -> np.ndarray:
        """The free part of a reduced vector (in place): T v at every guided node."""
        y = v[self.dofs]
        v[self.dofs] = y - np.einsum("kij,kj->ki", self.held, y)
        return v

    def project_matrix(self, data: np.ndarray) -> None:
        """P A P + d Q on the guided nodes' blocks of the CSR ``data`` (in place)."""
        blocks = data[self.pos].reshape(-1, 3, 3)
        own = blocks[self.own]
        d = np.trace(own, axis1=1, axis2=2) / 3.0
        if not np.all(d > 0.0):
            fallback = float(np.max(np.abs(data), initial=0.0)) or 1.0
            d = np.where(d > 0.0, d, fallback)
        out = self.row_t @ blocks @ self.col_t
        mine = out[self.own] + d[:, None, None] * self.held[self.own_guide]
        out[self.own] = 0.5 * (mine + np.swapaxes(mine, 1, 2))
        data[self.pos.ravel()] = out.reshape(-1)
