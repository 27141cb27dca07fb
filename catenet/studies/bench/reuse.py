"""Factorisation reuse (modified Newton) in dynamic runs, and the cost of an idle obstacle.

Three scenes, each run with ``reuse=True`` (the default: Newton keeps its factorisation
across iterations and time steps while it converges fast enough) and ``reuse=False`` (a
fresh factorisation every Newton iteration), interleaved in one process:

- relax: the paper's dynamic relaxation of the n = 34 net at alpha = pi/4 under 100 Pa
  (configs/fig4i_n34_alpha_pi4.toml with solver.method = "dynamic": h = 0.01 s, mu = 1/s)
  to equilibrium;
- contact: the same net (n = 34, edge 1 cm, about 1e4 DOF) under its weight and 300 Pa
  falling onto a sphere below its centre, h = 1 ms for STEPS steps (it touches, presses
  in and swings);
- idle: the relax run with a sphere far below the net (never touched) against the same
  run without it: what an obstacle costs while it is not in contact.

Reported: median wall times, the speed-up, factorisations and Newton iterations, and the
largest difference of the final states, relative to the largest displacement.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from catenet.studies.bench.common import (
    Study,
    interleaved,
    no_progress,
    paper_net,
    pyplot,
    save_figure,
    set_threads,
    warm_up,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "reuse"
TITLE = "Factorisation reuse in dynamic runs (modified Newton)"

STEPS = 1000  # contact scene: time steps of 1 ms
QUICK_STEPS = 200
TARGET = 3.0  # the speed-up issue 11 asks for
SAME = 1e-8  # the largest relative difference of the final states allowed
IDLE_COST = 0.10  # an untouched obstacle may cost this share of the run


def relax_scene():
    """(net, loads, solve_dynamic keywords): the paper's n = 34 net relaxed at h = 0.01 s."""
    sq, loads = paper_net(34, alpha=math.pi / 4)
    return sq.net, loads, {"dt": 1e-2, "damping": 1.0, "t_end": 10.0}


def contact_scene(steps: int = STEPS):
    """(net, loads, sphere, keywords): the n = 34 net, weight and 300 Pa, onto a sphere."""
    from catenet.geometry import pressure_force
    from catenet.net import Loads
    from catenet.terms.contact import Sphere, default_stiffness

    sq, _ = paper_net(34, alpha=0.3)
    net = sq.net
    loads = Loads(force=pressure_force(net, 300.0, 1.0), gravity=np.array([0.0, 0.0, -9.81]))
    free = np.flatnonzero(~net.fixed)
    per_node = 300.0 / free.size + float(np.max(net.mass)) * 9.81
    ball = Sphere(free, [0.0, 0.0, -0.23], 0.2, kappa=default_stiffness(per_node, 1e-2), dhat=1e-2)
    kw = {"dt": 1e-3, "damping": 5.0, "t_end": steps * 1e-3, "stop_at_equilibrium": False}
    return net, loads, ball, kw


def _runner(net, loads, kw, terms=(), **extra):
    from catenet.dynamic import solve_dynamic
    from catenet.static import Workspace

    def run():
        ws = Workspace(net, terms=terms)
        return solve_dynamic(net, loads, workspace=ws, **kw, **extra)

    return run


