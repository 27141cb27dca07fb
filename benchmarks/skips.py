"""What each skip saves, and whether catenet skips by default.

On the paper's n = 34 net (alpha = 0, p = 100 Pa, 1 cm edges), each row times one variant
against catenet's default way of doing the same thing, in one process after a warm-up
(medians of repeats):

- method: static equilibrium instead of dynamic relaxation (the case defaults dt = 1e-2,
  mu = 1, t_end = 10);
- gravity: a scene without gravity (``Loads.gravity = None``) against zero gravity
  computed;
- output: final state only (``output.every = 0``) against a trajectory frame every step
  (needs ``catenet.run.runner``);
- symbolic analysis: once per net (Workspace) against once per factorisation, and against
  ``pypardiso.spsolve``; for a static solve, 20 dynamic steps and a 10-step continuation;
- matrix type: PARDISO mtype 2 (SPD: catenet's choice for tension-only nets), -2 (symmetric
  indefinite: bilateral nets), 11
  (general, full matrix);
- iterative refinement: PARDISO's refinement steps after each solve, catenet's setting
  against none;
- threads: BLAS/MKL threads left at their defaults against one thread, in child
  processes.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/skips.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging

from benchmarks.common import (
    Study,
    interleaved,
    load_average,
    no_progress,
    paper_net,
    pyplot,
    repeat,
    run_child,
    save_figure,
    set_threads,
    tabulate,
    thread_env,
    warm_up,
)

log = logging.getLogger(__name__)

NAME = "skips"
TITLE = "What each skip saves"


def run(
    out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1, n: int = 34
) -> Study:
    import numpy as np

    from catenet.solver.static import solve_static

    set_threads(threads)
    warm_up()
    reps = 3 if quick else 7
    sq, loads = paper_net(n)
    net = sq.net
    ref = solve_static(net, loads, rtol=1e-10)
    scale = -float(ref.x[sq.center, 2])
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")

    def add(skip, variant, default, seconds, x=None, iterations=None, note="", **extra):
        err = float(np.max(np.abs(x - ref.x))) / scale if x is not None else float("nan")
        rows.append(
            {
                "skip": skip,
                "variant": variant,
                "default": default,
                "seconds": seconds,
                "iterations": iterations,
                "error_vs_static": err,
                "note": note,
                **extra,
            }
        )

    parts = [_method, _gravity, _output, _analysis, _mtype, _refinement, _threads]
    for k, part in enumerate(parts):
        progress(k, len(parts), part.__name__.strip("_"))
        try:
            part(net, loads, add, study, reps=reps, quick=quick, n=n)
        except Exception as exc:  # one part failing must not lose the others
            log.exception("skips: %s failed", part.__name__)
            study.findings.append(f"skips/{part.__name__.strip('_')}: failed: {exc!r}")
    progress(len(parts), len(parts), "")

    # Ratios to the default of each skip.
    for skip in dict.fromkeys(r["skip"] for r in rows):
        sel = [r for r in rows if r["skip"] == skip]
        base = next((r for r in sel if r["default"]), None)
        for r in sel:
            r["ratio_to_default"] = r["seconds"] / base["seconds"] if base else float("nan")
        if base:
            faster = [
                r
                for r in sel
                if not r["default"]
                and r["seconds"] < 0.8 * base["seconds"]
                and not r["note"].startswith("failed")
            ]
            for r in faster:
                study.findings.append(
                    f"{skip}: the default ({base['variant']}, {base['seconds']:.3g} s) is "
                    f"slower than {r['variant']} ({r['seconds']:.3g} s, "
                    f"x{r['ratio_to_default']:.2f})"
                )
    return tabulate(study, out_dir, figure, _line)


def _line(r: dict) -> str:
    return (
        f"{r['skip']:<18s} {r['variant']:<46s} {'*' if r['default'] else ' '} "
        f"{r['seconds']:8.4f} s  x{r['ratio_to_default']:6.2f}  {r['note']}"
    )


# --- parts ----------------------------------------------------------------------------------


def _method(net, loads, add, study, *, reps, quick, n):
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import Workspace, solve_static

    ws = Workspace(net)
    t, _, res = repeat(lambda: solve_static(net, loads, workspace=ws), reps)
    add("method", "static (solve_static)", True, t, res.x, res.iterations)
    t, _, res = repeat(
        lambda: solve_dynamic(net, loads, dt=1e-2, damping=1.0, t_end=10.0, workspace=ws),
        1 if quick else 2,
        warmup=0,
    )
    add(
        "method",
        "dynamic relaxation (dt 1e-2, mu 1)",
        False,
        t,
        res.x,
        res.iterations,
        note=f"{res.steps} steps, {res.message}",
    )


def _gravity(net, loads, add, study, *, reps, quick, n):
    import numpy as np

    from catenet.model.net import Loads
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import Workspace, solve_static

    ws = Workspace(net)
    with_g = Loads(force=loads.force, gravity=np.zeros(3))
    cases = {"no gravity (gravity=None)": loads, "zero gravity computed": with_g}
    static = {k: (lambda lo=lo: solve_static(net, lo, workspace=ws)) for k, lo in cases.items()}
    for k, (t, _, res) in interleaved(static, reps).items():
        add("gravity (static)", k, k.startswith("no"), t, res.x, res.iterations)
    dynamic = {
        k: (lambda lo=lo: solve_dynamic(net, lo, dt=1e-2, damping=1.0, t_end=0.2, workspace=ws))
        for k, lo in cases.items()
    }
    for k, (t, _, res) in interleaved(dynamic, reps).items():
        add(
            "gravity (dynamic)",
            k,
            k.startswith("no"),
            t,
            None,
            res.iterations,
            note=f"{res.steps} steps",
        )
    try:
        from catenet.case import build, load_case
    except ImportError:
        study.findings.append(
            "gravity: catenet.case not available: the default case's gravity was not checked"
        )
        return
    scene = build(load_case(None))
    if scene.loads.gravity is not None:
        study.findings.append(
            f"gravity: the default case (no [load] gravity) builds Loads.gravity = "
            f"{scene.loads.gravity!r}: it should be None so that none is computed"
        )
    else:
        study.summary.append("gravity: the default case builds Loads.gravity = None: good")


def _output(net, loads, add, study, *, reps, quick, n):
    import tempfile

    try:
        from catenet.case import load_case
        from catenet.run.runner import run_case
    except ImportError as exc:
        study.findings.append(f"output: not measured ({exc}): catenet.run.runner/case missing")
        return
    with tempfile.TemporaryDirectory(prefix="catenet-bench-") as tmp:
        base = [
            "geometry.alpha=0.0",
            "solver.method='dynamic'",
            "solver.dt=0.01",
            "solver.t_end=0.5",
            f"geometry.n={n}",
        ]
        fns = {}
        for every in (1, 0):
            case = load_case(None, [*base, f"output.every={every}"])
            out = Path(tmp) / f"every{every}.h5"

            def go(case=case, out=out):
                if out.exists():
                    out.unlink()
                return run_case(case, out)

            fns[every] = go
        for every, (t, _, res) in interleaved(fns, reps).items():
            out = Path(tmp) / f"every{every}.h5"
            size = out.stat().st_size if out.exists() else 0
            add(
                "output (dynamic, 50 steps)",
                f"every = {every}",
                every == 1,
                t,
                None,
                res.iterations,
                note=f"file {size / 1e6:.2f} MB",
                file_bytes=size,
            )
        case = load_case(None, ["geometry.alpha=0.0", f"geometry.n={n}"])
        if case.output.every != 0:
            study.summary.append(
                f"output: the default case writes every = {case.output.every} (SPEC default); "
                "a static run has one frame, so this costs nothing there"
            )


def _analysis(net, loads, add, study, *, reps, quick, n):
    from benchmarks.solvers import PypardisoSpsolve, ReanalysingPardiso, install
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.loadsteps import continuation
    from catenet.solver.static import Workspace, solve_static

    variants = [
        ("analyse once (Workspace)", True, None),
        ("analyse every factorisation", False, ReanalysingPardiso),
        ("pypardiso.spsolve", False, PypardisoSpsolve),
    ]
    for name, default, cls in variants:
        ws = Workspace(net)
        if cls is not None:
            install(ws, cls)
        t, _, res = repeat(lambda ws=ws: solve_static(net, loads, workspace=ws), reps)
        add(
            "analysis (static)",
            name,
            default,
            t,
            res.x,
            res.iterations,
            analyse_count=res.stats.analyse_count,
        )
        t, _, res = repeat(
            lambda ws=ws: solve_dynamic(net, loads, dt=1e-2, damping=1.0, t_end=0.2, workspace=ws),
            reps,
        )
        add(
            "analysis (dynamic)",
            name,
            default,
            t,
            None,
            res.iterations,
            note=f"{res.steps} steps",
            analyse_count=res.stats.analyse_count,
        )
    factors = [0.1 * k for k in range(1, 11)]
    t, _, res = repeat(lambda: continuation(net, loads, factors), 1 if quick else 3)
    add(
        "analysis (10 load steps)",
        "one Workspace (continuation)",
        True,
        t,
        res[-1].x,
        sum(r.iterations for r in res),
    )

    def separate():
        x = None
        out = []
        for f in factors:
            out.append(solve_static(net, loads, factor=f, x0=x))
            x = out[-1].x
        return out

    t, _, res = repeat(separate, 1 if quick else 3)
    add(
        "analysis (10 load steps)",
        "a new Workspace per step",
        False,
        t,
        res[-1].x,
        sum(r.iterations for r in res),
    )


def _mtype(net, loads, add, study, *, reps, quick, n):
    from catenet.errors import CatenetError
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import Workspace, solve_static

    names = {
        -2: "mtype -2 (symmetric indefinite)",
        2: "mtype 2 (SPD)",
        11: "mtype 11 (general, full matrix)",
    }
    default = getattr(Workspace(net).solver, "mtype", None)  # what catenet picks for this net
    spaces = {}
    for mtype in names:
        try:
            spaces[mtype] = Workspace(net, mtype=mtype)
        except Exception as exc:
            add(
                "mtype (static)",
                names[mtype],
                mtype == default,
                float("nan"),
                note=f"failed: {exc!r}",
            )
            study.findings.append(f"mtype {mtype}: Workspace(net, mtype={mtype}) fails: {exc!r}")
    for label in ("mtype (static)", "mtype (dynamic)"):
        fns = {}
        for mtype, ws in spaces.items():
            if label.endswith("(static)"):
                fns[mtype] = lambda ws=ws: solve_static(net, loads, workspace=ws)
            else:
                fns[mtype] = lambda ws=ws: solve_dynamic(
                    net, loads, dt=1e-2, damping=1.0, t_end=0.2, workspace=ws
                )
            try:  # a failing type is reported, not timed
                fns[mtype]()
            except CatenetError as exc:
                del fns[mtype]
                add(label, names[mtype], mtype == default, float("nan"), note=f"failed: {exc}")
                study.findings.append(f"{label} {names[mtype]}: {type(exc).__name__}: {exc}")
        for mtype, (t, _, res) in interleaved(fns, reps).items():
            ws = spaces[mtype]
            add(
                label,
                names[mtype],
                mtype == default,
                t,
                res.x if label.endswith("(static)") else None,
                res.iterations,
                factorize_seconds=res.stats.factorize_seconds,
                solve_seconds=res.stats.solve_seconds,
                upper=ws.system.upper,
                factor_nnz=getattr(ws.solver, "factor_nnz", None),
            )


def _refinement(net, loads, add, study, *, reps, quick, n):
    """PARDISO's iterative refinement (iparm[7]) after every solve: catenet's setting
    against none (catenet checks the backward error of every solve anyway)."""
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.linear import PardisoSolver
    from catenet.solver.static import Workspace, solve_static

    probe = Workspace(net)
    if not isinstance(probe.solver, PardisoSolver):
        return
    default_steps = int(probe.solver.iparm[7])
    variants = list(dict.fromkeys((default_steps, 0, 1)))

    def fresh(steps):
        ws = Workspace(net)
        ws.solver.iparm[7] = steps
        return ws

    static = {s: (lambda s=s: solve_static(net, loads, workspace=fresh(s))) for s in variants}
    dyn_ws = {s: fresh(s) for s in variants}
    dynamic = {
        s: (
            lambda s=s: solve_dynamic(
                net, loads, dt=1e-2, damping=1.0, t_end=0.2, workspace=dyn_ws[s]
            )
        )
        for s in variants
    }
    for label, fns in (("refinement (static)", static), ("refinement (dynamic)", dynamic)):
        for s, (t, _, res) in interleaved(fns, reps).items():
            add(
                label,
                f"iparm[8] = {s} refinement steps",
                s == default_steps,
                t,
                res.x if label.endswith("(static)") else None,
                res.iterations,
                factorize_seconds=res.stats.factorize_seconds,
                solve_seconds=res.stats.solve_seconds,
            )


_THREADS_CHILD = r"""
import json, sys, time, statistics
from benchmarks.common import paper_net, warm_up, load_average
mode = sys.argv[2]
if mode == "catenet-threads-1":
    from catenet.solver.threads import set_threads
    set_threads(1)
