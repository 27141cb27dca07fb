"""catenet, the floor and MuJoCo on the thrown net refined to a 101 x 101 grid (30 615
DOF; ``big_net.py``): CPU seconds per simulated second over a short window around first
contact, each tool at a step that gives its own answer.

The scene: ``big_net.py``'s case (the tether net of ``thrown_net.toml`` as a 0.2 m grid of
Dyneema cords, started 5 cm above the free 8 t box, frictionless), to ``--t-end``
(0.1 s: first contact at about 0.015 s, the centre of the net stopped on the box and its
rim still falling by the end; ``--t-end 0.05`` keeps MuJoCo's runs short). Rows:

- catenet (bdf2) at fixed steps ``DT`` (10 ms) and at its default steps (no dt: bdf2
  with steps chosen by the default ``solver.tolerance``): steps taken (and failed), Newton
  iterations per step, the box's momentum at the end, the closest approach of a node to
  the box;
- the floor (``floor_step.py``: the same step in plain Numba and LAPACK) at ``DT``, else
  the first of its halvings at which every step converges (its Newton stops at 100
  iterations);
- MuJoCo 4 (``mujoco_net.py`` as ``benchmarks/peers/README.md`` section 4 sets it up:
  tendons with catenet's edge law, Newton solver, contacts ``solref = 0.001 1``) with
  ``implicitfast`` and ``discrete``, each at the largest step of ``MJ_STEPS`` that stays
  finite (MuJoCo's bad-acceleration warning counts as a blow-up: it resets such a run)
  and whose box momentum at the end is within ``TOLERANCE`` of its own answer at half
  that step (its own accuracy), timed over all steps (``mj_step`` with
  ``nstep``), its penetration from a watched run. One model per integrator (the step
  set in ``opt.timestep``: compiling the 10 201 bodies' model takes about a minute).

Errors are the box's momentum at the end against catenet's at ``DT / 4`` (bdf2), over
its norm. CPU seconds of the stepping alone (a warm process, one thread).
``python benchmarks/peers/big_net_compare.py [--side 101] [--t-end 0.1]`` prints the
Markdown table of docs/performance.md and writes ``results/peers-big-net.csv``.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

HERE = Path(__file__).resolve().parent
if __package__ in (None, ""):
    sys.path.insert(0, str(HERE.parents[1]))

import numpy as np  # noqa: E402

from benchmarks.peers import big_net, floor_compare  # noqa: E402

DT = 0.01
TOLERANCE = 0.05
MJ_STEPS = {
    "implicitfast": (1e-4, 5e-5, 4e-5, 2e-5, 1e-5),
    "discrete": (2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5),
}
RESULTS = HERE.parent / "results" / "peers-big-net.csv"
OUT = HERE.parents[1] / "out" / "big_net"


def catenet_row(dt: float | None, t_end: float, watch: bool) -> dict:
    """catenet at dt (None: its default steps); a failure is a row too."""
    from catenet.errors import ConvergenceError

    try:
        r = floor_compare.catenet_run("big", dt, watch=watch)
    except ConvergenceError as exc:
        return {"failed": str(exc).split(":")[0], "steps": 0, "iterations": exc.iterations}
    return r


class MuJoCo:
    """One MuJoCo model of the scene per integrator, run at several steps."""

    def __init__(self, integrator: str, t_end: float):
        from benchmarks.peers import mujoco_capture as mc
        from benchmarks.peers import mujoco_net as mn

        case, scene = floor_compare._case(floor_compare.SCENES["big"], DT)
        self.arrays = mc.scene_arrays(case, scene, [t_end])
        self.t_end = t_end
        self.run = mn.Run(self.arrays, integrator, "Newton", MJ_STEPS[integrator][0], 0,
                          mc.TIMECONST)  # fmt: skip

    def at(self, dt: float, watch: bool) -> dict:
        self.run.dt = dt
        self.run.model.opt.timestep = dt
        out = self.run.go([self.t_end], watch=watch)
        return {"momentum": np.asarray(out["momentum"][-1]), "finite": out["finite"],
                "cpu": out["cpu_seconds"], "steps": out["steps"],
                "penetration": out["penetration"]}  # fmt: skip


def rows(t_end: float, tools: list[str], log=print) -> list[dict]:
    out: list[dict] = []
    ref = catenet_row(DT / 4, t_end, watch=False)
    if "momentum" not in ref:
        raise SystemExit(f"catenet's reference at {DT / 4} s failed: {ref['failed']}")
    p_ref = ref["momentum"]
    scale = float(np.linalg.norm(p_ref))
    log(f"reference (catenet bdf2, dt {DT / 4}): momentum {p_ref}")

    def err(p) -> float:
        return float(np.linalg.norm(np.asarray(p) - p_ref) / scale)

    def row(tool, dt, steps, its, r, penetration, own="") -> dict:
        failed = r.get("failed", "")
        return {
            "tool": tool, "dt [s]": dt, "steps": steps,
            "Newton it. per step": "" if its is None else its / max(steps, 1),
            "box momentum z [kg m/s]": float(r["momentum"][2]) if "momentum" in r else "",
            "error vs catenet's reference": err(r["momentum"]) if "momentum" in r else "",
            "error vs own reference": own,
            "CPU [s]": r.get("cpu", ""),
            "CPU per simulated second [s]": r["cpu"] / t_end if "cpu" in r else "",
            "deepest penetration [m]": penetration, "failed": failed,
        }  # fmt: skip

    if "catenet" in tools:
        for dt in (DT, None):
            r = catenet_row(dt, t_end, watch=False)
            if "momentum" in r:
                w = catenet_row(dt, t_end, watch=True)
                pen = 0.0 if w["closest"] > 0 else -w["closest"]
            else:
                pen = ""
            label = "catenet (bdf2)" if dt else "catenet (default steps)"
            step = dt if dt else (t_end / r["steps"] if r["steps"] else "")
            out.append(row(label, step, r["steps"], r["iterations"], r, pen))
            log(out[-1])
    if "floor" in tools:  # at DT, else the first of its halvings it converges at
        for h in (DT, DT / 2, DT / 4):
            try:
                r = floor_compare.floor_run("big", h)
            except RuntimeError as exc:  # its Newton did not converge in a step
                out.append(row("floor (bdf2)", h, 0, None, {"failed": str(exc)}, ""))
                log(out[-1])
                continue
            pen = 0.0 if r["closest"] > 0 else -r["closest"]
            out.append(row("floor (bdf2)", h, r["steps"], r["iterations"], r, pen))
            log(out[-1])
            break
    for integrator in ("implicitfast", "discrete"):
        if integrator not in tools:
            continue
        mj = MuJoCo(integrator, t_end)
        for dt in MJ_STEPS[integrator]:
            r = mj.at(dt, watch=False)
            log(f"MuJoCo {integrator} dt {dt}: finite {r['finite']}, cpu {r['cpu']:.3g}, "
                f"momentum {r['momentum']}")  # fmt: skip
            if not r["finite"]:
                continue
            own = mj.at(dt / 2, watch=False)
            e_own = float(np.linalg.norm(r["momentum"] - own["momentum"]) / scale)
            log(f"  against dt {dt / 2}: {e_own:.3g}")
            if own["finite"] and e_own <= TOLERANCE:
                pen = mj.at(dt, watch=True)["penetration"]
                out.append(row(f"MuJoCo {integrator}", dt, r["steps"], None, r, pen, e_own))
                log(out[-1])
                break
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--side", type=int, default=101)
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--tools", nargs="+", default=["catenet", "floor", "implicitfast", "discrete"])
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    floor_compare.SCENES["big"] = big_net.write(args.side, 0.05, args.t_end, OUT)
    floor_compare.floor_run("drop", 0.1)  # the floor's kernels compiled before any timing
    found = rows(args.t_end, args.tools)
    print(floor_compare.table(found), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(found[0]))
        w.writeheader()
        w.writerows(found)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
