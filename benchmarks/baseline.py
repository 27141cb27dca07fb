"""Baseline comparison: catenet against a plain NumPy/SciPy/pypardiso implementation.

THE BASELINE (``baseline_static``) is what a careful first implementation of the same
model looks like without catenet's engineering: per-edge gradient and Hessian vectorised
in NumPy, the matrix assembled every Newton iteration with
``scipy.sparse.coo_matrix(...).tocsr()``, and ``pypardiso.spsolve`` for every Newton step
(which re-runs PARDISO's symbolic analysis whenever the matrix changes). It uses the same
regularised Newton idea as catenet (Levenberg-Marquardt shift c D, Armijo backtracking on
the potential, c shrinking after full steps) and the same convergence test, so both stop
at the same equilibrium; the study checks that they do.

The study times, on the paper's nets (alpha = 0, p = 100 Pa, 1 cm edges):
catenet with PARDISO (a first solve building its Workspace, and a solve reusing one),
catenet with SciPy's SuperLU (``linear="scipy"``), the baseline, and, where openseespy
imports, OpenSees with corotTruss elements (in a child process).
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/baseline.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import json
import logging

from benchmarks.common import (
    Study,
    interleaved,
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

NAME = "baseline"
TITLE = "catenet against a plain NumPy/SciPy implementation (and OpenSees)"

ARMIJO = 1e-4


# --- THE BASELINE: plain NumPy + SciPy + pypardiso ------------------------------------------


def baseline_static(
    nodes,
    edges,
    rest_length,
    EA,
    fixed,
    force,
    *,
    tension_only=True,
    rtol=1e-8,
    max_iter=200,
    solver="pypardiso",
):
    """Static equilibrium by regularised Newton, in plain NumPy (the baseline).

    nodes (N, 3), edges (M, 2), rest_length (M,), EA (M,), fixed (N,) bool, force (N, 3).
    ``solver``: "pypardiso" (``pypardiso.spsolve``) or "scipy" (``scipy.sparse.linalg.
    spsolve``). Returns (x (N, 3), info dict: iterations, residual, converged, seconds per
    phase).
    """
    import time
    import warnings

    import numpy as np
    import scipy.sparse as sp

    if solver == "pypardiso":
        import pypardiso

        spsolve = pypardiso.spsolve
    else:
        from scipy.sparse.linalg import spsolve

    x = np.array(nodes, dtype=float)
    edges = np.asarray(edges)
    i, j = edges[:, 0], edges[:, 1]
    l0 = np.asarray(rest_length, float)
    EA = np.asarray(EA, float)
    fixed = np.asarray(fixed, bool)
    n = len(x)
    free = np.repeat(~fixed, 3)
    f = np.asarray(force, float).reshape(-1)
    f_free = f[free]
    f_norm = float(np.linalg.norm(f))
    # The reduced numbering of the free DOFs and the (M, 6) DOFs of every edge.
    red = np.full(3 * n, -1)
    red[free] = np.arange(int(free.sum()))
    dofs = np.concatenate([3 * i[:, None] + np.arange(3), 3 * j[:, None] + np.arange(3)], 1)
    rows = np.repeat(red[dofs], 6, axis=1).ravel()
    cols = np.tile(red[dofs], (1, 6)).ravel()
    keep = (rows >= 0) & (cols >= 0)
    rows, cols = rows[keep], cols[keep]
    nf = int(free.sum())
    D = np.zeros(n)
    np.add.at(D, i, 0.5 * EA / l0)
    np.add.at(D, j, 0.5 * EA / l0)
    D = np.repeat(D[~fixed], 3)
    seconds = {"assembly": 0.0, "solve": 0.0}

    def energy_grad(x):
        e = x[j] - x[i]
        length = np.sqrt(np.einsum("ij,ij->i", e, e))
        eps = length / l0 - 1.0
        if tension_only:
            eps = np.where(eps > 0.0, eps, 0.0)
        energy = 0.5 * float(np.sum(EA * eps**2 * l0))
        fe = (EA * eps / length)[:, None] * e
        g = np.zeros((n, 3))
        np.add.at(g, j, fe)
        np.add.at(g, i, -fe)
        g = g.reshape(-1)
        phi = energy - float(f @ x.reshape(-1))
        scale = max(f_norm, float(np.linalg.norm(g)))
        return phi, g[free] - f_free, scale

    def hessian(x, c):
        e = x[j] - x[i]
        length = np.sqrt(np.einsum("ij,ij->i", e, e))
        eps = length / l0 - 1.0
        t = e / length[:, None]
        tt = t[:, :, None] * t[:, None, :]
        axial = EA / l0
        geom = EA * eps / length
        if tension_only:
            slack = eps <= 0.0
            axial = np.where(slack, 0.0, axial)
            geom = np.where(slack, 0.0, geom)
        h = (axial - geom)[:, None, None] * tt + geom[:, None, None] * np.eye(3)
        block = np.block([[h, -h], [-h, h]])  # (M, 6, 6)
        vals = block.reshape(len(l0), 36).ravel()[keep]
        a = sp.coo_matrix((vals, (rows, cols)), shape=(nf, nf)).tocsr()
        if c > 0:
            a = a + sp.diags(c * D, format="csr")
        return a

    def c_start(g):
        return float(min(max(np.max(np.abs(g) / (D * 0.1 * np.min(l0))), 1e-11), 1e12))

    phi, g, scale = energy_grad(x)
    gnorm = float(np.linalg.norm(g))
    tol = rtol * scale
    c = 0.0
    it = 0
    y = x.reshape(-1)
    while gnorm > tol and it < max_iter:
        it += 1
        while True:
            t0 = time.perf_counter()
            a = hessian(x, c)
            t1 = time.perf_counter()
            try:
                with warnings.catch_warnings():  # SciPy warns of a singular matrix
                    warnings.simplefilter("ignore")
                    dy = spsolve(a, -g)
                ok = bool(np.all(np.isfinite(dy))) and float(g @ dy) < 0
            except Exception:  # a singular matrix: raise the regularisation
                ok = False
            seconds["assembly"] += t1 - t0
            seconds["solve"] += time.perf_counter() - t1
            if ok:
                break
            c = max(10.0 * c, c_start(g))
        slope = float(g @ dy)
        y0 = y[free].copy()
        alpha = 1.0
        for _ in range(30):  # backtracking (Armijo)
            y[free] = y0 + alpha * dy
            phi_t, g_t, scale_t = energy_grad(x)
            if phi_t <= phi + ARMIJO * alpha * slope:
                break
            alpha *= 0.5
        else:  # no decrease along dy (a singular matrix gave a useless step): raise c
            y[free] = y0
            c = max(10.0 * c, c_start(g))
            continue
        # A full step along which Phi still falls steeply (a slack net falling freely,
        # held back only by c D) is lengthened fourfold at a time while Phi decreases.
        while alpha >= 1.0 and float(g_t @ dy) < 0.9 * slope and alpha < 1e6:
            y[free] = y0 + 4.0 * alpha * dy
            trial = energy_grad(x)
            if not trial[0] < phi_t:
                y[free] = y0 + alpha * dy
                break
            alpha *= 4.0
            phi_t, g_t, scale_t = trial
        phi, g, scale = phi_t, g_t, scale_t
        gnorm = float(np.linalg.norm(g))
        tol = rtol * scale
        if alpha > 1.0:
            c = c / (2.0 * alpha)
        elif alpha == 1.0:
            c = 0.5 * c
        elif alpha < 0.25:
            c = max(4.0 * c, c_start(g) if c == 0.0 else 0.0)
        if c < 1e-12:
            c = 0.0
        log.debug("baseline %3d: |r| = %.3e  step %.3g  c = %.3g", it, gnorm, alpha, c)
    info = {
        "iterations": it,
        "residual": gnorm,
        "converged": gnorm <= tol,
        "assembly_seconds": seconds["assembly"],
        "solve_seconds": seconds["solve"],
    }
    return x, info


# --- OpenSees (child process) ---------------------------------------------------------------

_OPENSEES_CHILD = r"""
import ctypes, json, os, sys, time, importlib.util
import numpy as np
out = {}
try:
    spec = importlib.util.find_spec("openseespylinux")
    if spec is not None:  # its wheel does not find its own libblas.so.3: load it first
        lib = os.path.join(spec.submodule_search_locations[0], "lib", "libblas.so.3")
        if os.path.exists(lib):
            ctypes.CDLL(lib, mode=ctypes.RTLD_GLOBAL)
    import openseespy.opensees as ops