def _difference(a, b, x0) -> float:
    """max |a - b| over the largest displacement from x0."""
    scale = float(np.max(np.abs(a.x - x0)))
    return float(np.max(np.abs(a.x - b.x))) / scale if scale > 0 else 0.0


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    from catenet.terms.contact import Sphere

    out_dir = Path(out_dir)
    set_threads(threads)
    warm_up()
    repeats = 1 if quick else 3
    rows = []
    total = 3
    progress(0, total, "relax")
    net, loads, kw = relax_scene()
    scenes = [("relax", net, loads, kw, ())]
    c_net, c_loads, ball, c_kw = contact_scene(QUICK_STEPS if quick else STEPS)
    scenes.append(("contact", c_net, c_loads, c_kw, (ball,)))
    for done, (name, n, lo, k, terms) in enumerate(scenes):
        progress(done, total, name)
        t = interleaved(
            {
                "reuse": _runner(n, lo, k, terms, reuse=True),
                "fresh": _runner(n, lo, k, terms, reuse=False),
            },
            repeats=repeats,
            warmup=0 if quick else 1,
        )
        a, b = t["reuse"][2], t["fresh"][2]
        row = {
            "scene": name,
            "dofs": a.stats["dofs"],
            "steps_reuse": a.steps,
            "steps_fresh": b.steps,
            "reuse_s": t["reuse"][0],
            "fresh_s": t["fresh"][0],
            "speedup": t["fresh"][0] / t["reuse"][0],
            "factorizations_reuse": a.stats["factorize_count"],
            "factorizations_fresh": b.stats["factorize_count"],
            "iterations_reuse": a.iterations,
            "iterations_fresh": b.iterations,
            "max_rel_difference": _difference(a, b, n.nodes),
        }
        if terms:
            row["min_gap_reuse_m"] = float(terms[0].gap(a.x).min())
        rows.append(row)
    progress(2, total, "idle obstacle")
    free = np.flatnonzero(~net.fixed)
    far = Sphere(free, [0.0, 0.0, -5.0], 0.5, kappa=1.0, dhat=1e-2)
    t = interleaved(
        {"idle": _runner(net, loads, kw, (far,)), "none": _runner(net, loads, kw)},
        repeats=repeats,
        warmup=0 if quick else 1,
    )
    a, b = t["idle"][2], t["none"][2]
    rows.append(
        {
            "scene": "idle obstacle",
            "dofs": a.stats["dofs"],
            "steps_reuse": a.steps,
            "steps_fresh": b.steps,
            "reuse_s": t["idle"][0],
            "fresh_s": t["none"][0],
            "idle_cost": t["idle"][0] / t["none"][0] - 1.0,
            "max_rel_difference": _difference(a, b, net.nodes),
        }
    )
    progress(total, total)
    csv = write_csv(rows, out_dir / f"{NAME}.csv")
    figure = _figure(rows, out_dir)
    summary, findings = [], []
    for r in rows[:2]:
        summary.append(
            f"{r['scene']} ({r['dofs']} DOF, {r['steps_reuse']} steps): reuse "
            f"{r['reuse_s']:.2f} s, fresh {r['fresh_s']:.2f} s: {r['speedup']:.2f}x;"
            f" factorisations "
            f"{r['factorizations_reuse']} vs {r['factorizations_fresh']}, Newton iterations "
            f"{r['iterations_reuse']} vs {r['iterations_fresh']}; max difference "
            f"{r['max_rel_difference']:.1e} (relative)"
        )
        if r["speedup"] < TARGET:
            findings.append(
                f"reuse: {r['scene']}: {r['speedup']:.2f}x faster with reuse (target {TARGET:g}x)"
            )
        if not r["max_rel_difference"] < SAME:
            findings.append(
                f"reuse: {r['scene']}: the final states differ by {r['max_rel_difference']:.1e} "
                f"(relative; allowed {SAME:g})"
            )
    idle = rows[2]
    summary.append(
        f"an obstacle never touched: {idle['reuse_s']:.2f} s against {idle['fresh_s']:.2f} s "
        f"without it ({100 * idle['idle_cost']:+.1f} %)"
    )
    if idle["idle_cost"] > IDLE_COST:
        findings.append(
            f"reuse: an untouched obstacle costs {100 * idle['idle_cost']:.0f} % "
            f"(allowed {100 * IDLE_COST:.0f} %)"
        )
    return Study(NAME, rows, csv, figure, findings, summary)


def _figure(rows, out_dir: Path) -> Path:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    labels = [r["scene"] for r in rows]
    y = np.arange(len(rows))
    ax.barh(y + 0.2, [r["fresh_s"] for r in rows], 0.4, label="fresh factorisation / no obstacle")
    ax.barh(y - 0.2, [r["reuse_s"] for r in rows], 0.4, label="reused / idle obstacle")
    for k, r in enumerate(rows):
        note = f"{r['speedup']:.2f}x" if "speedup" in r else f"{100 * r['idle_cost']:+.1f} %"
        ax.text(max(r["fresh_s"], r["reuse_s"]) * 1.02, k, note, va="center", fontsize=8)
    ax.set_yticks(y, labels)
    ax.set_xlabel("wall time [s]")
    ax.set_title("Dynamic runs: modified Newton against a factorisation per iteration")
    ax.set_xlim(0, 1.25 * max(max(r["fresh_s"], r["reuse_s"]) for r in rows))
    ax.legend(fontsize=8, loc="lower right")
    return save_figure(fig, out_dir, NAME)
