"""What every study shares: thread control, timing, CSV and figures (the paper's scenes
are the test suite's, tests/scenes.py).

Timings on a shared machine are noisy: every study times after a JIT warm-up, repeats
short runs and keeps the median, and compares settings as ratios measured in one run.
"""

from __future__ import annotations

import csv
import json
import logging
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"
if str(TESTS) not in sys.path:  # the suite's scenes (tests/scenes.py) are the studies' too
    sys.path.insert(0, str(TESTS))

from scenes import (  # noqa: E402
    PAPER_DENSITY,
    PAPER_E,
    PAPER_EDGE,
    PAPER_PRESSURE,
    PAPER_RADIUS,
    compressed_catenary,
    midpoint_cable,
    paper_material,
    paper_net,
)

log = logging.getLogger(__name__)

DEFAULT_OUT = ROOT / "benchmarks" / "results"

__all__ = [
    "PAPER_DENSITY",
    "PAPER_E",
    "PAPER_EDGE",
    "PAPER_PRESSURE",
    "PAPER_RADIUS",
    "compressed_catenary",
    "midpoint_cable",
    "paper_material",
    "paper_net",
]

Progress = Callable[[float, float, str], None]


@dataclass
class Study:
    """What a study leaves behind: its table, its files and what it found."""

    name: str
    rows: list[dict]
    csv: Path
    figure: Path | None = None
    findings: list[str] = field(default_factory=list)
    summary: list[str] = field(default_factory=list)


def no_progress(done: float, total: float, note: str = "") -> None:
    """The default progress callback: nothing."""


# --- threads --------------------------------------------------------------------------------


def set_threads(k: int) -> None:
    """Threads of MKL (PARDISO), Numba and OpenBLAS: catenet.solver.threads.set_threads."""
    from catenet.solver.threads import set_numba_threads
    from catenet.solver.threads import set_threads as set_catenet_threads

    set_catenet_threads(k)
    set_numba_threads(k)  # Numba's pool too, as the studies were measured with it


def thread_env(threads: int | None) -> dict:
    """Environment of a child process with ``threads`` BLAS/MKL/Numba threads (None: as is)."""
    env = child_env()
    if threads is not None:
        for var in (
            "OMP_NUM_THREADS",
            "MKL_NUM_THREADS",
            "OPENBLAS_NUM_THREADS",
            "NUMBA_NUM_THREADS",
        ):
            env[var] = str(threads)
    else:
        for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
            env.pop(var, None)
    return env


# --- timing ---------------------------------------------------------------------------------


def timed(fn: Callable[[], Any]) -> tuple[float, Any]:
    start = time.perf_counter()
    out = fn()
    return time.perf_counter() - start, out


def repeat(fn: Callable[[], Any], repeats: int = 5, warmup: int = 1) -> tuple[float, list, Any]:
    """Median wall time of ``fn`` over ``repeats`` runs after ``warmup`` runs:
    (median seconds, all times, the last return value)."""
    out = None
    for _ in range(warmup):
        out = fn()
    times = []
    for _ in range(repeats):
        t, out = timed(fn)
        times.append(t)
    return statistics.median(times), times, out


def interleaved(fns: dict, repeats: int = 5, warmup: int = 1) -> dict:
    """Times several variants in turn (A B C A B C ...), so that a change in the machine's
    load hits all of them alike: {key: (median seconds, times, last return value)}."""
    out: dict[str, Any] = {k: None for k in fns}
    times: dict = {k: [] for k in fns}
    for _ in range(warmup):
        for k, fn in fns.items():
            out[k] = fn()
    for _ in range(repeats):
        for k, fn in fns.items():
            t, out[k] = timed(fn)
            times[k].append(t)
    return {k: (statistics.median(times[k]), times[k], out[k]) for k in fns}


def warm_up() -> None:
    """Compile (or load from the cache) every kernel on a tiny net, so that no timed run
    pays for the JIT, and solve a small square net (about 600 DOF), so that no measured
    run pays for the first solve's fixed allocations either (PARDISO's and MKL's
    buffers: 2-3 MiB of resident memory that a 5-node cable does not reach). The tiny
    net is solved by PARDISO too ("auto" takes the band for it): its first call's own
    set-up (10-18 MiB) is no part of a measured solve."""
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import solve_static

    net, loads, _ = midpoint_cable(1.0, nodes=5)
    solve_static(net, loads)
    solve_static(net, loads, linear="pardiso")
    solve_dynamic(net, loads, dt=0.1, damping=1.0, t_end=0.2)
    square, force = paper_net(10, edge=0.05)
    solve_static(square.net, force)


