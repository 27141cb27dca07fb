"""catenet's form finding against compas_fd's, on square roofs of 1e3 to 1e5 edges.

    python benchmarks/peers/formfind_compas.py [--sides 23,71,224] [--out benchmarks/results]

The net (``roof``): an n x n grid on a 30 m square, its boundary fixed on the saddle
z = 3 (x^2 - y^2) / 225, the same force density Q in every edge, no load. Per size, in
rounds (medians; the shared machine's load hits both alike):

- engine, in this process: catenet's ``formfind(net, Q)`` (the Python API; the net built
  before) and the same with ``Net.from_arrays`` included, against compas_fd's
  ``fd_numpy(vertices=, fixed=, edges=, forcedensities=)`` from the lists a JSON file
  gives;
- whole process: ``catenet formfind CASE.toml -o OUT.h5`` (a ``graph`` case reading the
  net's JSON file) against ``python fd_compas_net.py NET.json Q OUT.json`` (read the same
  JSON, ``fd_numpy``, write the positions, forces and lengths as JSON);
- the check: the largest difference of the positions over the span, and of the forces
  over the largest force.

Both on one thread. Writes ``peers-formfind.csv``; ``table.py`` renders it.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ[_var] = "1"  # before NumPy, MKL and Numba load

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from opensees import RESULTS, run_process, write_csv  # noqa: E402

SCRIPT = HERE / "fd_compas_net.py"
SIDES = (23, 71, 224)  # 1012, 9940 and 99904 edges
ROUNDS = {23: 7, 71: 7, 224: 3}
SPAN = 30.0
Q = 2.0e4  # N/m
E, RADIUS, DENSITY = 160e9, 0.006, 7850.0


def roof(n: int) -> dict:
    """nodes, edges and fixed nodes of the n x n roof (lists, as JSON gives them)."""
    s = np.linspace(-0.5 * SPAN, 0.5 * SPAN, n)
    x, y = np.meshgrid(s, s)
    edge = np.zeros((n, n), bool)
    edge[[0, -1], :] = edge[:, [0, -1]] = True
    z = np.where(edge, 3.0 * (x**2 - y**2) / 225.0, 0.0)
    k = np.arange(n * n).reshape(n, n)
    edges = np.vstack(
        [
            np.column_stack([k[:, :-1].ravel(), k[:, 1:].ravel()]),
            np.column_stack([k[:-1, :].ravel(), k[1:, :].ravel()]),
        ]
    )
    nodes = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    return {
        "nodes": nodes.tolist(),
        "edges": edges.tolist(),
        "fixed": np.flatnonzero(edge.ravel()).tolist(),
    }


def write_inputs(folder: Path, n: int, d: dict):
    """NET.json (the graph case's file, which compas_fd's script reads too) and CASE.toml."""
    net_json = folder / f"roof-{n}.json"
    net_json.write_text(json.dumps(d))
    case = folder / f"roof-{n}.toml"
    case.write_text(
        f'title = "roof {n} x {n}"\n'
        f'[geometry]\nkind = "graph"\nfile = "{net_json.name}"\n'
        f"[material]\nE = {E!r}\nradius = {RADIUS!r}\ndensity = {DENSITY!r}\n"
        f'[formfind]\nmethod = "linear"\nforce_density = {Q!r}\n'
        f'[output]\nfile = "{folder / f"roof-{n}.h5"}"\n'
    )
    return net_json, case


def measure(n: int, folder: Path) -> dict:
    from compas_fd.solvers import fd_numpy

    from catenet import Net
    from catenet.formfind import formfind

    d = roof(n)
    net_json, case = write_inputs(folder, n, d)
    EA = E * np.pi * RADIUS**2
    arrays = (np.array(d["nodes"]), np.array(d["edges"]))

    def build():
        return Net.from_arrays(*arrays, EA=EA, fixed=d["fixed"])

    net = build()
    edges = [tuple(e) for e in d["edges"]]
    q = [Q] * len(edges)

    def compas():
        return fd_numpy(vertices=d["nodes"], fixed=d["fixed"], edges=edges, forcedensities=q)

    fns = {
        "catenet": lambda: formfind(net, Q),
        "catenet_with_net": lambda: formfind(build(), Q),
        "compas": compas,
    }
    for f in fns.values():  # warm-up
        f()
    keys = (*fns, "catenet_process", "compas_process")
    times: dict[str, list] = {k: [] for k in keys}
    cpu: dict[str, list] = {k: [] for k in keys}
    peaks: dict[str, list] = {"catenet_process": [], "compas_process": []}
    exe = Path(sys.executable).with_name("catenet")
    out_json = folder / "out.json"
    for _ in range(ROUNDS.get(n, 3)):
        for key, f in fns.items():
            start, c0 = time.perf_counter(), time.process_time()
            value = f()
            times[key].append(time.perf_counter() - start)
            cpu[key].append(time.process_time() - c0)
            if key == "catenet":
                found = value
            elif key == "compas":
                ref = value
        for key, cmd in (
            (
                "catenet_process",
                [str(exe), "formfind", str(case), "-o", str(folder / f"found-{n}.h5"), "-q"],
            ),
            (
                "compas_process",
                [sys.executable, str(SCRIPT), str(net_json), repr(Q), str(out_json)],
            ),
        ):
            p = run_process(cmd)
            if p["code"] != 0:
                raise RuntimeError(f"{key} failed ({p['code']}): {p['stderr']}")
            times[key].append(p["seconds"])
            cpu[key].append(p["cpu_s"])
            peaks[key].append(p["peak_mib"])
        print(
            f"{len(d['edges'])} edges: "
            + ", ".join(f"{k} {v[-1]:.3g} s" for k, v in times.items()),
            flush=True,
        )
    med = {k: statistics.median(v) for k, v in times.items()}
    mc = {k: statistics.median(v) for k, v in cpu.items()}
    other = json.loads(out_json.read_text())
    force = np.asarray(found.force).ravel()
    return {
        "side": n,
        "edges": len(d["edges"]),
        "free_nodes": n * n - len(d["fixed"]),
        "rounds": ROUNDS.get(n, 3),
        "catenet_engine_s": med["catenet"],
        "catenet_engine_with_net_s": med["catenet_with_net"],
        "compas_engine_s": med["compas"],
        "engine_ratio": med["catenet"] / med["compas"],
        "engine_with_net_ratio": med["catenet_with_net"] / med["compas"],
        "catenet_process_s": med["catenet_process"],
        "compas_process_s": med["compas_process"],
        "process_ratio": med["catenet_process"] / med["compas_process"],
        "catenet_engine_cpu_s": mc["catenet"],
        "catenet_engine_with_net_cpu_s": mc["catenet_with_net"],
        "compas_engine_cpu_s": mc["compas"],
        "engine_cpu_ratio": mc["catenet"] / mc["compas"],
        "engine_with_net_cpu_ratio": mc["catenet_with_net"] / mc["compas"],
        "catenet_process_cpu_s": mc["catenet_process"],
        "compas_process_cpu_s": mc["compas_process"],
        "process_cpu_ratio": mc["catenet_process"] / mc["compas_process"],
        "compas_solve_in_process_s": float(other["solve_s"]),
        "catenet_peak_mib": max(peaks["catenet_process"]),
        "compas_peak_mib": max(peaks["compas_process"]),
        "max_dx_over_span": float(np.abs(found.x - np.asarray(ref.vertices)).max()) / SPAN,
        "max_dforce_over_force": float(np.abs(force - np.asarray(ref.forces).ravel()).max())
        / float(np.abs(force).max()),
        "process_max_dx_over_span": float(np.abs(found.x - np.asarray(other["xyz"])).max()) / SPAN,
        "backend": found.backend,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sides", default=",".join(map(str, SIDES)))
    p.add_argument("--out", type=Path, default=RESULTS)
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(int(s), Path(tmp)) for s in a.sides.split(",")]
    write_csv(rows, a.out / "peers-formfind.csv")


if __name__ == "__main__":
    main()
