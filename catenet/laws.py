"""Material laws of the edges, as data: which law every edge follows and its parameters.

The stretch kernels get a ``Law`` explicitly (law id, parameters and tension-only switch
per edge, and the smoothing of the switch); nothing about the law is state of a solver.
Each law is the strain energy density w(eps) of ``catenet.kernels.laws`` with w''(0) = 1,
so EA is its small-strain stiffness and every law reduces to the paper's at small strain.

``LAWS`` names the laws users choose from (the case key ``material.law``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

#: Law ids of the kernels (``catenet.kernels.laws.density`` branches on them).
LINEAR = 0


@dataclass(frozen=True)
class LawInfo:
    """A law users can name: its kernel id, parameter names and what it is."""

    id: int
    params: tuple[str, ...]
    doc: str


LAWS = {
    "linear": LawInfo(LINEAR, (), "the paper's: tension EA eps (small strain)"),
}


@dataclass(frozen=True, eq=False)
class Law:
    """Per edge: law id ``kind`` (M,), parameters ``params`` (M, P), ``tension_only`` (M,);
    ``smooth`` > 0 smooths the tension-only switch (the static solver's continuation)."""

    kind: np.ndarray
    params: np.ndarray
    tension_only: np.ndarray
    smooth: float = 0.0

    @classmethod
    def uniform(cls, n_edges: int, name: str = "linear", *, tension_only=True, params=()):
        """Every edge of one law; ``tension_only`` a bool or one per edge."""
        info = LAWS[name]
        p = np.zeros((n_edges, max(len(info.params), 1)))
        p[:, : len(params)] = params
        only = np.broadcast_to(np.asarray(tension_only, dtype=np.bool_), (n_edges,))
        return cls(
            kind=np.full(n_edges, info.id, dtype=np.int64),
            params=np.ascontiguousarray(p),
            tension_only=np.ascontiguousarray(only),
        )

    def smoothed(self, smooth: float) -> Law:
        """The same law with the tension-only switch smoothed by ``smooth`` (0: exact)."""
        return dataclasses.replace(self, smooth=float(smooth))

    @property
    def any_tension_only(self) -> bool:
        return bool(self.tension_only.any())

    @property
    def all_tension_only(self) -> bool:
        return bool(self.tension_only.all())
