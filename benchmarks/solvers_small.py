"""The small-system solver's threshold (catenet/solver/banded.py): PARDISO against the
bordered band (LAPACK) on the matrices of one implicit step of the drop
(benchmarks/peers/mujoco_drop.toml: a free box on a square net) at several net sizes,
and of the same nets without the box: CPU time of a factorisation and a checked solve,
each the median of repeats, one thread. ``BAND_MAX_DOF`` is set where the band stops
paying. ``python benchmarks/solvers_small.py`` writes ``results/solvers-small.csv``.
"""

from __future__ import annotations

import csv
import os
import sys
import time
from pathlib import Path

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

SIZES = (4, 6, 8, 10, 12, 14, 18, 22)
SCENE = Path(__file__).resolve().parent / "peers" / "mujoco_drop.toml"
OUT = Path(__file__).resolve().parent / "results" / "solvers-small.csv"


def matrices(n: int, body: bool):
    """A step's matrix of the drop's net of n cables (with or without the box): the
    workspace's pattern, its values near the box's first touch, and the PARDISO
    solver."""
    import tomllib

    from catenet.case import build, parse_case
    from catenet.solver.workspace import Workspace
    from catenet.terms import Inertia

    case = tomllib.loads(SCENE.read_text())
    case["geometry"]["n"] = n
    case["geometry"]["edge_length"] = 0.5 / n
    if not body:
        del case["obstacle"]
    scene = build(parse_case(case))
    ws = Workspace(scene.net, terms=scene.terms, linear="pardiso")
    free = ws.system.free_dofs
    m = np.repeat(scene.net.mass[~scene.net.fixed], 3)
    inertia = Inertia(free)
    inertia.set_step(m / 1e-4, scene.net.nodes.reshape(-1)[free])
    x = scene.net.nodes.copy()
    x[:, 2] -= 0.002 * np.sin(np.pi * (x[:, 0] - x[:, 0].min()) / np.ptp(x[:, 0]))
    data = ws.system.hessian(x, None, (inertia,)).copy()
    return ws, data


def cpu(fn, repeats: int = 30) -> float:
    fn()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        fn()
        times.append(time.process_time() - start)
    return float(np.median(times))


def run(out: Path = OUT) -> list[dict]:
    from catenet.solver.banded import BandLayout, BandSolver

    rows = []
    for body in (True, False):
        for n in SIZES:
            ws, data = matrices(n, body)
            s = ws.system
            pardiso = ws.solver
            layout = BandLayout(s.indptr, s.indices, s.n_free)
            band = BandSolver(s.indptr, s.indices, upper=True, dof_node=pardiso.dof_node,
                              layout=layout, fallback=pardiso)  # fmt: skip
            b = np.ones(s.n_free)

            def both(solver, data=data, b=b):
                solver.factorize(data, definite=False)
                return solver.solve(b)

            x_p, x_b = both(pardiso), both(band)
            row = {
                "body": body,
                "dofs": s.n_free,
                "half_width": layout.p,
                "border": layout.nb,
                "banded": band.stats["band"] > 0,
                "pardiso_ms": 1e3 * cpu(lambda s=pardiso: both(s)),
                "band_ms": 1e3 * cpu(lambda s=band: both(s)),
                "difference": float(np.abs(x_p - x_b).max() / np.abs(x_p).max()),
            }
            row["ratio"] = row["band_ms"] / row["pardiso_ms"]
            rows.append(row)
            print(", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                            for k, v in row.items()), flush=True)  # fmt: skip
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows


if __name__ == "__main__":
    run()
