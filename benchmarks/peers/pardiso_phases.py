"""PARDISO through catenet's binding against pypardiso's solver object, phase by phase.

    python benchmarks/peers/pardiso_phases.py [--sizes 1e4,1e5] [--out benchmarks/results]

catenet calls MKL's PARDISO through its own ctypes binding (``catenet.solver.linear``,
``PardisoSolver``: zero-based CSR passed as it is, its own iparm, one handle kept across a
run's factorisations); pypardiso 0.4 offers ``PyPardisoSolver`` (phases set by
``set_phase``; ``factorize(A)`` = phase 12, ``solve(A, b)`` = phase 33 once it finds A equal
to the matrix it factorised, else 13). Measured on the tangent stiffness of the paper's
square net at its equilibrium (the n = 34 net, 10047 DOF, and the 1e5-DOF net of
``opensees.py``), upper triangle, symmetric positive definite (mtype 2), one thread;
medians of interleaved repeats, all in this one process (CPU time, which a shared machine
inflates less, and wall time):

- ``catenet``: analysis (11), numeric factorisation (22), solve (33) of the binding, and its
  checked ``solve`` (backward error of the first solve after each factorisation);
- ``pypardiso``: the same phases through ``PyPardisoSolver`` with its own iparm (all zero:
  MKL's defaults), ``set_phase`` and ``_call_pardiso`` (the call ``factorize`` and ``solve``
  make), and with catenet's iparm copied in (the wrapper's cost alone);
- ``pypardiso public``: ``factorize(A)`` then ``solve(A, b)``, as its users call it;
- start-up, in fresh processes (medians): ``import pypardiso`` (which makes a solver and
  looks for ``mkl_rt`` at import) against catenet's ``mkl_runtime()``, each after NumPy,
  SciPy and catenet's linear-solver module (with its Numba kernels) are imported.

Writes ``peers-pardiso.csv`` and ``peers-pardiso-startup.csv``; ``table.py`` renders them.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from opensees import RESULTS, SIZES, paper_net, run_process, write_csv  # noqa: E402

REPEATS = {"1e4": 9, "1e5": 5}
STARTUP_REPEATS = 9
FLOOR = "import numpy, scipy.sparse, catenet.solver.linear"  # numba's kernels, no MKL yet
STARTUP = {
    "python: import numpy, scipy.sparse": "import numpy, scipy.sparse",
    "+ import catenet.solver.linear (Numba kernels; no MKL)": FLOOR,
    "+ import pypardiso (finds and loads mkl_rt)": FLOOR + "; import pypardiso",
    "+ catenet's mkl_runtime() (finds and loads mkl_rt)": FLOOR
    + "; catenet.solver.linear.mkl_runtime()",
    "+ import pypardiso, spsolve of a 3x3 system": FLOOR
    + "; import pypardiso, numpy as np"
    + "; pypardiso.spsolve(scipy.sparse.identity(3, format='csr'), np.ones(3))",
}


def tangent(x, net):
    """The tangent stiffness of the tension-only net at positions x: (upper CSR, free
    DOF count). Per edge, k = EA / l0 and K_e = k (t t^T + (1 - l0 / l) (I - t t^T)) for
    l > l0, zero for a slack edge."""
    import scipy.sparse as sp

    a, b = net.edges[:, 0], net.edges[:, 1]
    d = x[b] - x[a]
    length = np.linalg.norm(d, axis=1)
    t = d / length[:, None]
    k = net.EA / net.rest_length
    taut = length > net.rest_length
    tt = t[:, :, None] * t[:, None, :]
    ke = k[:, None, None] * (
        tt + (1.0 - net.rest_length / length)[:, None, None] * (np.eye(3) - tt)
    )
    ke[~taut] = 0.0
    free = ~net.fixed
    dof = -np.ones((len(x), 3), dtype=np.int64)
    dof[free] = np.arange(3 * int(free.sum())).reshape(-1, 3)
    rows, cols, vals = [], [], []
    for p, q, sign in ((a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)):
        r = dof[p][:, :, None].repeat(3, axis=2)
        c = dof[q][:, None, :].repeat(3, axis=1)
        rows.append(r.ravel())
        cols.append(c.ravel())
        vals.append((sign * ke).ravel())
    r, c, v = (np.concatenate(z) for z in (rows, cols, vals))
    keep = (r >= 0) & (c >= 0) & (c >= r)
    n = 3 * int(free.sum())
    K = sp.csr_matrix((v[keep], (r[keep], c[keep])), shape=(n, n))
    K.sum_duplicates()
    K.sort_indices()
    return K


def interleaved(fns: dict, repeats: int) -> dict:
    """key: (median wall time, median CPU time, the last value)."""
    times = {k: [] for k in fns}
    cpu = {k: [] for k in fns}
    out = {}
    for _ in range(repeats):
        for key, f in fns.items():
            start, c0 = time.perf_counter(), time.process_time()
            out[key] = f()
            times[key].append(time.perf_counter() - start)
            cpu[key].append(time.process_time() - c0)
    return {k: (statistics.median(v), statistics.median(cpu[k]), out[k]) for k, v in times.items()}


def phases(label: str) -> list[dict]:
    import pypardiso
    import scipy.sparse as sp

    from catenet import solve_static
    from catenet.solver.linear import PardisoSolver

    sq, loads, force = paper_net(*SIZES[label])
    res = solve_static(sq.net, loads)
    K = tangent(res.x, sq.net)
    n = K.shape[0]
    b = np.random.default_rng(0).standard_normal(n)
    dof_node = np.arange(n) // 3

    Kfull = sp.csr_matrix(K + K.T - sp.diags(K.diagonal()))
    cat = PardisoSolver(K.indptr, K.indices, upper=True, dof_node=dof_node, mtype=2)
    data = np.ascontiguousarray(K.data)
    cat.analyse(data)  # warm: one full pass before timing
    cat.factorize(data)
    cat.solve(b)

    def pp(iparm=None):
        s = pypardiso.PyPardisoSolver(mtype=2)
        if iparm is not None:
            s.iparm[:] = iparm
            s.iparm[34] = 0  # pypardiso passes one-based indices
        return s

    own, same = pp(), pp(cat.iparm)
    public = pp()

    def call(s, phase, rhs=None):
        s.set_phase(phase)
        return s._call_pardiso(K, b if rhs is None else rhs)

    for s in (own, same):
        call(s, 11)
        call(s, 22)
        call(s, 33)
    public.factorize(K)
    public.solve(K, b)

    fns = {
        ("catenet", "analysis"): lambda: cat.analyse(data),
        ("catenet", "factorisation"): lambda: cat._factorize(data),
        ("catenet", "solve"): lambda: cat._solve(b),
        ("catenet", "factorize + checked solve"): lambda: (cat.factorize(data), cat.solve(b))[1],
    }
    for name, s in (("pypardiso, its iparm", own), ("pypardiso, catenet's iparm", same)):
        fns[(name, "analysis")] = lambda s=s: call(s, 11)
        fns[(name, "factorisation")] = lambda s=s: call(s, 22)
        fns[(name, "solve")] = lambda s=s: call(s, 33)
    fns[("pypardiso public", "factorize(A) (phase 12)")] = lambda: public.factorize(K)
    fns[("pypardiso public", "solve(A, b) (phase 33)")] = lambda: public.solve(K, b)
    # spsolve keeps the last factorisation while A is unchanged: a Newton loop changes A
    # every time, so the two matrices alternate (phase 13: analysis, factorisation, solve).
    fulls = [Kfull, Kfull.copy()]
    fulls[1].data *= 1.0 + 1e-15
    fns[("pypardiso.spsolve", "new A each call, full matrix, mtype 11")] = lambda: (
        pypardiso.spsolve(fulls.reverse() or fulls[0], b)
    )
    t = interleaved(fns, REPEATS[label])
    ref = t[("catenet", "solve")][2]
    rows = []
    for (tool, phase), (sec, cpu, value) in t.items():
        solved = isinstance(value, np.ndarray) and "solve" in phase + tool
        x = value.reshape(ref.shape) if solved else None
        rows.append(
            {
                "size": label,
                "dofs": n,
                "nnz_upper": K.nnz,
                "tool": tool,
                "phase": phase,
                "seconds": sec,
                "cpu_s": cpu,
                "over_catenet": cpu / t[("catenet", _base(phase))][1] if _base(phase) else "",
                "max_dx_over_x": float(np.abs(x - ref).max() / np.abs(ref).max())
                if x is not None
                else "",
                "repeats": REPEATS[label],
            }
        )
        print(rows[-1], flush=True)
    return rows


def _base(phase: str) -> str:
    for p in ("analysis", "factorisation", "solve"):
        if phase == p:
            return p
    return ""


def startup() -> list[dict]:
    times = {k: [] for k in STARTUP}
    cpu = {k: [] for k in STARTUP}
    for _ in range(STARTUP_REPEATS):
        for key, code in STARTUP.items():
            p = run_process([sys.executable, "-c", code])
            if p["code"] != 0:
                raise RuntimeError(f"{key}: {p['stderr']}")
            times[key].append(p["seconds"])
            cpu[key].append(p["cpu_s"])
    first = list(STARTUP)[1]
    floor, floor_cpu = statistics.median(times[first]), statistics.median(cpu[first])
    rows = [
        {
            "process": k,
            "seconds": statistics.median(v),
            "cpu_s": statistics.median(cpu[k]),
            "over_floor_s": statistics.median(v) - floor,
            "cpu_over_floor_s": statistics.median(cpu[k]) - floor_cpu,
            "repeats": STARTUP_REPEATS,
        }
        for k, v in times.items()
    ]
    for r in rows:
        print(r, flush=True)
    return rows


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="1e4,1e5")
    p.add_argument("--out", type=Path, default=RESULTS)
    p.add_argument("--startup-only", action="store_true")
    a = p.parse_args()
    write_csv(startup(), a.out / "peers-pardiso-startup.csv")
    if a.startup_only:
        return
    rows = [r for s in a.sizes.split(",") for r in phases(s)]
    write_csv(rows, a.out / "peers-pardiso.csv")


if __name__ == "__main__":
    main()
