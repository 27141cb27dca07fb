"""Static equilibrium of square nets from about 1e3 to 1e7 DOF: time and peak memory.

The paper's net (alpha = 0, p = 100 Pa, L = 1 m) refined in both ways at once: k times
more cables and k times shorter edges (n = 34 k, edge = 1 cm / k), so the DOF grow as
k^2 (1e4 at k = 1). Each size runs in a fresh interpreter (one thread) so that its peak
resident memory (VmHWM of /proc/self/status, else ``ru_maxrss``: both see MKL's
allocations, unlike tracemalloc; ru_maxrss alone would keep the parent's peak across
exec) is its own. Reported per size: the time to build the net,
the warm static solve (a new Workspace: pattern and solver set-up included) split into
set-up, assembly, symbolic analysis, numeric factorisation, triangular solves and the
Newton loop's own work, Newton iterations, factor nonzeros, peak memory and the memory
guard's estimate for the same net (``catenet.case.guard``, from the case alone); and the
fitted exponent of time against DOF. At the sizes in VARIANT_SIZES the solve is repeated
with PARDISO's other choices (VARIANTS: the parallel nested dissection ordering, the
out-of-core factor), rows marked by their ``variant``.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/scale.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging

from benchmarks.common import (
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
TITLE = "Static solve from 1e3 to 1e7 DOF"

# (cables n, edge length [m]): about 1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6, 3e6, 1e7 DOF.
SIZES = (
    (10, 1 / 30),
    (18, 1 / 55),
    (34, 0.01),
    (58, 1 / 170),
    (108, 1 / 320),
    (188, 1 / 550),
    (340, 1 / 1000),
    (588, 1 / 1730),
    (1076, 1 / 3162),
)
QUICK_MAX_DOF = 1.5e5
TIMEOUT = 2400.0
#: PARDISO's choices measured besides the default (METIS ordering, in-core factor):
#: iparm entries (0-based) set before the analysis.
VARIANTS = {
    "parallel ND": {"1": 3},  # parallel nested dissection ordering (OpenMP METIS)
    "out-of-core": {"59": 2},  # the factor on disk (MKL_PARDISO_OOC_PATH)
}
VARIANT_SIZES = ((340, 1 / 1000),)
QUICK_VARIANT_SIZES = ((108, 1 / 320),)

_CHILD = r"""
import json, resource, sys, time
args = json.loads(sys.argv[2]) if len(sys.argv) > 2 else ARGS
import os
os.chdir(args.get("workdir", "."))
out = {}
def rss():  # peak MiB of this process: VmHWM (ru_maxrss keeps the parent's across exec)
    try:
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # (Linux: KiB)
from benchmarks.common import paper_net, warm_up
from catenet.solver.static import Workspace, solve_static
warm_up()
try:  # the peak from here on: the warm-up's own (its small solves' dense checks) cleared
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")
except OSError:
    pass
out["rss_after_import_mib"] = rss()
s = time.perf_counter()
sq, loads = paper_net(args["n"], edge=args["edge"])
out["build_seconds"] = time.perf_counter() - s
out["rss_after_build_mib"] = rss()
net = sq.net
out["nodes"] = net.n_nodes; out["edges"] = net.n_edges
runs = []
for k in range(args["repeats"]):
    s, cpu = time.perf_counter(), time.process_time()
    ws = Workspace(net)
    for key, value in args.get("iparm", {}).items():
        ws.solver.iparm[int(key)] = value
    res = solve_static(net, loads, workspace=ws)
    total = time.perf_counter() - s
    st = res.stats.as_dict()
    st["total_seconds"] = total
    st["total_cpu_seconds"] = time.process_time() - cpu  # immune to a loaded machine
    st["factor_nnz"] = getattr(ws.solver, "factor_nnz", None)
    iparm = getattr(ws.solver, "iparm", None)  # PARDISO's memory report [KiB]: analysis, factor
    st["pardiso_kib"] = None if iparm is None else max(int(iparm[14]), int(iparm[15] + iparm[16]))
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


def guard_estimate_mib(n: int, edge: float) -> float:
    """The memory guard's estimate [MiB] for the square net case of these parameters."""
    from catenet.case.guard import estimate_memory
    from catenet.case.kinds.square_net import SquareNetConfig

    geometry = SquareNetConfig(n=n, alpha=0.0, size=1.0, edge_length=edge)
    return estimate_memory(*geometry.estimate_size()[:3]) / 2.0**20


def measure(n: int, edge: float, *, threads: int, variant: str = "default") -> dict:
    """One size in a fresh interpreter: the row of the table (``error`` when it failed)."""
    import json
    import tempfile

    repeats = 3 if 3 * n / edge < 5e4 else 1
    args = {"n": n, "edge": edge, "repeats": repeats, "iparm": VARIANTS.get(variant, {})}
    env = thread_env(threads)
    row: dict = {"variant": variant, "n": n, "edge": edge}
    with tempfile.TemporaryDirectory(prefix="catenet-ooc-") as tmp:
        args["workdir"] = tmp  # PARDISO's out-of-core files go to the working directory
        out = run_child(_CHILD.replace("ARGS", json.dumps(args)), timeout=TIMEOUT, env=env)
    if "error" in out:
        row.update(error=out["error"], wall_seconds=out["wall_seconds"])
        return row
    r = out["run"]
    parts = ("setup", "assembly", "analyse", "factorize", "solve")
    guard = guard_estimate_mib(n, edge)
    row.update(
        {
            "nodes": out["nodes"],
            "edges": out["edges"],
            "dofs": int(r["dofs"]),
            "nnz": r["nnz"],
            "factor_nnz": r["factor_nnz"],
            "pardiso_mib": None if r.get("pardiso_kib") is None else r["pardiso_kib"] / 1024,
            "iterations": out["iterations"],
            "converged": out["converged"],
            "build_seconds": out["build_seconds"],
            "total_seconds": r["total_seconds"],
            "total_cpu_seconds": r["total_cpu_seconds"],
            **{f"{k}_seconds": r[f"{k}_seconds"] for k in parts},
            "other_seconds": r["total_seconds"] - sum(r.get(f"{k}_seconds", 0.0) for k in parts),
            "setup_share": r["setup_seconds"] / max(r["factorize_seconds"], 1e-12),
            "repeats": len(out["total_all"]),
            "peak_rss_mib": out["peak_rss_mib"],
            "rss_after_import_mib": out["rss_after_import_mib"],
            "rss_after_build_mib": out["rss_after_build_mib"],
            "guard_estimate_mib": guard,
            "guard_ratio": guard / out["peak_rss_mib"],
            "delta": out["delta"],
            "child_wall_seconds": out["wall_seconds"],
        }
    )
    return row


