"""Supports that hold a node in some directions only: rollers (held along a normal, free
in the plane across it) and sliders (free along a direction only), in any orientation.

A guided node moves on the affine set x = X + T (x - X) through its given position X,
T = 1 - Q the projector onto its free directions and Q onto the held ones (both
symmetric, T Q = 0). The solvers keep the constraint exactly: the residual and the
Newton matrix of a guided node are projected (T g; T K T + d Q on its diagonal block,
``catenet.solver.system``), so that every step lies in the free directions and the
reaction is Q (grad E - f): along the normal of a roller, across the direction of a
slider. Arrays only, like ``catenet.model.net``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError
from catenet.model.rodends import RodEnds

#: A normal or direction shorter than this (relative to its largest component's scale)
#: names no direction.
SHORTEST = 1e-12


def unit(vector, what: str) -> np.ndarray:
    """The unit vector along ``vector`` (3,); ConfigError naming ``what`` for a vector
    that is not three finite numbers or has no length."""
    v = np.asarray(vector, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ConfigError(f"{what} = {np.asarray(vector).tolist()!r}: must be three finite numbers")
    scale = float(np.max(np.abs(v)))
    if not scale > 0.0:
        raise ConfigError(f"{what} = {v.tolist()!r}: must not be zero (it names a direction)")
    v = v / scale
    length = float(np.linalg.norm(v))
    return v / length


@dataclass(frozen=True, eq=False)
class Guides:
    """Guided nodes: ``nodes`` (K,) their indices, ``held`` (K, 3, 3) the projector Q
    onto each node's held directions, ``free_count`` (K,) how many directions each node
    keeps (2: a roller, 1: a slider), ``axis`` (K, 3) the unit normal of a roller, the
    unit direction of a slider."""

    nodes: np.ndarray
    held: np.ndarray
    free_count: np.ndarray
    axis: np.ndarray

    @classmethod
    def roller(cls, nodes, normal, what: str = "normal") -> Guides:
        """Nodes held along ``normal`` only (free in the plane across it)."""
        n = unit(normal, what)
        return cls._of(nodes, np.outer(n, n), 2, n)

    @classmethod
    def slider(cls, nodes, direction, what: str = "direction") -> Guides:
        """Nodes free along ``direction`` only (held in the two directions across it)."""
        d = unit(direction, what)
        return cls._of(nodes, np.eye(3) - np.outer(d, d), 1, d)

    @classmethod
    def _of(cls, nodes, q: np.ndarray, free: int, axis: np.ndarray) -> Guides:
        idx = np.atleast_1d(np.asarray(nodes, dtype=np.int64)).ravel()
        held = np.repeat(q[None], idx.size, axis=0)
        axes = np.repeat(axis[None], idx.size, axis=0)
        return cls(idx, held, np.full(idx.size, free, dtype=np.int64), axes)

    @classmethod
    def join(cls, parts) -> Guides | None:
        """One ``Guides`` of several (None: none given)."""
        parts = [p for p in parts if p is not None and p.nodes.size]
        if not parts:
            return None
        return cls(
            np.concatenate([p.nodes for p in parts]),
            np.concatenate([p.held for p in parts]),
            np.concatenate([p.free_count for p in parts]),
            np.concatenate([p.axis for p in parts]),
        )

    def __len__(self) -> int:
        return int(self.nodes.size)

    @property
    def held_count(self) -> int:
        """How many directions the guides hold, in all (2 per slider, 1 per roller)."""
        return int(np.sum(3 - self.free_count))

    @property
    def tangent(self) -> np.ndarray:
        """(K, 3, 3) the projector T = 1 - Q onto each node's free directions."""
        return np.eye(3)[None] - self.held

    def basis(self) -> list[np.ndarray]:
        """Per node, an orthonormal basis (3, k) of its k free directions."""
        out = []
        for t, k in zip(self.tangent, self.free_count, strict=True):
            w, v = np.linalg.eigh(t)
            out.append(v[:, np.argsort(w)[::-1][: int(k)]])
        return out

    def check(self, n: int, fixed: np.ndarray) -> list[str]:
        """Problems of these guides on a net of ``n`` nodes pinned at ``fixed`` (N,)."""
        problems = []
        nodes = self.nodes
        shapes = (self.held.shape, self.free_count.shape, self.axis.shape)
        if shapes != ((nodes.size, 3, 3), nodes.shape, (nodes.size, 3)):
            return [f"guides: {nodes.size} nodes, held, free_count, axis {shapes}: must be "
                    "(K, 3, 3), (K,), (K, 3)"]  # fmt: skip
        bad = nodes[(nodes < 0) | (nodes >= n)]
        if bad.size:
            return [f"guides: node {int(bad[0])}: node indices must be in 0..{n - 1}"]
        both = nodes[fixed[nodes]]
        if both.size:
            problems.append(
                f"node {int(both[0])}: is both fixed and on a roller or slider: a fixed node "
                "is held in every direction already; list it in one support only"
            )
        values, counts = np.unique(nodes, return_counts=True)
        if (counts > 1).any():
            problems.append(
                f"node {int(values[counts > 1][0])}: is on more than one roller or slider: "
                "one guide per node (a node held in every direction is a fixed node)"
            )
        q = self.held
        if not np.allclose(q, np.swapaxes(q, 1, 2), atol=1e-12) or not np.allclose(
            q @ q, q, atol=1e-12
        ):
            problems.append("guides: held must be symmetric projectors")
        return problems

    def project(self, vectors: np.ndarray) -> np.ndarray:
        """The free part T v of each guided node's vector ``vectors`` (K, 3)."""
        return vectors - np.einsum("kij,kj->ki", self.held, vectors)

    def held_part(self, vectors: np.ndarray) -> np.ndarray:
        """The held part Q v of each guided node's vector ``vectors`` (K, 3)."""
        return np.einsum("kij,kj->ki", self.held, vectors)

    def place(self, x: np.ndarray, reference: np.ndarray) -> None:
        """Puts every guided node of x (N, 3) on its guide through ``reference`` (N, 3)
        (in place): x = X + T (x - X)."""
        k = self.nodes
        x[k] = reference[k] + self.project(x[k] - reference[k])

    def same_as(self, other: Guides | None) -> bool:
        return (
            other is not None
            and np.array_equal(self.nodes, other.nodes)
            and np.array_equal(self.held, other.held)
            and np.array_equal(self.free_count, other.free_count)
            and np.array_equal(self.axis, other.axis)
        )


