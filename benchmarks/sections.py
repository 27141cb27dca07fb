"""The fragments of docs/performance.md that come from the studies' tables: one function
per study, each the lines (Markdown tables and the sentences whose numbers they hold) from
its CSV file in the results directory, an empty list when the study has not run. The
page's prose and headings are written by hand in the page."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from benchmarks.common import read_csv


def as_float(v) -> float:
    """A CSV cell as a number; nan when it is not one."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def as_text(v, fmt="{:.3g}") -> str:
    """A CSV cell formatted as a number by ``fmt``, or as it is when it is not one."""
    x = as_float(v)
    if math.isnan(x):
        return str(v) if v not in (None, "") else ""
    return fmt.format(x)


def md_table(header: list[str], rows: list[list]) -> list[str]:
    """The lines of a Markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out


def read_study(results: Path, name: str) -> list[dict] | None:
    """The rows of ``<name>.csv`` in ``results``; None when the study has not run."""
    path = results / f"{name}.csv"
    return read_csv(path) if path.exists() else None


def static(results: Path) -> list[str]:
    rows = read_study(results, "baseline")
    if not rows:
        return []
    out: list[str] = []
    n34 = [r for r in rows if r["n"] == "34"]
    cat = next((r for r in n34 if r["method"] == "catenet (pardiso)"), None)
    base = next((r for r in n34 if r["method"].startswith("baseline numpy+pypardiso")), None)
    if cat:
        out += [
            f"catenet solves the n = 34 net ({cat['dofs']} free DOF, {cat['iterations']} Newton "
            f"iterations) in **{as_text(cat['seconds'])} s** "
            f"(set-up {as_text(cat.get('setup_seconds'))} s, "
            f"assembly {as_text(cat.get('assembly_seconds'))} s, symbolic analysis "
            f"{as_text(cat.get('analyse_seconds'))} s, numeric factorisation "
            f"{as_text(cat.get('factorize_seconds'))} s, "
            f"solves {as_text(cat.get('solve_seconds'))} s; "
            "the rest is the Newton loop's vector work)"
            + (
                f", **{as_text(base['ratio_to_catenet'], '{:.1f}')} times faster** than the plain "
                "NumPy + `scipy.sparse` + `pypardiso.spsolve` implementation of the same "
                "model and Newton method (`benchmarks/baseline.py`), which "
                "reaches the same equilibrium "
                f"(to {as_text(base['max_error_rel'], '{:.0e}')} of delta)."
                if base
                else "."
            ),
            "",
        ]
    out += md_table(
        [
            "n",
            "DOF",
            "method",
            "time [s]",
            "x catenet",
            "Newton it.",
            "x catenet per it.",
            "max |x - x_ref| / delta",
        ],
        [
            [
                r["n"],
                r["dofs"],
                r["method"],
                as_text(r["seconds"]),
                as_text(r["ratio_to_catenet"], "{:.1f}"),
                r["iterations"],
                as_text(r.get("ratio_per_iteration"), "{:.1f}"),
                as_text(r["max_error_rel"], "{:.0e}"),
            ]
            for r in rows
        ],
    )
    return out


def step_size(results: Path) -> list[str]:
    rows = read_study(results, "step-size")
    if not rows:
        return []
    out = md_table(
        [
            "n",
            "DOF",
            "h [s]",
            "wall [s]",
            "steps",
            "Newton it./step",
            "wall / simulated",
            "equilibrium",
            "error vs static",
        ],
        [
            [
                r["n"],
                r["dofs"],
                as_text(r["h"], "{:g}"),
                as_text(r["wall_seconds"]),
                r["steps"],
                as_text(r["iterations_per_step"], "{:.2f}"),
                as_text(r["time_ratio"]),
                "yes" if r["equilibrium"] == "True" else "capped",
                as_text(r["error_vs_static"], "{:.0e}"),
            ]
            for r in rows
        ],
    )
    statics = {r["n"]: r["static_seconds"] for r in rows}
    out += [
        "",
        "The static solve of the same nets (one run, rtol 1e-10) takes "
        + ", ".join(f"{as_text(v)} s (n = {k})" for k, v in statics.items())
        + ".",
    ]
    return out


def pareto(results: Path) -> list[str]:
    best = read_study(results, "pareto-best")
    if not best:
        return []
    out = md_table(
        [
            "scene",
            "error <=",
            "fastest setting",
            "time [s]",
            "error",
            "fastest dynamic",
            "time [s]",
        ],
        [
            [
                a["case"],
                as_text(a["target"], "{:.0e}"),
                a["setting"],
                as_text(a["seconds"]),
                as_text(a["error"], "{:.1e}"),
                d["setting"],
                as_text(d["seconds"]),
            ]
            for a, d in zip(best[0::2], best[1::2], strict=True)
        ],
    )
    rows: list[dict[str, Any]] = read_study(results, "pareto") or []
    net = sorted(
        {as_float(r["edge"]) for r in rows if r["case"] == "net" and r["method"] == "static"}
    )
    errs = []
    for e in net:
        sel = [
            r
            for r in rows
            if r["case"] == "net"
            and r["method"] == "static"
            and as_float(r["edge"]) == e
            and as_float(r["rtol"]) <= 1e-8
        ]
        if sel:
            lowest = min(as_float(r["error"]) for r in sel)
            errs.append(f"{e * 1e3:g} mm: {as_text(lowest, '{:.1e}')}")
    if errs:
        out += [
            "",
            "Error of the net's centre deflection at rtol 1e-8 for edge " + ", ".join(errs) + ".",
        ]
    ratio = _static_vs_dynamic(results)
    if ratio:
        out += ["", f"Dynamic relaxation of the n = 34 net to the same tolerance takes {ratio}."]
    return out


def _static_vs_dynamic(results: Path) -> str:
    rows = read_study(results, "step-size") or []
    sel = {as_float(r["h"]): r for r in rows if r["n"] == "34" and r["equilibrium"] == "True"}
    if not sel:
        return ""
    static = as_float(next(iter(sel.values()))["static_seconds"])
    parts = [
        f"{as_float(sel[h]['wall_seconds']) / static:.0f} times with h = {h:g} s"
        for h in (1.0, 0.01)
        if h in sel
    ]
    return " and ".join(parts) + " as long as the static solve" if parts else ""


def skips(results: Path) -> list[str]:
    rows = read_study(results, "skips")
    if not rows:
        return []
    out = md_table(
        ["what", "variant", "time [s]", "x default", "Newton it.", "note"],
        [
            [
                r["skip"],
                r["variant"] + (" *" if r["default"] == "True" else ""),
                as_text(r["seconds"]),
                as_text(r["ratio_to_default"], "{:.2f}"),
                r["iterations"],
                r["note"].replace("|", "/"),
            ]
            for r in rows
        ],
    )
    return out


def cold_start(results: Path) -> list[str]:
    rows = read_study(results, "cold-start")
    if not rows:
        return []
    out = md_table(
        ["command", "Numba cache", "threads", "time [s]", "runs"],
        [
            [r["command"], r["numba_cache"], r["threads"], as_text(r["seconds"]), r["runs"]]
            for r in rows
        ],
    )
    heavy = next(
        (r.get("heavy_modules_imported") for r in rows if r.get("heavy_modules_imported")), None
    )
    if heavy:
        out += ["", f"Heavy modules imported by `catenet --help`: {heavy}."]
    return out


def revisions(results: Path) -> list[str]:
    """``benchmarks/compare_revisions.py``: whole `catenet run` processes of this revision
    against another one, interleaved in one run."""
    rows = read_study(results, "revisions")
    if not rows or len(rows) != 2 or "median_cpu_s" not in rows[0]:
        return []
    this, other = rows
    cpu = as_float(this["median_cpu_s"]) / as_float(other["median_cpu_s"])
    wall = as_float(this["median_s"]) / as_float(other["median_s"])
    same = this.get("dx_rel") == this.get("dtension_rel") == "0.000e+00"
    out = md_table(
        ["revision", "CPU [s], median", "CPU [s], least", "wall [s], median", "runs"],
        [
            [
                f"`{r['revision']}`",
                as_text(r["median_cpu_s"]),
                as_text(r["min_cpu_s"]),
                as_text(r["median_s"]),
                r["runs"],
            ]
            for r in rows
        ],
    )
    out += [
        "",
        f"`catenet run {this['case']}` at `{this['revision']}` takes **{cpu:.3f}x** the CPU "
        f"time of `{other['revision']}` ({wall:.3f}x the wall time on the shared machine); "
        + (
            "the two give the same /result/x and /result/tension to the bit."
            if same
            else f"their /result/x differ by {this['dx_rel']} (relative)."
        ),
    ]
    differences = this.get("file_differences", "")
    if differences:
        why = (
            " (the resolved case text: each revision writes every key it knows)"
            if "attribute case of /: differs" in differences
            else ""
        )
        out += [
            "",
            "Datasets and attributes of the earlier revision's file that the new one lacks "
            f"or holds otherwise: {differences}{why}.",
        ]
    return out


def stress(results: Path) -> list[str]:
    rows = read_study(results, "stress")
    if not rows:
        return []
    passed = sum(r["passed"] == "True" for r in rows)
    out = [
        f"{passed} of {len(rows)} hard scenes give a right answer.",
        "",
    ]
    out += md_table(
        ["scene", "outcome", "check", "value", "Newton it.", "time [s]", "right"],
        [
            [
                r["id"],
                r["status"],
                r.get("check", ""),
                as_text(r.get("value"), "{:.1e}"),
                r.get("iterations", ""),
                as_text(r["seconds"], "{:.2f}"),
                "yes" if r["passed"] == "True" else "**no**",
            ]
            for r in rows
        ],
    )
    bad = [r for r in rows if r["passed"] != "True"]
    if bad:
        out += ["", "Scenes without a right answer (reported to be fixed in the solver):", ""]
        out += [f"- {r['id']}: {r['status']}; {r.get('message', '')}" for r in bad]
    return out


def formfind(results: Path) -> list[str]:
    rows = read_study(results, "formfind")
    if not rows:
        return []
    out = md_table(
        [
            "edges",
            "linear [s]",
            "SciPy backend [s]",
            "plain spsolve [s]",
            "forces [s]",
            "lengths [s]",
        ],
        [
            [
                r["edges"],
                as_text(r["linear_s"]),
                as_text(r["scipy_s"]),
                as_text(r["plain_s"]),
                as_text(r["forces_s"]) if r.get("forces_s") else "-",
                as_text(r["lengths_s"]) if r.get("lengths_s") else "-",
            ]
            for r in rows
            if r.get("linear_s")
        ],
    )
    for r in rows:
        if r.get("loaded_static_s"):
            out += [
                "",
                f"A form-found roof of {r['loaded_dofs']} DOF (tension-only) under snow: its "
                f"nonlinear static analysis takes {as_text(r['loaded_static_s'])} s "
                f"({r['loaded_iterations']} Newton iterations), "
                f"{as_text(r['loaded_over_square'])} times the static solve of the paper's "
                f"square net of {r['square_dofs']} DOF in the same run "
                f"({as_text(r['square_static_s'])} s); with the form finding "
                f"({as_text(r['loaded_formfind_s'])} s), "
                f"{as_text(r['loaded_total_over_square'])} times."
                + (
                    " The paper's net is mostly chains of subdivided cables, cheaper to factorise "
                    "per DOF than the roof's grid of four-edge joints; against the static solve "
                    "of the same grid flat and unstressed under the same snow "
                    f"({as_text(r['flat_static_s'])} s, {r['flat_iterations']} iterations), "
                    f"the loaded analysis costs {as_text(r['loaded_over_flat'])} times, "
                    f"{as_text(r['loaded_total_over_flat'])} with the form finding."
                    if r.get("flat_static_s")
                    else ""
                ),
            ]
    return out


def flush(results: Path) -> list[str]:
    rows = read_study(results, "flush")
    if not rows:
        return []
    out = md_table(
        ["scheme", "DOF", "steps", "time [s]", "ratio to per-frame flush"],
        [
            [
                r["scheme"],
                r["dofs"],
                r["steps"],
                as_text(r["wall_seconds"]),
                as_text(r["ratio_to_per_frame"]),
            ]
            for r in rows
        ],
    )
    return out
