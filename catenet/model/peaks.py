"""Peaks over a run: each edge's largest tension and each node's largest displacement,
with the time (or load factor) at which they occur.

A dynamic run's design values are its peaks, not its final state (an impact, a capture),
and a result file keeps only every k-th frame (``output.every``): the solve path shows
every accepted time step and every load step to a ``Peaks`` (``catenet.solver.path``),
which keeps the running maxima in place (O(M + N) per step, no copy of the states).

With ``between`` (a dynamic run whose steps are chosen by accuracy, long where little
happens) a peak is also looked for between the states: where a value's middle state of
the last three is above both neighbours, the parabola through the three has its top
between them, and that top (value and time) is the peak where it is larger. A second
order scheme's states lie on such parabolas to its own accuracy, so the top is as good as
the steps: on a safety net's impact at fixed steps of 5 ms the top of the parabola
lands within 0.3 % of the fine-step peak tension where the largest state is 2 % below.
Where the two steps differ by more than EVEN the states' own maxima stand: a mooring line
whose fairlead stops after being pulled had a parabola over steps of 1.2 and 0.28 s
report 269 kN at 7.87 s where the tension then was at most 234 kN.

Snaps: a tension-only edge (``only``) that was taut (its tension above ``floor``, a
strain of TAUT of its EA: not round-off's), went slack and is taut again has snapped;
``snap_time`` is the first such state's time, ``before_snap`` the largest tension of any
edge before it and ``snapped`` the edges that snapped. A snatch's peak rides on the
ropes' axial waves (``catenet.run.integrator_advice.snatch``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from catenet.model.net import Net

#: The parabola through three states is read only where their two steps differ by at
#: most this ratio: steps chosen by accuracy grow at most twofold where the motion is
#: smooth, and are cut short where it is not (a support that stops, a contact), where a
#: parabola through unequal steps across the kink invents a top.
EVEN = 2.5

#: A tension-only edge is taut, for its snaps, above this strain's tension: a free rope
#: sinking in still water carries round-off's, 1e-7 N on a 20 mm wire.
TAUT = 1e-6


class Peaks:
    """Running maxima over the states a run passes through.

    tension (M,): each edge's largest tension [N] (its first occurrence's ``tension_time``);
    tension_low (M,): each edge's least tension [N] (a strut's largest compression);
    displacement (N,): each node's largest |x - X| from the reference positions X [m]
    (``displacement_time``). Before any state both are -inf / nan; ``seen`` counts the
    states. Times are seconds in a dynamic run and load factors in a static one.
    """

    def __init__(
        self,
        reference: np.ndarray,
        n_edges: int,
        between: bool = False,
        only: np.ndarray | None = None,
        floor: np.ndarray | float = 0.0,
    ):
        self.reference = np.asarray(reference, dtype=np.float64)
        self.only = np.zeros(n_edges, dtype=bool) if only is None else np.asarray(only, bool)
        self.floor = floor  # (a tension at or below it is slack, for the snaps)
        self.snapped = np.zeros(n_edges, dtype=bool)  # (module docstring: snaps)
        self.snap_time = np.nan
        self.before_snap = -np.inf
        self._taut = np.zeros(n_edges, dtype=bool)  # taut at some state so far
        self._slack = np.zeros(n_edges, dtype=bool)  # ... and slack since
        n = len(self.reference)
        self.tension = np.full(n_edges, -np.inf)
        self.tension_time = np.full(n_edges, np.nan)
        self.tension_low = np.full(n_edges, np.inf)
        self.displacement = np.full(n, -np.inf)
        self.displacement_time = np.full(n, np.nan)
        self.seen = 0
        self._u = np.empty(n)
        self.between = between
        self._last: list[tuple[float, np.ndarray, np.ndarray]] = []  # (t, T, u) of 2 states

    @classmethod
    def of(cls, net: Net) -> Peaks:
        """The peaks of a run of ``net``, its tension-only edges' snaps counted."""
        only = net.law.tension_only
        return cls(net.nodes, net.n_edges, only=only, floor=TAUT * np.asarray(net.EA))

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
        if self.only.any():
            self._snaps(t, tension)
        d = np.asarray(x) - self.reference
        u = np.sqrt(np.einsum("ij,ij->i", d, d), out=self._u)
        if self.between and len(self._last) == 2:
            (t_a, tension_a, u_a), (t_b, tension_b, u_b) = self._last
            _top((t_a, t_b, t), (tension_a, tension_b, tension), self.tension, self.tension_time)
            _top((t_a, t_b, t), (u_a, u_b, u), self.displacement, self.displacement_time)
        up = tension > self.tension
        self.tension[up] = tension[up]
        self.tension_time[up] = t
        np.minimum(self.tension_low, tension, out=self.tension_low)
        up = u > self.displacement
        self.displacement[up] = u[up]
        self.displacement_time[up] = t
        self.seen += 1
        if self.between:
            self._last = [*self._last[-1:], (float(t), tension.copy(), u.copy())]

    def _snaps(self, t: float, tension: np.ndarray) -> None:
        """The tension-only edges' snaps (module docstring) at the state of time t."""
        taut = tension > self.floor
        back = self._slack & taut & self.only
        if back.any():
            if not np.isfinite(self.snap_time):
                self.snap_time = float(t)
                self.before_snap = float(np.max(self.tension, initial=-np.inf))
            self.snapped |= back
            self._slack &= ~back
        self._slack |= self._taut & ~taut
        self._taut |= taut

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


def _top(
    times: tuple[float, float, float],
    values: tuple[np.ndarray, np.ndarray, np.ndarray],
    peak: np.ndarray,
    when: np.ndarray,
) -> None:
    """Raises ``peak`` (with its time ``when``) in place to the top of the parabola through
    three states' ``values`` at ``times`` where the middle one is above both neighbours
    (the module docstring)."""
    (t_a, t_b, t_c), (a, b, c) = times, values
    h1, h2 = t_b - t_a, t_c - t_b
    if not (h1 > 0.0 and h2 > 0.0) or max(h1, h2) > EVEN * min(h1, h2):
        return  # (steps cut short: where the motion is not smooth, the samples' own)
    k = np.flatnonzero((b > a) & (b >= c) & (b >= peak))
    if not len(k):
        return
    s1, s2 = (b[k] - a[k]) / h1, (c[k] - b[k]) / h2
    curve = (s2 - s1) / (h1 + h2)  # < 0 at a top: the parabola's t^2 coefficient
    slope = s1 + curve * h1  # its slope at t_b
    top = b[k] - slope * slope / (4.0 * curve)
    at = t_b - slope / (2.0 * curve)
    up = np.isfinite(top) & (top > peak[k])
    peak[k[up]], when[k[up]] = top[up], at[up]
