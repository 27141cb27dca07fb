"""docs/performance.md's table on dynamic runs: modified Newton and an obstacle never
touched, from ``reuse.csv`` (``python -m benchmarks reuse``)."""

from __future__ import annotations

import math
from pathlib import Path

from benchmarks.sections import as_float, as_text, md_table, read_study


def reuse(results: Path) -> list[str]:
    rows = read_study(results, "reuse")
    if not rows:
        return []
    repeats = sorted({r["repeats"] for r in rows})
    out = [f"Times are medians of {' or '.join(repeats)} repeats.", ""]
    table = []
    for r in rows:
        same = r["variant"] == r["reference"]
        if same:
            ratio = "reference"
        elif r["ratio_is"] == "cost":
            ratio = f"{100 * (as_float(r['ratio']) - 1):+.1f} % time"
        else:
            ratio = f"{as_text(r['ratio'], '{:.2f}')}x faster"
        table.append(
            [
                r["scene"],
                r["variant"],
                r["dofs"],
                r["steps"],
                as_text(r["seconds"]),
                ratio,
                r["factorizations"],
                r["iterations"],
                "" if same else as_text(r["max_rel_difference"], "{:.1e}"),
                _sci(r.get("static_rel_difference")),
            ]
        )
    out += md_table(
        [
            "scene",
            "variant",
            "DOF",
            "steps",
            "time [s]",
            "against the reference",
            "factorisations",
            "Newton iterations",
            "difference",
            "from static",
        ],
        table,
    )
    return out


def _sci(v) -> str:
    """A CSV number as 1.2e-08; blank where there is none (nan)."""
    return "" if math.isnan(as_float(v)) else as_text(v, "{:.1e}")
