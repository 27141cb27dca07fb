"""Run time against error: which settings buy which accuracy.

Three scenes, each against a reference it converges to:

- ``cable``: the paper's midpoint-loaded cable (L = 1 m, F = 0.01 EA, Fig. 2b); reference
  Eq. 17 (``catenet.validate.analytic.midpoint_load_deflection``). The discrete model is exact here
  (straight halves), so the error is the solver's alone.
- ``catenary``: the paper's compressed catenary (dL/L = 0.2, self-weight, Fig. 2a/c);
  reference the exact elastic catenary (``catenet.validate.analytic.elastic_catenary``): the
  error is discretisation (O(edge^2)) plus the solver's.
- ``net``: the n = 34 square net (alpha = 0, p = 100 Pa); reference the Richardson
  extrapolation of static solutions with 5, 2.5 and 1.25 mm edges (rtol 1e-11) with the
  order observed from those three (about 1: see ``reference``).

The error is |delta - delta_ref| / delta_ref of the mid-span / centre deflection. Varied:
method (static, dynamic), time step h, rtol and edge length. Times are warm medians
including the Workspace set-up; dynamic runs stop at equilibrium or after a wall-time
budget (a capped run still gives a point: the time spent and the error reached).
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/pareto.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging
import math
import time

from benchmarks.common import (
    PAPER_EDGE,
    Study,
    compressed_catenary,
    midpoint_cable,
    no_progress,
    paper_material,
    paper_net,
    pyplot,
    repeat,
    save_figure,
    set_threads,
    warm_up,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "pareto"
TITLE = "Run time against error"

F_BAR = 0.01  # midpoint force / EA
DL = 0.2  # catenary: supports moved inward by dL (both together)
TARGETS = (1e-2, 1e-3, 1e-4, 1e-6)
NET_REFERENCE_EDGES = (0.005, 0.0025, 0.00125)


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    set_threads(threads)
    warm_up()
    budget = 3.0 if quick else 10.0
    plan = _plan(quick)
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    refs: dict[str, float] = {}
    for k, job in enumerate(plan):
        case = job["case"]
        progress(k, len(plan), f"{case} {job['method']} {job.get('h', '')}")
        if case not in refs:
            refs[case] = reference(case)
        try:
            seconds, delta, extra = _solve(job, budget, quick)
        except Exception as exc:  # a CatenetError is a result too: record it
            log.warning("pareto: %s: %r", job, exc)
            rows.append(
                {
                    **job,
                    "seconds": float("nan"),
                    "error": float("nan"),
                    "note": f"{type(exc).__name__}: {exc}",
                }
            )
            study.findings.append(f"pareto {job}: {type(exc).__name__}: {exc}")
            continue
        err = abs(delta - refs[case]) / refs[case]
        rows.append(
            {
                **job,
                "seconds": seconds,
                "error": err,
                "delta": delta,
                "delta_ref": refs[case],
                **extra,
            }
        )
    progress(len(plan), len(plan), "")
    _front(rows)
    write_csv(rows, study.csv)
    best = recommend(rows)
    write_csv(best, Path(out_dir) / f"{NAME}-best.csv")
    study.figure = figure(rows, out_dir)
    for b in best:
        study.summary.append(
            f"{b['case']:<9s} error <= {b['target']:.0e}: {b['setting']}  "
            f"({b['seconds']:.3g} s, error {b['error']:.1e})"
        )
    return study


def _plan(quick: bool) -> list[dict]:
    rtols = (1e-4, 1e-8) if quick else (1e-3, 1e-4, 1e-6, 1e-8, 1e-10)
    plan = []
    cable_nodes = (21, 101) if quick else (11, 21, 51, 101, 201)
    cat_nodes = (21, 101) if quick else (11, 21, 51, 101, 201, 401)
    net_edges = (0.02, 0.01) if quick else (0.04, 0.02, 0.01, 0.005)
    steps = (0.1, 1.0) if quick else (1e-3, 1e-2, 1e-1, 1.0)
    for case, sizes, key in (
        ("cable", cable_nodes, "nodes"),
        ("catenary", cat_nodes, "nodes"),
        ("net", net_edges, "edge"),
    ):
        for size in sizes:
            for rtol in rtols:
                plan.append({"case": case, "method": "static", key: size, "rtol": rtol})
        mid = 101 if case != "net" else PAPER_EDGE
        for h in steps if case != "net" else [s for s in steps if s >= 1e-2]:
            for rtol in (1e-8,) if quick else (1e-4, 1e-6, 1e-8):
                plan.append({"case": case, "method": "dynamic", key: mid, "h": h, "rtol": rtol})
    for job in plan:
        if "edge" not in job:
            job["edge"] = 1.0 / (job["nodes"] - 1)
    return plan


def _scene(case: str, size, *, ramp: float = 0.0):
    """(net, loads, probe node, sign of delta) of a scene."""
    if case == "cable":
        net, loads, mid = midpoint_cable(F_BAR * paper_material().EA, nodes=int(size))
        return net, loads, mid
    if case == "catenary":
        net, loads = compressed_catenary(DL, nodes=int(size), ramp=ramp)
        return net, loads, (int(size) - 1) // 2
    sq, loads = paper_net(34, edge=float(size))
    return sq.net, loads, sq.center


def _solve(job: dict, budget: float, quick: bool):
    from catenet.scene import Scene
    from catenet.solver import path as sv

    size = job.get("nodes", job["edge"])
    if job["method"] == "static":
        net, loads, probe = _scene(job["case"], size)
        settings = sv.Settings(rtol=job["rtol"])
        t, _, res = repeat(
            lambda: sv.solve(Scene(net, loads), settings), 3 if net.n_nodes < 2e4 else 1
        )
        return (
            t,
            -float(res.x[probe, 2]),
            {"iterations": res.iterations, "steps": 1, "dofs": 3 * int((~net.fixed).sum())},
        )
    net, loads, probe = _scene(job["case"], size, ramp=0.5 if job["case"] == "catenary" else 0)
    start = time.perf_counter()

    def stop(step: sv.Step) -> bool:
        return time.perf_counter() - start > budget

    settings = sv.Settings("dynamic", dt=job["h"], damping=1.0, t_end=500.0, rtol=job["rtol"])
    res = sv.solve(Scene(net, loads), settings, on_step=stop)
    t = time.perf_counter() - start
    return (
        t,
        -float(res.x[probe, 2]),
        {
            "iterations": res.iterations,
            "steps": res.steps,
            "equilibrium": res.equilibrium,
            "capped": res.outcome == "interrupted",
            "simulated_seconds": res.time,
            "dofs": 3 * int((~net.fixed).sum()),
        },
    )


def reference(case: str) -> float:
    """The deflection each scene converges to."""
    from catenet.validate import analytic

    mat = paper_material()
    if case == "cable":
        return analytic.midpoint_load_deflection(F_BAR * mat.EA, 1.0, mat.EA)
    if case == "catenary":
        w = mat.line_density * 9.81
        return analytic.elastic_catenary(1.0, mat.EA, w, 1.0 - DL).sag
    from catenet.solver.static import solve_static

    deltas = []
    for edge in NET_REFERENCE_EDGES:
        sq, loads = paper_net(34, edge=edge)
        res = solve_static(sq.net, loads, rtol=1e-11)
        deltas.append(-float(res.x[sq.center, 2]))
    d0, d1, d2 = deltas
    # Richardson extrapolation with the observed order: the centre deflection of the
    # paper's net converges at about first order in the edge length (its load is p L^2/N
    # on every node, whatever the node's share of cable), not at second.
    order = math.log2(abs(d1 - d0) / abs(d2 - d1))
    log.info("pareto: net deflections %s, observed order %.2f", deltas, order)
    return d2 + (d2 - d1) / (2.0**order - 1.0)


def _front(rows: list[dict]) -> None:
    """Marks the Pareto-optimal rows of each case (no other row is both faster and more
    accurate)."""
    for r in rows:
        r["pareto"] = False
        if not math.isfinite(r.get("error", math.nan)):
            continue
        r["pareto"] = not any(
            o is not r
            and o["case"] == r["case"]
            and math.isfinite(o["error"])
            and o["seconds"] <= r["seconds"]
            and o["error"] <= r["error"]
            and (o["seconds"] < r["seconds"] or o["error"] < r["error"])
            for o in rows
        )


def _setting(r: dict) -> str:
    size = f"{r['nodes']} nodes" if r["case"] != "net" else f"edge {r['edge'] * 1e3:g} mm"
    if r["method"] == "static":
        return f"static, {size}, rtol {r['rtol']:.0e}"
    return f"dynamic h = {r['h']:g} s, {size}, rtol {r['rtol']:.0e}"


def recommend(rows: list[dict]) -> list[dict]:
    """For each case and target error, the fastest row that meets it (and the fastest
    dynamic one, for those who need the motion)."""
    out = []
    for case in dict.fromkeys(r["case"] for r in rows):
        for target in TARGETS:
            for method in ("any", "dynamic"):
                ok = [
                    r
                    for r in rows
                    if r["case"] == case
                    and r.get("error", math.inf) <= target
                    and (method == "any" or r["method"] == method)
                ]
                if not ok:
                    out.append(
                        {
                            "case": case,
                            "target": target,
                            "method": method,
                            "setting": "none reached this",
                            "seconds": float("nan"),
                            "error": float("nan"),
                        }
                    )
                    continue
                best = min(ok, key=lambda r: r["seconds"])
                out.append(
                    {
                        "case": case,
                        "target": target,
                        "method": method,
                        "setting": _setting(best),
                        "seconds": best["seconds"],
                        "error": best["error"],
                    }
                )
    return out


def figure(rows, out_dir):
    plt = pyplot()
    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 4), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        sel = [r for r in rows if r["case"] == case and math.isfinite(r.get("error", math.nan))]
        for method, marker in (("static", "o"), ("dynamic", "s")):
            pts = [r for r in sel if r["method"] == method]
            if not pts:
                continue
            sc = ax.scatter(
                [r["seconds"] for r in pts],
                [max(r["error"], 1e-16) for r in pts],
                c=[math.log10(r["rtol"]) for r in pts],
                cmap="viridis",
                marker=marker,
                label=method,
                vmin=-10,
                vmax=-3,
                edgecolors="k" if method == "dynamic" else "none",
            )
        front = sorted((r for r in sel if r["pareto"]), key=lambda r: r["seconds"])
        ax.plot(
            [r["seconds"] for r in front],
            [max(r["error"], 1e-16) for r in front],
            "k-",
            lw=0.8,
            label="Pareto front",
        )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("run time [s]")
        ax.set_ylabel("relative error of delta")
        ax.set_title(case)
        ax.legend(fontsize=7)
    fig.colorbar(sc, ax=axes[0].tolist(), label="log10 rtol")
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
