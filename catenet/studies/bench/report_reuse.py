"""The README performance section's part on dynamic runs: modified Newton and an obstacle
never touched, from ``reuse.csv`` (``catenet bench reuse``)."""

from __future__ import annotations

import math
from pathlib import Path

from catenet.studies.bench.report_sections import as_float, as_text, md_table, read_study


def reuse(results: Path) -> list[str]:
    rows = read_study(results, "reuse")
    if not rows:
        return []
    repeats = sorted({r["repeats"] for r in rows})
    out = [
        "### Dynamic runs: factorisation reuse and idle obstacles",
        "",
        "Variants of each scene interleaved in one process, medians of "
        f"{' or '.join(repeats)} repeats (`catenet bench reuse`): the paper's relaxation of "
        "the n = 34 net (h = 0.01 s) with `solver.reuse = true` (modified Newton) against a "
        "factorisation per Newton iteration (the default), and the same with every solve's "
        "backward error checked (before: the check is now left to each factorisation's first "
        "solve); the n = 34 net falling onto a sphere (h = 1 ms); the relaxation with a "
        "sphere it never touches against none, and the same with PARDISO symmetric "
        "indefinite throughout (before: it now keeps Cholesky while the sphere is out of "
        "reach). Difference: the largest difference of the final states from the "
        "reference's, relative to the largest displacement; from static: from the static "
        "equilibrium solved to 1e-12 (runs that stop at rest within rtol are about rtol "
        "from it and from each other).",
        "",
    ]
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
    return out + [""]


def _sci(v) -> str:
    """A CSV number as 1.2e-08; blank where there is none (nan)."""
    return "" if math.isnan(as_float(v)) else as_text(v, "{:.1e}")
