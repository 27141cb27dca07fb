"""The 10 lowest natural modes of a large prestressed net against a static solve of it.

For each size, in a fresh process (so that its peak memory is its own): the paper's
square net (alpha = 0, L = 10 m, two edges per segment between crossings, E = 10 MPa,
r = 1 cm, rho = 1000 kg/m^3, 100 N of prestress, p = 10 Pa), its workspace (pattern and
symbolic analysis, shared), the static solve (`catenet run`'s path), then the 10 lowest
modes about the equilibrium (`catenet modes`' path: one factorisation of K - sigma M,
shift-invert Lanczos). Reports the seconds of each, their ratio (modes / static), the
Lanczos solves, and the process's peak resident memory. Threads as `catenet run`
sets them (solver.threads, default 1: on a shared machine OpenBLAS's spinning threads
slow ARPACK's short vector operations down tenfold).

Usage: `python benchmarks/modes.py [--sizes 1e5,1e6] [-o benchmarks/results]`: a table
on stdout and `modes.csv` in the output directory. `--worker DOFS` runs one size (used
by the script itself).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CASE = """\
[geometry]
kind = "square_net"
n = {n}
alpha = 0.0
size = 10.0
edge_length = {edge!r}
[material]
E = 10e6
radius = 0.01
density = 1000.0
prestress = 100.0
[load]
pressure = 10.0
[solver]
linear = "{linear}"
"""


def net_for(dofs: float) -> tuple[int, float]:
    """(n, edge_length) of a square net with about ``dofs`` free DOFs: m = n/2 cables per
    family at spacing d = L / (m + 1), two edges per segment: about 3 m^2 free nodes."""
    m = max(3, int(round(math.sqrt(dofs / 9.0))))
    m += 1 - m % 2  # odd: a joint at the centre
    return 2 * m, 10.0 / (m + 1) / 2


def worker(dofs: float, linear: str) -> dict:
    from catenet.case import build, load_case
    from catenet.solver import path as sv
    from catenet.solver.modes import natural_modes
    from catenet.solver.threads import set_threads

    n, edge = net_for(dofs)
    with tempfile.TemporaryDirectory() as tmp:
        case_file = Path(tmp) / "net.toml"
        case_file.write_text(CASE.format(n=n, edge=edge, linear=linear))
        case = load_case(case_file, ())
    scene = build(case)
    set_threads(case.solver.threads)  # as catenet run and catenet modes do (default 1)
    settings = sv.Settings.of(case.solver)
    begin = time.perf_counter()
    ws = sv.workspace(scene, settings)
    setup = time.perf_counter() - begin
    begin = time.perf_counter()
    result = sv.solve(scene, settings, workspace=ws)
    static = time.perf_counter() - begin
    factorizations = ws.solver.stats["factorize"]
    begin = time.perf_counter()
    modes = natural_modes(ws, result.x, 10)
    seconds = time.perf_counter() - begin
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # MB (Linux: kB)
    return {
        "dofs": int(ws.system.n_free),
        "n": n,
        "backend": ws.solver.name,
        "setup_s": round(setup, 3),
        "static_s": round(static, 3),
        "static_newton": int(result.iterations),
        "static_factorizations": int(factorizations),
        "modes_s": round(seconds, 3),
        "ratio": round(seconds / static, 3),
        "factorize_s": round(modes.stats.get("factorize_seconds", 0.0), 3),
        "lanczos_solves": int(modes.stats.get("solves", 0)),
        "f1_hz": float(modes.frequency[0]),
        "f10_hz": float(modes.frequency[-1]),
        "residual": float(modes.stats["residual"]),
        "peak_mb": round(peak, 1),
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1e5", help="free DOFs, comma-separated")
    parser.add_argument("-o", "--output", default="benchmarks/results")
    parser.add_argument("--linear", default="auto")
    parser.add_argument("--worker", type=float, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker is not None:
        print(json.dumps(worker(args.worker, args.linear)))
        return
    rows = []
    for size in (float(s) for s in args.sizes.split(",")):
        done = subprocess.run(
            [sys.executable, __file__, "--worker", repr(size), "--linear", args.linear],
            capture_output=True, text=True, env=os.environ.copy(),
        )  # fmt: skip
        if done.returncode != 0:
            sys.exit(f"size {size:g}: failed\n{done.stderr}")
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        r = rows[-1]
        print(
            f"{r['dofs']:>9} DOFs ({r['backend']}): static {r['static_s']:.3g} s "
            f"({r['static_factorizations']} factorisations), 10 modes {r['modes_s']:.3g} s "
            f"({r['lanczos_solves']} solves), ratio {r['ratio']:.3g}, peak {r['peak_mb']:.0f} MB, "
            f"f1 = {r['f1_hz']:.5g} Hz",
            flush=True,
        )
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "modes.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
