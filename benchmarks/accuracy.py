"""Dynamic runs at default settings against fixed steps: the drop of
benchmarks/peers/mujoco_drop.toml (a 12 kg box onto the n = 10 net; the box's momentum at
0.4 s) and the safety net of benchmarks/safety_net.toml (a 100 kg ball dropped 3.3 m into
a 6 x 6 m net; the largest rope tension over the run), each without ``solver.dt`` (steps
chosen by the default ``solver.tolerance``, bdf2: catenet/solver/adaptive.py) and with
fixed bdf2 steps halved down to the reference, the finest.

For each run: the answer, its error against the reference, the steps, Newton iterations
and the CPU seconds of the solve (one thread, JIT warm). The peak tension is the top of
the parabola through the states about it (``catenet.model.peaks``), at fixed steps too.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/accuracy.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import time
import tomllib

from benchmarks.common import Study, no_progress, set_threads, write_csv

NAME = "accuracy"
TITLE = "Dynamic runs at default settings against fixed steps (a drop, a safety net)"

HERE = Path(__file__).resolve().parent
SCENES = {
    "drop": (HERE / "peers" / "mujoco_drop.toml", (1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4)),
    "safety net": (HERE / "safety_net.toml", (5e-3, 2.5e-3, 1.25e-3, 6.25e-4)),
}
REFERENCE = 3.125e-4  # the finest fixed step of both: the answers' reference


def once(scene: str, dt: float | None) -> dict:
    """One run of ``scene``: at its defaults (``dt`` None: no dt in the case) or at fixed
    bdf2 steps of ``dt``: the answer, counts, CPU seconds."""
    import numpy as np

    import catenet
    from catenet.case import build, parse_case
    from catenet.model.peaks import Peaks

    path, _ = SCENES[scene]
    case = tomllib.loads(path.read_text())
    case["solver"].pop("dt", None)
    if dt is not None:
        case["solver"].update(dt=dt, integrator="bdf2")
    parsed = parse_case(case)
    built = build(parsed)
    settings = catenet.Settings.of(parsed.solver)
    peaks = Peaks(built.net.nodes, built.net.n_edges, between=True)
    start = time.process_time()
    result = catenet.solve(built, settings, peaks=peaks)
    cpu = time.process_time() - start
    if scene == "drop":
        (body,) = built.rigid
        value = body.mass * float(result.v[body.frame.nodes, 2].mean())
    else:
        value = float(np.max(peaks.tension))
    span = float(parsed.solver.t_end)
    return {
        "scene": scene,
        "run": "default" if dt is None else "bdf2 fixed",
        "tolerance": settings.tolerance if dt is None else float("nan"),
        "h": span / result.steps,
        "value": value,
        "steps": result.steps,
        "iterations": result.iterations,
        "cpu_seconds": cpu,
    }


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    set_threads(threads)
    rows = []
    plans = [(s, steps[:2] if quick else steps) for s, (_, steps) in SCENES.items()]
    total = sum(len(steps) + 2 for _, steps in plans)
    done = 0
    once("drop", 1e-2)  # warm: the JIT and the first solve's allocations
    for scene, steps in plans:
        reference = steps[-1] if quick else REFERENCE
        progress(done, total, f"{scene}: bdf2 at h = {reference:g} (the reference)")
        ref = once(scene, reference)
        done += 1
        mine = []
        for dt in (None, *steps):
            progress(done, total, f"{scene}: {'default' if dt is None else f'h = {dt:g}'}")
            mine.append(once(scene, dt))
            done += 1
        for row in [*mine, ref]:
            row["error"] = row["value"] / ref["value"] - 1.0
        rows += [*mine, ref]
    study = Study(NAME, rows, write_csv(rows, Path(out_dir) / f"{NAME}.csv"))
    study.summary += [_line(row) for row in rows]
    return study


def _line(row: dict) -> str:
    what = "momentum [kg m/s]" if row["scene"] == "drop" else "peak tension [N]"
    return (
        f"{row['scene']:>10} {row['run']:>10} h = {row['h']:<9.3g} {what} {row['value']:9.5g} "
        f"({100 * row['error']:+6.2f} %), {row['steps']} steps, {row['iterations']} "
        f"iterations, {row['cpu_seconds']:.2f} s CPU"
    )


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
