"""``catenet plot DIR`` for any sweep: each output column against each swept parameter.

One figure per swept (numeric) parameter, ``DIR/sweep_<parameter>.png``: a panel per
output column that varies (the summary's numbers: deflection, largest displacement,
tension, compression, reaction, strain, slack edges, peaks), the rows that succeeded
plotted against the parameter, one line per combination of the other parameters.
"""

from __future__ import annotations

import logging
import math
import re
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

# the output columns drawn, in this order, with their labels (units SI)
OUTPUTS = {
    "delta": "delta: probe z-deflection (down) [m]",
    "max_displacement": "largest displacement [m]",
    "max_tension": "largest tension [N]",
    "max_compression": "largest compression (struts) [N]",
    "max_strain": "largest strain [-]",
    "slack_edges": "slack edges",
    "max_reaction": "largest reaction [N]",
    "peak_tension": "peak tension over the run [N]",
    "peak_displacement": "peak displacement over the run [m]",
    "iterations": "Newton iterations",
}


def _number(v) -> float:
    if isinstance(v, bool) or v is None:
        return math.nan
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _file_name(key: str) -> str:
    return "sweep_" + re.sub(r"[^A-Za-z0-9_.-]+", "_", key) + ".png"


def plot_columns(directory: Path, out: Path | None = None, *, dpi: int = 120) -> list[Path]:
    """The figures of the sweep in ``directory`` (written to ``out``, default the
    directory); the paths written (none when no row has a number to draw yet).
    ConfigError for a directory that holds no sweep."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from catenet.sweep import read_table

    directory = Path(directory)
    out = Path(out) if out is not None else directory
    out.mkdir(parents=True, exist_ok=True)
    keys, _, table = read_table(directory)
    n = len(next(iter(table.values()), []))
    error = table.get("error", [""] * n)
    ok = np.array([not e for e in error], dtype=bool)
    params = {k: np.array([_number(v) for v in table[k]]) for k in keys if k in table}
    params = {k: v for k, v in params.items() if np.isfinite(v).any()}
    outputs = {}
    for c, label in OUTPUTS.items():
        if c in table:
            v = np.array([_number(x) for x in table[c]])
            v[~ok] = np.nan
            good = v[np.isfinite(v)]
            if good.size and np.ptp(good) > 0:
                outputs[c] = (label, v)
    if not params:
        log.info("%s: no swept parameter with a number to plot against", directory)
        return []
    written = []
    for key, x in params.items():
        others = [k for k in keys if k != key]
        groups: dict[tuple, list[int]] = {}
        for i in range(n):
            groups.setdefault(tuple(str(table[k][i]) for k in others), []).append(i)
        panels = list(outputs.items()) or [("delta", ("delta [m]", np.full(n, np.nan)))]
        cols = min(3, len(panels))
        rows = math.ceil(len(panels) / cols)
        fig = Figure(figsize=(4.4 * cols, 3.4 * rows), layout="constrained")
        FigureCanvasAgg(fig)
        for j, (_, (label, y)) in enumerate(panels):
            ax = fig.add_subplot(rows, cols, j + 1)
            ax.grid(True, lw=0.3)
            for g, idx in groups.items():
                order = np.array(sorted(idx, key=lambda i: x[i]))
                name = ", ".join(f"{k}={v}" for k, v in zip(others, g, strict=True))
                ax.plot(x[order], y[order], "o-", ms=3, lw=1.0, label=name or None)
            ax.set_xlabel(key)
            ax.set_ylabel(label)
            if j == 0 and others and len(groups) <= 10:
                ax.legend(fontsize="x-small", loc="best")
        failed = int(np.count_nonzero(~ok))
        note = f" ({failed} failed rows left out)" if failed else ""
        fig.suptitle(f"{directory.name}: outputs against {key}{note}")
        path = out / _file_name(key)
        fig.savefig(path, dpi=dpi)
        written.append(path)
        log.info("wrote %s", path)
    return written


def is_square_net_sweep(directory: Path) -> bool:
    """Whether the sweep's base case is the paper's square net (its report applies)."""
    from catenet.sweep import read_journal

    header, _ = read_journal(Path(directory))
    base = (header or {}).get("base") or {}
    return (base.get("geometry") or {}).get("kind") == "square_net"