except Exception as exc:
    out["error"] = f"openseespy does not import: {exc}"
    json.dump(out, open(sys.argv[1], "w")); sys.exit(0)
d = json.load(open(os.environ["CATENET_BENCH_NET"]))
nodes = np.array(d["nodes"]); edges = np.array(d["edges"]); fixed = np.array(d["fixed"])
force = np.array(d["force"]); EA = d["EA"]; pre = d["prestrain"]; steps = d["steps"]
start = time.perf_counter()
ops.wipe(); ops.model("basic", "-ndm", 3, "-ndf", 3)
for k, p in enumerate(nodes):
    ops.node(k + 1, *p)
for k in np.flatnonzero(fixed):
    ops.fix(int(k) + 1, 1, 1, 1)
ops.uniaxialMaterial("Elastic", 1, EA, 0.0, 0.0)       # E = EA, no compression (Eneg = 0)
ops.uniaxialMaterial("InitStrainMaterial", 2, 1, pre)  # a small pretension
for k, (a, b) in enumerate(edges):
    ops.element("corotTruss", k + 1, int(a) + 1, int(b) + 1, 1.0, 2)
ops.timeSeries("Linear", 1); ops.pattern("Plain", 1, 1)
for k in np.flatnonzero(np.any(force != 0, axis=1)):
    ops.load(int(k) + 1, *force[k])
