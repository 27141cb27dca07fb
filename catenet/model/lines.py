"""What an offshore engineer reads off a mooring line over time: its path from the
anchor (``LinePath``), the anchor's uplift angle, the touchdown point, the snap events
of a tension record (slack, then taut again) and its spectrum.

A line is a named cable, its edges in order along it; its anchor is the end lower in
the given geometry (a line's anchor lies on the seabed, its fairlead above). The
uplift angle is the angle of the line's first edge above the horizontal at the anchor
[deg] (0: the line leaves the anchor along the seabed). The touchdown point is where the
grounded stretch that starts at the anchor ends: the unstretched arc length from the
anchor to the last node of that stretch in contact with an obstacle [m] (0: the line
lifts at the anchor), within one edge as the nodes resolve it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: A line is slack where its least tension falls to this share of its largest over the
#: record or below (a margin against round-off; a tension-only edge carries 0 slack).
SLACK = 1e-6


@dataclass(frozen=True)
class LinePath:
    """A line's nodes (K + 1,) and edges (K,) in order from its anchor, and the
    unstretched arc length from the anchor at each node (K + 1,) [m]."""

    nodes: np.ndarray
    edges: np.ndarray
    arc: np.ndarray

    def uplift(self, x: np.ndarray) -> float:
        """The angle of the line above the horizontal at its anchor [deg]."""
        d = x[self.nodes[1]] - x[self.nodes[0]]
        return math.degrees(math.atan2(float(d[2]), math.hypot(float(d[0]), float(d[1]))))

    def touchdown(self, grounded: np.ndarray) -> float:
        """The arc length from the anchor to the end of the grounded stretch that starts
        there (``grounded`` (N,): nodes in contact; the anchor itself counts as on the
        seabed) [m]."""
        on = grounded[self.nodes[1:]]
        k = int(np.argmin(on)) if not on.all() else on.size  # leading grounded nodes
        return float(self.arc[k])


def line_paths(nodes: np.ndarray, edges: np.ndarray, rest: np.ndarray, cable_edge) -> list:
    """Each named cable's ``LinePath`` (``cable_edge`` (M,): its cable's index, -1
    none), from its end lower in ``nodes`` (the given geometry)."""
    cable_edge = np.asarray(cable_edge)
    paths: list[LinePath | None] = []
    for c in range(int(cable_edge.max(initial=-1)) + 1):
        mine = np.flatnonzero(cable_edge == c)
        if not mine.size:
            paths.append(None)
            continue
        a, b = (int(v) for v in edges[mine[0]])
        if mine.size > 1 and a in edges[mine[1]]:
            a, b = b, a
        order = [a, b]
        for e in mine[1:]:
            i, j = (int(v) for v in edges[e])
            order.append(j if i == order[-1] else i)
        ids, seq = np.array(order), mine
        if nodes[ids[-1], 2] < nodes[ids[0], 2]:  # the anchor is the lower end
            ids, seq = ids[::-1], seq[::-1]
        arc = np.concatenate([[0.0], np.cumsum(rest[seq])])
        paths.append(LinePath(ids.copy(), seq.copy(), arc))
    return paths


class Lines:
    """Every line's records of a state at once (``LinePath``s, None: a cable without
    edges): the arrays padded to the longest line, so that a step costs a few array
    operations whatever the number of lines."""

    def __init__(self, paths: list):
        c = len(paths)
        k = max((p.edges.size for p in paths if p is not None), default=0)
        self.edges = np.zeros((c, k), dtype=np.int64)
        self.nodes = np.zeros((c, k + 1), dtype=np.int64)
        self.arc = np.zeros((c, k + 1))
        self.count = np.zeros(c, dtype=np.int64)  # edges of each line (0: none)
        for i, p in enumerate(paths):
            if p is None:
                continue
            n = p.edges.size
            self.count[i] = n
            self.edges[i, :n], self.edges[i, n:] = p.edges, p.edges[-1]  # pad: repeat
            self.nodes[i, : n + 1], self.nodes[i, n + 1 :] = p.nodes, p.nodes[-1]
            self.arc[i, : n + 1], self.arc[i, n + 1 :] = p.arc, p.arc[-1]

    def tension_range(self, tension: np.ndarray) -> np.ndarray:
        """(C, 2) each line's least and largest edge tension (0, 0 without edges)."""
        t = tension[self.edges]
        out = np.column_stack([t.min(axis=1), t.max(axis=1)]) if t.size else np.zeros((0, 2))
        out[self.count == 0] = 0.0
        return out.reshape(-1, 2)

    def uplift(self, x: np.ndarray) -> np.ndarray:
        """(C,) each line's angle above the horizontal at its anchor [deg]."""
        if not self.nodes.shape[1] > 1:
            return np.zeros(len(self.count))
        d = x[self.nodes[:, 1]] - x[self.nodes[:, 0]]
        out = np.degrees(np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1])))
        return np.where(self.count > 0, out, 0.0)

    def touchdown(self, grounded: np.ndarray) -> np.ndarray:
        """(C,) each line's arc length from its anchor to the end of the grounded
        stretch that starts there (``LinePath.touchdown``) [m]."""
        on = grounded[self.nodes[:, 1:]]
        inside = np.arange(on.shape[1])[None, :] < self.count[:, None]
        off = ~on & inside
        lead = np.where(off.any(axis=1), off.argmax(axis=1), self.count)
        return self.arc[np.arange(len(self.count)), lead]


def snaps(time: np.ndarray, least: np.ndarray, largest: float) -> np.ndarray:
    """The times at which a line goes taut again after being slack: its least tension
    ``least`` (S,) at ``time`` (S,) rises above SLACK x ``largest`` (its largest tension
    over the record) from at or below it."""
    limit = SLACK * max(float(largest), 0.0)
    slack = np.asarray(least) <= limit
    back = np.flatnonzero(slack[:-1] & ~slack[1:]) + 1
    return np.asarray(time)[back]


def spectrum(time: np.ndarray, values: np.ndarray, segments: int = 4) -> tuple:
    """(frequency [Hz], one-sided power spectral density [unit^2/Hz]) of a record
    ``values`` (S,) at ``time`` (S,) (steps of any length: resampled at their median on
    a uniform grid), by Welch's method: ``segments`` Hann-windowed halves-overlapping
    pieces, the mean removed; the area under it is the record's variance. Empty arrays
    for a record shorter than 16 samples."""
    t = np.asarray(time, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if t.size < 16 or not t[-1] > t[0]:
        return np.zeros(0), np.zeros(0)
    dt = float(np.median(np.diff(t)))
    grid = np.arange(t[0], t[-1] + 0.5 * dt, dt)
    u = np.interp(grid, t, v)
    from scipy.signal import welch

    size = max(16, int(2 * grid.size / (segments + 1)))
    f, p = welch(u, fs=1.0 / dt, window="hann", nperseg=min(size, grid.size), detrend="constant")
    return f, p


def spectral_summary(f: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """(peak period [s], significant double amplitude 4 sqrt(m0)) of a spectrum (nan,
    nan for an empty or flat one). The peak period is nan where the peak is in the
    lowest bin above the mean's: its period is a segment's length or longer, which the
    record is too short to tell (a 3 s record of a 9 s motion)."""
    if not f.size or not np.any(p[1:] > 0):
        return math.nan, math.nan
    k = 1 + int(np.argmax(p[1:]))  # not the mean's bin
    m0 = float(np.sum(p)) * float(f[1] - f[0])  # Welch's bins: the variance
    period = 1.0 / float(f[k]) if k > 1 else math.nan
    return period, 4.0 * math.sqrt(max(m0, 0.0))
