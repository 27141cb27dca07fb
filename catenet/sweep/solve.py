"""One job, in whatever process runs it: its load levels solved in turn on one net and
one Workspace, each from the previous equilibrium (a net of tension-only edges, which
cannot lose stability) or along its own load path from the start (bilateral edges: their
path is judged, and a level beyond a snap-through collapses, as in ``catenet run``; from
the level before, Newton had jumped to the far branch, called stable), one table row
per level.

``make_task`` packs a job as plain picklable data; ``run_job`` runs it and never raises
for a failing case (every row carries its error). ``_solve`` is the one place that calls
the solvers.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING

from catenet.errors import CatenetError, ConfigError
from catenet.scene import Scene
from catenet.sweep.jobs import SUMMARY_COLUMNS, Job, Sweep, case_api, mode_columns, overrides

if TYPE_CHECKING:
    from catenet.solver.result import Result

log = logging.getLogger(__name__)

RUNS_DIR = "runs"
RUNNING_DIR = ".running"
CRASH_VARIABLE = "CATENET_TEST_CRASH"


def make_task(
    sweep: Sweep, job: Job, out: Path, *, save_runs: bool, threads: int, crash_hook: bool
) -> dict:
    """Everything a worker needs, as plain picklable data."""
    return {
        "index": job.index,
        "base": sweep.base,
        "source": sweep.source,
        "base_dir": sweep.base_dir,
        "settings": [list(s) for s in job.settings],
        "levels": [[list(s) for s in level] for level in (job.levels or ((),))],
        "out": str(out),
        "save_runs": save_runs,
        "threads": threads,
        "crash_hook": crash_hook,
        "modes": sweep.modes,
        "load_case": sweep.load_case,
    }


def run_job(task: dict) -> dict:
    """Solve one job's load levels in turn, each from the previous equilibrium.

    Never raises for a failing case: every row carries its error. Returns
    ``{"index": ..., "rows": [...], "pid": ..., "attempts": ...}``: ``attempts`` counts
    the starts of the job since the marker ``DIR/.running/<index>`` ("pid attempt") was
    last cleared, so a start after a worker died mid-job (a Dask scheduler reruns such a
    task by itself) knows it is the second."""
    out = Path(task["out"])
    index = task["index"]
    marker = out / RUNNING_DIR / str(index)
    attempt = 1
    if task.get("crash_hook"):
        with contextlib.suppress(OSError, ValueError, IndexError):
            attempt = int(marker.read_text().split()[1]) + 1  # left by a start that died
        with contextlib.suppress(OSError):
            marker.write_text(f"{os.getpid()} {attempt}")
        _test_crash(out, index)
    try:
        from catenet.solver.threads import set_threads

        set_threads(int(task["threads"]))
        rows = _solve_levels(task)
    finally:
        if task.get("crash_hook"):
            with contextlib.suppress(OSError):
                marker.unlink()
    return {"index": index, "rows": rows, "pid": os.getpid(), "attempts": attempt}


def _test_crash(out: Path, index: int) -> None:
    target = os.environ.get(CRASH_VARIABLE, "")
    if target.strip() != str(index):
        return
    flag = out / f".crash-{index}"
    try:
        fd = os.open(flag, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return
    os.close(fd)
    log.warning("test hook %s=%s: this worker exits now", CRASH_VARIABLE, index)
    os._exit(1)


def nan_row() -> dict:
    """A row of no result (the measures nan, no error yet)."""
    nan = float("nan")
    return {
        "delta": nan,
        "delta_over_L": nan,
        "F_bar": nan,
        "max_strain": nan,
        "slack_edges": -1,
        **{
            key: (-1 if key.endswith(("_node", "_edge")) or key == "probe" else nan)
            for key in SUMMARY_COLUMNS
        },
        "max_utilisation": nan,
        "max_utilisation_edge": -1,
        "max_utilisation_cable": "",
        "peak_utilisation": nan,
        "iterations": 0,
        "wall_time": 0.0,
        "converged": False,
        "error": "",
        "attempts": 1,
        "run_file": "",
    }


def failed_rows(job: Job, message: str) -> list[dict]:
    """The rows of a job that did not run (its worker died), each with ``message``."""
    rows = []
    for _ in job.levels or ((),):
        row = nan_row()
        row["error"] = message
        rows.append(row)
    return rows


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, ConfigError):
        return "; ".join(exc.problems)
    if isinstance(exc, CatenetError):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def _solve_levels(task: dict) -> list[dict]:
    import numpy as np

    case = case_api()
    base_dir = Path(task["base_dir"])
    settings = [tuple(s) for s in task["settings"]]
    levels = [[tuple(s) for s in level] for level in task["levels"]]
    rows: list[dict] = []
    ws = None
    ws_net = None
    x_prev = None
    path: list = []  # (load level, equilibrium) of the current net, for the predictor
    reference = None  # the external force of the path's first level
    load_keys = {key for level in levels for key, _ in level}
    scenes = _Scenes(case, pressure_only=load_keys == {"load.pressure"})
    for k, level in enumerate(levels):
        start = time.perf_counter()
        row = nan_row()
        row.update(dict.fromkeys(mode_columns(int(task.get("modes", 0))), float("nan")))
        values = dict(settings + level)
        try:
            data = case.apply_overrides(task["base"], overrides(settings + level))
            parsed = case.parse_case(data, source=task["source"], base_dir=base_dir)
            scene = scenes.build(parsed)
            net = scene.net
            # A workspace serves the next level only for the same net and no other terms
            # (obstacles, bodies: their barrier may change with the swept keys or loads).
            if ws is None or not _same_net(ws_net, net) or scene.terms:
                from catenet.solver import path as sv

                ws = sv.workspace(scene, sv.Settings.of(parsed.solver))
                ws_net, x_prev, path = net, None, []
            if not net.law.all_tension_only:  # its path is judged: each level's whole path
                x_prev, path = None, []
            force = scene.loads.external_force(ws_net)
            if not path:
                reference = force
            level_of = _load_level(force, reference)
            x0 = x_prev
            if parsed.solver.method == "static" and level_of is not None and len(path) >= 2:
                from catenet.solver.start import predict

                x0 = predict([x for _, x in path[-2:]], [s for s, _ in path[-2:]], level_of)
            result = _solve(parsed, scene, ws_net, ws, x0)
            _plausible(parsed, scene, result)
            x_prev = result.x
            path = path + [(level_of, result.x)] if level_of is not None else []
            if task.get("load_case"):
                result = _solve_case(parsed, scene, ws, result, task["load_case"])
            row.update(_measure(scene, ws_net, result, np))
            if task.get("modes"):
                row.update(_frequencies(scene, ws, result, int(task["modes"])))
            if task["save_runs"]:
                row["run_file"] = _save_run(Path(task["out"]), task["index"], k, scene, result)
        except (CatenetError, ArithmeticError, ValueError, MemoryError, OSError) as exc:
            row["error"] = _error_text(exc)
            good = exc.last_good if isinstance(exc, CatenetError) else None
            state = None if good is None else good.x
            if state is not None and ws_net is not None and np.shape(state) == ws_net.nodes.shape:
                x_prev = np.asarray(state)
            path = []
            spent = exc.iterations if isinstance(exc, CatenetError) else 0
            row["iterations"] = int(spent or 0)
            log.info("job %s level %s %s: %s", task["index"], k, values, row["error"])
        except Exception as exc:  # an unexpected failure of one case must not end the sweep
            row["error"] = _error_text(exc)
            log.exception("job %s level %s %s failed", task["index"], k, values)
        row["wall_time"] = time.perf_counter() - start
        rows.append(row)
    return rows


class _Scenes:
    """The scenes of a job's load levels. When the only load key is ``load.pressure`` of
    a square net, the net is built once and each level's loads are the first level's with
    the pressure part, -p L^2/N per node (contract §2), computed for its p; the second
    level is also built in full once to check that this gives the same net and forces
    (else every level is built); a scene with other terms (obstacles, bodies, whose
    barrier stiffness follows the loads) is built for every level. Saves a net build per
    level: 10-40 % of a job."""

    def __init__(self, case_module, *, pressure_only: bool):
        self.case_api = case_module
        self.fast = pressure_only
        self.first = None
        self.other = None  # the first level's force minus its pressure part
        self.checked = False

    def build(self, case):
        import dataclasses

        import numpy as np

        from catenet.model.builders import pressure_force

        if not self.fast or self.first is None or case.geometry.kind != "square_net":
            scene = self.case_api.build(case)
            if scene.terms:  # obstacles, bodies: their terms depend on the loads; built anew
                self.fast = False
            if self.fast and self.first is None and case.geometry.kind == "square_net":
                self.first = scene
                force = scene.loads.force
                pressure = pressure_force(scene.net, case.load.pressure, scene.size)
                self.other = (np.zeros_like(pressure) if force is None else force) - pressure
            return scene
        first = self.first
        force = self.other + pressure_force(first.net, case.load.pressure, first.size)
        loads = dataclasses.replace(first.loads, force=force)
        scene = dataclasses.replace(first, case=case, loads=loads)
        if not self.checked:
            self.checked = True
            full = self.case_api.build(case)
            want = full.loads.external_force(full.net)
            got = loads.external_force(first.net)
            scale = float(np.max(np.abs(want), initial=0.0)) or 1.0
            if not (
                _same_net(first.net, full.net)
                and full.probe == first.probe
                and full.size == first.size
                and float(np.max(np.abs(want - got), initial=0.0)) <= 1e-14 * scale
            ):
                log.debug("pressure levels: the loads are not -p L^2/N: building every level")
                self.fast = False
                return full
        return scene


def _same_net(a, b) -> bool:
    """Whether the nets are the same (``Net.same_as``: the law, point masses and bodies
    included); a is None before the first."""
    return a is not None and a.same_as(b)


def _load_level(force, reference) -> float | None:
    """The multiple of ``reference`` that ``force`` is, or None when it is not one (then
    the levels of a job are not proportional and no equilibrium is predicted)."""
    import numpy as np

    ref2 = float(np.vdot(reference, reference))
    if ref2 == 0.0:
        return None
    level = float(np.vdot(force, reference)) / ref2
    if np.linalg.norm(force - level * reference) > 1e-9 * np.linalg.norm(force):
        return None
    return level


def _solve(case, scene, net, ws, x_prev):
    """One load level through the one solve path: static from the previous equilibrium
    (the first level in ``solver.steps`` load steps), or the dynamic run of the case from
    it (which must reach t_end or equilibrium)."""
    import dataclasses

    from catenet.errors import ConvergenceError
    from catenet.solver import path as sv

    settings = sv.Settings.of(case.solver)
    if x_prev is not None and settings.method == "static":
        settings = dataclasses.replace(settings, steps=1)
    problem = Scene(net, scene.loads, scene.terms)
    r = sv.solve(problem, settings, workspace=ws, start=sv.Start(x=x_prev))
    if not r.converged:
        raise ConvergenceError(
            f"dynamic run did not converge: {r.message}", iterations=r.iterations, state=r.x
        )
    return r


def _plausible(case, scene, result) -> None:
    """Raises for a level whose equilibrium ``catenet run`` would not call an answer
    (exit 1 there): an unstable one, or one no cable structure reaches (a unit slip, a
    mechanism flown off: ``catenet.run.runner.implausible_message``). Rows of both had
    said converged."""
    from catenet.errors import ConvergenceError
    from catenet.run.runner import implausible_message

    if result.stable is False:
        raise ConvergenceError(f"the equilibrium found is unstable: {result.diagnosis}")
    if message := implausible_message(case, scene, result):
        raise ConvergenceError(f"the result is {message}")


def _solve_case(case, scene, ws, base, name: str):
    """The load case or combination ``name`` solved from the level's base state."""
    from catenet.errors import ConvergenceError
    from catenet.run.cases import pick, solve_cases
    from catenet.solver import path as sv

    (run,) = solve_cases(scene, sv.Settings.of(case.solver), ws, base, pick(scene, name))
    if not run.converged:
        raise ConvergenceError(f"load case {name}: {run.error}", state=base.x)
    return run.result


