"""The integrators on an impact: the drop of benchmarks/peers/mujoco_drop.toml (a 12 kg box,
not spinning, dropped at 1 m/s onto the n = 10 square net of docs/guide/bodies.md;
frictionless, undamped; it meets the net at about 0.14 s and is thrown back up by 0.4 s).

For each integrator (implicit Euler and bdf2: a case with contact refuses newmark,
catenet.case.timing.newmark_refused) and each step h: the box's vertical momentum at
0.4 s, its error against bdf2 at the finest step, the steps, Newton iterations and the
CPU seconds of the solve (one thread, JIT warm), and the run's energy balance: the
largest share of the largest energy the integrator created (its ``numerical`` column)
and lost.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/drop.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import time
import tomllib

from benchmarks.common import Study, no_progress, pyplot, save_figure, set_threads, tabulate

NAME = "drop"
TITLE = "The integrators on an impact (a box dropped onto a net)"

SCENE = Path(__file__).resolve().parent / "peers" / "mujoco_drop.toml"
SCHEMES = (("implicit_euler", None), ("bdf2", None))
STEPS = (1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4)
REFERENCE = 3.125e-4  # bdf2's finest step: the answer the others are measured against
TOLERANCES = (1e-2, 3e-3, 1e-3)  # bdf2 with steps chosen by accuracy (3e-3: the default)


def label(name: str, rho_inf: float | None) -> str:
    return name if rho_inf is None else f"{name} rho_inf={rho_inf:g}"


def drop(
    name: str, rho_inf: float | None, dt: float | None, tolerance: float | None = None
) -> dict:
    """One run of the drop: the box's momentum, counts, CPU seconds, energy shares;
    ``tolerance``: steps chosen by accuracy (``dt`` None), its row's h the mean step."""
    import numpy as np

    import catenet
    from catenet.case import build, parse_case

    case = tomllib.loads(SCENE.read_text())
    case["solver"].update(integrator=name)
    if tolerance is None:
        case["solver"]["dt"] = dt
    else:
        del case["solver"]["dt"]
        case["solver"]["tolerance"] = tolerance
    if rho_inf is not None:
        case["solver"]["rho_inf"] = rho_inf
    parsed = parse_case(case)
    scene = build(parsed)
    energies: list = []
    start = time.process_time()
    result = catenet.solve(
        scene, catenet.Settings.of(parsed.solver), on_step=lambda s: energies.append(s.energy)
    )
    cpu = time.process_time() - start
    (body,) = scene.rigid
    rows = np.array([e for e in energies if e is not None])
    largest = float(np.abs(rows[:, :4]).max()) if len(rows) else float("nan")
    return {
        "scheme": label(name, rho_inf) + ("" if tolerance is None else f" tolerance={tolerance:g}"),
        "h": dt if tolerance is None else float(parsed.solver.t_end) / result.steps,
        "momentum": body.mass * float(result.v[body.frame.nodes, 2].mean()),
        "converged": bool(result.converged),
        "steps": result.steps,
        "iterations": result.iterations,
        "cpu_seconds": cpu,
        "created": float(rows[:, -1].max()) / largest if len(rows) else float("nan"),
        "lost": -float(rows[:, -1].min()) / largest if len(rows) else float("nan"),
    }


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    set_threads(threads)
    steps = STEPS[:2] if quick else STEPS
    reference = steps[-1] if quick else REFERENCE
    tolerances = TOLERANCES[:1] if quick else TOLERANCES
    total = len(SCHEMES) * len(steps) + len(tolerances) + 1
    drop("bdf2", None, steps[0])  # warm: the JIT and the first solve's allocations
    progress(0, total, f"bdf2 at h = {reference:g} (the reference)")
    ref = drop("bdf2", None, reference)
    rows = []
    done = 1
    for name, rho in SCHEMES:
        for dt in steps:
            progress(done, total, f"{label(name, rho)}, h = {dt:g}")
            row = drop(name, rho, dt)
            row["error"] = row["momentum"] / ref["momentum"] - 1.0
            rows.append(row)
            done += 1
    for tol in tolerances:
        progress(done, total, f"bdf2, tolerance = {tol:g}")
        row = drop("bdf2", None, None, tol)
        row["error"] = row["momentum"] / ref["momentum"] - 1.0
        rows.append(row)
        done += 1
    ref["error"] = 0.0
    rows.append(ref)
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    study.findings.append(f"reference: bdf2 at h = {reference:g} s, {ref['momentum']:.4g} kg m/s")
    return tabulate(study, out_dir, figure, _line)


def _line(row: dict) -> str:
    return (
        f"{row['scheme']:>24} h = {row['h']:<8g} momentum {row['momentum']:8.4g} kg m/s "
        f"({100 * row['error']:+6.1f} %), {row['steps']} steps, {row['cpu_seconds']:.2f} s CPU"
    )


def figure(rows: list[dict], out_dir: Path) -> Path:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for scheme in dict.fromkeys(r["scheme"] for r in rows):
        sel = [r for r in rows if r["scheme"] == scheme and float(r["error"]) != 0.0]
        ax.loglog(
            [float(r["h"]) for r in sel], [abs(float(r["error"])) for r in sel], "o-", label=scheme
        )
    ax.set_xlabel("time step h [s]")
    ax.set_ylabel("|momentum error| against bdf2 at the finest h")
    ax.set_title("a 12 kg box dropped onto a net (benchmarks/peers/mujoco_drop.toml)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


def section(results: Path) -> list[str]:
    """docs/performance.md's table of this study (``python -m benchmarks render``)."""
    from benchmarks.sections import as_text, md_table, read_study

    rows = read_study(results, NAME)
    if not rows:
        return []
    return md_table(
        [
            "integrator",
            "h (mean) [s]",
            "momentum [kg m/s]",
            "error",
            "steps",
            "CPU [s]",
            "energy lost",
        ],
        [
            [
                r["scheme"],
                as_text(r["h"], "{:g}"),
                as_text(r["momentum"], "{:.4g}"),
                f"{100 * float(r['error']):+.1f} %",
                r["steps"],
                as_text(r["cpu_seconds"], "{:.2f}"),
                f"{100 * float(r['lost']):.1f} %",
            ]
            for r in rows
        ],
    )


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
