"""Time histories of loads and support motion: a table of (t, factor) points.

The factor is linear between the points, the first factor before the first point and the
last factor after the last point. Dynamic runs scale a load (or a support's displacement)
by the factor at the end of each time step; static runs do not use histories.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.errors import ConfigError
from catenet.model.limits import carried


class History:
    """factor(t) from (t, factor) points with strictly increasing times."""

    __slots__ = ("times", "factors")

    def __init__(self, points, *, path: str = "history"):
        problem = history_problem(points)
        if problem:
            raise ConfigError(f"{path} = {_show(points)}: {problem}")
        arr = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        self.times = np.ascontiguousarray(arr[:, 0])
        self.factors = np.ascontiguousarray(arr[:, 1])

    def __call__(self, t: float) -> float:
        return float(np.interp(t, self.times, self.factors))

    @property
    def end(self) -> float:
        """The time of the last point: the factor is constant from there on."""
        return float(self.times[-1])

    def __repr__(self) -> str:
        return f"History({np.column_stack([self.times, self.factors]).tolist()})"


#: What a history table must be, as messages say it.
NEED = "[[t, factor], ...]: at least one point, finite numbers, times strictly increasing"


def history_problem(points) -> str:
    """What is wrong with a history table (empty: nothing)."""
    if not isinstance(points, (list, tuple)) or not points:
        return f"must be {NEED}"
    rows = []
    for k, p in enumerate(points):
        if not isinstance(p, (list, tuple)) or len(p) != 2:
            return f"point {k} = {_show(p)}: must be a pair [t, factor]"
        pair = []
        for v in p:
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                return f"point {k} = {_show(p)}: must be two numbers [t, factor]"
            try:
                f = float(v)
            except OverflowError:
                f = math.inf
            if not carried(f):
                return f"point {k} = {_show(p)}: must be finite numbers within +-1e+100"
            pair.append(f)
        rows.append(pair)
    for k in range(1, len(rows)):
        if not rows[k][0] > rows[k - 1][0]:
            return (
                f"times must be strictly increasing: point {k} (t = {rows[k][0]!r}) does not "
                f"follow point {k - 1} (t = {rows[k - 1][0]!r}); a jump needs two close times"
            )
    return ""


def _show(v) -> str:
    text = repr(v)
    return text if len(text) <= 72 else text[:68] + " ..."


class Sine:
    """factor(t) = r(t) sin(2 pi t / period + phase) of a sinusoidal motion (its
    amplitude the displacement it scales), r(t) = (1 - cos(pi t / ramp)) / 2 over the
    ramp and 1 after it: a smooth start (position and velocity zero at t = 0; ramp 0:
    the sine at once). It never settles (``end`` infinite); a static run takes its value
    at t = 0 (``static``)."""

    __slots__ = ("period", "phase", "ramp")

    def __init__(self, period: float, phase: float = 0.0, ramp: float = 0.0):
        self.period, self.phase, self.ramp = float(period), float(phase), float(ramp)

    def __call__(self, t: float) -> float:
        r = 1.0
        if self.ramp > 0.0:
            r = 0.0 if t <= 0.0 else 0.5 * (1.0 - math.cos(math.pi * min(t / self.ramp, 1.0)))
        return r * math.sin(2.0 * math.pi * t / self.period + self.phase)

    @property
    def end(self) -> float:
        return math.inf

    @property
    def static(self) -> float:
        """The factor a static run takes: the motion's value at t = 0."""
        return self(0.0)

    def __repr__(self) -> str:
        return f"Sine(period={self.period}, phase={self.phase}, ramp={self.ramp})"
