"""The report's tables of a dynamic run's lines over time, from its /history (every
accepted step; ``catenet.model.lines``): per named cable its largest and least tension
with their times, its snap events (slack, then taut again: count and times), its
largest anchor uplift angle and the range of its touchdown point, and the spectrum of
its fairlead tension (peak period, significant range); with an irregular sea
(``water.spectrum``) the spectra themselves, one column per line."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from catenet.model.lines import snaps, spectral_summary, spectrum
from catenet.output.history import History, read_history
from catenet.output.states import States
from catenet.report.tables import Table

MAX_SNAP_TIMES = 5  # snap times listed per line (the count is always the whole)
MAX_SPECTRUM_ROWS = 80  # frequencies of the spectrum table, from 0 up


def lines_tables(states: States) -> list[Table]:
    """The lines' tables of a dynamic run in water with named cables (none otherwise: a
    roof net's cables have no anchor, touchdown or fairlead, as the run's summary
    shows lines in water only)."""
    water = states.case.get("water") if isinstance(states.case, dict) else None
    if states.method != "dynamic" or not isinstance(water, dict):
        return []
    history = lines_history(states.path)
    if history is None:
        return []
    tables = [lines_table(history)]
    if water.get("spectrum"):
        tables.append(spectrum_table(history))
    return tables


def lines_history(path) -> History | None:
    """The /history of a result file with named lines and at least two steps (None
    otherwise, or for a file written before the lines' histories)."""
    history = read_history(path)
    if history is None or not history.cable_names or len(history.time) < 2:
        return None
    if history.cable_tension_range.shape[1:] != (len(history.cable_names), 2):
        return None  # a file written before these histories
    return history


def _fairlead(history: History, k: int) -> np.ndarray:
    """The tension record at a line's fairlead: of its two end edges the one with the
    larger tension over the record (a hanging line's upper end)."""
    ends = history.cable_end_tension[:, k, :]
    return ends[:, int(np.argmax(ends.max(axis=0)))]


@dataclass
class LineRecord:
    """One named line over a dynamic run (``line_records``): its largest and least
    tension [N] with their times [s], its snap events' times, its largest anchor uplift
    [deg] with its time, its touchdown range [m] (NaN without a seabed) and its fairlead
    tension's peak period [s] and significant range 4 sqrt(m0) [N]."""

    name: str
    largest: float
    largest_t: float
    least: float
    least_t: float
    snaps: np.ndarray
    uplift: float
    uplift_t: float
    touchdown: tuple[float, float]
    period: float
    significant: float


def line_records(history: History) -> list[LineRecord]:
    """Each named line's record over the run's /history (every accepted step)."""
    t = history.time
    out = []
    for k, name in enumerate(history.cable_names):
        low, high = history.cable_tension_range[:, k, 0], history.cable_tension_range[:, k, 1]
        hi, lo = int(np.argmax(high)), int(np.argmin(low))
        up = history.anchor_uplift[:, k]
        u = int(np.argmax(up))
        down = history.touchdown[:, k] if history.touchdown is not None else None
        reach = (float(down.min()), float(down.max())) if down is not None else (math.nan,) * 2
        period, sig = spectral_summary(*spectrum(t, _fairlead(history, k)))
        out.append(
            LineRecord(
                name, float(high[hi]), float(t[hi]), float(low[lo]), float(t[lo]),
                snaps(t, low, float(high[hi])), float(up[u]), float(t[u]), reach, period, sig,
            )
        )  # fmt: skip
    return out


def lines_table(history: History) -> Table:
    columns = (
        "line",
        "largest tension [N]",
        "largest at t [s]",
        "least tension [N]",
        "least at t [s]",
        "snap events",
        "snap times [s]",
        "largest uplift [deg]",
        "uplift at t [s]",
        "touchdown min [m]",
        "touchdown max [m]",
        "fairlead peak period [s]",
        "fairlead 4 sigma [N]",
    )
    rows = []
    for r in line_records(history):
        shown = ", ".join(f"{v:.4g}" for v in r.snaps[:MAX_SNAP_TIMES])
        if r.snaps.size > MAX_SNAP_TIMES:
            shown += ", ..."
        rows.append(
            [
                r.name, r.largest, r.largest_t, r.least, r.least_t, int(r.snaps.size),
                shown or "none", r.uplift, r.uplift_t, *r.touchdown, r.period, r.significant,
            ]
        )  # fmt: skip
    note = (
        "every accepted time step (/history): tension over the line's edges; a snap: the "
        "line's least tension rises from slack (at most 1e-6 of its largest) to taut; "
        "uplift: the line's angle above the horizontal at its anchor (its lower end); "
        "touchdown: arc length from the anchor where the line leaves the seabed (runs "
        "with obstacles); fairlead: the spectrum of the tension at the upper end "
        "(Welch, Hann): its peak period (n/a where the record is too short to tell it) "
        "and 4 sqrt(m0)"
    )
    return Table("lines", "Lines over time", columns, rows, note)


def spectrum_table(history: History) -> Table:
    """The one-sided spectral density of each line's fairlead tension [N^2/Hz]."""
    t = history.time
    spectra = [spectrum(t, _fairlead(history, k)) for k in range(len(history.cable_names))]
    f = spectra[0][0]
    columns = ("frequency [Hz]", *(f"{n} [N^2/Hz]" for n in history.cable_names))
    rows = [
        [float(f[i]), *(float(p[i]) for _, p in spectra)]
        for i in range(min(f.size, MAX_SPECTRUM_ROWS))
    ]
    note = (
        "Welch's estimate (Hann window, 4 half-overlapping segments) of the fairlead "
        "tension on a uniform grid of the run's median step; its area is the variance"
    )
    return Table("tension_spectrum", "Fairlead tension spectrum", columns, rows, note)
