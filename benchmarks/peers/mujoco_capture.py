"""catenet side by side with MuJoCo: a net and a free box, two scenes.

    python benchmarks/peers/mujoco_capture.py --python /path/to/venv/bin/python
        [--scenes drop,capture] [--integrators discrete,implicitfast] [--out benchmarks/results]

``--python``: an interpreter with ``mujoco`` and NumPy (MuJoCo is not one of catenet's
dependencies); catenet runs in this process. The scenes are catenet cases:

- ``drop``: ``mujoco_drop.toml``, the 12 kg box of docs/guide/bodies.md dropped
  (turned 0.3 rad about z) on a pinned square net under gravity, frictionless, to 0.4 s;
- ``capture``: ``configs/contact/envisat_capture.toml`` shortened to t = CAPTURE_T_END
  (first contact at t = 1.39 s): the tether net with four corner masses thrown at the
  tumbling 8 t box in orbit, friction 0.3, the tether to the fixed chaser.

MuJoCo gets the same arrays (``mujoco_scene``: nodes, lumped masses, edges with
catenet's tension-only law as tendons of stiffness EA / r with the dead band [0, r], the
box's mass, inertia and initial motion); ``mujoco_net.py`` builds and steps the model.

For each tool and scene (catenet with its default implicit Euler; MuJoCo with each
integrator): a fine-step reference (runs at h and h / 2, extrapolated to first order),
compared between the tools (the box's momentum, linear and angular, at the end); the
largest stable step (finite, no blow-up, the box's final momentum within STABLE_TOL of
the tool's own reference, over its largest momentum; ``largest_stable_step``) and the
largest step within the scene's accuracy (ACCURATE_TOL unless it says otherwise),
timed there: the stepping alone (engine) and the whole process (``catenet run`` writing
its HDF5 result, against the MuJoCo script building its model from the JSON scene and
stepping); and the deepest penetration of a net node into the box over the run
(catenet: the nodes' distance to the box surface; MuJoCo: its contact distance, node
spheres of the cords' radius). A row more: MuJoCo with its default contacts.
``--integrator-check``: catenet's implicit Euler and newmark at three steps.

Writes ``peers-mujoco.csv`` (one row per scene, tool and setting) and
``peers-mujoco.json`` (the same with every step tried), keeping the rows of scenes not
run this time.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ[_var] = "1"  # one thread, both tools

import argparse  # noqa: E402
import csv  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
from mujoco_scene import (  # noqa: E402
    Outcome,
    box_distance,
    extrapolate,
    largest_stable_step,
    momentum_error,
    momentum_scale,
)

SCRIPT = HERE / "mujoco_net.py"
RESULTS = HERE.parent / "results"
CAPTURE_T_END = 2.0
#: The box's final momentum against the tool's own fine-step answer, over the largest
#: momentum of the box in that answer: "stable" within STABLE_TOL (finite and roughly
#: right), "accurate" within ACCURATE_TOL (unless the scene says otherwise).
STABLE_TOL = 0.2
ACCURATE_TOL = 0.02
#: MuJoCo's contact time constant [s] (solref; damping ratio 1). Its default, 0.02 s, lets
#: the node spheres sink through the box's face in the drop scene and the box fall
#: through the net (the "default contacts" row). With 1e-3 s MuJoCo's ``refsafe`` makes
#: the contacts as stiff as the step allows (implicitfast: max(solref, 2 dt), from
#: dt = 5e-4 s up; discrete: the stiffest zero-restitution row for the step, from 1e-3 s).
TIMECONST = 1e-3


@dataclass(frozen=True)
class SceneCase:
    """A scene: its case file, overrides, the sample times and the reference step."""

    name: str
    path: Path
    overrides: tuple
    t_end: float
    ref_dt: float  # catenet's reference runs: at ref_dt and ref_dt / 2
    mujoco_ref_dt: float  # MuJoCo's
    cap_dt: float  # the largest step tried
    accurate_tol: float = ACCURATE_TOL  # the accuracy both tools are timed at
    accurate_ratio: float = 1.15  # how tight the bracket of that step


SCENES = {
    "drop": SceneCase("drop", HERE / "mujoco_drop.toml", (), 0.4, 5e-4, 1e-4, 0.1),
    "capture": SceneCase(
        "capture",
        ROOT / "configs" / "contact" / "envisat_capture.toml",
        (f"solver.t_end={CAPTURE_T_END}",),
        CAPTURE_T_END,
        2.5e-3,
        2.5e-4,
        0.25,
        0.05,  # catenet's runs at 2.5e-3 and 1.25e-3 s differ by 2 %: 2 % would need
        1.3,  # steps below 1e-3 s, an hour of runs on the busy machine
    ),
}


def _samples(t_end: float, count: int = 20) -> list[float]:
    return [t_end * (k + 1) / count for k in range(count)]


def build(path, overrides=(), dt: float | None = None, integrator: str = "implicit_euler"):
    """(case, scene) of a case file under overrides, with the step and integrator."""
    from catenet.case.parse import load_case
    from catenet.case.scene import build as build_scene

    sets = list(overrides) + [f"solver.integrator={integrator!r}".replace("'", '"')]
    if dt is not None:
        sets.append(f"solver.dt={dt!r}")
    case = load_case(path, sets)
    return case, build_scene(case)


def scene_arrays(case, scene, samples) -> dict:
    """The ``mujoco_scene`` dict of a built case with one free box and no other obstacle."""
    if len(scene.rigid) != 1 or case.obstacles[scene.rigid[0].obstacle].kind != "box":
        raise ValueError("the MuJoCo comparison takes a case with one free box")
    body = scene.rigid[0]
    obs = case.obstacles[body.obstacle]
    net, n = scene.net, int(body.frame.nodes[0])
    v = np.zeros((net.n_nodes, 3)) if scene.velocity is None else scene.velocity
    edges = np.asarray(net.edges)
    if (edges >= n).any() or not net.tension_only:
        raise ValueError("the MuJoCo comparison takes a net of tension-only edges")
    w = np.zeros(3) if obs.angular_velocity is None else np.asarray(obs.angular_velocity, float)
    g = scene.loads.gravity
    return {
        "nodes": net.nodes[:n].tolist(),
        "velocity": v[:n].tolist(),
        "mass": net.mass[:n].tolist(),
        "fixed": net.fixed[:n].tolist(),
        "edges": edges.tolist(),
        "EA": net.EA.tolist(),
        "rest_length": net.rest_length.tolist(),
        "radius": float(case.material.radius),
        "gravity": [0.0, 0.0, 0.0] if g is None else list(map(float, g)),
        "box": {
            "center": body.center.tolist(),
            "half_size": list(map(float, obs.half_size)),
            "axes": body.axes.tolist(),
            "mass": body.mass,
            "inertia": body.inertia.tolist(),
            "velocity": [0.0] * 3 if obs.velocity is None else list(map(float, obs.velocity)),
            "angular_velocity": w.tolist(),
            "friction": float(obs.friction or 0.0),
        },
        "dt": float(case.solver.dt),
        "t_end": float(case.solver.t_end),
        "samples": samples,
    }


def catenet_side(path, overrides, dt: float, samples, integrator: str = "implicit_euler") -> dict:
    """catenet's run of a case at step dt: the box's momentum and angular momentum
    (about its centre, world frame) at the samples (the first step at or after each),
    the linear momentum of everything, the nearest net node's distance to the box
    surface, the deepest penetration of a node over every step (0: none; nodes are
    points), the first step's time at which a node came within the barrier's reach of
    the box, the time of the solve."""
    from catenet.solver import path as sv
    from catenet.solver.linear import resolve_backend

    case, scene = build(path, overrides, dt, integrator)
    body = scene.rigid[0]
    frame, half = body.frame, np.asarray(case.obstacles[body.obstacle].half_size, float)
    n = int(frame.nodes[0])
    mass = scene.net.mass
    settings = sv.Settings.of(case.solver, linear=resolve_backend(case.solver.linear))
    ws = sv.workspace(scene, settings)
    targets = list(samples)
    rec = {k: [] for k in ("time", "momentum", "angular_momentum", "total_momentum", "gap")}
    reach = max((float(t.dhat) for t in scene.terms if hasattr(t, "dhat")), default=0.0)
    deepest, first = [0.0], [None]

    def on_step(step) -> bool:
        c, R = frame.pose(step.x)
        d = box_distance(step.x[:n], c, R @ body.axes, half)
        deepest[0] = max(deepest[0], float(-d.min()))
        if first[0] is None and float(d.min()) < reach:
            first[0] = float(step.time)
        while targets and step.time >= targets[0] - 1e-6 * dt:  # the first step at or after
            targets.pop(0)
            p, L0 = frame.momentum(step.x, step.v)
            rec["time"].append(float(step.time))
            rec["momentum"].append(p.tolist())
            rec["angular_momentum"].append((L0 - np.cross(c, p)).tolist())
            rec["total_momentum"].append((mass[:, None] * step.v).sum(axis=0).tolist())
            rec["gap"].append(float(d.min()))
        return False

    t0, c0 = time.perf_counter(), time.process_time()
    finite = True
    try:
        result = sv.solve(scene, settings, workspace=ws, on_step=on_step)
        finite = bool(result.converged) and bool(np.isfinite(result.x).all())
    except Exception as exc:  # noqa: BLE001 (a failed run is an outcome here)
        finite, result = False, exc
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    finite = finite and len(rec["momentum"]) == len(samples)
    return {
        **rec,
        "finite": finite,
        "penetration": max(0.0, deepest[0]),
        "first_contact": first[0],
        "seconds": seconds,
        "cpu_seconds": cpu,
        "steps": getattr(result, "steps", None),
        "iterations": getattr(result, "iterations", None),
    }


def mujoco_side(
    python: str, scene_file: Path, dt: float, integrator: str, timed=False, timeconst=TIMECONST
) -> dict:
    """One MuJoCo process (``mujoco_net.py``) at step dt; its output, with the whole
    process's wall and CPU seconds."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.json"
        cmd = [python, str(SCRIPT), str(scene_file), str(out), "--dt", repr(dt)]
        cmd += ["--integrator", integrator, "--timeconst", repr(timeconst)]
        cmd += ["--timed"] if timed else []
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode != 0 or not out.exists():
            return {"finite": False, "error": done.stderr[-2000:], "process_seconds": wall}
        res = json.loads(out.read_text())
    res["process_seconds"] = wall
    res["process_cpu_seconds"] = (after.ru_utime - before.ru_utime) + (
        after.ru_stime - before.ru_stime
    )
    return res


