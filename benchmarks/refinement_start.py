"""Newton iterations from the flat, unstressed net against refinement, by start.

The paper's n = 34 net (configs/fig4g_n34_alpha_0.toml) at several edge lengths, solved
statically from each of these starts (catenet/solver/start.py, catenet/solver/nested.py):

- stretched: the stretched start (``solver.start = "stretched"``, the default below
  70 000 free DOFs);
- nested: the same case solved on one coarse net of about 10 000 free DOFs (edges
  dofs / 10 000 times longer, at least 2x), its displacements carried along each cable
  onto the fine net (``solver.start = "nested"``; the default from 70 000 free DOFs);
- nested 2x: a hierarchy of nets, each with edges twice as long as the next finer, the
  coarsest below 15 000 free DOFs (the nested start with other constants);
- 4 load steps: load continuation (``solver.steps = 4``) from the stretched start.

Each cell: Newton iterations on the fine net (+ those on the coarse nets) and the
seconds of the whole solve (coarse nets, workspace and analysis included; one run on a
shared machine: ratios, not absolutes). Every start reaches the same equilibrium (the
largest difference of positions from the stretched start's is printed). Prints a
Markdown table.

    python benchmarks/refinement_start.py [EDGE ...]   (default: 0.01 0.005 0.002 0.001 0.0002)
"""

from __future__ import annotations

import contextlib
import dataclasses
import sys
import time
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/refinement_start.py
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

CASE = "configs/fig4g_n34_alpha_0.toml"
EDGES = (0.01, 0.005, 0.002, 0.001, 0.0002)
STARTS = ("stretched", "nested", "nested 2x", "4 load steps")


def scene(edge: float):
    from catenet.case import build, load_case
    from catenet.solver.path import Settings

    case = load_case(CASE, [f"geometry.edge_length={edge}"])
    return build(case), Settings.of(case.solver)


@contextlib.contextmanager
def halving():
    """The nested start as a hierarchy of nets, edges twice as long each level."""
    from catenet.solver import nested

    saved = nested.COARSE_DOFS, nested.NESTED_DOFS
    nested.COARSE_DOFS, nested.NESTED_DOFS = float("inf"), 15_000
    try:
        yield
    finally:
        nested.COARSE_DOFS, nested.NESTED_DOFS = saved


def run(fine, settings, start: str):
    """The Result of one start, and its seconds."""
    from catenet.solver.path import solve

    if start == "4 load steps":
        settings = dataclasses.replace(settings, start="stretched", steps=4)
    elif start == "nested 2x":
        settings = dataclasses.replace(settings, start="nested")
    else:
        settings = dataclasses.replace(settings, start=start)
    with halving() if start == "nested 2x" else contextlib.nullcontext():
        t = time.perf_counter()
        r = solve(fine, settings)
        seconds = time.perf_counter() - t
    assert r.converged, r.message
    return r, seconds


def cell(r, seconds: float) -> str:
    coarse = f" + {r.nested.iterations}" if r.nested is not None else ""
    return f"{r.iterations}{coarse} ({seconds:.2f} s)"


def main(edges=EDGES) -> None:
    from catenet.solver.nested import free_dofs

    run(*scene(0.01), "stretched")  # warm-up: Numba's cache, the backend's first use
    print(
        "| edge [m] | DOF | "
        + " | ".join(f"{s}: iterations (s)" for s in STARTS)
        + " | same state to [m] |"
    )
    print("|---|---|" + "---|" * len(STARTS) + "---|")
    for edge in edges:
        fine, settings = scene(edge)
        results = [run(fine, settings, s) for s in STARTS]
        base = results[0][0].x
        gap = max(float(np.max(np.abs(r.x - base))) for r, _ in results[1:])
        cells = " | ".join(cell(r, t) for r, t in results)
        print(f"| {edge:g} | {free_dofs(fine.net)} | {cells} | {gap:.0e} |", flush=True)


if __name__ == "__main__":
    main(tuple(float(a) for a in sys.argv[1:]) or EDGES)