def _measure(scene, net, result, np) -> dict:
    """The row of a level: the run's summary (``catenet.model.summary``, the numbers
    ``catenet run`` prints and writes as /result attributes) and the paper's measures."""
    import dataclasses

    from catenet.model import summary

    scene = dataclasses.replace(scene, net=net) if scene.net is not net else scene
    numbers = summary.flat(summary.summarize_result(scene, result))
    delta = numbers["delta"]
    force = scene.loads.external_force(net)
    EA = float(np.median(net.EA))
    return {
        "delta": delta,
        "delta_over_L": delta / float(scene.size),
        "F_bar": float(np.linalg.norm(force.sum(axis=0))) / EA,
        "max_strain": float(result.max_strain),
        "slack_edges": numbers["slack_edges"],
        **{key: numbers[key] for key in SUMMARY_COLUMNS},
        "max_utilisation": numbers.get("max_utilisation", float("nan")),
        "max_utilisation_edge": numbers.get("max_utilisation_edge", -1),
        "max_utilisation_cable": numbers.get("max_utilisation_cable", ""),
        "peak_utilisation": numbers.get("peak_utilisation", float("nan")),
        "iterations": int(result.iterations),
        "converged": bool(result.converged),
    }


def _frequencies(scene, ws, result, count: int) -> dict:
    """f1..fK [Hz] of the row's equilibrium (``catenet.solver.modes``; nan where the net
    has fewer modes with a frequency). A net without mass or a count above its free DOFs
    gives the row an error; the other measures stay."""
    import numpy as np

    from catenet.run.modes import added_line
    from catenet.solver.modes import natural_modes

    count = min(count, ws.system.n_free - 6 * len(scene.rigid))
    added = added_line(scene.case, scene)  # material.added_mass, if any
    cables = scene.cables
    found = natural_modes(ws, result.x, count, cables=cables, added=added)
    f = np.full(count, np.nan)
    f[: found.count] = found.frequency
    return {f"f{k + 1}": float(f[k]) for k in range(count)}


def _save_run(out: Path, index: int, level: int, scene: Scene, result: Result) -> str:
    """The level's HDF5 result file (contract §5, as ``catenet run`` writes it: a
    static equilibrium is the frame at load factor 1) under DIR/runs/; its path relative
    to DIR."""
    from catenet.output import ResultWriter

    rel = Path(RUNS_DIR) / f"job{index:05d}-level{level:03d}.h5"
    case = scene.case
    attrs = {"source": str(case.source), "sweep_job": index, "sweep_level": level}
    every = int(case.output.every)
    with ResultWriter(out / rel, scene, every=every, xdmf=case.output.xdmf, attrs=attrs) as writer:
        t = float(result.time) if case.solver.method == "dynamic" else 1.0
        if not case.solver.method == "dynamic":
            result.time = t
        if every > 0:
            writer.frame(t, result.x, result.v, result.tension, last=True)
        writer.result(result)
    return str(rel)
