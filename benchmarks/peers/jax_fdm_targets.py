"""catenet's form finding with targets against jax_fdm's (Pastrana et al. 2023) on a
force-density problem both solve: the spider net of configs/formfind/spider.toml (12
radials, 3 rings, the outer ring fixed), 300 N down at each of its 37 free nodes, its
centre asked 3 m below the ring, one force density per edge (84) within 1 .. 1e5 N/m
from 500 N/m.

    python benchmarks/peers/jax_fdm_targets.py --python /path/to/venv-with-jax_fdm/bin/python

catenet (this process): ``formfind_targets`` on the case (Levenberg-Marquardt, adjoint
Jacobian), run twice, the second timed; jax_fdm (a child process, ``jax_fdm_net.py``):
``constrained_fdm`` with L-BFGS-B on the squared error, gradients by JAX, run twice (the
first compiles), the second timed. Both on one thread. Prints a Markdown table: the
centre's z reached, the evaluations and gradients, CPU and wall time.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ[_var] = "1"  # before NumPy, MKL and Numba load

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SPIDER = ROOT / "configs" / "formfind" / "spider.toml"
LOAD, Q0, Z, BOUNDS = -300.0, 500.0, -3.0, (1.0, 1e5)


def problem() -> tuple[dict, dict]:
    """(the catenet case, the net as jax_fdm_net.py reads it)."""
    case = tomllib.loads(SPIDER.read_text())
    net = json.loads((SPIDER.parent / "spider.json").read_text())
    case["geometry"]["file"] = str(SPIDER.parent / "spider.json")
    free = [k for k in range(len(net["nodes"])) if k not in net["fixed"]]
    case["geometry"]["sets"]["free"] = free
    case["load"] = {"point": [{"node": "free", "force": [0.0, 0.0, LOAD]}]}
    case["formfind"] = {
        "force_density": Q0,
        "force_density_min": BOUNDS[0],
        "force_density_max": BOUNDS[1],
    }
    case["target"] = [{"node": 0, "z": Z}]
    edges = [
        [a, b]
        for c in case["geometry"]["cable"]
        for a, b in zip(c["nodes"], c["nodes"][1:], strict=False)
    ]
    peer = {
        "nodes": net["nodes"],
        "edges": edges,
        "fixed": net["fixed"],
        "loads": [[k, [0.0, 0.0, LOAD]] for k in free],
        "q0": Q0,
        "node": 0,
        "z": Z,
        "q_min": BOUNDS[0],
        "q_max": BOUNDS[1],
        "maxiter": 1000,
        "tol": 1e-14,
    }
    return case, peer


def catenet_side(case: dict) -> dict:
    sys.path.insert(0, str(ROOT))
    from catenet.case import build, parse_case
    from catenet.formfind.case import formfind_scene

    out = {}
    for run in ("first", "again"):
        start, cpu = time.perf_counter(), time.process_time()
        found = formfind_scene(build(parse_case(case)))
        out[run] = {"wall_s": time.perf_counter() - start, "cpu_s": time.process_time() - cpu}
    d = found.design
    out.update(z=float(found.x[0, 2]), evaluations=d.evaluations, gradients=d.gradients)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--python", required=True, help="a Python that imports jax_fdm")
    args = parser.parse_args()
    case, peer = problem()
    ours = catenet_side(case)
    with tempfile.TemporaryDirectory() as tmp:
        net, out = Path(tmp) / "net.json", Path(tmp) / "out.json"
        net.write_text(json.dumps(peer))
        subprocess.run([args.python, str(HERE / "jax_fdm_net.py"), net, out], check=True)
        theirs = json.loads(out.read_text())
    print(
        "| tool | centre z [m] | evaluations / gradients | CPU [s] | wall [s] | first run CPU [s] |"
    )
    print("|---|---|---|---|---|---|")
    for name, r, count in (
        ("catenet", ours, f"{ours['evaluations']} / {ours['gradients']}"),
        ("jax_fdm (L-BFGS-B)", theirs, "see its log"),
    ):
        print(
            f"| {name} | {r['z']:.12g} | {count} | {r['again']['cpu_s']:.3g} | "
            f"{r['again']['wall_s']:.3g} | {r['first']['cpu_s']:.3g} |"
        )


if __name__ == "__main__":
    main()