from catenet.solver.static import Workspace, solve_static
from catenet.solver.dynamic import solve_dynamic
warm_up()
sq, loads = paper_net(int(sys.argv[3]))
ws = Workspace(sq.net)
def t(fn, k):
    fn(); out = []
    for _ in range(k):
        s = time.perf_counter(); fn(); out.append(time.perf_counter() - s)
    return statistics.median(out)
static = t(lambda: solve_static(sq.net, loads, workspace=ws), 5)
out = {"static": static, "load": load_average()}
if not QUICK:
    out["dynamic"] = t(lambda: solve_dynamic(sq.net, loads, dt=1e-3, damping=1.0, t_end=0.03,
                                             workspace=ws), 3)
json.dump(out, open(sys.argv[1], "w"))
"""


def _threads(net, loads, add, study, *, reps, quick, n):
    variants = [
        ("BLAS/MKL threads as installed (all cores)", True, None, "default"),
        ("catenet set_threads(1) (MKL, Numba)", False, None, "catenet-threads-1"),
        ("one thread everywhere (OPENBLAS/MKL_NUM_THREADS=1)", False, 1, "default"),
    ]
    for name, default, env_threads, mode in variants:
        code = (
            _THREADS_CHILD.replace("mode = sys.argv[2]", f"mode = {mode!r}")
            .replace("int(sys.argv[3])", str(n))
            .replace("QUICK", str(bool(quick)))
        )
        out = run_child(code, timeout=600, env=thread_env(env_threads))
        if "error" in out:
            add("threads (static)", name, default, float("nan"), note=f"failed: {out['error']}")
            continue
        note = f"load average {out['load']:.1f}"
        add("threads (static)", name, default, out["static"], note=note)
        if "dynamic" in out:
            add("threads (dynamic, 30 steps)", name, default, out["dynamic"], note=note)
    study.summary.append(
        f"threads measured at load average {load_average():.1f} (other processes share the cores)"
    )


def figure(rows, out_dir):
    import math

    plt = pyplot()
    skips = list(dict.fromkeys(r["skip"] for r in rows))
    fig, ax = plt.subplots(figsize=(10, 0.24 * len(rows) + 1.0))
    labels, values, colors = [], [], []
    for s in skips:
        for r in (r for r in rows if r["skip"] == s):
            labels.append(f"{s}: {r['variant']}")
            v = r["ratio_to_default"]
            values.append(v if isinstance(v, float) and math.isfinite(v) else 0.0)
            colors.append("tab:blue" if r["default"] else "tab:orange")
    y = range(len(labels))
    ax.barh(list(y), values, color=colors)
    ax.set_yticks(list(y), labels, fontsize=7)
    ax.invert_yaxis()
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("wall time / catenet's default (blue)")
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
