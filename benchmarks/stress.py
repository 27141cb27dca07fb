"""Numerical-stability stress test: the whole scene matrix of ``tests/stress_matrix.py``
(hard scenes, each a right answer or a clear catenet error; the quick subset runs in
``tests/solver/test_stress.py``), timed, into ``stress.csv`` and ``bench-stress.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/stress.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging

from benchmarks.common import (
    Study,
    no_progress,
    pyplot,
    save_figure,
    set_threads,
    warm_up,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "stress"
TITLE = "Numerical-stability stress test"


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    from stress_matrix import run_scene, scenes  # tests/ (on the path by benchmarks.common)

    set_threads(threads)
    warm_up()
    todo = scenes(quick)
    rows: list[dict] = []
    study = Study(NAME, rows, Path(out_dir) / f"{NAME}.csv")
    for k, scene in enumerate(todo):
        progress(k, len(todo), scene.id)
        rows.append(run_scene(scene))
    progress(len(todo), len(todo), "")
    write_csv(rows, study.csv)
    study.figure = figure(rows, out_dir)
    for r in rows:
        flag = "ok  " if r["passed"] else "FAIL"
        study.summary.append(
            f"{flag} {r['id']:<40s} {r['status']:<28s} {r.get('check', ''):<16s} "
            f"{_num(r.get('value'))} it {r.get('iterations')}  {r['seconds']:.2f} s"
        )
        if not r["passed"]:
            study.findings.append(
                f"stress {r['id']} ({r['params']}): {r['status']}; check {r.get('check')} = "
                f"{_num(r.get('value'))} (tol {_num(r.get('tol'))}), equilibrium error "
                f"{_num(r.get('equilibrium_error'))}; {r.get('message', '')}; "
                f"Newton history: {r.get('history', '')}"
            )
        elif r["slow"]:
            study.findings.append(f"stress {r['id']}: slow ({r['seconds']:.1f} s)")
    return study


def _num(v) -> str:
    return f"{v:.2e}" if isinstance(v, float) else str(v)


def figure(rows, out_dir):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 0.28 * len(rows) + 1.2))
    y = list(range(len(rows)))
    colors = ["tab:green" if r["passed"] else "tab:red" for r in rows]
    ax.barh(y, [max(r["seconds"], 1e-3) for r in rows], color=colors)
    ax.set_yticks(y, [f"{r['id']} [{r['status']}]" for r in rows], fontsize=6)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("wall time [s] (green: right answer, red: finding)")
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
