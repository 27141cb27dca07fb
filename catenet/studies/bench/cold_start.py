"""Cold start: what a user waits for, in fresh processes.

- ``catenet --help`` (it should import neither NumPy nor Numba: the heavy modules it does
  import are listed);
- ``import catenet``;
- ``catenet run`` on the bundled default case (n = 34, alpha = pi/4, p = 100 Pa) with an
  empty Numba cache (``NUMBA_CACHE_DIR`` a fresh directory: every kernel is compiled) and
  with that cache warm; where ``catenet run`` is missing, a ``python -c`` script that
  builds the same net and calls ``solve_static``.

Every command runs as the user would run it (threads as installed) and, for comparison,
with one BLAS/MKL thread. Times are medians of fresh processes.
"""

from __future__ import annotations

import logging
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

_SOLVE = r"""
import math, sys
from catenet.geometry import Material, pressure_force, square_net
from catenet.net import Loads
from catenet.static import solve_static
sq = square_net(34, math.pi / 4, 1.0, 0.01, Material.from_E(10e6, radius=0.01, density=1000.0))
solve_static(sq.net, Loads(force=pressure_force(sq.net, 100.0, 1.0)))
"""


def _catenet_exe() -> list[str]:
    exe = Path(sys.executable).parent / "catenet"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("catenet")
    return [found] if found else [sys.executable, "-m", "catenet"]


def _has_run_command() -> bool:
    try:
        import importlib.util

        return importlib.util.find_spec("catenet.cli.run") is not None
    except ImportError:
        return False


def _time(cmd: list[str], env: dict, repeats: int, cwd: str) -> tuple[float, list[float], str]:
    times = []
    err = ""
    for _ in range(repeats):
        start = time.perf_counter()
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=cwd, timeout=600)
        times.append(time.perf_counter() - start)
        if proc.returncode != 0:
            err = (proc.stderr.strip().splitlines() or ["?"])[-1][:200]
    return statistics.median(times), times, err


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    reps = 3 if quick else 5
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    exe = _catenet_exe()
    has_run = _has_run_command()
    with tempfile.TemporaryDirectory(prefix="catenet-cold-") as tmp:
        out_h5 = str(Path(tmp) / "out" / "default.h5")
        if has_run:
            run_cmd, run_label = [*exe, "run", "-q", "-o", out_h5], "catenet run (default case)"
        else:
            run_cmd = [sys.executable, "-c", _SOLVE]
            run_label = "python -c solve_static (default case)"
            study.findings.append("cold-start: catenet run is missing; timed solve_static")
        plan = [
            ("catenet --help", [*exe, "--help"], None),
            ("python -c 'import catenet'", [sys.executable, "-c", "import catenet"], None),
        ]
        for k, (label, cmd, _) in enumerate(plan):
            progress(k, 6, label)
            for env_threads in (None,):
                t, times, err = _time(cmd, thread_env(env_threads), reps, tmp)
                rows.append(
                    {
                        "command": label,
                        "numba_cache": "",
                        "threads": "as installed",
                        "seconds": t,
                        "runs": len(times),
                        "seconds_max": max(times),
                        "error": err,
                    }
                )
        k = 2
        for env_threads, tlabel in ((None, "as installed"), (1, "1")):
            cache = Path(tmp) / f"numba-cache-{tlabel.replace(' ', '-')}"
            cache.mkdir()
            env = thread_env(env_threads)
            env["NUMBA_CACHE_DIR"] = str(cache)
            progress(k, 6, f"{run_label}, cold, threads {tlabel}")
            t, times, err = _time(run_cmd, env, 1, tmp)
            rows.append(
                {
                    "command": run_label,
                    "numba_cache": "empty (JIT compiles)",
                    "threads": tlabel,
                    "seconds": t,
                    "runs": 1,
                    "seconds_max": t,
                    "error": err,
                }
            )
            progress(k + 1, 6, f"{run_label}, warm, threads {tlabel}")
            t, times, err = _time(run_cmd, env, reps, tmp)
            rows.append(
                {
                    "command": run_label,
                    "numba_cache": "warm",
                    "threads": tlabel,
                    "seconds": t,
                    "runs": len(times),
                    "seconds_max": max(times),
                    "error": err,
                }
            )
            k += 2
        code = _HELP_MODULES.replace("HEAVY", repr(HEAVY))
        mods_file = Path(tmp) / "modules.txt"
        subprocess.run(
            [sys.executable, "-c", code, str(mods_file)],
            capture_output=True,
            timeout=120,
            env=thread_env(None),
        )
        heavy = mods_file.read_text().split() if mods_file.exists() else ["(unknown)"]
    progress(6, 6, "")
    load = load_average()
    for r in rows:
        r["load_average"] = load
        if r["command"] == "catenet --help":
            r["heavy_modules_imported"] = " ".join(heavy) or "none"
    write_csv(rows, study.csv)
    study.figure = figure(rows, out_dir)
    for r in rows:
        study.summary.append(
            f"{r['command']:<40s} {r['numba_cache']:<22s} threads {r['threads']:<13s} "
            f"{r['seconds']:6.2f} s (median of {r['runs']}) {r['error']}"
        )
    study.summary.append(f"catenet --help imports: {' '.join(heavy) or 'no heavy module'}")
    if heavy:
        study.findings.append(
            f"catenet --help imports {', '.join(heavy)} (through catenet/__init__.py); it "
            "should import none of them"
        )
    warm = [r for r in rows if r["numba_cache"] == "warm" and r["threads"] == "as installed"]
    if warm and warm[0]["seconds"] > 3.0:
        study.findings.append(
            f"cold-start: warm {run_label} takes {warm[0]['seconds']:.2f} s (target 3 s)"
        )
    for r in rows:
        if r["error"]:
            study.findings.append(f"cold-start: {r['command']} failed: {r['error']}")

    return study


def figure(rows, out_dir):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 3.2))
    labels = [
        f"{r['command']}\n{r['numba_cache']} threads {r['threads']}".replace(
            " threads as installed", ""
        )
        for r in rows
    ]
    ax.barh(range(len(rows)), [r["seconds"] for r in rows], color="tab:blue")
    ax.set_yticks(range(len(rows)), labels, fontsize=7)
    ax.invert_yaxis()
    ax.axvline(3.0, color="r", lw=0.8, ls="--", label="3 s target (warm run)")
    ax.set_xlabel("wall time of a fresh process [s]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)
