"""catenet against OpenSees on the paper's square net, from 1e3 to 1e6 DOF.

    python benchmarks/peers/opensees.py [--sizes 1e3,1e4,...] [--out benchmarks/results]

OpenSees is set up as its users would (``opensees_net.py``): ``corotTruss`` elements, a
tension-only elastic material under a tiny pretension (``InitStrainMaterial``, strain
PRETENSION), the whole load in ONE step, plain Newton, SYSTEM as the linear solver (the
fastest of OpenSees' sparse solvers that converged: see ``--systems``), NormUnbalance <=
RTOL |f| (catenet: |residual| <= RTOL max(|f|, |internal force|)). Both run on one thread.

First the check (``--check``, the n = 34 net, catenet at RTOL_CHECK, OpenSees at
OPENSEES_RTOL_CHECK: each near its round-off floor): OpenSees against catenet on
the same pretensioned net. OpenSees' ``InitStrainMaterial`` gives the force
EA ((l - l0) / l0 + e0) = (EA / l0) (l - l0 (1 - e0)); catenet's edge gives
(EA' / r) (l - r): rest length r = l0 (1 - e0) and EA' = EA (1 - e0) make them the same
law, so the two must agree to their tolerance; catenet without the pretension differs by
its cross term only.

Then per size, in rounds (so that the shared machine's load hits both alike; medians):

- engine: catenet's ``solve_static`` in this process (a fresh Workspace each time, as
  ``catenet run`` does; after a warm-up), against OpenSees' ``analyze(1)`` in a process
  that built and analysed the model once before (warm; at 1e6 DOF the one analysis of
  the whole process);
- whole process: ``catenet run CASE.toml`` (parse, build, solve, write the HDF5 result;
  Numba's cache warm) against ``python opensees_net.py NET.npz OUT.npz`` (import
  openseespy, read the arrays, build, analyse, write the positions);
- Newton iterations, each process's peak resident memory (GNU time's %M) and the largest
  difference of the two equilibria over catenet's centre deflection.

Writes ``peers-opensees.csv`` and ``peers-opensees-check.csv``; ``table.py`` renders them.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ[_var] = "1"  # before NumPy, MKL and Numba load: one thread, both tools

import argparse  # noqa: E402
import csv  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import re  # noqa: E402
import signal  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
SCRIPT = HERE / "opensees_net.py"
RESULTS = HERE.parent / "results"

# The paper's net (L = 1 m, E = 10 MPa, r = 1 cm, p = 100 Pa), refined both ways: n cables,
# edge length [m]. DOF: 975, 10047, 28623, 97848, 288207, 958800.
SIZES = {
    "1e3": (10, 0.03),
    "1e4": (34, 0.01),
    "3e4": (58, 1 / 170),
    "1e5": (108, 1 / 320),
    "3e5": (186, 1 / 550),
    "1e6": (340, 0.001),
}
ROUNDS = {"1e3": 7, "1e4": 7, "3e4": 5, "1e5": 3, "3e5": 2, "1e6": 1}
E, RADIUS, DENSITY, PRESSURE, SIZE = 10e6, 0.01, 1000.0, 100.0, 1.0
PRETENSION = 1e-12
RTOL = 1e-8
RTOL_CHECK = 1e-12  # catenet: its round-off floor ends it (about 6e-10 N here)
OPENSEES_RTOL_CHECK = 1e-10  # OpenSees' floor: NormUnbalance stalls near 3e-11 N here
SYSTEM = "SparseSYM"
SYSTEMS = ("SparseSYM", "UmfPack", "Mumps", "SparseGeneral", "ProfileSPD", "BandSPD")
TIMEOUT = 600.0


def paper_net(n: int, edge: float):
    """(SquareNet, Loads, force (N, 3)) through catenet's public API."""
    from catenet import Loads, Material, pressure_force, square_net

    material = Material.from_E(E, radius=RADIUS, density=DENSITY, tension_only=True)
    sq = square_net(n, 0.0, SIZE, edge, material)
    force = pressure_force(sq.net, PRESSURE, SIZE)
    return sq, Loads(force=force), force


