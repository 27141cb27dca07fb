"""Form finding with compas_fd, as its users call it: the script a whole compas_fd process runs.

    python benchmarks/peers/fd_compas_net.py NET.json Q OUT.json

NET.json is the file of a catenet ``graph`` case (``nodes``, ``edges``, ``fixed``), Q the
force density [N/m] of every edge; ``fd_numpy`` finds the free nodes' positions;
OUT.json gets the positions, the edges' forces and lengths, and ``solve_s`` (the
``fd_numpy`` call alone). Imports only the standard library and compas_fd.
"""

from __future__ import annotations

import json
import sys
import time


def main() -> None:
    from compas_fd.solvers import fd_numpy

    with open(sys.argv[1]) as fh:
        d = json.load(fh)
    edges = [tuple(e) for e in d["edges"]]
    start = time.perf_counter()
    r = fd_numpy(
        vertices=d["nodes"],
        fixed=d["fixed"],
        edges=edges,
        forcedensities=[float(sys.argv[2])] * len(edges),
    )
    solve = time.perf_counter() - start
    with open(sys.argv[3], "w") as fh:
        json.dump(
            {
                "xyz": r.vertices.tolist(),
                "forces": r.forces.ravel().tolist(),
                "lengths": r.lengths.ravel().tolist(),
                "solve_s": solve,
            },
            fh,
        )


if __name__ == "__main__":
    main()
