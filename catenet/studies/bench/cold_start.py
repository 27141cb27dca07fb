"""Cold start: what a user waits for, in fresh processes.

- ``catenet --help`` (it should import neither NumPy nor Numba: the heavy modules it does
  import are listed) and ``import catenet``;
- ``catenet run`` on the bundled default case (the n = 34 net of configs/
  fig4i_n34_alpha_pi4.toml: alpha = pi/4, p = 100 Pa) with a warm Numba cache and with an
  empty one (``NUMBA_CACHE_DIR`` a fresh directory: every kernel it uses is compiled);
- against two references, timed in the same rounds (interleaved, so that a machine's
  load falls on all of them alike): the import floor, a process that only imports what a
  Numba/PARDISO/HDF5 tool cannot avoid (numpy, scipy.sparse, h5py, numba) and loads MKL's
  runtime, and the plain script, a whole process of the plain NumPy/SciPy/pypardiso
  implementation (``baseline.baseline_static``) solving the same net and writing its
  state with h5py.

The targets (issue 13): a warm ``catenet run`` within 1.3x the import floor and 0.8x the
plain script; a first run with an empty cache within 2 s. Times are medians of fresh
processes; the CPU seconds (user + system of the children) are less sensitive to the
machine's load. One ``python -X importtime`` run of ``catenet run`` lists the packages
whose imports cost most.
"""

from __future__ import annotations

