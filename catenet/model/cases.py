"""Loads of a load case solved from a base state: the base loads in full plus a load
factor times the case's own force, so that a static run's load steps 1/steps .. 1 go
from the base state (already in equilibrium under the base loads) to the case's."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.model.net import Loads, Net


@dataclass(frozen=True, eq=False)
class Increment(Loads):
    """``base`` in full (its supports in their final place) plus ``factor`` x ``added``
    (N, 3) [N]. Static: a load factor scales the added force only."""

    base: Loads = Loads()
    added: np.ndarray | None = None

    def external_force(
        self, net: Net, factor: float = 1.0, time: float | None = None
    ) -> np.ndarray:
        f = self.base.external_force(net, 1.0, time=time)
        if self.added is not None:
            f += self.added if factor == 1.0 else factor * self.added
        return f

    def support_positions(self, net: Net, *, time: float | None = None, factor: float = 1.0):
        return self.base.support_positions(net, time=time, factor=1.0)


def combined(forces: dict[str, np.ndarray], factors: dict[str, float]) -> np.ndarray:
    """The force of a combination: sum of factor x each named case's force (N, 3)."""
    out: np.ndarray | None = None
    for name, f in factors.items():
        part = f * forces[name]
        out = part if out is None else out + part
    assert out is not None, "a combination names at least one load case (its check says so)"
    return out
