"""Form finding: the force density method on cable-net roofs of 1e3 to 1e5 edges.

Per net (a square grid with a saddle boundary, uniform q, its own weight off): the linear
method with catenet's default backend (one factorisation of D = C_f^T Q C_f for the three
coordinates, pattern and scatter from the topology), the same with SciPy's SuperLU, and a
plain implementation for reference (D assembled with scipy.sparse products, spsolve per
coordinate); the "forces" method (least squares on log q) to targets from a linear
solution with other force densities. Times are medians of interleaved repeats, the
ratios taken within the run.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from catenet.studies.bench.common import (
    Study,
    interleaved,
    no_progress,
    pyplot,
    save_figure,
    timed,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "formfind"
TITLE = "Form finding (force density method)"

SIZES = (23, 71, 224)  # grid side: about 1e3, 1e4 and 1e5 edges
QUICK_SIZES = (23, 71)
FORCES_MAX_EDGES = 2_000  # the nonlinear method on the smallest net only


def roof(n: int):
    """A roof of 2 n (n - 1) edges: n x n grid on a 30 m square, boundary fixed on
    z = 3 (x^2 - y^2) / 225."""
    from catenet.net import Net

    s = np.linspace(-15.0, 15.0, n)
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
    return Net.from_arrays(nodes, edges, EA=8.0e6, fixed=edge.ravel())


def plain(net, q: np.ndarray) -> np.ndarray:
    """The textbook implementation: incidence matrices, sparse products, spsolve."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    m, n = net.n_edges, net.n_nodes
    rows = np.r_[np.arange(m), np.arange(m)]
    C = sp.csr_matrix((np.r_[-np.ones(m), np.ones(m)], (rows, net.edges.T.ravel())), (m, n))
    free = ~net.fixed
    Cf, Cx = C[:, free], C[:, net.fixed]
    Q = sp.diags(q)
    D = (Cf.T @ Q @ Cf).tocsc()
    b = -(Cf.T @ (Q @ (Cx @ net.nodes[net.fixed])))
    x = net.nodes.copy()
    x[free] = np.column_stack([spsolve(D, b[:, c]) for c in range(3)])
    return x


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    from catenet.formfind import formfind
    from catenet.linsolve import pardiso_available

    out_dir = Path(out_dir)
    sizes = QUICK_SIZES if quick else SIZES
    repeats = 3 if quick else 5
    rows = []
    for done, n in enumerate(sizes):
        progress(done, len(sizes), f"{2 * n * (n - 1)} edges")
        net = roof(n)
        q = np.full(net.n_edges, 2.0e4)
        fns = {
            "default": lambda net=net, q=q: formfind(net, q),
            "scipy": lambda net=net, q=q: formfind(net, q, linear="scipy"),
            "plain": lambda net=net, q=q: plain(net, q),
        }
        t = interleaved(fns, repeats=repeats, warmup=1)
        found = t["default"][2]
        err = float(np.max(np.abs(found.x - t["plain"][2])))
        row = {
            "edges": net.n_edges,
            "free_nodes": int(np.count_nonzero(~net.fixed)),
            "backend": found.backend,
            "linear_s": t["default"][0],
            "scipy_s": t["scipy"][0],
            "plain_s": t["plain"][0],
            "plain_over_linear": t["plain"][0] / t["default"][0],
            "max_diff_to_plain_m": err,
        }
        if net.n_edges <= FORCES_MAX_EDGES:
            rng = np.random.default_rng(0)
            target = formfind(net, rng.uniform(1.0e4, 3.0e4, net.n_edges)).force
            sec, ff = timed(
                lambda net=net, q=q, t=target: formfind(net, q, method="forces", force=t, tol=1e-9)
            )
            row.update(
                forces_s=sec,
                forces_iterations=ff.iterations,
                forces_factorizations=ff.factorizations,
                forces_residual=ff.residual,
            )
        rows.append(row)
    progress(len(sizes), len(sizes))
    csv = write_csv(rows, out_dir / f"{NAME}.csv")
    figure = _figure(rows, out_dir)
    ten = min(rows, key=lambda r: abs(r["edges"] - 1e4))
    backend = ten["backend"]
    summary = [
        f"{r['edges']:>7} edges: linear {r['linear_s'] * 1e3:.1f} ms ({r['backend']}), "
        f"SciPy {r['scipy_s'] * 1e3:.1f} ms, plain spsolve {r['plain_s'] * 1e3:.1f} ms "
        f"({r['plain_over_linear']:.1f}x)"
        + (
            f"; forces {r['forces_s']:.2f} s ({r['forces_iterations']} iterations)"
            if "forces_s" in r
            else ""
        )
        for r in rows
    ]
    findings = []
    if ten["linear_s"] >= 1.0:
        findings.append(
            f"formfind: the linear method on {ten['edges']} edges took {ten['linear_s']:.2f} s "
            "(not well under a second)"
        )
    if backend != "pardiso" and pardiso_available():
        findings.append("formfind: the default backend is not PARDISO although it is available")
    return Study(NAME, rows, csv, figure, findings, summary)


def _figure(rows, out_dir: Path) -> Path:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    m = [r["edges"] for r in rows]
    for key, label in (
        ("linear_s", "catenet formfind (linear)"),
        ("scipy_s", "catenet, SciPy backend"),
        ("plain_s", "plain scipy.sparse + spsolve"),
    ):
        ax.loglog(m, [r[key] for r in rows], "o-", label=label)
    forces = [(r["edges"], r["forces_s"]) for r in rows if "forces_s" in r]
    if forces:
        ax.loglog(*zip(*forces, strict=True), "s--", label='method = "forces"')
    ax.set_xlabel("edges")
    ax.set_ylabel("wall time [s]")
    ax.set_title("Form finding of a cable-net roof")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, out_dir, NAME)
