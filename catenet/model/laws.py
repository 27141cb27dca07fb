"""Material laws of the edges, as data: which law every edge follows and its parameters.

The stretch kernels get a ``Law`` explicitly (law id, parameters and tension-only switch
per edge, the shared table rows, and the smoothing of the switch); nothing about the law is
state of a solver. Each law is the strain energy density w(eps) of ``catenet.kernels.laws``
with w''(0) = 1, so EA is its small-strain stiffness and every law reduces to the paper's at
small strain.

``LAWS`` names the laws users choose from (the case key ``material.law``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from catenet.errors import ConfigError
from catenet.kernels.law_ids import HENCKY, LINEAR, NEO_HOOKEAN, TABLE


@dataclass(frozen=True)
class LawInfo:
    """A law users can name: its kernel id, what it is, and the largest strain it is meant
    for (a warning says when a result goes beyond it; a table's is its last point)."""

    id: int
    doc: str
    max_strain: float = math.inf


LAWS = {
    "linear": LawInfo(LINEAR, "the paper's: tension EA eps (small strain)", 0.05),
    "neo_hookean": LawInfo(
        NEO_HOOKEAN, "1D incompressible neo-Hookean: EA (lambda - lambda^-2) / 3 (large strain)"
    ),
    "hencky": LawInfo(
        HENCKY, "logarithmic strain: EA ln(lambda) / lambda (force peaks at eps = e - 1)", 1.0
    ),
    "table": LawInfo(TABLE, "piecewise-linear tension against strain (material.table)"),
}


@dataclass(frozen=True, eq=False)
class Law:
    """Per edge: law id ``kind`` (M,), parameters ``params`` (M, 2), ``tension_only`` (M,);
    ``table`` (K, 3) holds the rows (eps, N/EA, w) of every tabulated law (a table edge's
    params are its first row and row count); ``smooth`` > 0 smooths the tension-only switch
    (the static solver's continuation)."""

    kind: np.ndarray
    params: np.ndarray
    tension_only: np.ndarray
    table: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((2, 3)))
    smooth: float = 0.0

    @classmethod
    def uniform(cls, n_edges: int, name: str = "linear", *, tension_only=True, table=None):
        """Every edge of one law; ``tension_only`` a bool or one per edge; ``table`` the
        (strain, tension / EA) points of the "table" law (see ``table_rows``)."""
        if name not in LAWS:
            raise ConfigError(f"material.law = {name!r}: must be one of {', '.join(LAWS)}")
        params = np.zeros((n_edges, 2))
        rows = np.zeros((2, 3))
        if name == "table":
            if table is None:
                raise ConfigError("material.table: missing: the table law needs its points")
            rows = np.asarray(table, dtype=np.float64)
            params[:, 1] = len(rows)
        only = np.broadcast_to(np.asarray(tension_only, dtype=np.bool_), (n_edges,))
        return cls(
            kind=np.full(n_edges, LAWS[name].id, dtype=np.int64),
            params=np.ascontiguousarray(params),
            tension_only=np.array(only),  # a writable copy: one compiled kernel, not two
            table=np.ascontiguousarray(rows),
        )

    @classmethod
    def concat(cls, laws: Sequence[Law]) -> Law:
        """One law of the edges of several, in order, their tables stacked (a table edge's
        first-row parameter shifted to where its rows went)."""
        tables, offset = [], 0
        params = []
        for lw in laws:
            p = lw.params.copy()
            if np.any(lw.kind == TABLE):
                p[lw.kind == TABLE, 0] += offset
                tables.append(lw.table)
                offset += len(lw.table)
            params.append(p)
        return cls(
            kind=np.ascontiguousarray(np.concatenate([lw.kind for lw in laws])),
            params=np.ascontiguousarray(np.concatenate(params)),
            tension_only=np.ascontiguousarray(np.concatenate([lw.tension_only for lw in laws])),
            table=np.ascontiguousarray(np.concatenate(tables)) if tables else np.zeros((2, 3)),
        )

    def name(self, k: int) -> str:
        """The name (in ``LAWS``) of edge k's law."""
        return next(name for name, info in LAWS.items() if info.id == int(self.kind[k]))

    def smoothed(self, smooth: float) -> Law:
        """The same law with the tension-only switch smoothed by ``smooth`` (0: exact)."""
        return dataclasses.replace(self, smooth=float(smooth))

    def with_tension_only(self, tension_only) -> Law:
        only = np.broadcast_to(np.asarray(tension_only, dtype=np.bool_), self.kind.shape)
        return dataclasses.replace(self, tension_only=np.array(only))

    @cached_property
    def kernel_kind(self) -> np.ndarray | None:
        """``kind`` as the kernels take it: None where every edge follows the linear law,
        so that they are compiled (and loaded from the JIT cache) without the other laws."""
        return None if np.all(self.kind == LINEAR) else self.kind

    @property
    def any_tension_only(self) -> bool:
        return bool(self.tension_only.any())

    @property
    def all_tension_only(self) -> bool:
        return bool(self.tension_only.all())

    @cached_property
    def convex(self) -> bool:
        """Whether every edge's energy is convex in x (tension-only edges of laws whose
        force does not fall with strain): the matrices are then positive semidefinite.
        (Once per law: its arrays are never changed in place; a changed law is a new one,
        ``dataclasses.replace``.)"""
        if not self.all_tension_only:
            return False
        return not np.any(self.kind == HENCKY)

    def max_strain(self) -> np.ndarray:
        """Per edge, the largest strain its law is meant for."""
        by_id = {info.id: info.max_strain for info in LAWS.values()}
        out = np.array([by_id[int(k)] for k in range(max(by_id) + 1)])[self.kind]
        table = self.kind == TABLE
        if table.any():
            last = (self.params[table, 0] + self.params[table, 1] - 1).astype(np.int64)
            out[table] = self.table[last, 0]
        return out

    def past_peak(self, strain: np.ndarray) -> np.ndarray:
        """Per edge at ``strain``, whether its law's force has passed its peak and falls
        (hencky: beyond eps = e - 1, where EA ln(lambda) / lambda peaks at EA / e)."""
        return (self.kind == HENCKY) & (strain > math.e - 1.0)

    def strain_for_tension(self, tension: np.ndarray, EA: np.ndarray) -> np.ndarray:
        """Per edge, the strain at which it carries ``tension`` [N] (NaN where it cannot:
        compression in a tension-only edge, or beyond what the law reaches)."""
        from catenet.kernels.laws import strains_for_forces

        tension = np.broadcast_to(np.asarray(tension, dtype=np.float64), self.kind.shape)
        EA = np.broadcast_to(np.asarray(EA, dtype=np.float64), self.kind.shape)
        return strains_for_forces(
            self.kind,
            self.params,
            self.table,
            self.tension_only,
            np.array(tension),  # writable copies: one compiled kernel
            np.array(EA),
        )


