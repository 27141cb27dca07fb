"""``catenet bench``: what catenet costs on this machine.

``check(repeats, threads)`` measures, on the bundled default case (the paper's densest net,
n = 34 at alpha = pi/4 under 100 Pa, about 10^4 DOF):

- the static solve warm: once to compile and fill the caches, then ``repeats`` times on
  one workspace, the median (and the fastest) wall time, Newton iterations and DOF;
- the linear-solver backend ``solver.linear = "auto"`` picks here and the threads in use;
- the cold start: ``catenet --help`` and ``catenet run`` (that case, its result file in a
  scratch directory) in fresh processes, as a user runs them.

The repository's ``benchmarks/`` holds the full timing studies; this is the check a user
runs on their own machine. Nothing here writes a file but the caller.
"""

from __future__ import annotations

import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from catenet.errors import CatenetError


@dataclass
class Measure:
    """One measured quantity: a name, its value and unit, and what it is."""

    name: str
    value: float | int | str
    unit: str = ""
    note: str = ""


@dataclass
class BenchReport:
    """The measures of ``check`` and the machine they were taken on."""

    measures: list[Measure] = field(default_factory=list)
    machine: dict = field(default_factory=dict)

    def add(self, name: str, value, unit: str = "", note: str = "") -> None:
        self.measures.append(Measure(name, value, unit, note))

    def value(self, name: str):
        return next(m.value for m in self.measures if m.name == name)


def check(repeats: int = 5, threads: int | None = None, cold: bool = True) -> BenchReport:
    """Measures the default case's warm solve, the backend, threads and (``cold``) the
    cold start. ``threads``: MKL/Numba/OpenBLAS threads of the warm solve (None: as
    installed)."""
    report = BenchReport(machine=machine())
    backend(report, threads)
    warm_solve(report, repeats)
    if cold:
        cold_start(report, min(repeats, 3))
    return report


def machine() -> dict:
    """The processor, cores and Python this runs on."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "system": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
    }


def backend(report: BenchReport, threads: int | None) -> None:
    import numba

    from catenet.solver import linear
    from catenet.solver.threads import set_numba_threads, set_threads

    if threads is not None:
        set_threads(threads)
        set_numba_threads(threads)  # the report shows Numba's count: its pool starts here
    name = linear.resolve_backend("auto")
    report.add("backend", name, note='what solver.linear = "auto" picks on this machine')
    mkl: int | str = "-"  # PARDISO's thread count; "-": another backend
    if name == "pardiso":
        try:
            mkl = int(linear.mkl_runtime().libmkl.MKL_Get_Max_Threads())
        except (AttributeError, OSError):
            mkl = "unknown"
    report.add("mkl_threads", mkl, note="PARDISO's threads")
    report.add("numba_threads", int(numba.get_num_threads()))


def warm_solve(report: BenchReport, repeats: int) -> None:
    from catenet.case import build, load_case
    from catenet.solver import path as sv

    case = load_case(None)
    scene = build(case)
    settings = sv.Settings.of(case.solver, linear="auto")
    ws = sv.workspace(scene, settings)
    start = time.perf_counter()
    first = sv.solve(scene, settings, workspace=ws)
    report.add("first_solve", time.perf_counter() - start, "s", "JIT cache loaded or compiled")
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        res = sv.solve(scene, settings, workspace=ws)
        times.append(time.perf_counter() - start)
    report.add("dofs", int(3 * int((~scene.net.fixed).sum())), note="free DOF of the n = 34 net")
    report.add("newton_iterations", int(res.iterations))
    report.add("converged", bool(first.converged and res.converged))
    report.add("solve_median", statistics.median(times), "s", f"warm, {repeats} repeats")
    report.add("solve_min", min(times), "s", f"warm, {repeats} repeats")


def cold_start(report: BenchReport, repeats: int) -> None:
    exe = [sys.executable, "-m", "catenet"]
    with tempfile.TemporaryDirectory(prefix="catenet-bench-") as tmp:
        out = str(Path(tmp) / "default.h5")
        for name, args in (("help", ["--help"]), ("run", ["run", "-q", "-o", out])):
            walls = []
            for _ in range(max(repeats, 1)):
                start = time.perf_counter()
                proc = subprocess.run([*exe, *args], capture_output=True, text=True, cwd=tmp)
                walls.append(time.perf_counter() - start)
                if proc.returncode != 0:
                    last = (proc.stderr.strip().splitlines() or ["?"])[-1]
                    raise CatenetError(f"catenet {' '.join(args)} failed: {last}")
            command = "catenet --help" if name == "help" else "catenet run (the default case)"
            report.add(f"cold_{name}", statistics.median(walls), "s", f"{command}, fresh process")
