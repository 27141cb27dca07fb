"""The figures of an HTML report, as base64 PNG: the largest utilisation (or, where no
material gives a breaking load, the largest tension) of every cable in every state; and
per state the deformed net in the view that shows it best, each edge coloured by its
utilisation (or tension)."""

from __future__ import annotations

import base64
import io

import numpy as np

from catenet.model.units import unit_in
from catenet.output.states import State, States
from catenet.report.tables import Report

#: Cables drawn one bar each up to this many (beyond, the figure of every state's net
#: tells more than bars).
MAX_BARS = 40


def figures(report: Report, states: States) -> dict[str, list[str]]:
    """Per section name the PNGs (base64) to show there ("": under the title)."""
    import matplotlib

    matplotlib.use("Agg")
    out: dict[str, list[str]] = {}
    bars = _cable_bars(report)
    if bars is not None:
        out[""] = [bars]
    for state, sec in zip(states.states, report.sections, strict=False):
        out[sec.name] = [_net(states, state, report.units)]
    return out


def _png(fig) -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _cable_bars(report: Report) -> str | None:
    """Bars of each cable's largest utilisation (else tension) per state."""
    import matplotlib.pyplot as plt

    states = [s for s in report.sections if s.kind != "envelope"]
    tables = [next(t for t in s.tables if t.key == "cables") for s in states]
    names = [row[0] for row in tables[0].rows] if tables else []
    if not names or len(names) > MAX_BARS:
        return None
    col = tables[0].columns.index("max utilisation [-]")
    use = np.array([[row[col] for row in t.rows] for t in tables], dtype=np.float64)
    what = "max utilisation [-]"
    if not np.isfinite(use).any():
        col = next(k for k, c in enumerate(tables[0].columns) if c.startswith("max tension ["))
        use = np.array([[row[col] for row in t.rows] for t in tables], dtype=np.float64)
        what = tables[0].columns[col]
    wide = min(16.0, max(6.0, 2.0 + 0.3 * len(names) * len(states) ** 0.5))
    fig, ax = plt.subplots(figsize=(wide, 3.5))
    width = 0.8 / len(states)
    pos = np.arange(len(names))
    for k, s in enumerate(states):
        ax.bar(pos + k * width, np.nan_to_num(use[k]), width, label=s.name)
    if what.startswith("max utilisation"):
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.set_xticks(pos + 0.4 - width / 2, names, rotation=45, ha="right")
    ax.set_ylabel(what)
    ax.legend(fontsize=8, ncols=min(6, len(states)), loc="lower left", bbox_to_anchor=(0.0, 1.02))
    return _png(fig)


def _net(states: States, s: State, units: str) -> str:
    """The net of state ``s`` in plan (x-y) and in elevation (its wider horizontal
    axis against z), edges coloured by utilisation (0 to at least 1) or else tension,
    supports as black squares."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    x = s.x
    e = states.mesh.edges
    use = s.get("utilisation")
    label = "utilisation [-]"
    if use is None or not np.isfinite(use).any():
        use, label = s.get("tension"), f"tension [{unit_in('N', units)}]"
    values = np.zeros(len(e)) if use is None else np.nan_to_num(use)
    top = float(values.max()) if values.size else 1.0
    low = 0.0 if label.startswith("utilisation") else float(min(values.min(initial=0.0), 0.0))
    norm = Normalize(
        low, max(top, 1.0) if label.startswith("utilisation") else max(top, low + 1e-12)
    )
    span = np.ptp(x, axis=0)
    side = 0 if span[0] >= span[1] else 1
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.2))
    fixed = states.mesh.fixed
    for ax, (a, b) in zip(axes, ((0, 1), (side, 2)), strict=True):
        segs = list(np.stack([x[e[:, 0]][:, [a, b]], x[e[:, 1]][:, [a, b]]], axis=1))
        lines = LineCollection(segs, array=values, cmap="viridis", norm=norm, linewidths=1.5)
        ax.add_collection(lines)
        if fixed is not None and fixed.any():
            ax.plot(x[fixed, a], x[fixed, b], "ks", ms=4)
        ax.autoscale()
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{'xyz'[a]} [{unit_in('m', units)}]")
        ax.set_ylabel(f"{'xyz'[b]} [{unit_in('m', units)}]")
    axes[0].set_title("plan")
    axes[1].set_title("elevation")
    fig.colorbar(lines, ax=list(axes), label=label)
    fig.suptitle(s.name if s.kind != "base" else "base state")
    return _png(fig)