ops.constraints("Plain"); ops.numberer("RCM"); ops.system(d["system"])
ops.test("NormUnbalance", d["tol"], 100); ops.algorithm(*d["algorithm"])
ops.integrator("LoadControl", 1.0 / steps); ops.analysis("Static")
build = time.perf_counter() - start
ok = 0
iterations = 0
for s in range(steps):
    ok = ops.analyze(1)
    iterations += ops.testIter()
    if ok != 0:
        break
wall = time.perf_counter() - start
x = np.array([ops.nodeCoord(k + 1) for k in range(len(nodes))]) + np.array(
    [ops.nodeDisp(k + 1) for k in range(len(nodes))])
out.update(ok=int(ok), seconds=wall, iterations=iterations, build_seconds=build, x=x.tolist(),
           version=ops.version() if hasattr(ops, "version") else "")
json.dump(out, open(sys.argv[1], "w"))
"""


def opensees_static(
    net,
    force,
    *,
    prestrain=1e-4,
    steps=10,
    tol=None,
    system="UmfPack",
    algorithm=("Newton",),
    timeout=600.0,
) -> dict:
    """The net as OpenSees corotTruss elements (tension-only elastic material with a small
    pretension ``prestrain``, which a flat net needs for a regular first stiffness), under
    ``force`` in ``steps`` load increments, Newton with a NormUnbalance test. Runs in a
    child process. Returns seconds and x, or ``error``."""
    import os
    import tempfile

    import numpy as np

    tol = float(1e-8 * np.linalg.norm(force)) if tol is None else tol
    data = {
        "nodes": net.nodes.tolist(),
        "edges": net.edges.tolist(),
        "fixed": net.fixed.tolist(),
        "force": np.asarray(force).tolist(),
        "EA": float(net.EA[0]),
        "prestrain": prestrain,
        "steps": steps,
        "tol": tol,
        "system": system,
        "algorithm": list(algorithm),
    }
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(data, fh)
        path = fh.name
    try:
        env = thread_env(1)
        env["CATENET_BENCH_NET"] = path
        return run_child(_OPENSEES_CHILD, timeout=timeout, env=env)
    finally:
        os.unlink(path)


# --- the study ------------------------------------------------------------------------------


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    set_threads(threads)
    warm_up()
    nets = (10, 34) if quick else (10, 22, 34)
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    for k, n in enumerate(nets):
        progress(k, len(nets), f"n = {n}")
        compare(n, rows, study, quick=quick)
    progress(len(nets), len(nets), "")
    for n in nets:
        sel = {r["method"]: r for r in rows if r["n"] == n}
        base = sel["catenet (pardiso)"]
        for r in rows:
            if r["n"] == n:
                r["ratio_to_catenet"] = r["seconds"] / base["seconds"]
                r["ratio_per_iteration"] = (r["seconds"] / max(r["iterations"], 1)) / (
                    base["seconds"] / max(base["iterations"], 1)
                )
    tabulate(study, out_dir, figure, _line)
    for r in rows:
        # Prestrained rows compare other nets (their error is against catenet on the same
        # pretensioned net, or against the unprestrained one): not a finding.
        if r["max_error_rel"] > 1e-5 and "prestrain" not in r["method"]:
            study.findings.append(
                f"{r['method']} on n = {r['n']}: equilibrium differs from catenet's by "
                f"{r['max_error_rel']:.1e} of delta"
            )
    return study


def _line(r: dict) -> str:
    return (
        f"n = {r['n']:2d}  {r['method']:<50s} {r['seconds']:8.3f} s  "
        f"x{r['ratio_to_catenet']:6.1f}  {r['iterations']:3d} it  "
        f"error {r['max_error_rel']:.1e}"
    )


def compare(n: int, rows: list, study: Study, *, quick: bool) -> None:
    """Every method on the paper's net with ``n`` cables; one row each."""
    import numpy as np

    from catenet.solver.static import Workspace, solve_static

    repeats = 3 if quick else 7
    few = 2 if quick else 3
    sq, loads = paper_net(n)
    net = sq.net
    f = loads.external_force(net)
    ref = solve_static(net, loads, rtol=1e-10)
    scale = -float(ref.x[sq.center, 2])

    def row(method, seconds, x, iterations, times=(), reference=ref.x, **extra):
        err = float(np.max(np.abs(x - reference))) / scale
        rows.append(
            {
                "n": n,
                "dofs": 3 * int((~net.fixed).sum()),
                "method": method,
                "seconds": seconds,
                "iterations": iterations,
                "max_error_rel": err,
                "repeats": len(times),
                "seconds_min": min(times) if times else seconds,
                **extra,
            }
        )

    def split(res):
        s = res.stats.as_dict()
        return {
            k: s[k]
            for k in (
                "setup_seconds",
                "assembly_seconds",
                "analyse_seconds",
                "factorize_seconds",
                "solve_seconds",
            )
            if k in s
        }

    args = (net.nodes, net.edges, net.rest_length, net.EA, net.fixed, f)
    ws = Workspace(net)
    # The headline comparison, timed in turn (A B C A B C ...) so that a change in the
    # machine's load hits every variant alike.
    fns = {
        "catenet (pardiso)": lambda: solve_static(net, loads),
        "catenet (pardiso, reused Workspace)": lambda: solve_static(net, loads, workspace=ws),
        "baseline numpy+pypardiso": lambda: baseline_static(*args),
    }
    main = interleaved(fns, repeats)
    for method, (t, times, res) in main.items():
        if method.startswith("baseline"):
            x, info = res
            row(
                method,
                t,
                x,
                info["iterations"],
                times,
                assembly_seconds=info["assembly_seconds"],
                solve_seconds=info["solve_seconds"],
            )
        else:
            row(method, t, res.x, res.iterations, times, **split(res))
    t, times, res = repeat(lambda: solve_static(net, loads, linear="scipy"), few)
    row("catenet (scipy)", t, res.x, res.iterations, times, **split(res))
    if not quick:
        t, times, (x, info) = repeat(lambda: baseline_static(*args, solver="scipy"), few)
        row(
            "baseline numpy+scipy",
            t,
            x,
            info["iterations"],
            times,
            assembly_seconds=info["assembly_seconds"],
            solve_seconds=info["solve_seconds"],
        )
    if n == 34 and not quick:
        opensees_rows(net, loads, f, scale, row, study)


