"""The sections of the README performance section, one per study, each from its study's
CSV file in the results directory (an empty list when the file is missing)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from catenet.studies.bench.common import read_csv


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
    out = ["### Static solve of the paper's nets, against a plain implementation", ""]
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
                "model and Newton method (`catenet/studies/bench/baseline.py`), which "
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
    out += [
        "",
        "OpenSees rows (where present) solve the same net as `corotTruss` elements with a "
        "tension-only elastic material; a flat unstressed net has no transverse stiffness, "
        "so OpenSees needs a pretension (1e-4 strain, `InitStrainMaterial`) and load steps "
        "(20, `NewtonLineSearch`, UmfPack; plain Newton with 10 steps and SparseSYM fail); "
        "they are compared with catenet on the same pretensioned net (rest lengths / "
        "(1 + 1e-4)); the remaining difference (~3e-5 of delta) is the cross term of the two "
        "ways to pretension. openseespy 3.7 installs from PyPI but its Linux wheel does not "
        "find its bundled `libblas.so.3`; the study loads that library first.",
        "",
        "![catenet against the baseline](figures/bench-baseline.png)",
        "",
    ]
    return out


def step_size(results: Path) -> list[str]:
    rows = read_study(results, "step-size")
    if not rows:
        return []
    out = [
        "### Time against step size (paper Fig. B10)",
        "",
        "Dynamic relaxation (implicit Euler, mu = 1) of the paper's nets (alpha = 0, "
        "p = 100 Pa, 1 cm edges) from rest until the static residual and the inertial "
        "force fall below rtol = 1e-8 of the load; runs that had not arrived within their "
        "wall-time budget are marked capped (the ratio is still measured over the "
        "simulated time reached). Error: max |x - x_static| / delta_static.",
        "",
    ]
    out += md_table(
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
        "",
        "![time against step size](figures/bench-step-size.png)",
        "",
    ]
    return out


def pareto(results: Path) -> list[str]:
    best = read_study(results, "pareto-best")
    if not best:
        return []
    out = [
        "### Run time against error: which settings for which accuracy",
        "",
        "Three scenes against references they converge to: the midpoint-loaded cable "
        "(F = 0.01 EA, Eq. 17: the discrete model is exact, so only the solver errs), the "
        "compressed catenary (dL/L = 0.2, the exact elastic catenary: discretisation "
        "error O(edge^2) plus the solver's) and the n = 34 net (Richardson extrapolation "
        "of 5, 2.5 and 1.25 mm edges with the observed order, about 1). Error: relative "
        "error of the mid-span / centre deflection. Fastest setting found for each "
        "target:",
        "",
    ]
    out += md_table(
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
            "The net's centre deflection converges only at about first order in the "
            "edge length (the paper's load puts p L^2 / N on every node, whatever its "
            "share of cable), so the paper's 1 cm edges carry a discretisation error of "
            "about half a per cent: error of delta at rtol 1e-8 for edge " + ", ".join(errs) + ".",
        ]
    out += [
        "",
        "Recommendations:",
        "",
        '- For an equilibrium, use `solver.method = "static"`: it is the fastest way to '
        "every accuracy in every scene" + _static_vs_dynamic(results) + ".",
        "- `rtol` costs little: Newton converges quadratically, so going from 1e-4 to 1e-8 "
        "adds one or two iterations. Keep the default 1e-8; the error is then set by the "
        "discretisation alone.",
        "- The discretisation sets the accuracy of a sagging cable or net: the catenary's "
        "error falls as edge^2 (halving the edge length gains a factor of 4 for about twice "
        "the run time), the net's only as edge^1 (a factor of 2 for about twice the DOF). "
        "A cable under point loads only (straight pieces) is exact with any number of "
        "edges. For 1e-2 on a net the paper's 1 cm edges suffice; 1e-3 needs edges of "
        "about 2 mm (extrapolated from the first-order error above).",
        '- Dynamic relaxation (`method = "dynamic"`) is for the motion itself; if it is '
        "used to reach an equilibrium, take the largest step (h = 1 s arrives in a handful "
        "of steps; the final state does not depend on h or mu) rather than a small h, whose "
        "cost grows as 1/h.",
        "",
        "![run time against error](figures/bench-pareto.png)",
        "",
    ]
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
    return (
        (
            "; dynamic relaxation of the n = 34 net to the same tolerance takes "
            + " and ".join(parts)
            + " as long"
        )
        if parts
        else ""
    )


def skips(results: Path) -> list[str]:
    rows = read_study(results, "skips")
    if not rows:
        return []
    out = [
        "### What each skip saves",
        "",
        "Each variant against catenet's default (marked *) on the n = 34 net, one process, "
        "medians of repeats.",
        "",
    ]
    out += md_table(
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
    out += ["", "![skips](figures/bench-skips.png)", ""]
    return out


def cold_start(results: Path) -> list[str]:
    rows = read_study(results, "cold-start")
    if not rows:
        return []
    out = [
        "### Cold start",
        "",
        "Fresh processes, as a user runs them; `empty` Numba cache: `NUMBA_CACHE_DIR` "
        "points at a new directory, so every kernel is compiled.",
        "",
    ]
    out += md_table(
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
    out += ["", "![cold start](figures/bench-cold-start.png)", ""]
    return out


def stress(results: Path) -> list[str]:
    rows = read_study(results, "stress")
    if not rows:
        return []
    passed = sum(r["passed"] == "True" for r in rows)
    out = [
        "### Numerical-stability stress test",
        "",
        f"{passed} of {len(rows)} hard scenes give a right answer (a converged state that "
        "passes its check, or a clear catenet error where that is right). Loads from 1e-9 "
        "to 0.5 EA, EA from 1e-2 to 1e9 N, h from 1e-6 to 1e3 s, damping 0 to 1e3, "
        "zero-slack cables under self-weight, supports moved in by half the span and more, "
        "bilateral cables in compression, point loads on a net, a 1e5-edge cable and "
        "random graphs. Checks: Eq. 17, the exact discrete chain, equilibrium (residual and "
        "reaction balance recomputed from the answer), static = dynamic.",
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
    out += ["", "![stress test](figures/bench-stress.png)", ""]
    return out


def formfind(results: Path) -> list[str]:
    rows = read_study(results, "formfind")
    if not rows:
        return []
    out = [
        "### Form finding",
        "",
        "The force density method on square roofs (`catenet bench formfind`), set-up "
        "included: the linear method is one sparse factorisation for the three coordinates; "
        "`plain spsolve` assembles the same system with scipy.sparse products and calls "
        "`spsolve` per coordinate; `forces` and `lengths` meet a target force or length "
        "in every edge to 1e-9 (damped Newton on log q, one sparse saddle-point solve per "
        "step).",
        "",
    ]
    out += md_table(
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
    out += ["", "![form finding](figures/bench-formfind.png)", ""]
    return out


def flush(results: Path) -> list[str]:
    rows = read_study(results, "flush")
    if not rows:
        return []
    out = [
        "### Writing trajectories",
        "",
        "1000 dynamic steps keeping every frame (`catenet bench flush`): frames flushed in "
        "batches into a spare file that replaces the result file whole, against the earlier "
        "per-frame flush in place; the frames of both files are bitwise equal.",
        "",
    ]
    out += md_table(
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
    return out + [""]