def load_average() -> float:
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def child_env(env: dict | None = None) -> dict:
    """``env`` (default: this process's) with the repository root and tests/ first on
    PYTHONPATH, so that a child process imports ``benchmarks`` and the scenes."""
    env = dict(os.environ if env is None else env)
    paths = [str(ROOT), str(TESTS), *filter(None, env.get("PYTHONPATH", "").split(os.pathsep))]
    env["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(paths))
    return env


def run_child(code: str, *, timeout: float, env: dict | None = None) -> dict:
    """Runs ``code`` in a fresh interpreter; the code writes a JSON object to the path in
    ``sys.argv[1]``. Returns that object with ``returncode`` and ``wall_seconds``, or
    ``error`` (the tail of stderr) when the child fails or times out."""
    with tempfile.TemporaryDirectory(prefix="catenet-bench-") as tmp:
        path = Path(tmp) / "out.json"
        start = time.perf_counter()
        try:
            proc = subprocess.run(
                [sys.executable, "-c", code, str(path)],
                capture_output=True,
                text=True,
                timeout=timeout,
                env=child_env(env),
            )
        except subprocess.TimeoutExpired:
            return {
                "error": f"timed out after {timeout:.0f} s",
                "returncode": None,
                "wall_seconds": time.perf_counter() - start,
            }
        wall = time.perf_counter() - start
        out: dict = {}
        if path.exists():
            out = json.loads(path.read_text())
        out["returncode"] = proc.returncode
        out["wall_seconds"] = wall
        if proc.returncode != 0 and "error" not in out:
            out["error"] = (proc.stderr.strip().splitlines() or ["(no stderr)"])[-1][:300]
        return out


# --- output ---------------------------------------------------------------------------------


def tabulate(study: Study, out_dir: Path, figure, line) -> Study:
    """A study's table: ``study.rows`` into ``study.csv``, its figure (``figure(rows,
    out_dir)``, the path it saves) and one summary line per row (``line(row)``; None: no
    line for that row)."""
    write_csv(study.rows, study.csv)
    study.figure = figure(study.rows, out_dir)
    study.summary += [text for text in map(line, study.rows) if text is not None]
    return study


def write_csv(rows: Sequence[dict], path: Path) -> Path:
    """Rows (dicts) as CSV, columns in order of first appearance; floats with 6 digits."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    columns: list[str] = []
    for row in rows:
        for key in row:
            if key not in columns:
                columns.append(key)
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _fmt(row.get(k, "")) for k in columns})
    return path


def read_csv(path: Path) -> list[dict]:
    with Path(path).open(newline="") as fh:
        return [dict(r) for r in csv.DictReader(fh)]


def _fmt(value):
    if isinstance(value, bool) or value is None:
        return "" if value is None else str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return f"{value:.6g}"
    return value


def pyplot():
    """matplotlib's pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, out_dir: Path, name: str) -> Path:
    path = Path(out_dir) / f"bench-{name}.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    pyplot().close(fig)
    return path


def machine() -> dict:
    """The machine and software the numbers come from."""
    info: dict[str, Any] = {
        "cpu": _cpu_model(),
        "cores": os.cpu_count(),
        "system": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
    }
    for mod in ("numpy", "scipy", "numba", "pypardiso", "mkl"):
        info[mod] = _version(mod)
    info["catenet"] = _version("catenet")
    try:
        import resource  # noqa: F401

        with open("/proc/meminfo") as fh:
            kb = int(fh.readline().split()[1])
        info["memory_gib"] = round(kb / 2**20, 1)
    except (OSError, ValueError, ImportError):
        pass
    return info


def write_machine(out_dir: Path) -> Path:
    path = Path(out_dir) / "machine.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(machine(), indent=2) + "\n")
    return path


def _cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return platform.processor() or "unknown"


def _version(dist: str) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(dist)
    except PackageNotFoundError:
        return ""


def geometric_fit(x: Iterable[float], y: Iterable[float]) -> tuple[float, float]:
    """Exponent b and prefactor a of y = a x^b by least squares in log-log."""
    import numpy as np

    lx, ly = np.log(np.asarray(list(x), float)), np.log(np.asarray(list(y), float))
    b, la = np.polyfit(lx, ly, 1)
    return float(b), float(np.exp(la))
