"""Internal axial damping of the cables (``material.axial_damping``, c [N s]): a dashpot
in parallel with each edge's stretch, the tension c de/dt added to the elastic one
(MoorDyn's BA, OrcaFlex's axial damping). It is the rope's own material damping: it
damps the axial waves that ring along an undamped line after an impact (and that
``solver.damping``, proportional to the mass, leaves alone), not the line's motion as
a whole.

In a time step the scheme's velocity is affine in the positions, v = kv (x - c)
(implicit Euler: kv = 1 / h, c = x_n; ``set_motion``). With each edge's tangent t taken
at the step's start (lagged, as the water's drag takes it), the edge's strain rate is
kv t . (dx - dc) / l0 (dx = x_j - x_i, dc = c_j - c_i), and the damping force is the
gradient of the convex quadratic

    Psi(x) = sum_e 1/2 (c_e kv / l0_e) (t_e . (dx_e - dc_e))^2,

whose Hessian (c_e kv / l0_e) t_e t_e^T on the edge's 6 x 6 block is exact and positive
semi-definite: Newton stays quadratic and the step stays implicit (no stability limit).
What it guarantees: the force opposes the edge's rate of stretch, so it only removes
energy (``losses``: the energy balance books it as dissipated, >= 0 for implicit Euler).
A static step (kv = 0) sees none: an equilibrium is the same with or without it.
"""

from __future__ import annotations

import numpy as np

from catenet.model.net import Net
from catenet.terms.base import Term, register


@register("axial_damping")
class AxialDamping(Term):
    """The dashpot ``c`` [N s] (M,) of every edge of ``net`` (0: none), see the module
    docstring."""

    medium = True  # has begin_run, set_motion, kinetic, losses (catenet.terms.base)
    lagged = False
    structural = True  # the ropes' own force (their tensions hold it): no contact

    def __init__(self, net: Net, c: np.ndarray):
        c = np.asarray(c, dtype=np.float64)
        if c.shape != (net.n_edges,) or not np.all(np.isfinite(c)) or np.any(c < 0.0):
            raise ValueError("axial damping: one finite c >= 0 per edge")
        self.net = self.edge_net = net
        self.edges = np.ascontiguousarray(net.edges, dtype=np.int64)
        self.rate = c / net.rest_length  # [N s / m]: c / l0
        self.kv = 0.0  # 0: a static step (nothing moves)
        self.tang = np.zeros((net.n_edges, 3))
        self.centre = np.zeros_like(net.nodes)
        self._force = np.zeros_like(net.nodes)  # the force at the last step's end
        self._lag(net.nodes)

    def _lag(self, x: np.ndarray) -> None:
        d = x[self.edges[:, 1]] - x[self.edges[:, 0]]
        length = np.linalg.norm(d, axis=1)
        safe = np.where(length > 0.0, length, 1.0)
        self.tang = np.where((length > 0.0)[:, None], d / safe[:, None], 0.0)

    # --- the step's motion (catenet.solver.stepper) ----------------------------------
    def begin_step(self, x: np.ndarray, time: float | None, start: float | None = None) -> None:
        """A time step: the tangents at its start; a static step: no damping."""
        if time is None:
            self.kv = 0.0
        self._lag(x)

    def begin_run(self, x: np.ndarray, t: float) -> None:
        self.kv = 0.0
        self._lag(x)
        self._force[:] = 0.0

    def set_motion(self, kv: float, centre: np.ndarray, ka: float, centre_a: np.ndarray) -> None:
        self.kv = float(kv)
        self.centre[:] = centre

    # --- the term --------------------------------------------------------------------
    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        e = self.edges
        local = np.concatenate([3 * e[:, :1] + np.arange(3), 3 * e[:, 1:] + np.arange(3)], axis=1)
        return np.repeat(local, 6, axis=1).ravel(), np.tile(local, (1, 6)).ravel()

    def _stretch(self, x: np.ndarray) -> np.ndarray:
        """t . (dx - dc) of every edge (its stretch since the scheme's centre)."""
        i, j = self.edges[:, 0], self.edges[:, 1]
        w = (x[j] - x[i]) - (self.centre[j] - self.centre[i])
        return np.einsum("ij,ij->i", self.tang, w)

    def tension(self, x: np.ndarray) -> np.ndarray:
        """The damping tension c de/dt of every edge at x [N] (0 in a static step)."""
        if self.kv == 0.0:
            return np.zeros(len(self.edges))
        return self.kv * self.rate * self._stretch(x)

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        if self.kv == 0.0:
            return 0.0
        s = self._stretch(x)
        force = (self.kv * self.rate * s)[:, None] * self.tang
        n = len(grad)
        i, j = self.edges[:, 0], self.edges[:, 1]
        for a in range(3):  # (bincount: the edges' sums per node, no np.add.at loop)
            grad[:, a] += np.bincount(j, force[:, a], n) - np.bincount(i, force[:, a], n)
        return 0.5 * float(np.sum(self.kv * self.rate * s * s))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> bool:
        blocks = values.reshape(-1, 6, 6)
        if self.kv == 0.0:
            blocks[:] = 0.0
            return False
        k = (self.kv * self.rate)[:, None, None] * np.einsum("ei,ej->eij", self.tang, self.tang)
        blocks[:, :3, :3] = k
        blocks[:, 3:, 3:] = k
        blocks[:, :3, 3:] = -k
        blocks[:, 3:, :3] = -k
        return True

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        if self.kv == 0.0:
            return 0.0, 0.0
        size = np.abs(x[self.edges]).sum(axis=(1, 2)) + np.abs(self.centre[self.edges]).sum(
            axis=(1, 2)
        )
        return float(np.linalg.norm(self.kv * self.rate * size)), abs(energy)

    # --- the energy balance (catenet.solver.energy) ----------------------------------
    def mass_blocks(self) -> np.ndarray:
        return np.zeros((self.net.n_nodes, 3, 3))

    def kinetic(self, v: np.ndarray) -> float:
        return 0.0

    def losses(
        self,
        x_old: np.ndarray,
        x_new: np.ndarray,
        h: float,
        mean: bool = False,
        commit: bool = True,
    ) -> tuple[float, float]:
        """(dissipated, 0) of the step from x_old to x_new: the dashpots' work against the
        motion, -F . dx (F the force at the step's end, or the mean of its two ends for
        the second-order schemes; ``commit``: the step is accepted, its end's force the
        next step's start)."""
        g = np.zeros_like(x_new)
        self.gradient(x_new, g)
        force = -g
        used = 0.5 * (force + self._force) if mean else force
        if commit:
            self._force = force
        return -float(np.sum(used * (x_new - x_old))), 0.0
