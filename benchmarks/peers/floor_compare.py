"""catenet, the floor and MuJoCo on a net meeting a free box: CPU time to a stated
accuracy, the deepest penetration, and catenet's time per step against the floor's.

Scenes: the drop (``mujoco_drop.toml``: a 12 kg box on the pinned n = 10 net under
gravity, 0.4 s) and the thrown net (``thrown_net.toml``: the tether net of the Envisat
capture without its tether meeting the free 8 t box, frictionless, 2 s). For each:

- catenet's reference: bdf2 at a fine step (``REFERENCE``); the accuracy of every run
  is its box momentum at the end against it, over the largest box momentum of the
  reference run;
- catenet (bdf2, its default set-up, one thread) and the floor (``floor_step.py``: the
  same step in plain Numba and LAPACK) at the step ``DT`` and, where that is not within
  ``TOLERANCE``, at the first of its halvings that is: the same answer, so the
  difference of their times per step is catenet's overhead over the hardware's floor;
- catenet as a user runs the scene, without its dt (``catenet (default steps)``: bdf2
  with steps chosen by the default ``solver.tolerance``), its mean step in ``dt``;
- MuJoCo 4 (``mujoco_net.py``, set up as ``benchmarks/peers/README.md`` section 4 says:
  tendons with catenet's edge law, Newton solver, contacts ``solref = 0.001 1``) with
  ``implicitfast`` and ``discrete``, each at the largest step of ``MJ_STEPS`` whose
  momentum is within ``TOLERANCE`` of MuJoCo's own answer at its finest step (the first
  to a given accuracy, not the first stable one), timed without watching (``mj_step``
  over all steps), its penetration from a watched run.

``python benchmarks/peers/floor_compare.py [--scenes drop thrown]`` prints the Markdown
table of docs/performance.md and writes ``results/peers-floor.csv``. CPU seconds of the
stepping alone (a warm process, one thread), the best of ``--repeats`` runs.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import time
from pathlib import Path

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

HERE = Path(__file__).resolve().parent
if __package__ in (None, ""):
    sys.path.insert(0, str(HERE.parents[1]))

import numpy as np  # noqa: E402

from benchmarks.peers import floor_step  # noqa: E402

SCENES = {
    "drop": HERE / "mujoco_drop.toml",
    "thrown": HERE / "thrown_net.toml",
}
DT = {"drop": 0.01, "thrown": 0.01}
REFERENCE = {"drop": 6.25e-4, "thrown": 1.25e-3}
TOLERANCE = {"drop": 0.02, "thrown": 0.05}
MJ_STEPS = (4e-3, 2e-3, 1e-3, 5e-4, 4e-4, 2.5e-4, 1e-4)
MJ_REFERENCE = 5e-5
RESULTS = HERE.parent / "results" / "peers-floor.csv"


def _case(path: Path, dt: float | None):
    """The scene at bdf2 steps of dt; None: as a user runs it without dt (steps chosen
    by the default solver.tolerance, catenet/solver/adaptive.py)."""
    import tomllib

    from catenet.case.parse import load_case, parse_case
    from catenet.case.scene import build

    if dt is not None:
        case = load_case(path, [f"solver.dt={dt!r}", 'solver.integrator="bdf2"'])
        return case, build(case)
    raw = tomllib.loads(path.read_text())
    raw["solver"].pop("dt", None)
    case = parse_case(raw, source=str(path), base_dir=path.parent)
    return case, build(case)


def catenet_run(name: str, dt: float | None, watch: bool = True) -> dict:
    """catenet (bdf2) at dt (None: its default steps, no dt given): the box's momentum
    at the end, counts and CPU seconds of the solve; ``watch``: also its largest and the
    closest approach of a node to the box, at every step (then the CPU seconds include
    that watching)."""
    import catenet
    from catenet.terms.rigid_contact import BodyContact

    case, scene = _case(SCENES[name], dt)
    (touch,) = [t for t in scene.terms if type(t) is BodyContact]
    (body,) = scene.rigid
    seen = {"closest": math.inf, "largest": 0.0}

    def on_step(state) -> None:
        seen["closest"] = min(seen["closest"], float(touch.gap(state.x).min()))
        p = body.mass * state.v[body.frame.nodes].mean(axis=0)
        seen["largest"] = max(seen["largest"], float(np.linalg.norm(p)))

    start = time.process_time()
    result = catenet.solve(
        scene, catenet.Settings.of(case.solver), on_step=on_step if watch else None
    )
    cpu = time.process_time() - start
    p = body.mass * result.v[body.frame.nodes].mean(axis=0)
    return {"momentum": p, "steps": result.steps, "iterations": result.iterations,
            "cpu": cpu, "t_end": float(case.solver.t_end), **seen}  # fmt: skip


def floor_run(name: str, dt: float) -> dict:
    case, scene = _case(SCENES[name], dt)
    floor = floor_step.Floor.of(scene)
    stats = floor.run(dt, float(case.solver.t_end), "bdf2")
    return {"momentum": floor.momentum(), "steps": stats.steps, "iterations": stats.iterations,
            "cpu": stats.cpu, "closest": stats.closest}  # fmt: skip


def mujoco_run(name: str, integrator: str, dt: float, watch: bool) -> dict:
    from benchmarks.peers import mujoco_capture as mc
    from benchmarks.peers import mujoco_net as mn

    case, scene = _case(SCENES[name], DT[name])
    arrays = mc.scene_arrays(case, scene, [float(case.solver.t_end)])
    run = mn.Run(arrays, integrator, "Newton", dt, 0, mc.TIMECONST)
    out = run.go(arrays["samples"], watch=watch)
    return {"momentum": np.asarray(out["momentum"][-1]), "finite": out["finite"],
            "cpu": out["cpu_seconds"], "steps": out["steps"],
            "penetration": out["penetration"]}  # fmt: skip


def best(fn, repeats: int) -> dict:
    rows = [fn() for _ in range(repeats)]
    return min(rows, key=lambda r: r["cpu"])


def scene_rows(name: str, repeats: int, integrators=("implicitfast", "discrete")) -> list[dict]:
    dt, tol = DT[name], TOLERANCE[name]
    ref = catenet_run(name, REFERENCE[name])
    scale = ref["largest"]

    def err(p) -> float:
        return float(np.linalg.norm(np.asarray(p) - ref["momentum"]) / scale)

    rows = []
    steps = [dt]  # the step compared with the floor, then halved until accurate
    while True:
        cat = best(lambda: catenet_run(name, steps[-1], watch=False), repeats)  # noqa: B023
        if err(cat["momentum"]) <= tol or len(steps) == 4:
            break
        steps.append(steps[-1] / 2)
    for h in sorted(set(steps[:1] + steps[-1:]), reverse=True):
        cat = best(lambda: catenet_run(name, h, watch=False), repeats)  # noqa: B023
        cat["closest"] = catenet_run(name, h)["closest"]  # the same run, watched
        flo = best(lambda: floor_run(name, h), repeats)  # noqa: B023
        for tool, r in (("catenet (bdf2)", cat), ("floor (bdf2)", flo)):
            rows.append({
                "scene": name, "tool": tool, "dt": h, "steps": r["steps"],
                "iterations per step": r["iterations"] / r["steps"],
                "error vs catenet's reference": err(r["momentum"]),
                "error vs own reference": "",
                "CPU [s]": r["cpu"], "ms per step": 1e3 * r["cpu"] / r["steps"],
                "deepest penetration [m]": 0.0 if r["closest"] > 0 else -r["closest"],
                "closest approach [m]": r["closest"],
            })  # fmt: skip
    default = best(lambda: catenet_run(name, None, watch=False), repeats)
    default["closest"] = catenet_run(name, None)["closest"]
    rows.append({
        "scene": name, "tool": "catenet (default steps)",
        "dt": float(default["t_end"]) / default["steps"], "steps": default["steps"],
        "iterations per step": default["iterations"] / default["steps"],
        "error vs catenet's reference": err(default["momentum"]), "error vs own reference": "",
        "CPU [s]": default["cpu"], "ms per step": 1e3 * default["cpu"] / default["steps"],
        "deepest penetration [m]": 0.0 if default["closest"] > 0 else -default["closest"],
        "closest approach [m]": default["closest"],
    })  # fmt: skip
    for integrator in integrators:
        own = mujoco_run(name, integrator, MJ_REFERENCE, watch=False)["momentum"]
        found = None
        for step in MJ_STEPS:
            r = mujoco_run(name, integrator, step, watch=True)
            e_own = float(np.linalg.norm(r["momentum"] - own) / scale)
            if r["finite"] and e_own <= tol:
                found = (step, r, e_own)
                break
        if found is None:
            continue
        step, watched, e_own = found
        timed = best(lambda: mujoco_run(name, integrator, step, watch=False), repeats)  # noqa: B023
        rows.append({
            "scene": name, "tool": f"MuJoCo {integrator}", "dt": step, "steps": timed["steps"],
            "iterations per step": "", "error vs catenet's reference": err(timed["momentum"]),
            "error vs own reference": e_own, "CPU [s]": timed["cpu"],
            "ms per step": 1e3 * timed["cpu"] / timed["steps"],
            "deepest penetration [m]": watched["penetration"], "closest approach [m]": "",
        })  # fmt: skip
    return rows


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}" if v != 0 else "0"
    return str(v)


def table(rows: list[dict]) -> str:
    keys = list(rows[0])
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(_fmt(r[k]) for k in keys) + " |" for r in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    floor_run("drop", 0.1)  # the floor's kernels compiled (or loaded) before any timing
    rows = []
    for name in args.scenes:
        rows += scene_rows(name, args.repeats)
        print(table(rows), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
