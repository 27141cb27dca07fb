"""jax_fdm's side of benchmarks/peers/jax_fdm_targets.py: one process that reads a net
and its target from JSON, finds the force densities with jax_fdm's ``constrained_fdm``
(L-BFGS-B on the squared error, gradients by JAX's automatic differentiation) twice (the
first run compiles), and writes what it found as JSON.

    python jax_fdm_net.py NET.json OUT.json
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ[_var] = "1"
os.environ.setdefault("JAX_ENABLE_X64", "1")  # double precision, as catenet
os.environ.setdefault(
    "XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
)

import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402


def solve(net: dict) -> dict:
    from jax_fdm.datastructures import FDNetwork
    from jax_fdm.equilibrium import constrained_fdm
    from jax_fdm.goals import NodeZCoordinateGoal
    from jax_fdm.losses import Loss, SquaredError
    from jax_fdm.optimization import LBFGSB
    from jax_fdm.parameters import EdgeForceDensityParameter

    nodes = {k: xyz for k, xyz in enumerate(net["nodes"])}
    network = FDNetwork.from_nodes_and_edges(nodes, [tuple(e) for e in net["edges"]])
    for k in net["fixed"]:
        network.node_support(k)
    for k, f in net["loads"]:
        network.node_load(k, f)
    for e in network.edges():
        network.edge_forcedensity(e, net["q0"])
    goals = [NodeZCoordinateGoal(net["node"], net["z"])]
    params = [EdgeForceDensityParameter(e, net["q_min"], net["q_max"]) for e in network.edges()]
    out = {}
    for run in ("first", "again"):
        start, cpu = time.perf_counter(), time.process_time()
        found = constrained_fdm(
            network,
            optimizer=LBFGSB(),
            loss=Loss(SquaredError(goals=goals)),
            parameters=params,
            maxiter=net["maxiter"],
            tol=net["tol"],
        )
        out[run] = {"wall_s": time.perf_counter() - start, "cpu_s": time.process_time() - cpu}
    out["z"] = float(found.node_coordinates(net["node"])[2])
    out["q"] = [float(found.edge_forcedensity(e)) for e in found.edges()]
    return out


if __name__ == "__main__":
    data = json.loads(open(sys.argv[1]).read())
    with open(sys.argv[2], "w") as f:
        json.dump(solve(data), f)
