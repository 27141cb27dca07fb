"""Stretching of the edges: the net's own energy, under its material law."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from catenet.kernels.stretch import (
    stretch_energy,
    stretch_gradient_work,
    stretch_held,
    stretch_hessian,
    stretch_near_taut,
    stretch_node_roundoff,
    stretch_release,
    stretch_tension,
)
from catenet.model.laws import Law
from catenet.model.net import Net
from catenet.terms.base import Term, register

RELEASES = 3  # an edge released this often in one solve stays released (no cycling)
HOLD_REACH = 1e-4  # safeguarded Newton holds edges slack by less than this strain (``hold``)
_NO_ROWS = np.zeros((0, 3))
_NO_VALUES = np.zeros(0)


@register("stretch")
@dataclass(frozen=True, eq=False)
class Stretch(Term):
    """U = sum over edges of EA l0 w(eps) (``catenet.kernels.stretch``).

    ``law``: the edges' material law (default: the net's, the paper's linear law);
    ``scale``: a factor on EA (the static solver's stiffness continuation; 1: the net's).
    ``with_law`` and ``scaled`` give variants that share the arrays and the pattern.
    """

    net: Net
    law: Law = None  # type: ignore[assignment]  # None: the net's (set below)
    scale: float = 1.0
    role = "internal"

    def __post_init__(self):
        if self.law is None:
            object.__setattr__(self, "law", self.net.law)
        object.__setattr__(self, "edge_net", self.net)

    @property
    def convex(self) -> bool:  # tension-only edges of a stiffening law
        return self.law.convex

    @cached_property
    def EA(self) -> np.ndarray:
        return self.net.EA if self.scale == 1.0 else self.net.EA * self.scale

    def with_law(self, law: Law) -> Stretch:
        return dataclasses.replace(self, law=law)

    def scaled(self, scale: float) -> Stretch:
        return dataclasses.replace(self, scale=float(scale))

    def _args(self):
        net, law = self.net, self.law
        return (
            net.edges,
            net.rest_length,
            self.EA,
            law.kernel_kind,
            law.params,
            law.table,
            law.tension_only,
        )

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        e = self.net.edges
        local = np.concatenate([3 * e[:, :1] + np.arange(3), 3 * e[:, 1:] + np.arange(3)], axis=1)
        rows = np.repeat(local, 6, axis=1).ravel()  # value 6a+b has row local[a]
        cols = np.tile(local, (1, 6)).ravel()  #               and col local[b]
        return rows, cols

    def energy(self, x: np.ndarray) -> float:
        return stretch_energy(x, *self._args(), self.law.smooth)

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        energy, self._work[0] = stretch_gradient_work(x, *self._args(), self.law.smooth, grad)
        return energy

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        stretch_hessian(x, *self._args(), self.law.smooth, values)
        if self._holding[0]:
            stretch_held(x, *self._args()[:6], self.held, values, _NO_ROWS)

    # --- Newton's safeguarded mode: near-slack edges held as if taut --------------------------
    @cached_property
    def held(self) -> np.ndarray:
        """Per edge: held in Newton's model as if taut while slack (``hold``)."""
        return np.zeros(self.net.n_edges, dtype=np.bool_)

    @cached_property
    def _released(self) -> np.ndarray:
        """Per edge: how often released in this solve (RELEASES: for good)."""
        return np.zeros(self.net.n_edges, dtype=np.int64)

    @cached_property
    def _recent(self) -> np.ndarray:
        """Per edge: released by the last step (not held at the next factorisation)."""
        return np.zeros(self.net.n_edges, dtype=np.bool_)

    @cached_property
    def _holding(self) -> np.ndarray:
        return np.zeros(1, dtype=np.bool_)

    def safeguard(self, on: bool) -> None:
        """Newton's safeguarded mode (``catenet.solver.newton``): while on, ``hold`` picks the
        edges the model holds; off, none is held and every release is forgotten."""
        on = on and self.law.smooth == 0.0 and self.law.any_tension_only
        self._holding[0] = on
        self.held[:] = False
        if not on:
            self._released[:] = 0
            self._recent[:] = False

    def hold(self, x: np.ndarray) -> None:
        """While safeguarded: Newton's model at x holds the tension-only edges slack by a
        strain below HOLD_REACH as if taut (their axial stiffness in the Hessian, their
        pull toward the rest length in the model's gradient: ``model_gradient``), but
        those the last step released and those released RELEASES times in this solve
        (``release``: held again once taut and slack anew). A net just at its rest lengths (a
        flat net thrown, a net meeting a body) has thousands of such edges; the exact
        Hessian, zero for each, lets Newton move their nodes as if free, far past the
        edges' lengths, and the line search then cuts the whole step: one ring of edges
        taken up per iteration. Held, they are taken up together."""
        if not self._holding[0]:
            return
        net = self.net
        stretch_near_taut(x, net.edges, net.rest_length, self.law.tension_only, HOLD_REACH,
                          self.held)  # fmt: skip
        np.logical_and(self.held, ~self._recent, out=self.held)
        np.logical_and(self.held, self._released < RELEASES, out=self.held)
        self._recent[:] = False

    def release(self, x: np.ndarray, dx: np.ndarray) -> int:
        """Releases the held slack edges that the model's step dx (N, 3) from x leaves
        below their rest length (the model pushes on them there; a cable cannot) for the
        next factorisation, for good at their RELEASES-th release: how many."""
        if not self._holding[0]:
            return 0
        net = self.net
        return int(
            stretch_release(x, dx, net.edges, net.rest_length, self.held, self._released,
                            self._recent)
        )  # fmt: skip

    def model_gradient(self, x: np.ndarray, grad: np.ndarray) -> int:
        """Adds the held slack edges' pull toward their rest length to grad (N, 3): the
        model's gradient, not Phi's; how many edges pulled."""
        if not self._holding[0]:
            return 0
        return int(stretch_held(x, *self._args()[:6], self.held, _NO_VALUES, grad))

    def tension(self, x: np.ndarray) -> np.ndarray:
        """Axial force of every edge [N] under the exact (unsmoothed) law."""
        out = np.empty(self.net.n_edges)
        stretch_tension(x, *self._args(), out)
        return out

    @cached_property
    def _k_norm(self) -> float:
        return float(np.sqrt(2.0 * np.sum((self.EA / self.net.rest_length) ** 2)))

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        """Coordinates of size |x| carry an error eps |x|, which each edge turns into a
        force error EA eps |x| / l0 at both of its nodes; a strain error eps changes an
        edge's energy by N |e| eps, however small the energy itself (a stiff strut at a
        small strain): differences of U below sum |N| |e| eps are noise (both levels in
        units of eps: see Potential)."""
        work = float(self._work[0])  # from the gradient at this x (System.roundoff)
        return self._k_norm * float(np.max(np.abs(x))), abs(energy) + 0.0625 * work

    def node_roundoff(self, x: np.ndarray, energy: float = 0.0) -> np.ndarray:
        """Per node, the round-off of the forces that meet there (units of eps): every
        edge's |N| + EA |x| / l0 (``kernels.stretch.stretch_node_roundoff``)."""
        level = np.zeros(x.shape[0])
        stretch_node_roundoff(x, *self._args(), self.law.smooth, level)
        return level

    @cached_property
    def _work(self) -> np.ndarray:
        """sum |N| |e| at the x of the last ``gradient`` call (``roundoff`` reads it)."""
        return np.zeros(1)

    def stiffness(self) -> np.ndarray:
        """Per node, half the sum of EA/l0 of its edges [N/m]."""
        net = self.net
        return net.axial_stiffness if self.scale == 1.0 else net.axial_stiffness * self.scale


