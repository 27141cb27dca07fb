"""A shape's gap and first contact for some of its items only (``Only``): the moving
obstacles' checks over a step (``catenet.terms.moving``: which nodes ride, the supports
an obstacle would run over; ``catenet.terms.moving_edges``: the edges held at a support;
``catenet.terms.pinch``) ask them of the nodes or edges concerned, not of the whole net."""

from __future__ import annotations

import numpy as np


class Only:
    """A shape's gap and first contact for some of its items only: node rows (K, 1) of a
    node barrier or edges (K, 2) of an edge barrier (its ``edges``, for the call)."""

    def __init__(self, shape, items):
        self.shape = shape
        self.edges = items.shape[1] == 2
        self.items = np.ascontiguousarray(items if self.edges else items[:, 0], dtype=np.int64)

    def _call(self, name, *args):
        attr = "edges" if self.edges else "nodes"
        keep = getattr(self.shape, attr)
        try:
            setattr(self.shape, attr, self.items)
            return getattr(self.shape, name)(*args)
        finally:
            setattr(self.shape, attr, keep)

    def gap(self, x) -> np.ndarray:
        return self._call("gap", x)

    def max_step(self, x, dx) -> float:
        if self.edges:
            return float(self._call("max_step_within", x, dx, 1.0))
        return float(self._call("max_step", x, dx))