def run(
    out_dir: Path,
    *,
    quick: bool = False,
    progress=no_progress,
    threads: int = 1,
    sizes=None,
    variant_sizes=None,
) -> Study:
    """``sizes`` (cables n, edge length), default SIZES; ``variant_sizes`` where PARDISO's
    VARIANTS run too, default VARIANT_SIZES (none when ``sizes`` are given)."""
    if variant_sizes is None:
        variant_sizes = () if sizes else QUICK_VARIANT_SIZES if quick else VARIANT_SIZES
    sizes = sizes or SIZES
    if quick:
        sizes = [s for s in sizes if 3 * s[0] / s[1] <= QUICK_MAX_DOF]
    # each size's variants right after its default run: their ratios are taken close in time
    jobs = []
    for n, edge in sizes:
        jobs.append((n, edge, "default"))
        if (n, edge) in variant_sizes:
            jobs += [(n, edge, v) for v in VARIANTS]
    jobs += [(n, edge, v) for n, edge in variant_sizes if (n, edge) not in sizes for v in VARIANTS]
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    failed = False
    for k, (n, edge, variant) in enumerate(jobs):
        if failed and variant == "default":
            continue  # larger sizes would fail the same way
        progress(k, len(jobs), f"n = {n}, edge = {edge:.3g}, {variant}")
        row = measure(n, edge, threads=threads, variant=variant)
        rows.append(row)
        write_csv(rows, study.csv)  # a study stopped at the largest sizes keeps the others
        if "error" in row:
            failed = failed or variant == "default"
            study.findings.append(f"scale: n = {n}, edge = {edge:.3g}, {variant}: {row['error']}")
        elif not row["converged"]:
            study.findings.append(f"scale: n = {n}, {variant}: static solve did not converge")
    progress(len(jobs), len(jobs), "")
    main = [r for r in rows if r["variant"] == "default" and "dofs" in r]
    ok = [r for r in main if r["dofs"] >= 5e3]
    if len(ok) >= 3:
        d = [r["dofs"] for r in ok]
        b, _ = geometric_fit(d, [r["total_seconds"] for r in ok])
        bf, _ = geometric_fit(d, [max(r["factorize_seconds"], 1e-9) for r in ok])
        bc, _ = geometric_fit(d, [r["total_cpu_seconds"] for r in ok])
        bm, _ = geometric_fit(d, [r["peak_rss_mib"] - r["rss_after_import_mib"] + 1 for r in ok])
        top = ok[-1]
        per_dof = (top["peak_rss_mib"] - top["rss_after_import_mib"]) * 1024 / top["dofs"]
        study.summary.append(
            f"fitted exponents (DOF >= 5e3): total time ~ DOF^{b:.2f} (CPU time "
            f"~ DOF^{bc:.2f}), "
            f"factorisation ~ DOF^{bf:.2f}, memory above start-up ~ DOF^{bm:.2f}; at "
            f"{top['dofs']} DOF: {per_dof:.2g} KiB per DOF above the "
            f"{top['rss_after_import_mib']:.0f} MiB after start-up"
        )
        for r in rows:
            r["fit_exponent_total"] = b
            r["fit_exponent_factorize"] = bf
            r["fit_exponent_cpu"] = bc
    ratios = [r["guard_ratio"] for r in main]
    if ratios and not all(0.7 <= q <= 1.3 for q in ratios):
        study.findings.append(
            "scale: the memory guard's estimate is off by more than 30 % of the measured "
            f"peak (estimate / peak from {min(ratios):.2f} to {max(ratios):.2f})"
        )
    write_csv(rows, study.csv)
    study.figure = figure(main, out_dir)
    for r in rows:
        if "dofs" not in r:
            study.summary.append(f"n = {r['n']}, {r['variant']}: {r.get('error')}")
            continue
        study.summary.append(
            f"{r['dofs']:>8d} DOF  {r['variant']:<12s} {r['total_seconds']:8.3f} s  (set-up "
            f"{r['setup_seconds']:.3f}, assembly {r['assembly_seconds']:.3f}, analyse "
            f"{r['analyse_seconds']:.3f}, factorise {r['factorize_seconds']:.3f}, solve "
            f"{r['solve_seconds']:.3f}, other {r['other_seconds']:.3f})  {r['iterations']} it  "
            f"peak {r['peak_rss_mib']:.0f} MiB (guard {r['guard_estimate_mib']:.0f})  "
            f"build {r['build_seconds']:.2f} s"
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
    ax2.loglog(d, [r["guard_estimate_mib"] for r in ok], "s--", label="memory guard's estimate")
    ax2.loglog(d, [r["rss_after_import_mib"] for r in ok], ":", label="after imports")
    ax2.set_xlabel("DOF")
    ax2.set_ylabel("memory [MiB]")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
