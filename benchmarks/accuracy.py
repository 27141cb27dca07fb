"""Dynamic runs at default settings against fixed steps: the drop of
benchmarks/peers/mujoco_drop.toml (a 12 kg box onto the n = 10 net; the box's momentum at
0.4 s), the safety net of benchmarks/safety_net.toml (a 100 kg ball dropped 3.3 m into
a 6 x 6 m net; the largest rope tension over the run) and two drop tests of other scales
written from the docs, benchmarks/tennis_net.toml (a 2 kg ball onto a 1 x 1 m net of
nylon cords) and benchmarks/cable_net_kn.toml (a 2 t mass onto a 20 x 20 m steel cable
net, in kN, m, t), their largest tension; each without ``solver.dt`` (steps chosen by
the default ``solver.tolerance``, bdf2: catenet/solver/adaptive.py), at a tenfold tighter
tolerance, and with fixed bdf2 steps halved down to the reference, the finest.

For each run: the answer, its error against the reference (the drop's largest tension
too), the steps, Newton iterations and the CPU seconds of the solve (one thread, JIT
warm). The peak tension is the top of the parabola through the states about it
(``catenet.model.peaks``), at fixed steps too. A run that fails is a row too (its steps
until then, the error's first line).
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
TITLE = "Dynamic runs at default settings against fixed steps (a drop, three drop tests)"

HERE = Path(__file__).resolve().parent
# scene: (case, fixed steps, the reference's step: the finest, the answers' reference)
SCENES = {
    "drop": (HERE / "peers" / "mujoco_drop.toml", (1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4), 3.125e-4),
    "safety net": (HERE / "safety_net.toml", (5e-3, 2.5e-3, 1.25e-3, 6.25e-4), 3.125e-4),
    "tennis net": (HERE / "tennis_net.toml", (2e-3, 1e-3, 5e-4, 2.5e-4), 1.25e-4),
    "cable net": (HERE / "cable_net_kn.toml", (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4), 6.25e-5),
}
TIGHTER = 0.1  # a tenfold tighter tolerance than the default, as the docs advise for a check
UNITS = {"cable net": "kN"}  # the peak tension's unit where it is not N


def once(scene: str, dt: float | None, tolerance: float | None = None) -> dict:
    """One run of ``scene``: at its defaults (``dt`` None: no dt in the case; with
    ``tolerance``, that one) or at fixed bdf2 steps of ``dt``: the answer, counts, CPU
    seconds."""
    import numpy as np

    import catenet
    from catenet.case import build, parse_case
    from catenet.errors import CatenetError
    from catenet.model.peaks import Peaks

    path, _, _ = SCENES[scene]
    case = tomllib.loads(path.read_text())
    case["solver"].pop("dt", None)
    if dt is not None:
        case["solver"].update(dt=dt, integrator="bdf2")
    elif tolerance is not None:
        case["solver"].update(tolerance=tolerance)
    parsed = parse_case(case)
    built = build(parsed)
    settings = catenet.Settings.of(parsed.solver)
    peaks = Peaks(built.net.nodes, built.net.n_edges, between=True)
    run = "bdf2 fixed" if dt is not None else "tolerance" if tolerance else "default"
    row = {
        "scene": scene,
        "run": run,
        "tolerance": settings.tolerance if dt is None else float("nan"),
    }
    start = time.process_time()
    try:
        result = catenet.solve(built, settings, peaks=peaks)
    except CatenetError as exc:  # a run that fails is a row too: where, after how many steps
        good = exc.last_good
        steps = good.steps if good is not None else 0
        return row | {
            "run": f"{run} (failed)",
            "h": float(good.time) / steps if good is not None and steps else float("nan"),
            "value": float("nan"),
            "peak_tension": float("nan"),
            "steps": steps,
            "iterations": good.iterations if good is not None else 0,
            "cpu_seconds": time.process_time() - start,
            "message": str(exc).splitlines()[0],
        }
    cpu = time.process_time() - start
    if scene == "drop":
        (body,) = built.rigid
        value = body.mass * float(result.v[body.frame.nodes, 2].mean())
    else:
        value = float(np.max(peaks.tension))
    span = float(parsed.solver.t_end)
    return row | {
        "h": span / result.steps,
        "value": value,
        "peak_tension": float(np.max(peaks.tension)),
        "steps": result.steps,
        "iterations": result.iterations,
        "cpu_seconds": cpu,
        "message": "",
    }


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    set_threads(threads)
    from catenet.solver.adaptive import TOLERANCE

    rows = []
    plans = [(s, steps[:2] if quick else steps, r) for s, (_, steps, r) in SCENES.items()]
    total = sum(len(steps) + 3 for _, steps, _ in plans)
    done = 0
    once("drop", 1e-2)  # warm: the JIT and the first solve's allocations
    for scene, steps, reference in plans:
        reference = steps[-1] if quick else reference
        progress(done, total, f"{scene}: bdf2 at h = {reference:g} (the reference)")
        ref = once(scene, reference)
        done += 1
        mine = []
        runs = [(None, None), (None, TIGHTER * TOLERANCE), *((dt, None) for dt in steps)]
        for dt, tolerance in runs:
            what = f"h = {dt:g}" if dt else f"tolerance {tolerance:g}" if tolerance else "default"
            progress(done, total, f"{scene}: {what}")
            mine.append(once(scene, dt, tolerance))
            done += 1
        for row in [*mine, ref]:
            row["error"] = row["value"] / ref["value"] - 1.0
            row["peak_error"] = row["peak_tension"] / ref["peak_tension"] - 1.0
        rows += [*mine, ref]
    study = Study(NAME, rows, write_csv(rows, Path(out_dir) / f"{NAME}.csv"))
    study.summary += [_line(row) for row in rows]
    return study


def _line(row: dict) -> str:
    unit = UNITS.get(row["scene"], "N")
    what = "momentum [kg m/s]" if row["scene"] == "drop" else f"peak tension [{unit}]"
    run = row["run"].replace("tolerance", f"tol {row['tolerance']:g}")
    if row["message"]:
        return (
            f"{row['scene']:>10} {run:>10} failed after {row['steps']} steps "
            f"({row['cpu_seconds']:.2f} s CPU): {row['message']}"
        )
    peak = (
        f", peak tension [N] {row['peak_tension']:.5g} ({100 * row['peak_error']:+6.2f} %)"
        if row["scene"] == "drop"
        else ""
    )
    return (
        f"{row['scene']:>10} {run:>10} h = {row['h']:<9.3g} {what} {row['value']:9.5g} "
        f"({100 * row['error']:+6.2f} %){peak}, {row['steps']} steps, {row['iterations']} "
        f"iterations, {row['cpu_seconds']:.2f} s CPU"
    )


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