def opensees_rows(net, loads, f, scale, row, study) -> None:
    """OpenSees on the same net, with the pretension it needs, against catenet on the
    same pretensioned net (rest lengths / (1 + prestrain))."""
    from catenet.solver.static import solve_static

    pre = 1e-4
    # The first configuration that converged on this net (Newton with 10 load steps, or
    # SparseSYM, fail: the first linearised step of a lightly pretensioned flat net
    # overshoots by an order of magnitude).
    out = opensees_static(net, f, prestrain=pre, steps=20, algorithm=("NewtonLineSearch",))
    if "error" in out or out.get("ok", 1) != 0:
        why = out.get("error") or f"analyze returned {out.get('ok')}"
        study.findings.append(f"OpenSees: no result ({why})")
        log.warning("OpenSees: %s", why)
        return
    import numpy as np

    pre_net = net.with_rest_length(net.rest_length / (1.0 + pre))
    t, times, res = repeat(lambda: solve_static(pre_net, loads), 3)
    row("catenet (pardiso), prestrain 1e-4", t, res.x, res.iterations, times)
    row(
        f"OpenSees {out.get('version', '')} corotTruss, prestrain 1e-4, 20 load steps",
        out["seconds"],
        np.array(out["x"]),
        out.get("iterations", 0),
        (out["seconds"],),
        reference=res.x,
        build_seconds=out["build_seconds"],
    )


def figure(rows, out_dir):
    plt = pyplot()
    nets = sorted({r["n"] for r in rows})
    methods = list(dict.fromkeys(r["method"] for r in rows))
    fig, ax = plt.subplots(figsize=(9, 4))
    width = 0.8 / len(methods)
    for m_i, m in enumerate(methods):
        xs, ys = [], []
        for n_i, n in enumerate(nets):
            sel = [r for r in rows if r["n"] == n and r["method"] == m]
            if sel:
                xs.append(n_i + (m_i - (len(methods) - 1) / 2) * width)
                ys.append(sel[0]["seconds"])
        ax.bar(xs, ys, width, label=m)
    ax.set_yscale("log")
    ax.set_xticks(range(len(nets)), [f"n = {n}" for n in nets])
    ax.set_ylabel("static solve, wall time [s]")
    ax.set_title("paper's net, alpha = 0, p = 100 Pa, 1 cm edges")
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