def catenet_process(path, overrides, dt: float, integrator: str = "implicit_euler") -> dict:
    """A whole ``catenet run`` of the case at step dt, writing its HDF5 file."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "catenet", "run", str(path), "-o", f"{tmp}/out.h5", "-q"]
        for o in [*overrides, f"solver.integrator={integrator}", f"solver.dt={dt!r}"]:
            cmd += ["--set", o.replace('"', "")]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"ok": done.returncode == 0, "process_seconds": wall, "process_cpu_seconds": cpu}


def outcome(res: dict) -> Outcome:
    p = res.get("momentum") or [[math.nan] * 3]
    return Outcome(
        bool(res.get("finite")), np.asarray(p[-1], float), res.get("seconds", 0.0),
        res.get("cpu_seconds", 0.0),
    )  # fmt: skip


@dataclass
class Reference:
    """A tool's fine-step answer: its runs at steps h and h / 2, the box's final
    momentum and angular momentum extrapolated from them (``extrapolate``), the scale
    of its momentum and how far the two runs are apart (over the scale)."""

    h: float
    coarse: dict
    fine: dict

    @property
    def momentum(self) -> np.ndarray:
        return extrapolate(self.coarse["momentum"][-1], self.fine["momentum"][-1])

    @property
    def angular_momentum(self) -> np.ndarray:
        c, f = self.coarse["angular_momentum"][-1], self.fine["angular_momentum"][-1]
        return extrapolate(c, f)

    @property
    def scale(self) -> float:
        return momentum_scale(self.fine["momentum"])

    @property
    def spread(self) -> float:
        return momentum_error(self.coarse["momentum"][-1], self.fine["momentum"][-1], self.scale)


def tools(sc: SceneCase, python: str, scene_file: Path, integrators, samples) -> dict:
    """Each tool's run at a step: catenet (implicit Euler, its default) in this process,
    MuJoCo with each integrator in its own."""
    runners = {"catenet": lambda dt: catenet_side(sc.path, sc.overrides, dt, samples)}
    for integ in integrators:
        runners[f"MuJoCo {integ}"] = lambda dt, integ=integ: mujoco_side(
            python, scene_file, dt, integ
        )
    return runners


def study(sc: SceneCase, python: str, integrators, log=print) -> list[dict]:
    """Every row of one scene: references, agreement, largest steps, timings."""
    samples = _samples(sc.t_end)
    case, scene = build(sc.path, sc.overrides)
    spec = scene_arrays(case, scene, samples)
    rows: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        scene_file = Path(tmp) / "scene.json"
        scene_file.write_text(json.dumps(spec))
        catenet_side(sc.path, sc.overrides, sc.cap_dt, samples)  # JIT warm-up
        runners = tools(sc, python, scene_file, integrators, samples)
        refs = {}
        for tool, runner in runners.items():
            h = sc.ref_dt if tool == "catenet" else sc.mujoco_ref_dt
            refs[tool] = Reference(h, runner(h), runner(h / 2))
        base = refs["catenet"]
        soft = mujoco_side(python, scene_file, sc.mujoco_ref_dt, integrators[0], timeconst=0.0)
        rows.append(_soft_row(sc, soft, base))
        for tool, runner in runners.items():
            ref = refs[tool]
            log(f"{sc.name} {tool}: p = {ref.momentum}, spread {ref.spread:.2g}")
            found = {}
            searches = (
                ("stable", STABLE_TOL, 1.15),
                ("accurate", sc.accurate_tol, sc.accurate_ratio),
            )
            for what, tol, ratio in searches:
                runs: dict = {}

                def run(dt, runner=runner, runs=runs):
                    runs[dt] = runner(dt)
                    return outcome(runs[dt])

                b = largest_stable_step(
                    run, ref.momentum, tol, start=ref.h, cap=sc.cap_dt, scale=ref.scale,
                    floor=ref.h / 64, ratio=ratio,
                )  # fmt: skip
                found[what] = (b, runs)
                log(f"  largest {what} step: {b.stable:.4g} s (fails at {b.unstable:.4g})")
            rows.append(_row(sc, tool, ref, base, found, runner, python, scene_file))
    return rows


def _row(sc, tool, ref, base, found, runner, python, scene_file) -> dict:
    dt_acc, dt_stable = found["accurate"][0].stable, found["stable"][0].stable
    if tool == "catenet":
        timed = runner(dt_acc)
        proc = catenet_process(sc.path, sc.overrides, dt_acc)
    else:
        timed = mujoco_side(python, scene_file, dt_acc, tool.split()[-1], timed=True)
        proc = timed
    at_stable = found["stable"][1].get(dt_stable) or runner(dt_stable)
    at_acc = found["accurate"][1].get(dt_acc) or timed

    def tried(what):
        out = []
        for dt, r in found[what][1].items():
            err = momentum_error(outcome(r).momentum, ref.momentum, ref.scale)
            out.append([dt, bool(r.get("finite")), _num(err)])
        return out

    return {
        "scene": sc.name,
        "tool": tool,
        "version": ref.fine.get("version", ""),
        "reference_dt": _num(ref.h / 2),
        "momentum": _vec(ref.momentum),
        "angular_momentum": _vec(ref.angular_momentum),
        "reference_spread": _num(ref.spread),
        "momentum_vs_catenet": _num(momentum_error(ref.momentum, base.momentum, base.scale)),
        "angular_momentum_vs_catenet": _num(
            momentum_error(ref.angular_momentum, base.angular_momentum)
        ),
        "penetration_reference": _num(ref.fine.get("penetration")),
        "stable_dt": _num(dt_stable),
        "first_unstable_dt": _num(found["stable"][0].unstable),
        "penetration_at_stable_dt": _num(at_stable.get("penetration")),
        "accurate_tol": sc.accurate_tol,
        "accurate_dt": _num(dt_acc),
        "penetration_at_accurate_dt": _num(at_acc.get("penetration")),
        "steps": timed.get("steps"),
        "engine_seconds": _num(timed.get("seconds")),
        "engine_cpu_seconds": _num(timed.get("cpu_seconds")),
        "process_seconds": _num(proc.get("process_seconds")),
        "process_cpu_seconds": _num(proc.get("process_cpu_seconds")),
        "tried_stable": tried("stable"),
        "tried_accurate": tried("accurate"),
    }


def _soft_row(sc, soft: dict, base) -> dict:
    """MuJoCo with its default contacts (solref 0.02 s) at its reference step."""
    p = soft.get("momentum", [[math.nan] * 3])[-1]
    return {
        "scene": sc.name,
        "tool": f"MuJoCo {soft.get('integrator', '')}, default contacts",
        "version": soft.get("version", ""),
        "reference_dt": _num(soft.get("dt")),
        "momentum": _vec(p),
        "angular_momentum": _vec(soft.get("angular_momentum", [[math.nan] * 3])[-1]),
        "momentum_vs_catenet": _num(momentum_error(p, base.momentum, base.scale)),
        "penetration_reference": _num(soft.get("penetration")),
    }


def integrator_check(sc: SceneCase, steps=(1e-3, 5e-4, 2.5e-4)) -> list[dict]:
    """The box's final momentum from catenet's two integrators at a few steps: does each
    converge as the step falls?"""
    samples = _samples(sc.t_end)
    rows = []
    for integ in ("implicit_euler", "newmark"):
        for dt in steps:
            res = catenet_side(sc.path, sc.overrides, dt, samples, integ)
            p = res["momentum"][-1] if res["momentum"] else [math.nan] * 3
            rows.append(
                {
                    "scene": sc.name,
                    "integrator": integ,
                    "dt": dt,
                    "finite": res["finite"],
                    "momentum": _vec(p),
                    "peak_momentum": _num(momentum_scale(res["momentum"])),
                }
            )
    return rows


def _num(v):
    if v is None:
        return ""
    v = float(v)
    return "inf" if math.isinf(v) else float(f"{v:.4g}")


def _vec(v) -> str:
    return "[" + ", ".join(f"{float(x):.5g}" for x in v) + "]"


def write(rows: list[dict], out: Path) -> None:
    """Writes the rows, keeping those of other scenes that ``out`` holds already (the
    scenes may be run one at a time)."""
    out.mkdir(parents=True, exist_ok=True)
    old = out / "peers-mujoco.json"
    if old.exists():
        scenes = {r["scene"] for r in rows}
        kept = [r for r in json.loads(old.read_text()) if r["scene"] not in scenes]
        rows = [r for name in SCENES for r in kept + rows if r["scene"] == name]
    (out / "peers-mujoco.json").write_text(json.dumps(rows, indent=1))
    flat = [{k: v for k, v in r.items() if not k.startswith("tried")} for r in rows]
    with open(out / "peers-mujoco.csv", "w", newline="") as f:
        names = list(dict.fromkeys(k for r in flat for k in r))
        w = csv.DictWriter(f, fieldnames=names, restval="")
        w.writeheader()
        w.writerows(flat)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--python", required=True, help="an interpreter with mujoco")
    parser.add_argument("--scenes", default="drop,capture")
    parser.add_argument("--integrators", default="discrete,implicitfast")
    parser.add_argument("--out", default=str(RESULTS))
    parser.add_argument(
        "--integrator-check", action="store_true",
        help="only catenet's two integrators at three steps (peers-mujoco-integrators.csv)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.integrator_check:
        rows = []
        for name in args.scenes.split(","):
            rows += integrator_check(SCENES[name])
        with open(Path(args.out) / "peers-mujoco-integrators.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        return
    rows = []
    for name in args.scenes.split(","):
        rows += study(SCENES[name], args.python, args.integrators.split(","))
    write(rows, Path(args.out))


if __name__ == "__main__":
    main()
