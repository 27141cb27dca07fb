"""Peaks over a run: each edge's largest tension and each node's largest displacement,
with the time (or load factor) at which they occur.

A dynamic run's design values are its peaks, not its final state (an impact, a capture),
and a result file keeps only every k-th frame (``output.every``): the solve path shows
every accepted time step and every load step to a ``Peaks`` (``catenet.solver.path``),
which keeps the running maxima in place (O(M + N) per step, no copy of the states).
"""

from __future__ import annotations

import numpy as np


class Peaks:
    """Running maxima over the states a run passes through.

    tension (M,): each edge's largest tension [N] (its first occurrence's ``tension_time``);
    tension_low (M,): each edge's least tension [N] (a strut's largest compression);
    displacement (N,): each node's largest |x - X| from the reference positions X [m]
    (``displacement_time``). Before any state both are -inf / nan; ``seen`` counts the
    states. Times are seconds in a dynamic run and load factors in a static one.
    """

    def __init__(self, reference: np.ndarray, n_edges: int):
        self.reference = np.asarray(reference, dtype=np.float64)
        n = len(self.reference)
        self.tension = np.full(n_edges, -np.inf)
        self.tension_time = np.full(n_edges, np.nan)
        self.tension_low = np.full(n_edges, np.inf)
        self.displacement = np.full(n, -np.inf)
        self.displacement_time = np.full(n, np.nan)
        self.seen = 0
        self._u = np.empty(n)

    def seed(self, arrays: dict[str, np.ndarray]) -> bool:
        """Goes on from the peaks of an earlier part of the run (``arrays()`` of it, as a
        result file stores them); False (and nothing taken) when their shapes differ."""
        shapes = {
            "peak_tension": self.tension.shape,
            "peak_tension_time": self.tension.shape,
            "least_tension": self.tension.shape,
            "peak_displacement": self.displacement.shape,
            "peak_displacement_time": self.displacement.shape,
        }
        if any(k not in arrays or np.shape(arrays[k]) != shape for k, shape in shapes.items()):
            return False
        self.tension[:] = arrays["peak_tension"]
        self.tension_time[:] = arrays["peak_tension_time"]
        self.tension_low[:] = arrays["least_tension"]
        self.displacement[:] = arrays["peak_displacement"]
        self.displacement_time[:] = arrays["peak_displacement_time"]
        self.seen += 1
        return True

    def observe(self, t: float, x: np.ndarray, tension: np.ndarray) -> None:
        """Takes the state x (N, 3) with its edge tensions (M,) at time (load factor) t."""
        tension = np.asarray(tension)
        up = tension > self.tension
        self.tension[up] = tension[up]
        self.tension_time[up] = t
        np.minimum(self.tension_low, tension, out=self.tension_low)
        d = np.asarray(x) - self.reference
        u = np.sqrt(np.einsum("ij,ij->i", d, d), out=self._u)
        up = u > self.displacement
        self.displacement[up] = u[up]
        self.displacement_time[up] = t
        self.seen += 1

    def arrays(self) -> dict[str, np.ndarray]:
        """The peaks as arrays (0 at time 0 for a run that saw no state, and the time of a
        value never taken, a non-finite state's, as 0: a result file holds finite numbers)."""
        empty = self.seen == 0
        return {
            "peak_tension": np.zeros_like(self.tension) if empty else self.tension.copy(),
            "peak_tension_time": np.nan_to_num(self.tension_time, nan=0.0),
            "least_tension": np.zeros_like(self.tension) if empty else self.tension_low.copy(),
            "peak_displacement": (
                np.zeros_like(self.displacement) if empty else self.displacement.copy()
            ),
            "peak_displacement_time": np.nan_to_num(self.displacement_time, nan=0.0),
        }
