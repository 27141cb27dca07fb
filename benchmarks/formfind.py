"""Form finding: the force density method on cable-net roofs of 1e3 to 1e5 edges.

Per net (a square grid with a saddle boundary, uniform q, its own weight off): the linear
method with catenet's default backend (one factorisation of D = C_f^T Q C_f for the three
coordinates, pattern and scatter from the topology), the same with SciPy's SuperLU, and a
plain implementation for reference (D assembled with scipy.sparse products, spsolve per
coordinate); the "forces" and "lengths" methods (damped Newton on log q) to the
forces and lengths of a linear solution with other force densities. Times are medians
of interleaved repeats, the ratios taken within the run.

Loaded: the roof of about 1e5 DOF (LOADED_N: 183 x 183 nodes) form-found (uniform q),
made tension-only, then its nonlinear static analysis under snow (SNOW [N/m^2] on the
plan area, lumped at the free nodes), each from a new Workspace, interleaved with the
static solve of the paper's square net of the same DOF count (``paper_net``, as in the
scale study): their ratio is the cost of the loaded analysis in static solves. The paper's
net is mostly chains of subdivided cables between crossings, so one factorisation of it
costs a fraction of one of the roof's grid, where every node is a joint of four edges;
the like-for-like reference is therefore also measured: the static solve of the same grid
flat and unstressed (boundary at z = 0, rest lengths = lengths) under the same snow, the
paper's kind of scene on the roof's topology.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/formfind.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging

import numpy as np

from benchmarks.common import (
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
LOADED_N, LOADED_SQUARE = 183, (108, 1 / 320)  # ~1e5 DOF each (98 283 and 97 848)
QUICK_LOADED_N, QUICK_LOADED_SQUARE = 58, (34, 0.01)  # ~1e4 DOF each
SNOW = 1000.0  # N/m^2


def roof(n: int):
    """A roof of 2 n (n - 1) edges: n x n grid on a 30 m square, boundary fixed on
    z = 3 (x^2 - y^2) / 225."""
    from catenet.model.net import Net

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
    from catenet.solver.linear import pardiso_available

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
                functools.partial(formfind, net, q, method="forces", force=target, tol=1e-9)
            )
            row.update(
                forces_s=sec,
                forces_iterations=ff.iterations,
                forces_factorizations=ff.factorizations,
                forces_residual=ff.residual,
            )
            goal = formfind(net, rng.uniform(1.0e4, 3.0e4, net.n_edges)).length
            sec, fl = timed(
                functools.partial(formfind, net, q, method="lengths", length=goal, tol=1e-9)
            )
            row.update(
                lengths_s=sec, lengths_iterations=fl.iterations, lengths_residual=fl.residual
            )
        rows.append(row)
    progress(len(sizes), len(sizes), "loaded roof")
    n, square = (QUICK_LOADED_N, QUICK_LOADED_SQUARE) if quick else (LOADED_N, LOADED_SQUARE)
    rows.append(loaded(n, square, repeats=1 if not quick else 2))
    progress(len(sizes), len(sizes))
    csv = write_csv(rows, out_dir / f"{NAME}.csv")
    figure = _figure(rows, out_dir)
    last = rows.pop()  # the loaded roof: its own lines
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
    summary.append(
        f"loaded roof, {last['loaded_dofs']} DOF: form finding {last['loaded_formfind_s']:.2f} s, "
        f"static analysis under snow {last['loaded_static_s']:.2f} s "
        f"({last['loaded_iterations']} Newton iterations); square net, "
        f"{last['square_dofs']} DOF: {last['square_static_s']:.2f} s "
        f"({last['square_iterations']}): ratio {last['loaded_over_square']:.2f} "
        f"({last['loaded_total_over_square']:.2f} with the form finding); the same grid "
        f"flat and unstressed under the same snow: {last['flat_static_s']:.2f} s "
        f"({last['flat_iterations']}): ratio {last['loaded_over_flat']:.2f} "
        f"({last['loaded_total_over_flat']:.2f} with the form finding)"
    )
    rows.append(last)
    findings = []
    if not (last["loaded_converged"] and last["flat_converged"]):
        findings.append("formfind: the loaded roof or its flat reference did not converge")
    if ten["linear_s"] >= 1.0:
        findings.append(
            f"formfind: the linear method on {ten['edges']} edges took {ten['linear_s']:.2f} s "
            "(not well under a second)"
        )
    if backend != "pardiso" and pardiso_available():
        findings.append("formfind: the default backend is not PARDISO although it is available")
    return Study(NAME, rows, csv, figure, findings, summary)


def loaded(n: int, square: tuple, *, repeats: int) -> dict:
    """The form-found roof's static analysis under snow against the square net's static
    solve of the same size, interleaved: one row."""
    from benchmarks.common import paper_net
    from catenet.formfind import formfind
    from catenet.model.net import Loads, Net
    from catenet.solver.static import Workspace, solve_static

    net = roof(n)
    found = formfind(net, 2.0e4)  # (warm: timed below, interleaved)
    built = Net.from_arrays(
        found.x,
        net.edges,
        EA=net.EA,
        fixed=net.fixed,
        rest_length=found.rest_length(),
        tension_only=True,
    )
    snow = np.zeros((net.n_nodes, 3))
    snow[~net.fixed, 2] = -SNOW * (30.0 / (n - 1)) ** 2
    sq, sq_loads = paper_net(square[0], edge=square[1])
    plane = net.nodes * np.array([1.0, 1.0, 0.0])
    flat = Net.from_arrays(plane, net.edges, EA=net.EA, fixed=net.fixed, tension_only=True)
    fns = {
        "formfind": lambda: formfind(net, 2.0e4),
        "roof": lambda: solve_static(built, Loads(force=snow), workspace=Workspace(built)),
        "square": lambda: solve_static(sq.net, sq_loads, workspace=Workspace(sq.net)),
        "flat": lambda: solve_static(flat, Loads(force=snow), workspace=Workspace(flat)),
    }
    t = interleaved(fns, repeats=repeats, warmup=1)
    res, ref, ff_s = t["roof"][2], t["square"][2], t["formfind"][0]
    reaction = float(np.abs(res.reaction.sum(axis=0) + snow.sum(axis=0)).max())
    return {
        "edges": net.n_edges,
        "free_nodes": int(np.count_nonzero(~net.fixed)),
        "backend": found.backend,
        "loaded_dofs": 3 * int(np.count_nonzero(~net.fixed)),
        "loaded_formfind_s": ff_s,
        "loaded_static_s": t["roof"][0],
        "loaded_iterations": res.iterations,
        "loaded_converged": bool(res.converged),
        "loaded_max_deflection_m": float(np.max(found.x[:, 2] - res.x[:, 2])),
        "loaded_reaction_balance_n": reaction,
        "square_dofs": 3 * int(np.count_nonzero(~sq.net.fixed)),
        "square_static_s": t["square"][0],
        "square_iterations": ref.iterations,
        "loaded_over_square": t["roof"][0] / t["square"][0],
        "loaded_total_over_square": (ff_s + t["roof"][0]) / t["square"][0],
        "flat_static_s": t["flat"][0],
        "flat_iterations": t["flat"][2].iterations,
        "flat_converged": bool(t["flat"][2].converged),
        "loaded_over_flat": t["roof"][0] / t["flat"][0],
        "loaded_total_over_flat": (ff_s + t["roof"][0]) / t["flat"][0],
    }


def _figure(rows, out_dir: Path) -> Path:
    rows = [r for r in rows if r.get("linear_s")]
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
    lengths = [(r["edges"], r["lengths_s"]) for r in rows if r.get("lengths_s")]
    if lengths:
        ax.loglog(*zip(*lengths, strict=True), "D--", label='method = "lengths"')
    ax.set_xlabel("edges")
    ax.set_ylabel("wall time [s]")
    ax.set_title("Form finding of a cable-net roof")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
