"""A cable net in OpenSees, as its users set one up: the script a whole OpenSees process runs.

    python benchmarks/peers/opensees_net.py NET.npz OUT.npz [--system SparseSYM] [--repeat 1]

NET.npz holds the net (``nodes`` (N, 3), ``edges`` (M, 2), ``fixed`` (N,) bool, ``force``
(N, 3) [N], ``EA`` [N]) and the analysis settings (``pretension``: the initial strain,
``tol``: NormUnbalance tolerance [N]). Every edge is a ``corotTruss`` (area 1, so E = EA)
of a tension-only elastic material (``Elastic`` with Eneg = 0) under a tiny pretension
(``InitStrainMaterial``): a flat net without one has no transverse stiffness and a singular
first tangent. The load is applied in ONE step (LoadControl 1.0), plain Newton, the
NormUnbalance test. OUT.npz gets the final positions ``x`` and the timings: ``build_s``
(the model's commands), ``analyze_s`` and ``analyze_cpu_s`` (wall and CPU time, one per
repeat; each repeat rebuilds the model), ``iterations``, ``residual`` (the last
NormUnbalance [N]), ``norms`` (all of them) and ``ok`` (analyze's return code, 0 =
converged).

Imports only NumPy and openseespy. openseespy 3.7's Linux wheel does not find its own
``libblas.so.3``: it is loaded first.
"""

from __future__ import annotations

import argparse
import ctypes
import importlib.util
import os
import time


def load_openseespy():
    spec = importlib.util.find_spec("openseespylinux")
    if spec is not None:  # the Linux wheel's bundled BLAS, which it does not find itself
        lib = os.path.join(spec.submodule_search_locations[0], "lib", "libblas.so.3")
        if os.path.exists(lib):
            ctypes.CDLL(lib, mode=ctypes.RTLD_GLOBAL)
    import openseespy.opensees as ops

    return ops


def build(ops, d, system: str) -> None:
    """The model and the analysis, from the arrays of ``d``."""
    import numpy as np

    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 3)
    for k, p in enumerate(d["nodes"].tolist()):
        ops.node(k + 1, *p)
    for k in np.flatnonzero(d["fixed"]).tolist():
        ops.fix(k + 1, 1, 1, 1)
    ops.uniaxialMaterial("Elastic", 1, float(d["EA"]), 0.0, 0.0)  # no compression
    ops.uniaxialMaterial("InitStrainMaterial", 2, 1, float(d["pretension"]))
    for k, (a, b) in enumerate(d["edges"].tolist()):
        ops.element("corotTruss", k + 1, a + 1, b + 1, 1.0, 2)
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    force = d["force"]
    for k in np.flatnonzero(np.any(force != 0.0, axis=1)).tolist():
        ops.load(k + 1, *force[k].tolist())
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system(system)
    ops.test("NormUnbalance", float(d["tol"]), 200)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("net")
    p.add_argument("out")
    p.add_argument("--system", default="SparseSYM")
    p.add_argument("--repeat", type=int, default=1)
    a = p.parse_args()
    ops = load_openseespy()
    import numpy as np

    d = dict(np.load(a.net))
    builds, analyses, cpu = [], [], []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        build(ops, d, a.system)
        t1, c1 = time.perf_counter(), time.process_time()
        ok = ops.analyze(1)
        t2 = time.perf_counter()
        cpu.append(time.process_time() - c1)
        builds.append(t1 - t0)
        analyses.append(t2 - t1)
    iterations = ops.testIter()
    norms = ops.testNorm() if hasattr(ops, "testNorm") else []
    n = len(d["nodes"])
    x = np.array([ops.nodeCoord(k + 1) for k in range(n)]) + np.array(
        [ops.nodeDisp(k + 1) for k in range(n)]
    )
    np.savez(
        a.out,
        x=x,
        build_s=np.array(builds),
        analyze_s=np.array(analyses),
        analyze_cpu_s=np.array(cpu),
        iterations=iterations,
        residual=norms[iterations - 1] if 0 < iterations <= len(norms) else float("nan"),
        norms=np.array(norms, dtype=float),  # the test's norm at every iteration
        ok=ok,
        version=str(ops.version()) if hasattr(ops, "version") else "",
    )


if __name__ == "__main__":
    main()
