"""Numerical-stability stress test: hard scenes, each checked against what is right.

Every scene must end in one of two ways: a converged answer that passes its check, or a
clear catenet error (``CatenetError``) where that is the right answer. Anything else (a
non-catenet exception, a NaN in a result, a check that fails) is a finding. Checks:

- ``eq17``: cable under a midpoint load against Eq. 17 (``catenet.analytic``), exact for
  the discrete model; relative error of delta.
- ``chain``: cable under self-weight against the exact discrete chain
  (``catenet.analytic.discrete_catenary``, the same model solved in closed form).
- ``equilibrium``: residual at the free nodes and the balance of reactions and applied
  loads, relative to the load scale, recomputed here from the returned state.
- ``static = dynamic``: the dynamic run's final equilibrium against the static one.
- ``bounded``: a dynamic run stopped long before equilibrium stays finite and bounded.

``scenes(quick)`` lists them (the quick subset runs in ``tests/test_stress.py``);
``run_scene`` runs one and returns its row.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from catenet.bench.common import (
    Study,
    compressed_catenary,
    midpoint_cable,
    no_progress,
    paper_material,
    pyplot,
    save_figure,
    set_threads,
    warm_up,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "stress"
TITLE = "Numerical-stability stress test"

SLOW_SECONDS = 10.0  # a scene slower than this is reported
EQ_TOL = 1e-6  # relative residual / reaction balance of a converged state


@dataclass(frozen=True)
class Scene:
    """One hard scene. ``fn(**params)`` returns a dict with ``results`` (list of Result),
    ``check``, ``value``, ``tol`` and optionally ``note``. ``errors_ok``: catenet error
    classes (names) that are a right answer here."""

    id: str
    group: str
    fn: Callable[..., dict]
    params: dict = field(default_factory=dict)
    quick: bool = True
    errors_ok: tuple[str, ...] = ()


# --- checks ---------------------------------------------------------------------------------


def equilibrium_error(net, loads, res, factor: float = 1.0) -> float:
    """max(|residual at free nodes|, |sum reactions + sum loads|) / load scale, from the
    returned positions and reactions."""
    import numpy as np

    from catenet.assembly import System

    system = System(net)
    _, g = system.gradient(res.x)
    f = loads.external_force(net, factor)
    free = ~net.fixed
    residual = float(np.linalg.norm(g[free] - f[free]))
    balance = float(np.linalg.norm(res.reaction.sum(axis=0) + f.sum(axis=0)))
    # Round-off of the internal forces: an error eps |x| in the coordinates makes a force
    # error EA eps |x| / l0 at each end of every edge (as in catenet.newton).
    k_norm = float(np.sqrt(2.0 * np.sum((net.EA / net.rest_length) ** 2)))
    roundoff = 1e2 * np.finfo(float).eps * k_norm * float(np.max(np.abs(res.x)))
    if max(residual, balance) <= roundoff:
        return 0.0
    scale = max(float(np.linalg.norm(f)), float(np.linalg.norm(g)), 1e-300)
    return max(residual, balance) / scale


def finite(res) -> bool:
    import numpy as np

    arrays = [res.x, res.tension, res.reaction] + ([res.v] if res.v is not None else [])
    scalars = [res.residual]
    return all(bool(np.all(np.isfinite(a))) for a in arrays) and all(
        math.isfinite(s) for s in scalars
    )


def _eq_row(check, value, tol, results, net, loads, note="", factor=1.0):
    """A row whose answer must also be an equilibrium (when the solver says so)."""
    eq = max(
        (equilibrium_error(net, loads, r, factor) for r in results if r.equilibrium), default=0.0
    )
    return {
        "results": results,
        "check": check,
        "value": value,
        "tol": tol,
        "equilibrium_error": eq,
        "note": note,
    }


# --- scenes ---------------------------------------------------------------------------------


def midpoint_load(
    F_bar: float | None = None,
    F: float | None = None,
    EA: float | None = None,
    nodes: int = 21,
    method: str = "static",
    h: float = 1e-2,
    damping: float = 1.0,
    steps: int | None = None,
    budget: float = 10.0,
):
    """Cable (L = 1) under a midpoint load, against Eq. 17."""
    from catenet import analytic
    from catenet.dynamic import solve_dynamic
    from catenet.static import solve_static

    EA = paper_material().EA if EA is None else EA
    F = F_bar * EA if F is None else F
    net, loads, mid = midpoint_cable(F, nodes=nodes, EA=EA)
    exact = analytic.midpoint_load_deflection(F, 1.0, EA)
    if method == "static":
        res = solve_static(net, loads)
    else:
        start = time.perf_counter()
        t_end = steps * h if steps else 1e6 * h

        def stop(step, t, x, v):
            return time.perf_counter() - start > budget

        res = solve_dynamic(net, loads, dt=h, damping=damping, t_end=t_end, on_step=stop)
    delta = -float(res.x[mid, 2])
    strain = res.max_strain
    if method == "dynamic" and not res.equilibrium:
        # Stopped before equilibrium (few steps of a tiny h, or capped): bounded motion.
        ok_bound = 0.0 <= delta <= 2.5 * exact or abs(delta) < 1e-12
        return _eq_row(
            "bounded",
            0.0 if ok_bound else delta / exact,
            1.0,
            [res],
            net,
            loads,
            note=f"{res.steps} steps to t = {res.time:.3g} s, {res.message}",
        )
    err = abs(delta - exact) / exact
    return _eq_row(
        "eq17", err, 1e-6, [res], net, loads, note=f"delta/L = {delta:.4g}, max strain {strain:.3g}"
    )


def self_weight(
    dL: float = 0.0,
    nodes: int = 101,
    EA: float | None = None,
    method: str = "static",
    h: float = 1e-2,
    ramp: float = 1.0,
    tension_only: bool = True,
    budget: float = 20.0,
):
    """Cable of length 1 under its own weight, supports moved inward by dL (0: a straight
    zero-slack cable), against the exact discrete chain."""
    from catenet import analytic
    from catenet.dynamic import solve_dynamic
    from catenet.static import solve_static

    net, loads = compressed_catenary(
        dL, nodes=nodes, EA=EA, tension_only=tension_only, ramp=ramp if method == "dynamic" else 0.0
    )
    EA_ = float(net.EA[0])
    w = float(net.line_density[0]) * 9.81
    exact = analytic.discrete_catenary(1.0, EA_, w, 1.0 - dL, nodes - 1).sag
    if method == "static":
        res = solve_static(net, loads)
    else:
        start = time.perf_counter()

        def stop(step, t, x, v):
            return time.perf_counter() - start > budget

        res = solve_dynamic(net, loads, dt=h, damping=1.0, t_end=1e4, on_step=stop)
        if not res.equilibrium:
            return _eq_row(
                "chain",
                math.inf,
                1e-6,
                [res],
                net,
                loads,
                note=f"no equilibrium within {budget:g} s wall ({res.steps} steps, "
                f"t = {res.time:.3g} s)",
            )
    mid = (nodes - 1) // 2
    sag = -float(res.x[mid, 2])
    return _eq_row(
        "chain",
        abs(sag - exact) / exact,
        1e-6,
        [res],
        net,
        loads,
        note=f"sag {sag:.6g} m, chain {exact:.6g} m",
    )


def bilateral_compression(
    dL: float = 0.1,
    nodes: int = 21,
    gravity: bool = False,
    perturb: float = 0.0,
    method: str = "static",
):
    """A bilateral (tension_only=False) straight cable whose supports move inward by dL.

    Without a transverse load the straight, uniformly compressed state is an equilibrium,
    but an unstable one (its geometric stiffness is negative); with ``perturb`` the start is
    off the line. Right answers: a catenet error, or a state that is an equilibrium and not
    the unstable straight one (every edge back near its rest length: buckled), or, with
    gravity, the hanging chain. The straight compressed state returned as converged is
    reported (``unstable``) as a silent unstable answer unless the result flags it
    (``Result.stable is False``, with a warning), which is a right answer."""
    import numpy as np

    from catenet.dynamic import solve_dynamic
    from catenet.static import solve_static

    net, loads = compressed_catenary(
        dL, nodes=nodes, tension_only=False, ramp=0.5 if method == "dynamic" else 0.0
    )
    if not gravity:
        from catenet.net import Loads

        loads = Loads(support_displacement=loads.support_displacement, ramp_time=loads.ramp_time)
    x0 = None
    if perturb:
        rng = np.random.default_rng(0)
        x0 = net.nodes.copy()
        x0[1:-1, 2] += perturb * rng.standard_normal(nodes - 2)
    if method == "static":
        res = solve_static(net, loads, x0=x0)
    else:
        res = solve_dynamic(net, loads, dt=1e-2, damping=1.0, t_end=50.0, x0=x0)
    strain = res.tension / net.EA
    compressed = float(-np.min(strain))
    if gravity:
        from catenet import analytic

        w = float(net.line_density[0]) * 9.81
        exact = analytic.discrete_catenary(1.0, float(net.EA[0]), w, 1.0 - dL, nodes - 1).sag
        sag = -float(res.x[(nodes - 1) // 2, 2])
        return _eq_row(
            "chain",
            abs(sag - exact) / exact,
            1e-6,
            [res],
            net,
            loads,
            note=f"min strain {-compressed:.3g}",
        )
    straight = float(np.max(np.abs(res.x[:, 1:]))) < 1e-9
    flagged = getattr(res, "stable", None) is False
    value = 1.0 if (straight and compressed > 1e-6 and not flagged) else 0.0
    return _eq_row(
        "unstable",
        value,
        0.5,
        [res],
        net,
        loads,
        note=(
            "straight compressed state (unstable) returned as converged"
            if value
            else "straight compressed state, flagged unstable"
            if flagged and straight
            else f"buckled or relaxed: min strain {-compressed:.3g}"
        )
        + f"; {res.message}",
    )


def net_point_load(F: float = 5.0, n: int = 10, h: float = 0.05):
    """A point load on one off-centre node of the paper's net (alpha = 0, 1 cm edges):
    static and dynamic agree and both are equilibria. Cables away from the load stay
    unstressed (no stiffness across them)."""
    import numpy as np

    from catenet.dynamic import solve_dynamic
    from catenet.geometry import square_net
    from catenet.net import Loads
    from catenet.static import solve_static

    sq = square_net(n, 0.0, 1.0, 0.01, paper_material())
    net = sq.net
    target = np.array([0.23, 0.11, 0.0])
    node = int(np.argmin(np.linalg.norm(net.nodes - target, axis=1) + 1e9 * net.fixed))
    f = np.zeros((net.n_nodes, 3))
    f[node, 2] = -F
    loads = Loads(force=f)
    rs = solve_static(net, loads)
    rd = solve_dynamic(net, loads, dt=h, damping=1.0, t_end=200.0)
    scale = max(float(np.max(np.abs(rs.x - net.nodes))), 1e-300)
    diff = float(np.max(np.abs(rs.x - rd.x))) / scale if rd.equilibrium else math.inf
    return _eq_row(
        "static = dynamic",
        diff,
        1e-5,
        [rs, rd],
        net,
        loads,
        note=f"node {node}, dynamic: {rd.steps} steps, {rd.message}",
    )


def net_pressure(load_bar: float = 1e-3, n: int = 10, dynamic: bool = False):
    """The paper's net under p L^2 / EA = load_bar (1e-9 .. 0.5): equilibrium, and the
    dynamic relaxation agrees with the static solve."""
    import numpy as np

    from catenet.bench.common import paper_net
    from catenet.dynamic import solve_dynamic
    from catenet.static import solve_static

    EA = paper_material().EA
    sq, loads = paper_net(n, pressure=load_bar * EA)
    net = sq.net
    rs = solve_static(net, loads)
    results = [rs]
    diff = 0.0
    if dynamic:
        rd = solve_dynamic(net, loads, dt=0.1, damping=1.0, t_end=500.0)
        results.append(rd)
        scale = max(float(np.max(np.abs(rs.x - net.nodes))), 1e-300)
        diff = float(np.max(np.abs(rs.x - rd.x))) / scale if rd.equilibrium else math.inf
    return _eq_row(
        "static = dynamic" if dynamic else "equilibrium",
        diff,
        1e-5,
        results,
        net,
        loads,
        note=f"delta/L = {-rs.x[sq.center, 2]:.4g}, max strain {rs.max_strain:.3g}",
    )


def random_graph(
    seed: int = 0, n_nodes: int = 60, support_share: float = 0.15, dynamic: bool = True
):
    """A random planar net (Delaunay edges of random points, random heights) with random
    supports and random point loads plus gravity. Right answers: a ConfigError (a part
    without support), or static and dynamic equilibria that agree."""
    import numpy as np
    from scipy.spatial import Delaunay

    from catenet.dynamic import solve_dynamic
    from catenet.geometry import graph
    from catenet.net import Loads
    from catenet.static import solve_static

    rng = np.random.default_rng(seed)
    pts = rng.random((n_nodes, 2))
    tri = Delaunay(pts).simplices
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]]]), axis=1)
    edges = np.unique(e, axis=0)
    # Thin the triangulation at random so that some nodes hang on few edges.
    keep = rng.random(len(edges)) > 0.3
    edges = edges[keep]
    used = np.unique(edges)
    remap = -np.ones(n_nodes, int)
    remap[used] = np.arange(len(used))
    nodes = np.column_stack([pts[used], 0.05 * rng.random(len(used))])
    edges = remap[edges]
    k = max(1, int(support_share * len(nodes)))
    fixed = rng.choice(len(nodes), size=k, replace=False)
    net = graph(nodes, edges, fixed, paper_material())
    f = np.zeros((net.n_nodes, 3))
    loaded = rng.choice(np.flatnonzero(~net.fixed), size=3, replace=False)
    f[loaded] = rng.normal(0.0, 5.0, (3, 3))
    loads = Loads(force=f, gravity=np.array([0.0, 0.0, -9.81]))
    rs = solve_static(net, loads)
    results = [rs]
    diff = 0.0
    note = f"{net.n_nodes} nodes, {net.n_edges} edges, {k} supports"
    if dynamic:
        rd = solve_dynamic(net, loads, dt=0.05, damping=1.0, t_end=500.0)
        results.append(rd)
        scale = max(float(np.max(np.abs(rs.x - net.nodes))), 1e-300)
        diff = float(np.max(np.abs(rs.x - rd.x))) / scale if rd.equilibrium else math.inf
        note += f"; dynamic {rd.steps} steps, {rd.message}"
    return _eq_row(
        "static = dynamic" if dynamic else "equilibrium", diff, 1e-5, results, net, loads, note=note
    )


def scenes(quick: bool = False) -> list[Scene]:
    """The scene matrix; ``quick``: the subset the tests run (about a minute)."""
    out: list[Scene] = []

    def add(id_, group, fn, quick_=True, errors_ok=(), **params):
        out.append(Scene(id_, group, fn, params, quick_, tuple(errors_ok)))

    for fb in (1e-9, 1e-6, 1e-3, 1e-2, 0.1, 0.5):
        add(f"midpoint F/EA={fb:g}", "load range", midpoint_load, F_bar=fb)
    for ea in (1e-2, 1.0, 1e3, 1e6, 1e9):
        add(f"midpoint F=1N EA={ea:g}", "EA range", midpoint_load, F=1.0, EA=ea)
    for h in (1e-6, 1e-4, 1e-2, 1.0, 1e3):
        steps = 200 if h <= 1e-4 else None
        add(
            f"midpoint dynamic h={h:g}",
            "time step range",
            midpoint_load,
            F_bar=1e-2,
            method="dynamic",
            h=h,
            steps=steps,
            quick_=h >= 1e-4,
        )
    for mu in (0.0, 1e-2, 1.0, 1e2, 1e3):
        add(
            f"midpoint dynamic mu={mu:g}",
            "damping range",
            midpoint_load,
            F_bar=1e-2,
            method="dynamic",
            h=1e-2,
            damping=mu,
            quick_=mu in (0.0, 1e3),
        )
    add("zero-slack self-weight static", "self-weight", self_weight, dL=0.0)
    add("zero-slack self-weight EA=1e9", "self-weight", self_weight, dL=0.0, EA=1e9)
    add(
        "zero-slack self-weight dynamic",
        "self-weight",
        self_weight,
        dL=0.0,
        method="dynamic",
        h=1e-2,
        quick_=False,
    )
    add("supports inward L/2 static", "moved supports", self_weight, dL=0.5)
    add(
        "supports inward L/2 dynamic",
        "moved supports",
        self_weight,
        dL=0.5,
        method="dynamic",
        h=1e-2,
        ramp=1.0,
        quick_=False,
    )
    add("supports inward 0.9 L static", "moved supports", self_weight, dL=0.9)
    add(
        "supports inward 0.2 L dynamic h=0.1 ramp 0.5 s",
        "moved supports",
        self_weight,
        dL=0.2,
        method="dynamic",
        h=0.1,
        ramp=0.5,
    )
    add(
        "supports inward L/2 dynamic h=1e3 ramp 1 s",
        "moved supports",
        self_weight,
        dL=0.5,
        method="dynamic",
        h=1e3,
        ramp=1.0,
    )
    errs = ("ConvergenceError", "SingularSystemError")
    add("bilateral compressed, no load", "bilateral", bilateral_compression, errors_ok=errs)
    add(
        "bilateral compressed, perturbed start",
        "bilateral",
        bilateral_compression,
        perturb=1e-3,
        errors_ok=errs,
    )
    add(
        "bilateral compressed, dynamic",
        "bilateral",
        bilateral_compression,
        method="dynamic",
        perturb=1e-3,
        errors_ok=errs,
        quick_=False,
    )
    add("bilateral compressed, gravity", "bilateral", bilateral_compression, gravity=True)
    add("net point load", "net", net_point_load)
    add("net point load F=0.5 EA", "net", net_point_load, F=0.5 * paper_material().EA, quick_=False)
    for lb in (1e-9, 1e-3, 0.5):
        add(f"net p L^2/EA={lb:g}", "net", net_pressure, load_bar=lb, quick_=lb != 1e-3)
    add(
        "net p L^2/EA=1e-3 static=dynamic",
        "net",
        net_pressure,
        load_bar=1e-3,
        dynamic=True,
        quick_=False,
    )
    add("cable 1e5 edges", "size", midpoint_load, F_bar=1e-2, nodes=100_001)
    for seed in range(6):
        add(
            f"random graph seed={seed}",
            "random graphs",
            random_graph,
            seed=seed,
            errors_ok=("ConfigError",),
            quick_=seed < 3,
        )
    return [s for s in out if s.quick] if quick else out


def run_scene(scene: Scene) -> dict:
    """Runs one scene; never raises. ``passed``: a right answer (see the module doc)."""
    from catenet.errors import CatenetError

    row = {
        "id": scene.id,
        "group": scene.group,
        "params": ", ".join(f"{k}={v}" for k, v in scene.params.items()),
    }
    start = time.perf_counter()
    try:
        out = scene.fn(**scene.params)
    except CatenetError as exc:
        name = type(exc).__name__
        row.update(
            status=f"error: {name}",
            passed=name in scene.errors_ok,
            message=str(exc).splitlines()[0][:300],
            iterations=getattr(exc, "iterations", None),
            history=_history(getattr(exc, "history", [])),
        )
    except Exception as exc:  # not a catenet error: always a finding
        log.warning("stress %s: %r", scene.id, exc)
        row.update(
            status=f"BUG: {type(exc).__name__}",
            passed=False,
            message=f"{type(exc).__name__}: {exc}"[:300],
        )
    else:
        results = out["results"]
        ok_finite = all(finite(r) for r in results)
        converged = all(r.converged for r in results)
        value, tol = out["value"], out["tol"]
        eq = out.get("equilibrium_error", 0.0)
        check_ok = math.isfinite(value) and value <= tol
        passed = ok_finite and check_ok and eq <= EQ_TOL
        status = "converged" if converged else "not converged"
        if not ok_finite:
            status = "NaN in result"
        row.update(
            status=status,
            passed=passed,
            check=out["check"],
            value=value,
            tol=tol,
            equilibrium_error=eq,
            iterations=sum(r.iterations for r in results),
            steps=sum(r.steps for r in results),
            message=out.get("note", ""),
            history=_history(results[0].history),
        )
    row["seconds"] = time.perf_counter() - start
    row["slow"] = row["seconds"] > SLOW_SECONDS
    return row


def _history(history) -> str:
    h = list(history)
    if len(h) > 8:
        h = h[:3] + ["..."] + h[-4:]
    return " ".join(x if isinstance(x, str) else f"{x:.2e}" for x in h)


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    set_threads(threads)
    warm_up()
    todo = scenes(quick)
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    for k, scene in enumerate(todo):
        progress(k, len(todo), scene.id)
        rows.append(run_scene(scene))
    progress(len(todo), len(todo), "")
    write_csv(rows, study.csv)
    study.figure = figure(rows, out_dir)
    for r in rows:
        flag = "ok  " if r["passed"] else "FAIL"
        study.summary.append(
            f"{flag} {r['id']:<40s} {r['status']:<28s} {r.get('check', ''):<16s} "
            f"{_num(r.get('value'))} it {r.get('iterations')}  {r['seconds']:.2f} s"
        )
        if not r["passed"]:
            study.findings.append(
                f"stress {r['id']} ({r['params']}): {r['status']}; check {r.get('check')} = "
                f"{_num(r.get('value'))} (tol {_num(r.get('tol'))}), equilibrium error "
                f"{_num(r.get('equilibrium_error'))}; {r.get('message', '')}; "
                f"Newton history: {r.get('history', '')}"
            )
        elif r["slow"]:
            study.findings.append(f"stress {r['id']}: slow ({r['seconds']:.1f} s)")
    return study


def _num(v) -> str:
    return f"{v:.2e}" if isinstance(v, float) else str(v)


def figure(rows, out_dir):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 0.28 * len(rows) + 1.2))
    y = list(range(len(rows)))
    colors = ["tab:green" if r["passed"] else "tab:red" for r in rows]
    ax.barh(y, [max(r["seconds"], 1e-3) for r in rows], color=colors)
    ax.set_yticks(y, [f"{r['id']} [{r['status']}]" for r in rows], fontsize=6)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("wall time [s] (green: right answer, red: finding)")
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)
