"""Computational time against the time step h (paper App. B, Fig. B10).

The paper's dynamic relaxation (implicit Euler, mu = 1) on its square nets, n in
{10, 22, 34}, alpha = 0, p = 100 Pa, 1 cm edges. Every run starts from the flat net at rest
and stops at equilibrium (static residual and inertial force below rtol of the load) or
when its wall-time budget is spent ("capped": small steps need tens of seconds of
simulated time). Reported: wall time, steps, Newton iterations per step, the ratio
computational time / simulated time of Fig. B10, and the distance of the final state from
the static equilibrium (``solve_static``, rtol 1e-10) as max |x - x_static| / delta_static.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/step_size.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging
import time

from benchmarks.common import (
    Study,
    no_progress,
    paper_net,
    pyplot,
    save_figure,
    set_threads,
    tabulate,
    warm_up,
)

log = logging.getLogger(__name__)

NAME = "step-size"
TITLE = "Time against step size (paper Fig. B10)"

STEPS = (1e-3, 3e-3, 1e-2, 3e-2, 1e-1, 3e-1, 1.0)
NETS = (10, 22, 34)
T_END = 200.0  # s: far beyond equilibrium; the run stops there at the latest


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    import numpy as np

    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import Workspace, solve_static

    set_threads(threads)
    warm_up()
    nets = (10, 34) if quick else NETS
    steps = (1e-2, 1e-1, 1.0) if quick else STEPS
    budget = 3.0 if quick else 20.0  # wall seconds per run
    rows = []
    total = len(nets) * len(steps)
    done = 0
    for n in nets:
        sq, loads = paper_net(n)
        net = sq.net
        ws = Workspace(net)
        ref = solve_static(net, loads, rtol=1e-10, workspace=ws)
        delta_ref = -float(ref.x[sq.center, 2])
        for h in steps:
            progress(done, total, f"n = {n}, h = {h:g}")
            start = time.perf_counter()

            def stop(step, t, x, v, start=start):
                return time.perf_counter() - start > budget

            res = solve_dynamic(
                net, loads, dt=h, damping=1.0, t_end=T_END, workspace=ws, on_step=stop
            )
            wall = time.perf_counter() - start
            err = float(np.max(np.abs(res.x - ref.x))) / delta_ref
            rows.append(
                {
                    "n": n,
                    "dofs": ws.system.n_free,
                    "h": h,
                    "wall_seconds": wall,
                    "steps": res.steps,
                    "newton_iterations": res.iterations,
                    "iterations_per_step": res.iterations / max(res.steps, 1),
                    "simulated_seconds": res.time,
                    "time_ratio": wall / res.time if res.time > 0 else float("nan"),
                    "equilibrium": bool(res.equilibrium),
                    "capped": res.outcome == "interrupted",
                    "error_vs_static": err,
                    "delta": -float(res.x[sq.center, 2]),
                    "delta_static": delta_ref,
                    "static_seconds": ref.wall_time,
                }
            )
            done += 1
    progress(total, total, "")
    return tabulate(Study(NAME, rows, Path(out_dir) / f"{NAME}.csv"), out_dir, figure, _line)


def _line(r: dict) -> str:
    capped = f"capped at {r['simulated_seconds']:.1f} s simulated"
    state = "equilibrium" if r["equilibrium"] else capped
    return (
        f"n = {r['n']:2d}  h = {r['h']:<6g} {r['wall_seconds']:7.2f} s  "
        f"{r['steps']:6d} steps  {r['iterations_per_step']:.2f} it/step  "
        f"time ratio {r['time_ratio']:.3g}  error {r['error_vs_static']:.1e}  ({state})"
    )


def figure(rows, out_dir):
    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for n in sorted({r["n"] for r in rows}):
        sel = [r for r in rows if r["n"] == n]
        h = [r["h"] for r in sel]
        (line,) = ax1.loglog(h, [r["time_ratio"] for r in sel], "o-", label=f"n = {n}")
        for r in sel:
            if r["capped"]:
                ax1.plot(r["h"], r["time_ratio"], "x", color="k", ms=9)
        ok = [r for r in sel if r["equilibrium"]]
        ax2.loglog(
            [r["h"] for r in ok],
            [r["wall_seconds"] for r in ok],
            "o-",
            color=line.get_color(),
            label=f"n = {n}",
        )
        if sel:
            ax2.axhline(sel[0]["static_seconds"], color=line.get_color(), ls=":", lw=1)
    ax1.set_xlabel("time step h [s]")
    ax1.set_ylabel("computational time / simulated time")
    ax1.set_title("Fig. B10 (x: run capped before equilibrium)")
    ax1.legend()
    ax2.set_xlabel("time step h [s]")
    ax2.set_ylabel("wall time to equilibrium [s]")
    ax2.set_title("dynamic relaxation (dotted: static solve)")
    ax2.legend()
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
