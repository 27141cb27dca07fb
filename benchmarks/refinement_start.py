"""Newton iterations from the flat, unstressed net against refinement (issue: they grow).

The paper's n = 34 net (configs/fig4g_n34_alpha_0.toml) at several edge lengths, solved
statically at default settings (the stretched start, catenet/solver/start.py), and again
from the coarse net's equilibrium interpolated onto the fine net (nested iteration, or grid
continuation: the net solved at 1 cm edges, its displacements interpolated linearly
over the plane of the flat net onto the fine net's nodes, which lie on the same cables).
Prints a Markdown table: edge, DOF, iterations and the residual history of each start.

    python benchmarks/refinement_start.py [EDGE ...]   (default: 0.01 0.002 0.001 0.0002)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/refinement_start.py
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

CASE = "configs/fig4g_n34_alpha_0.toml"
COARSE = 0.01  # m: the coarse net of the nested start
EDGES = (0.01, 0.002, 0.001, 0.0002)


def scene(edge: float):
    from catenet.case import build, load_case
    from catenet.solver.path import Settings

    case = load_case(CASE, [f"geometry.edge_length={edge}"])
    return build(case), Settings.of(case.solver)


def interpolated_start(coarse_scene, coarse_x, fine_scene) -> np.ndarray:
    """The coarse equilibrium's displacements, interpolated linearly over the flat net's
    plane (x, y) onto the fine net's nodes (the reference positions where outside)."""
    from scipy.interpolate import LinearNDInterpolator

    u = coarse_x - coarse_scene.net.nodes
    nodes = fine_scene.net.nodes
    x0 = nodes + LinearNDInterpolator(coarse_scene.net.nodes[:, :2], u)(nodes[:, :2])
    outside = ~np.all(np.isfinite(x0), axis=1)
    x0[outside] = nodes[outside]
    return x0


def main(edges=EDGES) -> None:
    from catenet.solver.path import Start, solve

    coarse, settings = scene(COARSE)
    base = solve(coarse, settings)
    print(f"coarse net ({COARSE} m edges): {base.iterations} iterations\n")
    print(
        "| edge [m] | DOF | default start: iterations | residual history [N] | "
        "nested start: iterations | residual history [N] |"
    )
    print("|---|---|---|---|---|---|")
    for edge in edges:
        fine, settings = scene(edge)
        dof = 3 * int(np.count_nonzero(~fine.net.fixed))
        t = time.perf_counter()
        plain = solve(fine, settings)
        t_plain = time.perf_counter() - t
        t = time.perf_counter()
        nested = solve(fine, settings, start=Start(interpolated_start(coarse, base.x, fine)))
        t_nested = time.perf_counter() - t
        assert plain.converged and nested.converged
        gap = float(np.max(np.abs(plain.x - nested.x)))

        def hist(r):
            return " ".join(f"{h:.1e}" for h in r.history)

        print(
            f"| {edge:g} | {dof} | {plain.iterations} ({t_plain:.1f} s) | {hist(plain)} | "
            f"{nested.iterations} ({t_nested:.1f} s; same state to {gap:.0e} m) | "
            f"{hist(nested)} |"
        )


if __name__ == "__main__":
    main(tuple(float(a) for a in sys.argv[1:]) or EDGES)