def write_inputs(folder: Path, n: int, edge: float, sq, force, tol: float):
    """The OpenSees arrays (NET.npz) and the catenet case (CASE.toml) of one net."""
    net = sq.net
    npz = folder / f"net-{n}.npz"
    np.savez(
        npz,
        nodes=net.nodes,
        edges=net.edges,
        fixed=net.fixed,
        force=force,
        EA=float(net.EA[0]),
        pretension=PRETENSION,
        tol=tol,
    )
    case = folder / f"net-{n}.toml"
    case.write_text(
        f'title = "square net n = {n}, edge {edge!r} m"\n'
        f'[geometry]\nkind = "square_net"\nn = {n}\nalpha = 0.0\nsize = {SIZE!r}\n'
        f"edge_length = {edge!r}\n"
        f"[material]\nE = {E!r}\nradius = {RADIUS!r}\ndensity = {DENSITY!r}\n"
        f"[load]\npressure = {PRESSURE!r}\n"
        f'[solver]\nmethod = "static"\nrtol = {RTOL!r}\n'
        f'[output]\nfile = "{folder / f"out-{n}.h5"}"\n'
    )
    return npz, case


def run_process(cmd: list, timeout: float | None = None) -> dict:
    """Wall time, CPU time (user + system), peak resident memory [MiB], exit code and
    stdout of one child process.

    The child runs under GNU time, which reports its peak: Linux carries a process's
    resident high-water mark across fork and exec, so ``ru_maxrss`` of a child forked from
    this (large) process would include this process's own memory."""
    timeout = TIMEOUT if timeout is None else timeout
    with tempfile.TemporaryDirectory() as tmp:
        peak = Path(tmp) / "peak"
        start = time.perf_counter()
        p = subprocess.Popen(
            ["/usr/bin/time", "-f", "%M %U %S", "-o", str(peak), *map(str, cmd)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,  # its own process group: a timeout ends the child too
        )
        try:
            out, err = p.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.communicate()
            raise
        wall = time.perf_counter() - start
        words = peak.read_text().split() if peak.exists() else []
        ok = len(words) >= 3
        return {
            "seconds": wall,
            "peak_mib": float(words[-3]) / 1024.0 if ok else math.nan,
            "cpu_s": float(words[-2]) + float(words[-1]) if ok else math.nan,
            "code": p.returncode,
            "stdout": out.decode(errors="replace"),
            "stderr": err.decode(errors="replace")[-2000:],
        }


def opensees(npz: Path, out: Path, *, repeat: int, system: str = SYSTEM) -> dict:
    """One OpenSees process: its wall time and peak memory, and what it wrote."""
    proc = run_process(
        [
            sys.executable,
            str(SCRIPT),
            str(npz),
            str(out),
            "--system",
            system,
            "--repeat",
            str(repeat),
        ]
    )
    if proc["code"] != 0 or not out.exists():
        raise RuntimeError(f"OpenSees failed ({proc['code']}): {proc['stderr']}")
    d = dict(np.load(out))
    out.unlink()
    return {**proc, **d}


def catenet_run(case: Path) -> dict:
    """One ``catenet run`` process: wall time, peak memory, its Newton iterations."""
    exe = Path(sys.executable).with_name("catenet")
    proc = run_process([str(exe), "run", str(case)])
    if proc["code"] != 0:
        raise RuntimeError(f"catenet run failed ({proc['code']}): {proc['stderr']}")
    m = re.search(r"(\d+) Newton iterations", proc["stdout"])
    proc["iterations"] = int(m.group(1)) if m else -1
    return proc


def catenet_engine(net, loads, rtol: float = RTOL):
    from catenet import solve_static

    start = time.perf_counter()
    res = solve_static(net, loads, rtol=rtol)
    return time.perf_counter() - start, res


def pretensioned(net, e0: float):
    """catenet's net with OpenSees' InitStrainMaterial law (see the module's text)."""
    from catenet import Net

    return Net.from_arrays(
        net.nodes,
        net.edges,
        EA=net.EA * (1.0 - e0),
        fixed=net.fixed,
        rest_length=net.rest_length * (1.0 - e0),
        tension_only=True,
    )


def check(folder: Path, systems=SYSTEMS, rtol: float = RTOL_CHECK) -> list[dict]:
    """The n = 34 net at RTOL_CHECK: every OpenSees system against catenet, with and
    without OpenSees' pretension."""
    sq, loads, force = paper_net(*SIZES["1e4"])
    tol = OPENSEES_RTOL_CHECK * float(np.linalg.norm(force[~sq.net.fixed]))
    npz, _ = write_inputs(folder, 34, SIZES["1e4"][1], sq, force, tol)
    _, same = catenet_engine(pretensioned(sq.net, PRETENSION), loads, rtol)
    _, plain = catenet_engine(sq.net, loads, rtol)
    delta = -float(same.x[sq.center, 2])
    rows = []
    for system in systems:
        o = opensees(npz, folder / "check.npz", repeat=2, system=system)
        rows.append(
            {
                "system": system,
                "rtol": rtol,
                "ok": int(o["ok"]),
                "iterations": int(o["iterations"]),
                "analyze_s": float(o["analyze_s"][-1]),
                "delta_m": -float(o["x"][sq.center, 2]),
                "catenet_delta_m": delta,
                "diff_same_law": float(np.abs(o["x"] - same.x).max()) / delta,
                "diff_no_pretension": float(np.abs(o["x"] - plain.x).max()) / delta,
                "catenet_same_vs_none": float(np.abs(same.x - plain.x).max()) / delta,
                "catenet_iterations": same.iterations,
                "catenet_residual_n": float(same.residual),
                "opensees_residual_n": float(o["residual"]),
                "tol_n": tol,
            }
        )
        print(rows[-1], flush=True)
    return rows


def measure(label: str, folder: Path, match: bool = False) -> dict:
    """One size: rounds of the four timings; medians. ``match``: OpenSees' tolerance is
    the residual catenet reached where that is larger than RTOL |f| (at 1e6 DOF,
    RTOL |f| is below the round-off floor of the residual)."""
    n, edge = SIZES[label]
    sq, loads, force = paper_net(n, edge)
    net = sq.net
    f_norm = float(np.linalg.norm(force[~net.fixed]))
    big = label == "1e6"
    _, first = catenet_engine(net, loads)  # warm-up
    tol = max(RTOL * f_norm, float(first.residual)) if match else RTOL * f_norm
    npz, case = write_inputs(folder, n, edge, sq, force, tol)
    keys = ("ce", "oe", "cr", "or", "ce_cpu", "oe_cpu", "cr_cpu", "or_cpu")
    times: dict[str, list] = {k: [] for k in keys}
    peaks: dict[str, list] = {"cr": [], "or": []}
    for _ in range(ROUNDS[label]):
        cpu = time.process_time()
        t, res = catenet_engine(net, loads)
        times["ce_cpu"].append(time.process_time() - cpu)
        times["ce"].append(t)
        if not big:
            o = opensees(npz, folder / "oe.npz", repeat=2)
            times["oe"].append(float(o["analyze_s"][-1]))
            times["oe_cpu"].append(float(o["analyze_cpu_s"][-1]))
        c = catenet_run(case)
        times["cr"].append(c["seconds"])
        times["cr_cpu"].append(c["cpu_s"])
        peaks["cr"].append(c["peak_mib"])
        try:
            w = opensees(npz, folder / "or.npz", repeat=1)
        except subprocess.TimeoutExpired:  # skipped, and said so in the row
            w = {
                "seconds": math.nan,
                "peak_mib": math.nan,
                "analyze_s": [math.nan],
                "analyze_cpu_s": [math.nan],
                "cpu_s": math.nan,
                "build_s": [math.nan],
                "iterations": -1,
                "ok": -99,
                "version": "",
                "x": np.full_like(res.x, math.nan),
            }
        times["or"].append(w["seconds"])
        times["or_cpu"].append(w["cpu_s"])
        peaks["or"].append(w["peak_mib"])
        if big:
            times["oe"].append(float(w["analyze_s"][0]))
            times["oe_cpu"].append(float(w["analyze_cpu_s"][0]))
        print(
            f"{label}: catenet {t:.3g} s / {c['seconds']:.3g} s, OpenSees "
            f"{times['oe'][-1]:.3g} s / {w['seconds']:.3g} s",
            flush=True,
        )
    delta = -float(res.x[sq.center, 2])
    med = {k: statistics.median(v) for k, v in times.items()}
    return {
        "size": label,
        "n": n,
        "edge_m": edge,
        "dofs": 3 * int((~net.fixed).sum()),
        "edges": net.n_edges,
        "rounds": ROUNDS[label],
        "catenet_engine_s": med["ce"],
        "opensees_engine_s": med["oe"],
        "opensees_engine_warm": not big,
        "engine_ratio": med["oe"] / med["ce"],
        "catenet_process_s": med["cr"],
        "opensees_process_s": med["or"],
        "process_ratio": med["or"] / med["cr"],
        "opensees_build_s": float(w["build_s"][0]),
        "catenet_iterations": res.iterations,
        "catenet_run_iterations": c["iterations"],
        "opensees_iterations": int(w["iterations"]),
        "opensees_ok": int(w["ok"]),  # -99: stopped after TIMEOUT s
        "catenet_engine_cpu_s": med["ce_cpu"],
        "opensees_engine_cpu_s": med["oe_cpu"],
        "engine_cpu_ratio": med["oe_cpu"] / med["ce_cpu"],
        "catenet_process_cpu_s": med["cr_cpu"],
        "opensees_process_cpu_s": med["or_cpu"],
        "process_cpu_ratio": med["or_cpu"] / med["cr_cpu"],
        "catenet_peak_mib": max(peaks["cr"]),
        "opensees_peak_mib": max(peaks["or"]),
        "delta_m": delta,
        "max_diff_over_delta": float(np.abs(w["x"] - res.x).max()) / delta,
        "catenet_residual_n": float(res.residual),
        "tol_n": RTOL * f_norm,
        "opensees_tol_n": tol,
        "opensees_version": str(w["version"]),
        "system": SYSTEM,
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, shared",
    }


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def write_csv(rows: list[dict], path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        names = list(dict.fromkeys(k for r in rows for k in r))  # every row's, in order
        w = csv.DictWriter(fh, fieldnames=names, restval="")
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {path}")


def main() -> None:
    global TIMEOUT
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default=",".join(SIZES), help="of " + ", ".join(SIZES))
    p.add_argument("--out", type=Path, default=RESULTS)
    p.add_argument("--check", action="store_true", help="run the check only")
    p.add_argument("--no-check", action="store_true", help="skip the check")
    p.add_argument("--systems", default=",".join(SYSTEMS), help="OpenSees systems to check")
    p.add_argument("--rtol-check", type=float, default=RTOL_CHECK)
    p.add_argument("--timeout", type=float, default=TIMEOUT, help="per process [s]")
    p.add_argument(
        "--match-residual",
        action="store_true",
        help="OpenSees' tolerance: the residual catenet reached, where larger than RTOL |f|",
    )
    a = p.parse_args()
    TIMEOUT = a.timeout
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if not a.no_check:
            rows = check(folder, a.systems.split(","), a.rtol_check)
            write_csv(rows, a.out / "peers-opensees-check.csv")
        if a.check:
            return
        sq, _, force = paper_net(*SIZES["1e3"])  # the JIT cache of `catenet run`: warm
        catenet_run(write_inputs(folder, 10, SIZES["1e3"][1], sq, force, 1.0)[1])
        path = a.out / "peers-opensees.csv"
        for label in a.sizes.split(","):  # each size replaces its row; the file after each
            row = measure(label, folder, a.match_residual)
            old = read_csv(path) if path.exists() else []
            rows = [r for r in old if r["size"] != label] + [row]
            write_csv(sorted(rows, key=lambda r: int(r["dofs"])), path)


if __name__ == "__main__":
    main()
