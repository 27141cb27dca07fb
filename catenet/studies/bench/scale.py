"""Static equilibrium of square nets from about 1e3 to 1e6 DOF: time and peak memory.

The paper's net (alpha = 0, p = 100 Pa, L = 1 m) refined in both ways at once: k times
more cables and k times shorter edges (n = 34 k, edge = 1 cm / k), so the DOF grow as
k^2 (1e4 at k = 1). Each size runs in a fresh interpreter (one thread) so that its peak
resident memory (``resource.getrusage(RUSAGE_SELF).ru_maxrss``, which sees MKL's
allocations, unlike tracemalloc) is its own. Reported per size: the time to build the net,
the warm static solve (a new Workspace: pattern and solver set-up included) split into
set-up, assembly, symbolic analysis, numeric factorisation, triangular solves and the
Newton loop's own work, Newton iterations, factor nonzeros and peak memory; and the fitted
exponent of time against DOF.
"""

from __future__ import annotations

import logging
from pathlib import Path

from catenet.studies.bench.common import (
    Study,
    geometric_fit,
    no_progress,
    pyplot,
    run_child,
    save_figure,
    thread_env,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "scale"
TITLE = "Static solve from 1e3 to 1e6 DOF"

# (cables n, edge length [m]): about 1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6 DOF.
SIZES = (
    (10, 1 / 30),
    (18, 1 / 55),
    (34, 0.01),
    (58, 1 / 170),
    (108, 1 / 320),
    (188, 1 / 550),
    (340, 1 / 1000),
)
QUICK_MAX_DOF = 1.5e5
TIMEOUT = 900.0

_CHILD = r"""
import json, resource, sys, time
args = json.loads(sys.argv[2]) if len(sys.argv) > 2 else ARGS
out = {}
def rss():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # MiB (Linux: KiB)
from catenet.studies.bench.common import paper_net, warm_up
from catenet.static import Workspace, solve_static
warm_up()
out["rss_after_import_mib"] = rss()
s = time.perf_counter()
sq, loads = paper_net(args["n"], edge=args["edge"])
out["build_seconds"] = time.perf_counter() - s
net = sq.net
out["nodes"] = net.n_nodes; out["edges"] = net.n_edges
runs = []
for k in range(args["repeats"]):
    s = time.perf_counter()
    ws = Workspace(net)
    res = solve_static(net, loads, workspace=ws)
    total = time.perf_counter() - s
    st = dict(res.stats)
    st["total_seconds"] = total
    st["factor_nnz"] = getattr(ws.solver, "factor_nnz", None)
    runs.append(st)
    out["iterations"] = res.iterations
    out["converged"] = bool(res.converged)
    out["delta"] = -float(res.x[sq.center, 2])
    out["residual"] = res.residual
    del ws, res
runs.sort(key=lambda r: r["total_seconds"])
out["run"] = runs[len(runs) // 2]
out["total_all"] = [r["total_seconds"] for r in runs]
out["peak_rss_mib"] = rss()
json.dump(out, open(sys.argv[1], "w"))
"""


def run(
    out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1, sizes=None
) -> Study:
    import json

    sizes = sizes or SIZES
    if quick:
        sizes = [s for s in sizes if 3 * s[0] / s[1] <= QUICK_MAX_DOF]
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    for k, (n, edge) in enumerate(sizes):
        progress(k, len(sizes), f"n = {n}, edge = {edge:.3g}")
        est = 3 * n / edge
        repeats = 3 if est < 5e4 else 1
        code = _CHILD.replace("ARGS", json.dumps({"n": n, "edge": edge, "repeats": repeats}))
        out = run_child(code, timeout=TIMEOUT, env=thread_env(threads))
        row = {"n": n, "edge": edge}
        if "error" in out:
            row.update(error=out["error"], wall_seconds=out["wall_seconds"])
            rows.append(row)
            study.findings.append(f"scale: n = {n}, edge = {edge:.3g}: {out['error']}")
            break  # larger sizes would fail the same way
        r = out["run"]
        dofs = int(r["dofs"])
        newton = r["total_seconds"] - sum(
            r.get(k, 0.0)
            for k in (
                "setup_seconds",
                "assembly_seconds",
                "analyse_seconds",
                "factorize_seconds",
                "solve_seconds",
            )
        )
        row.update(
            {
                "nodes": out["nodes"],
                "edges": out["edges"],
                "dofs": dofs,
                "nnz": r["nnz"],
                "factor_nnz": r["factor_nnz"],
                "iterations": out["iterations"],
                "converged": out["converged"],
                "build_seconds": out["build_seconds"],
                "total_seconds": r["total_seconds"],
                "setup_seconds": r["setup_seconds"],
                "assembly_seconds": r["assembly_seconds"],
                "analyse_seconds": r["analyse_seconds"],
                "factorize_seconds": r["factorize_seconds"],
                "solve_seconds": r["solve_seconds"],
                "other_seconds": newton,
                "repeats": len(out["total_all"]),
                "peak_rss_mib": out["peak_rss_mib"],
                "rss_after_import_mib": out["rss_after_import_mib"],
                "delta": out["delta"],
                "child_wall_seconds": out["wall_seconds"],
            }
        )
        rows.append(row)
        if not out["converged"]:
            study.findings.append(f"scale: n = {n}: static solve did not converge")
    progress(len(sizes), len(sizes), "")
    ok = [r for r in rows if "dofs" in r and r["dofs"] >= 5e3]
    if len(ok) >= 3:
        b, _ = geometric_fit([r["dofs"] for r in ok], [r["total_seconds"] for r in ok])
        bf, _ = geometric_fit(
            [r["dofs"] for r in ok], [max(r["factorize_seconds"], 1e-9) for r in ok]
        )
        top = ok[-1]
        per_dof = (top["peak_rss_mib"] - top["rss_after_import_mib"]) * 1024 / top["dofs"]
        study.summary.append(
            f"fitted exponents (DOF >= 5e3): total time ~ DOF^{b:.2f}, "
            f"factorisation ~ DOF^{bf:.2f}; memory at {top['dofs']} DOF: {per_dof:.2g} KiB "
            f"per DOF above the {top['rss_after_import_mib']:.0f} MiB after start-up"
        )
        for r in rows:
            r["fit_exponent_total"] = b
            r["fit_exponent_factorize"] = bf
    write_csv(rows, study.csv)
    study.figure = figure(rows, out_dir)
    for r in rows:
        if "dofs" not in r:
            study.summary.append(f"n = {r['n']}: {r.get('error')}")
            continue
        study.summary.append(
            f"{r['dofs']:>8d} DOF  {r['total_seconds']:8.3f} s  (set-up {r['setup_seconds']:.3f}, "
            f"assembly {r['assembly_seconds']:.3f}, analyse {r['analyse_seconds']:.3f}, "
            f"factorise {r['factorize_seconds']:.3f}, solve {r['solve_seconds']:.3f}, "
            f"other {r['other_seconds']:.3f})  {r['iterations']} it  "
            f"peak {r['peak_rss_mib']:.0f} MiB  build {r['build_seconds']:.2f} s"
        )
    return study


def figure(rows, out_dir):
    plt = pyplot()
    ok = [r for r in rows if "dofs" in r]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    d = [r["dofs"] for r in ok]
    parts = [
        ("total_seconds", "total"),
        ("setup_seconds", "set-up"),
        ("assembly_seconds", "assembly"),
        ("analyse_seconds", "symbolic analysis"),
        ("factorize_seconds", "factorisation"),
        ("solve_seconds", "solves"),
        ("other_seconds", "Newton loop (rest)"),
        ("build_seconds", "building the net"),
    ]
    for key, label in parts:
        ax1.loglog(
            d,
            [max(r[key], 1e-6) for r in ok],
            "o-" if key == "total_seconds" else ".--",
            label=label,
            lw=2 if key == "total_seconds" else 1,
        )
    ax1.set_xlabel("DOF")
    ax1.set_ylabel("wall time [s]")
    ax1.legend(fontsize=7)
    ax1.set_title("static solve, one thread")
    ax2.loglog(d, [r["peak_rss_mib"] for r in ok], "o-", label="peak RSS")
    ax2.loglog(d, [r["rss_after_import_mib"] for r in ok], ":", label="after imports")
    ax2.set_xlabel("DOF")
    ax2.set_ylabel("memory [MiB]")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)