@dataclass(frozen=True, eq=False)
class Elastic:
    """Elastic supports: ``nodes`` (K,) each held toward its given position by a linear
    spring of stiffness ``stiffness`` (K, 3, 3) [N/m], symmetric positive semidefinite
    (diagonal: kx, ky, kz). A node may have several (they add). ``ends``: rod ends on
    coupled 6 x 6 supports (``catenet.model.rodends``), None where there are none."""

    nodes: np.ndarray
    stiffness: np.ndarray
    ends: RodEnds | None = None

    @classmethod
    def of(cls, nodes, stiffness, what: str = "stiffness") -> Elastic:
        """Springs at ``nodes``: ``stiffness`` [kx, ky, kz] or a 3x3 matrix [N/m]."""
        k = spring_matrix(stiffness, what)
        idx = np.atleast_1d(np.asarray(nodes, dtype=np.int64)).ravel()
        return cls(idx, np.repeat(k[None], idx.size, axis=0))

    @classmethod
    def join(cls, parts) -> Elastic | None:
        parts = [p for p in parts if p is not None and len(p)]
        if not parts:
            return None
        return cls(
            np.concatenate([p.nodes for p in parts]),
            np.concatenate([p.stiffness for p in parts]),
            RodEnds.join([p.ends for p in parts]),
        )

    @classmethod
    def rod_ends(cls, ends: RodEnds) -> Elastic:
        """Rod ends on 6 x 6 supports alone (no translational spring)."""
        return cls(np.zeros(0, np.int64), np.zeros((0, 3, 3)), ends)

    def __len__(self) -> int:
        return int(self.nodes.size) + (0 if self.ends is None else len(self.ends))

    @property
    def held_nodes(self) -> np.ndarray:
        """Every node these springs hold (the rod ends' included)."""
        if self.ends is None:
            return self.nodes
        return np.concatenate([self.nodes, self.ends.nodes])

    def check(self, n: int) -> list[str]:
        """Problems of these springs on a net of ``n`` nodes."""
        nodes = self.nodes
        if self.stiffness.shape != (nodes.size, 3, 3):
            return [f"springs: stiffness of shape {self.stiffness.shape}: must be (K, 3, 3)"]
        bad = nodes[(nodes < 0) | (nodes >= n)]
        if bad.size:
            return [f"springs: node {int(bad[0])}: node indices must be in 0..{n - 1}"]
        return [] if self.ends is None else self.ends.check(n)

    def same_as(self, other: Elastic | None) -> bool:
        return (
            other is not None
            and np.array_equal(self.nodes, other.nodes)
            and np.array_equal(self.stiffness, other.stiffness)
            and (self.ends is None) == (other.ends is None)
            and (self.ends is None or self.ends.same_as(other.ends))
        )


def spring_matrix(stiffness, what: str = "stiffness") -> np.ndarray:
    """The 3x3 stiffness [N/m] of ``stiffness``: [kx, ky, kz] (each >= 0, not all 0) or
    a symmetric positive semidefinite 3x3 matrix; ConfigError naming ``what``."""
    from catenet.model.limits import MAGNITUDE, too_large

    try:
        k = np.asarray(stiffness, dtype=np.float64)
    except (TypeError, ValueError):
        k = np.zeros(0)
    shown = np.asarray(stiffness, dtype=object).tolist()
    if k.shape == (3,):
        ok = bool(np.all((k >= 0) & (k <= MAGNITUDE)) and k.max() > 0)
        if not ok:
            raise ConfigError(
                f"{what} = {shown!r}: must be [kx, ky, kz] [N/m], each finite and >= 0 "
                f"(within {too_large()}), not all zero"
            )
        return np.diag(k)
    if k.shape == (3, 3) and np.all(np.abs(k) <= MAGNITUDE):
        scale = float(np.max(np.abs(k)))
        symmetric = np.allclose(k, k.T, rtol=0.0, atol=1e-12 * scale)
        if symmetric and scale > 0:
            k = 0.5 * (k + k.T)
            if float(np.linalg.eigvalsh(k)[0]) >= -1e-12 * scale:
                return k
    raise ConfigError(
        f"{what} = {shown!r}: must be [kx, ky, kz] [N/m] or a symmetric positive "
        "semidefinite 3x3 matrix [[kxx, kxy, kxz], ...], finite and not zero (at a rod end "
        "also a 6x6 or [kx, ky, kz, krx, kry, krz])"
    )