import collections
import logging
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from catenet.studies.bench.common import (
    Study,
    load_average,
    no_progress,
    pyplot,
    save_figure,
    thread_env,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "cold-start"
TITLE = "Cold start"

HEAVY = ("numpy", "scipy", "numba", "h5py", "matplotlib", "pypardiso")
TARGET_FLOOR = 1.3  # warm catenet run / import floor
TARGET_PLAIN = 0.8  # warm catenet run / plain script
TARGET_COLD = 2.0  # s, catenet run with an empty Numba cache

RUN = "catenet run (n = 34)"
FLOOR = "import floor (numpy, scipy.sparse, h5py, numba, MKL)"
JIT_FLOOR = "import floor + first call of a cached Numba kernel"
PLAIN = "plain NumPy/SciPy/pypardiso script (n = 34)"

_HELP_MODULES = r"""
import sys
from catenet.cli import main
try:
    main(["--help"], standalone_mode=False)
except SystemExit:
    pass
heavy = [m for m in HEAVY if m in sys.modules]
open(sys.argv[1], "w").write(" ".join(heavy))
"""

# The floor: the imports any Numba/PARDISO/HDF5 tool pays, and MKL's runtime loaded (its
# path as catenet finds it, given on the command line; none where MKL is missing).
_FLOOR = r"""
import ctypes, sys
import numpy, scipy.sparse, h5py, numba
for path in [a for a in sys.argv[1:] if a != "--jit"]:
    ctypes.CDLL(path)
if "--jit" in sys.argv:  # and the first call of one cached kernel (Numba's own start-up)
    from catenet.kernels.sparse import dot
    dot(numpy.zeros(3), numpy.zeros(3))
"""

# The plain script: the same net solved by the plain NumPy/SciPy/pypardiso implementation
# and its state written with h5py, as a user without catenet's engine would.
_PLAIN = r"""
import math, sys
import h5py
from catenet.model.builders import Material, pressure_force, square_net
from catenet.studies.bench.baseline import baseline_static
sq = square_net(34, math.pi / 4, 1.0, 0.01, Material.from_E(10e6, radius=0.01, density=1000.0))
net = sq.net
x, info = baseline_static(
    net.nodes, net.edges, net.rest_length, net.EA, net.fixed, pressure_force(net, 100.0, 1.0)
)
assert info["converged"], info
with h5py.File(sys.argv[1], "w") as fh:
    fh["x"] = x
"""


def _catenet_exe() -> list[str]:
    exe = Path(sys.executable).parent / "catenet"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("catenet")
    return [found] if found else [sys.executable, "-m", "catenet"]


def _mkl_path() -> list[str]:
    from catenet.solver.linear import MklNotFound, mkl_runtime

    try:
        return [mkl_runtime().path]
    except MklNotFound:
        return []


def _once(cmd: list[str], env: dict, cwd: str) -> tuple[float, float, str]:
    """(wall seconds, CPU seconds of the child, the error's last line or '')."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=cwd, timeout=600)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    err = ""
    if proc.returncode != 0:
        err = (proc.stderr.strip().splitlines() or ["?"])[-1][:200]
    return wall, cpu, err


def _row(command: str, cache: str, threads: str, walls, cpus, errors) -> dict:
    return {
        "command": command,
        "numba_cache": cache,
        "threads": threads,
        "seconds": statistics.median(walls),
        "runs": len(walls),
        "seconds_max": max(walls),
        "cpu_seconds": statistics.median(cpus),
        "error": next((e for e in errors if e), ""),
    }


def _interleaved(plan: dict[str, tuple[list[str], dict]], reps: int, cwd: str) -> dict:
    """Every command of ``plan`` once per round, ``reps`` rounds: {label: (walls, cpus,
    errors)}."""
    out: dict[str, tuple[list, list, list]] = {label: ([], [], []) for label in plan}
    for _ in range(reps):
        for label, (cmd, env) in plan.items():
            wall, cpu, err = _once(cmd, env, cwd)
            out[label][0].append(wall)
            out[label][1].append(cpu)
            out[label][2].append(err)
    return out


def _run_times(path: str) -> dict:
    """solve_time and startup_time from the /result of a catenet run."""
    try:
        import h5py

        with h5py.File(path, "r") as fh:
            attrs = fh["result"].attrs
            return {k: float(attrs[k]) for k in ("solve_time", "startup_time") if k in attrs}
    except (OSError, KeyError, ImportError):
        return {}


def import_costs(cmd: list[str], env: dict, cwd: str, top: int = 8) -> list[tuple[str, float]]:
    """The packages whose imports cost most in one ``python -X importtime`` run of
    ``cmd`` (their modules' own times summed): [(package, seconds)]."""
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", *cmd],
        env=env,
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
    )
    cost: dict[str, float] = collections.defaultdict(float)
    for line in proc.stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        try:
            own, _, name = line.split(":", 1)[1].split("|")
            cost[name.strip().split(".")[0]] += int(own) / 1e6
        except ValueError:
            continue
    return sorted(cost.items(), key=lambda kv: -kv[1])[:top]  # (as Counter.most_common)


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    reps = 5 if quick else 11
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    exe = _catenet_exe()
    installed = thread_env(None)
    with tempfile.TemporaryDirectory(prefix="catenet-cold-") as tmp:
        out_h5 = str(Path(tmp) / "out" / "default.h5")
        run_cmd = [*exe, "run", "-q", "-o", out_h5]
        progress(0, 5, "catenet --help, import catenet")
        light = {
            "catenet --help": ([*exe, "--help"], installed),
            "python -c 'import catenet'": ([sys.executable, "-c", "import catenet"], installed),
        }
        for label, (walls, cpus, errs) in _interleaved(light, reps, tmp).items():
            rows.append(_row(label, "", "as installed", walls, cpus, errs))

        for k, (env_threads, tlabel) in enumerate(((None, "as installed"), (1, "1"))):
            if quick and env_threads is not None:
                break
            env = thread_env(env_threads)
            cache = Path(tmp) / f"numba-cache-{k}"
            progress(1 + 2 * k, 5, f"{RUN}, empty Numba cache, threads {tlabel}")
            cold: tuple[list, list, list] = ([], [], [])
            for rep in range(1 if quick or env_threads is not None else 3):
                empty = Path(tmp) / f"numba-empty-{k}-{rep}"
                empty.mkdir()
                wall, cpu, err = _once(run_cmd, {**env, "NUMBA_CACHE_DIR": str(empty)}, tmp)
                for store, value in zip(cold, (wall, cpu, err), strict=True):
                    store.append(value)
            rows.append(_row(RUN, "empty (JIT compiles)", tlabel, *cold))
            cache.mkdir()
            warm_env = {**env, "NUMBA_CACHE_DIR": str(cache)}
            _once(run_cmd, warm_env, tmp)  # fills the cache
            progress(2 + 2 * k, 5, f"{RUN}, warm, against the floor and the plain script")
            plan = {RUN: (run_cmd, warm_env)}
            if env_threads is None:
                plan[FLOOR] = ([sys.executable, "-c", _FLOOR, *_mkl_path()], env)
                plan[JIT_FLOOR] = ([sys.executable, "-c", _FLOOR, "--jit", *_mkl_path()], warm_env)
                plain_h5 = str(Path(tmp) / "plain.h5")
                plan[PLAIN] = ([sys.executable, "-c", _PLAIN, plain_h5], env)
            for label, (walls, cpus, errs) in _interleaved(plan, reps, tmp).items():
                row = _row(label, "warm" if label == RUN else "", tlabel, walls, cpus, errs)
                if label == RUN:
                    row.update(_run_times(out_h5))
                rows.append(row)
        progress(4, 5, "imports of catenet run (python -X importtime)")
        costs = import_costs(
            ["-m", "catenet", "run", "-q", "-o", out_h5],
            {**installed, "NUMBA_CACHE_DIR": str(Path(tmp) / "numba-cache-0")},
            tmp,
        )
        code = _HELP_MODULES.replace("HEAVY", repr(HEAVY))
        mods_file = Path(tmp) / "modules.txt"
        subprocess.run(
            [sys.executable, "-c", code, str(mods_file)],
            capture_output=True,
            timeout=120,
            env=installed,
        )
        heavy = mods_file.read_text().split() if mods_file.exists() else ["(unknown)"]
    progress(5, 5, "")
    load = load_average()
    _ratios(rows)
    for r in rows:
        r["load_average"] = load
        if r["command"] == "catenet --help":
            r["heavy_modules_imported"] = " ".join(heavy) or "none"
    write_csv(rows, study.csv)
    study.figure = figure(rows, out_dir)
    for r in rows:
        study.summary.append(
            f"{r['command']:<52s} {r['numba_cache']:<22s} threads {r['threads']:<13s} "
            f"{r['seconds']:6.3f} s (median of {r['runs']}, CPU {r['cpu_seconds']:.3f} s) "
            f"{r['error']}"
        )
    study.summary.append(f"catenet --help imports: {' '.join(heavy) or 'no heavy module'}")
    study.summary.append(
        "imports of catenet run, own time by package: "
        + ", ".join(f"{name} {sec:.3f} s" for name, sec in costs)
    )
    _findings(rows, heavy, study)
    return study


def _ratios(rows: list[dict]) -> None:
    """The warm run (threads as installed) against the floor and the plain script."""
    by = {r["command"]: r for r in rows if r["threads"] == "as installed" and r["runs"]}
    warm = next((r for r in rows if r["command"] == RUN and r["numba_cache"] == "warm"), None)
    if warm is None:
        return
    for key, label in (
        ("ratio_to_floor", FLOOR),
        ("ratio_to_jit_floor", JIT_FLOOR),
        ("ratio_to_plain", PLAIN),
    ):
        ref = by.get(label)
        if ref is not None and ref["seconds"] > 0:
            warm[key] = warm["seconds"] / ref["seconds"]
            warm[f"cpu_{key}"] = warm["cpu_seconds"] / max(ref["cpu_seconds"], 1e-9)


def _findings(rows: list[dict], heavy: list[str], study: Study) -> None:
    warm = next(
        (r for r in rows if r["command"] == RUN and r["numba_cache"] == "warm"),
        None,
    )
    if warm is not None:
        for key, target, what in (
            ("ratio_to_floor", TARGET_FLOOR, "the import floor"),
            ("ratio_to_plain", TARGET_PLAIN, "the plain script"),
        ):
            if key in warm:
                line = (
                    f"warm {RUN}: {warm[key]:.2f}x {what} (target {target}x; CPU "
                    f"{warm['cpu_' + key]:.2f}x)"
                )
                study.summary.append(line)
                if warm[key] > target:
                    study.findings.append(f"cold-start: {line}")
        if "ratio_to_jit_floor" in warm:
            study.summary.append(
                f"warm {RUN}: {warm['ratio_to_jit_floor']:.2f}x {JIT_FLOOR} (what any tool "
                "that calls a Numba kernel pays: Numba's target set-up imports scipy.linalg "
                "and registers its typing; no target)"
            )
        if "solve_time" in warm:
            study.summary.append(
                f"warm {RUN} as it reports itself: solve {warm['solve_time']:.3f} s, start-up "
                f"{warm['startup_time']:.3f} s"
            )
    for r in rows:
        if r["command"] == RUN and r["numba_cache"].startswith("empty"):
            if r["threads"] == "as installed" and r["seconds"] > TARGET_COLD:
                study.findings.append(
                    f"cold-start: {RUN} with an empty Numba cache takes {r['seconds']:.2f} s "
                    f"(target {TARGET_COLD} s)"
                )
        if r["error"]:
            study.findings.append(f"cold-start: {r['command']} failed: {r['error']}")
    if heavy:
        study.findings.append(
            f"catenet --help imports {', '.join(heavy)}; it should import none of them"
        )


def figure(rows, out_dir):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(rows) + 1.2))
    labels = [
        f"{r['command']}\n{r['numba_cache']} threads {r['threads']}".replace(
            " threads as installed", ""
        ).strip()
        for r in rows
    ]
    ax.barh(range(len(rows)), [r["seconds"] for r in rows], color="tab:blue", label="wall")
    ax.barh(
        range(len(rows)),
        [r["cpu_seconds"] for r in rows],
        height=0.3,
        color="tab:orange",
        label="CPU (user + system)",
    )
    ax.set_yticks(range(len(rows)), labels, fontsize=7)
    ax.invert_yaxis()
    floor = next((r["seconds"] for r in rows if r["command"] == FLOOR), None)
    plain = next((r["seconds"] for r in rows if r["command"] == PLAIN), None)
    if floor:
        ax.axvline(TARGET_FLOOR * floor, color="g", lw=0.8, ls="--", label="1.3x floor")
    if plain:
        ax.axvline(TARGET_PLAIN * plain, color="m", lw=0.8, ls=":", label="0.8x plain script")
    ax.axvline(TARGET_COLD, color="r", lw=0.8, ls="-.", label="2 s (empty cache)")
    ax.set_xlabel("time of a fresh process [s] (median)")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


__all__ = ["NAME", "TITLE", "import_costs", "run"]
