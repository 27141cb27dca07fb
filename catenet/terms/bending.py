"""Bending of rods: E = sum over hinges of EI / (l1 + l2) (|t2 - t1| - s0)^2, plus the
clamps' EI / l |t - t0|^2 (``catenet.kernels.bending`` derives it and its exact
derivatives; ``catenet.model.rods`` says which edges bend).

Guarantee: the energy, its gradient and its Hessian are finite and exact for every
state whose edges have nonzero length, folds of 180 degrees included (a fold is the
energy's smooth maximum, s = 2); for a straight rod (s0 = 0) they are smooth
everywhere. The Hessian is indefinite where a hinge is bent (the term is not convex).
A rod bends at its interior nodes only: a rod end is free to turn (pinned), unless it
is clamped; where two lines meet, they are pinned to each other.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from catenet.kernels.bending import bend_energy, bend_gradient, bend_hessian
from catenet.model.rods import Rods
from catenet.terms.base import Term, register


def _dense_pattern(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the dense Hessian blocks of each row of ``nodes`` (K, n), row-major
    over its 3n DOFs."""
    n = nodes.shape[1]
    local = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(nodes), 3 * n)
    rows = np.repeat(local, 3 * n, axis=1).ravel()
    cols = np.tile(local, (1, 3 * n)).ravel()
    return rows, cols


def dense_blocks(groups) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of a dense Hessian block over each of ``groups`` (arrays of node
    indices, of any lengths), row-major over its DOFs, one after another."""
    rows, cols = [], []
    for nodes in groups:
        dofs = (3 * np.asarray(nodes, dtype=np.int64)[:, None] + np.arange(3)).ravel()
        rows.append(np.repeat(dofs, dofs.size))
        cols.append(np.tile(dofs, dofs.size))
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(rows), np.concatenate(cols)


@register("bending")
class Bending(Term):
    """The rods' bending energy (module docstring)."""

    role = "internal"
    convex = False
    structural = True

    def __init__(self, rods: Rods, n_nodes: int):
        self.rods = rods
        self.n_nodes = int(n_nodes)
        self._k = np.ascontiguousarray(rods.k)
        self._kc = np.ascontiguousarray(rods.kc)

    def _args(self):
        r = self.rods
        return r.hinges, self._k, r.s0, r.clamps, r.tangent, self._kc

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        hr, hc = _dense_pattern(self.rods.hinges)
        cr, cc = _dense_pattern(self.rods.clamps)
        return np.concatenate([hr, cr]), np.concatenate([hc, cc])

    def energy(self, x: np.ndarray) -> float:
        return float(bend_energy(x, *self._args()))

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        return float(bend_gradient(x, *self._args(), grad))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        bend_hessian(x, *self._args(), values)

    @cached_property
    def _scale(self) -> np.ndarray:
        """Per node, the scale of its Hessian diagonal [N/m]: 4 k / lbar^2 at a hinge's
        interior node, k / lbar^2 at its two others, kc / l^2 at a clamp's nodes."""
        r = self.rods
        out = np.zeros(self.n_nodes)
        unit = self._k / r.voronoi**2
        np.add.at(out, r.hinges[:, 0], unit)
        np.add.at(out, r.hinges[:, 1], 4.0 * unit)
        np.add.at(out, r.hinges[:, 2], unit)
        clamp = self._kc / r.clamp_length**2
        np.add.at(out, r.clamps[:, 0], clamp)
        np.add.at(out, r.clamps[:, 1], clamp)
        return out

    def stiffness(self) -> np.ndarray:
        return self._scale

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """A coordinate error eps |x| moves a node's force by its stiffness times it; a
        tangent error eps changes a hinge's energy by 2 k s eps <= 2 sqrt(k E_h) eps
        (levels in units of eps, as every term's)."""
        size = float(np.max(np.abs(x)))
        total_k = float(np.sum(self._k) + np.sum(self._kc))
        level = float(np.linalg.norm(self._scale)) * size
        return level, abs(energy) + 2.0 * float(np.sqrt(total_k * abs(energy)))

    def node_roundoff(self, x: np.ndarray, energy: float) -> np.ndarray:
        return self._scale * float(np.max(np.abs(x)))
