"""Cost of mesh-obstacle contact against the mesh's size: is it linear in the nodes and
(nearly) independent of the triangles?

10^4 nodes lie within the activation distance of a sphere meshed with 320 to 20480
triangles (every node in contact: the worst case), and each one moves along a random
step toward it. One evaluation is what a Newton iteration asks: energy and gradient,
the Hessian blocks and the first contact along the step (``max_step``). Timings are
interleaved over the meshes and repeated; the table gives medians and ratios to the
320-triangle mesh, and the same for a grid of one cell (every triangle a candidate of
every node: the quadratic cost the grid avoids) on the smaller meshes.

Usage: ``python benchmarks/mesh_contact.py [-o DIR]`` (writes mesh_contact.csv).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from test_shapes import icosphere  # noqa: E402

from catenet.terms.shapes import MeshBarrier  # noqa: E402

NODES = 10_000
DHAT = 0.01


def one_cell(term: MeshBarrier) -> MeshBarrier:
    """The same term with a grid of one cell holding every triangle."""
    term.h = float(np.ptp(term.vertices, axis=0).max()) + 1.0
    term.dims = np.ones(3, dtype=np.int64)
    term.start = np.array([0, len(term.triangles)], dtype=np.int64)
    term.items = np.arange(len(term.triangles), dtype=np.int64)
    return term


def evaluate(term: MeshBarrier, x: np.ndarray, dx: np.ndarray, grad, values) -> float:
    start = time.perf_counter()
    grad.fill(0.0)
    term.gradient(x, grad)
    term.hessian(x, values)
    term.max_step(x, dx)
    return time.perf_counter() - start


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out", default=str(Path(__file__).parent / "results"))
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    u = rng.standard_normal((NODES, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    x = u * (1.0 + 0.5 * DHAT)  # all within dhat of the unit sphere (and its meshes)
    dx = -0.2 * u + 0.05 * rng.standard_normal((NODES, 3))
    nodes = np.arange(NODES)
    terms = {}
    for level in (2, 3, 4, 5):
        V, T = icosphere(level)
        V = V * (1.0 - 0.02 * 4.0**-level)  # inside the circumscribed sphere: no overlap
        terms[("grid", len(T))] = MeshBarrier(nodes, V, T, kappa=1.0, dhat=DHAT)
        if level <= 3:
            terms[("all", len(T))] = one_cell(MeshBarrier(nodes, V, T, kappa=1.0, dhat=DHAT))
    grad = np.zeros_like(x)
    values = np.zeros(9 * NODES)
    for term in terms.values():
        assert term.gap(x).min() > 0
        evaluate(term, x, dx, grad, values)  # compile
    times: dict = {k: [] for k in terms}
    for _ in range(args.repeats):
        for key, term in terms.items():
            times[key].append(evaluate(term, x, dx, grad, values))
    base = float(np.median(times[("grid", 320)]))
    rows = []
    for (how, n_tri), ts in times.items():
        med = float(np.median(ts))
        rows.append(
            {
                "candidates": how,
                "triangles": n_tri,
                "nodes": NODES,
                "seconds_per_evaluation": f"{med:.4g}",
                "ratio_to_320_grid": f"{med / base:.3g}",
            }
        )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "mesh_contact.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(
            f"{r['candidates']:>5} {r['triangles']:>6} triangles: {r['seconds_per_evaluation']} s"
            f" per evaluation ({r['ratio_to_320_grid']} x the 320-triangle grid)"
        )


if __name__ == "__main__":
    main()