@register("springs")
class Springs(Term):
    """Linear springs of zero rest length along the edges, stiffness q per edge [N/m]:
    U = 1/2 sum q |x_j - x_i|^2 (the force density method's energy). Its Hessian is the
    graph Laplacian of q times the 3x3 identity, in the stretching's pattern: the static
    solver's stretched start solves with it on the net's own factorisation."""

    role = "internal"
    convex = True

    def __init__(self, net: Net, q: np.ndarray):
        self.net = self.edge_net = net
        self.q = np.ascontiguousarray(q, dtype=np.float64)

    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return Stretch(self.net).pattern()

    def _e(self, x: np.ndarray) -> np.ndarray:
        edges = self.net.edges
        return x[edges[:, 1]] - x[edges[:, 0]]

    def energy(self, x: np.ndarray) -> float:
        e = self._e(x)
        return 0.5 * float(np.sum(self.q * np.einsum("ij,ij->i", e, e)))

    def gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        e = self._e(x)
        force = self.q[:, None] * e
        edges = self.net.edges
        np.add.at(grad, edges[:, 1], force)
        np.subtract.at(grad, edges[:, 0], force)
        return 0.5 * float(np.sum(force * e))

    def hessian(self, x: np.ndarray, values: np.ndarray) -> None:
        block = np.kron(np.array([[1.0, -1.0], [-1.0, 1.0]]), np.eye(3))  # (6, 6)
        values.reshape(-1, 6, 6)[:] = self.q[:, None, None] * block

    def roundoff(self, x: np.ndarray, energy: float) -> tuple[float, float]:
        return float(np.linalg.norm(self.q)) * float(np.max(np.abs(x))), abs(energy)

    def node_roundoff(self, x: np.ndarray, energy: float) -> np.ndarray:
        """Per node, the sum of q of its edges times max |x| (units of eps)."""
        out = np.zeros(x.shape[0])
        edges = self.net.edges
        np.add.at(out, edges[:, 0], self.q)
        np.add.at(out, edges[:, 1], self.q)
        return out * float(np.max(np.abs(x)))