def prestressed_lengths(
    law: Law,
    tension,
    EA: np.ndarray,
    length: np.ndarray,
    what: Callable[[int], str],
    edges: np.ndarray | None = None,
) -> np.ndarray:
    """Rest lengths l0 = |e| / (1 + eps) at which each edge of the given lengths |e| carries
    ``tension`` [N] under ``law`` (U = EA l0 w(eps): the tension EA w'(eps) equals it at
    eps = |e|/l0 - 1). ConfigError naming the key ``what(k)`` and the net's edge
    ``edges[k]`` (default k) for an edge that cannot (the law never reaches that tension,
    a compression of a tension-only edge, or l0 not positive)."""
    eps = law.strain_for_tension(tension, EA)
    bad = np.flatnonzero(~(np.isfinite(eps) & (eps > -1.0)))
    if bad.size:
        k = int(bad[0])
        t = float(np.broadcast_to(tension, eps.shape)[k])
        only = law.tension_only[k]
        edge = k if edges is None else int(edges[k])
        raise ConfigError(
            f"{what(k)} = {t!r}: cannot be met: edge {edge} cannot carry it under law "
            f"{law.name(k)!r} "
            f"(EA = {EA[k]:.6g} N{', tension-only' if only else ''}): its rest length would "
            "not be positive, or the law never reaches that tension"
            + (" (a compression needs tension_only = false)" if only and t < 0 else "")
        )
    return length / (1.0 + eps)


def table_rows(points, *, path: str = "material.table") -> tuple[np.ndarray, float]:
    """The kernel rows (eps, N/EA, w) and EA of a user table of (strain, tension [N]) points.

    The points must have strictly increasing strains > 0 and non-decreasing tensions with
    a positive first one; (0, 0) is the table's first row. EA is the first segment's slope,
    so that N/EA has slope 1 at eps = 0 like every law. Raises ConfigError otherwise."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 1 or not np.all(np.isfinite(pts)):
        raise ConfigError(
            f"{path} = {np.asarray(points).tolist()!r}: must be [[strain, tension], ...]: "
            "finite numbers, at least one point"
        )
    if pts[0, 0] == 0.0 and pts[0, 1] == 0.0:
        pts = pts[1:]
    if len(pts) < 1 or not pts[0, 0] > 0.0:
        raise ConfigError(f"{path}: strains must start above 0 ((0, 0) is implied)")
    strain = np.concatenate([[0.0], pts[:, 0]])
    tension = np.concatenate([[0.0], pts[:, 1]])
    if np.any(np.diff(strain) <= 0.0):
        k = int(np.flatnonzero(np.diff(strain) <= 0.0)[0])
        raise ConfigError(
            f"{path}[{k}] = {pts[k].tolist()}: strains must increase strictly (monotone table)"
        )
    if np.any(np.diff(tension) < 0.0) or not tension[1] > 0.0:
        bad = np.flatnonzero(np.diff(tension) < 0.0)
        k = int(bad[0]) if bad.size else 0
        raise ConfigError(
            f"{path}[{k}] = {pts[k].tolist()}: tensions must not decrease and the first must "
            "be > 0 (monotone table)"
        )
    EA = tension[1] / strain[1]
    n = tension / EA
    w = np.concatenate([[0.0], np.cumsum(0.5 * (n[1:] + n[:-1]) * np.diff(strain))])
    return np.column_stack([strain, n, w]), float(EA)


def tension_switches(value, n_edges: int, problems: list[str] | None = None) -> np.ndarray:
    """``tension_only`` as one bool per edge, from a bool or one bool per edge; else a
    problem in ``problems`` (ConfigError where None). A list of False once counted as
    True: any non-empty list is."""
    import reprlib

    arr = np.asarray(value)
    if arr.dtype == np.bool_ and arr.shape in ((), (n_edges,)):
        return np.array(np.broadcast_to(arr, (n_edges,)))
    problem = (
        f"tension_only = {reprlib.repr(value)}: must be a bool or a sequence of one bool "
        f"per edge ({n_edges})"
    )
    if problems is None:
        from catenet.errors import ConfigError

        raise ConfigError(problem)
    problems.append(problem)
    return np.ones(n_edges, dtype=np.bool_)
