"""Form finding by targets at scale: the hypar roof whose every free node must lie on a
given surface, under its own weight, with one force density per edge as the design
variables (about 1e3 and 1e4 of them), against the static solve of the same net.

    python benchmarks/targets.py [-o DIR] [--quick] [--direct]

Per roof (``hypar_on_surface`` of tests/scenes.py, the roof of tests/formfind): the
search's adjoint gradients and evaluations until every node is on the surface (to
formfind.tol = 1e-9 of the roof's size), its wall time and so the time per gradient
(everything of the search: shapes, adjoint solves, damped steps; the surface file is
read before, its time apart), the damped steps' own share (by conjugate residuals with
D's factors: ``catenet.formfind.krylov``, their iterations; the steps that fell back to
the direct saddle-point factorisation, ``catenet.formfind.damped``); then the static
analysis of the net found (``catenet run`` on the case it writes: the rest lengths that
carry the forces found, tension-only) under a snow load of SNOW [N/m^2] on its plan, and
the wall time of one Newton iteration there (the solve's time over its iterations), and
that of one back-substitution with the factors of the net's D. The ratios are measured
in the same run, from CPU times (one thread: a loaded machine's waits left out); the whole
search is given in Newton iterations too, with its products with J or J^T (one forward or
adjoint solve each) and its solves with D (back-substitutions: counts the machine does
not change). Each roof twice: on the surface mesh's flat triangles, and ``smooth`` (the
C1 height field through its vertices). Writes DIR/targets.csv (default
benchmarks/results; with --direct, every damped step by the direct factorisation,
DIR/targets-direct.csv) and prints the table.

With --first-order the same search from the same start is driven instead by SciPy's
L-BFGS-B on 1/2 |r|^2, its gradient J^T r one adjoint solve with D's factors (what a
gradient costs where no damped step is solved: jax_fdm's way), until every node is on the
surface or FIRST_ORDER_BUDGET gradients: DIR/targets-first-order.csv.
"""

from __future__ import annotations

import itertools
import sys
import tempfile
import time
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/targets.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import click

from benchmarks.common import write_csv

SIZES = (24, 72)  # grid side: 1104 and 10224 force densities
QUICK_SIZES = (8, 24)
SNOW = 500.0  # N/m^2 on the plan
FIRST_ORDER_BUDGET = 3000  # --first-order: L-BFGS-B's gradients at most


def first_order(search, s0, bounds, budget):
    """catenet.formfind.design's search from s0 by L-BFGS-B (SciPy) on 1/2 |r|^2, its
    gradient J^T r one adjoint solve (the Jacobian's operator, never formed): ("met", s)
    where every target is met, else (how it ended, the best s)."""
    import numpy as np
    import scipy.optimize

    from catenet.formfind import design

    class Met(Exception):
        pass

    def value_and_gradient(s):
        try:
            r = search.residual(s)
        except design._Met as met:
            raise Met from met
        jac = search.jacobian(s)
        return 0.5 * float(r @ r), np.asarray(jac.rmatvec(r))

    box = list(zip(*(np.broadcast_to(b, s0.shape) for b in bounds), strict=True))
    try:
        ended = scipy.optimize.minimize(
            value_and_gradient, s0, jac=True, method="L-BFGS-B", bounds=box,
            options={"maxfun": FIRST_ORDER_BUDGET, "maxiter": FIRST_ORDER_BUDGET,
                     "ftol": 0.0, "gtol": 0.0},
        )  # fmt: skip
    except Met:
        return "met", np.frombuffer(search.key or s0.tobytes()).copy()
    return f"L-BFGS-B: {ended.message}", search.best[1] if search.best else ended.x


def roof_row(n: int, smooth: bool = False) -> dict:
    """One roof (``smooth``: on the C1 height field through the surface mesh's vertices,
    else on its flat triangles): the search, then one static solve of the net found."""
    import numpy as np
    from scenes import hypar_on_surface

    from catenet.case import build, parse_case
    from catenet.formfind.case import formfind_scene
    from catenet.formfind.surface import read_height_field
    from catenet.model.net import Loads, Net
    from catenet.solver.static import Workspace, solve_static

    with tempfile.TemporaryDirectory() as folder:
        data, _ = hypar_on_surface(folder, n)
        data["target"][0]["smooth"] = smooth
        scene = build(parse_case(data, base_dir=Path(folder)))
        start = time.perf_counter()
        read_height_field(scene.case.targets[0].surface, smooth)  # (read once, then kept)
        read_s = time.perf_counter() - start
        start, cpu = time.perf_counter(), time.process_time()
        found = formfind_scene(scene)
        search_s, search_cpu = time.perf_counter() - start, time.process_time() - cpu
    d = found.design
    steps = d.extra.get("steps") or {}
    taken = steps.get("iterative", 0) + steps.get("factorizations", 0)  # (direct: one each)
    step_s = steps.get("iterative_s", 0.0) + steps.get("direct_s", 0.0)
    net = found.net
    built = Net.from_arrays(
        found.x,
        net.edges,
        EA=net.EA,
        fixed=net.fixed,
        rest_length=found.rest_length(),
        line_density=net.line_density,
        tension_only=True,
    )
    free = ~np.asarray(net.fixed)
    snow = np.zeros((net.n_nodes, 3))
    snow[free, 2] = -SNOW * (24.0 / n) ** 2
    loads = Loads(force=snow, gravity=np.array([0.0, 0.0, -9.81]))
    solve_static(built, loads, workspace=Workspace(built))  # (warm: Numba, PARDISO)
    start, cpu = time.perf_counter(), time.process_time()
    static = solve_static(built, loads, workspace=Workspace(built))
    static_s, static_cpu = time.perf_counter() - start, time.process_time() - cpu
    per_gradient = search_s / max(d.gradients, 1)
    back_s = back_substitution(found)
    per_newton = static_s / max(static.iterations, 1)
    newton_cpu = static_cpu / max(static.iterations, 1)  # (the ratios: CPU times, one thread)
    return {
        "force_densities": d.variables,
        "surface": "smooth" if smooth else "flat triangles",
        "free_nodes": int(np.count_nonzero(free)),
        "met": d.all_met,
        "largest_miss_m": float(np.abs(d.miss()).max()),
        "gradients": d.gradients,
        "evaluations": d.evaluations,
        "read_s": read_s,
        "search_s": search_s,
        "per_gradient_s": per_gradient,
        "steps": taken,
        "cr_iterations": steps.get("iterations", 0),
        "steps_direct": steps.get("factorizations", 0),
        "per_step_s": step_s / max(taken, 1),
        "back_substitution_s": back_s,
        "newton_over_back_substitution": per_newton / back_s,
        "static_iterations": static.iterations,
        "static_converged": bool(static.converged),
        "per_newton_s": per_newton,
        "search_cpu_s": search_cpu,
        "per_newton_cpu_s": newton_cpu,
        "gradient_over_newton": search_cpu / max(d.gradients, 1) / newton_cpu,
        "search_over_newton": search_cpu / newton_cpu,
        "products": steps.get("products", 0),
        "d_solves": found.stats["solves"],
        "step_over_newton": step_s / max(taken, 1) / per_newton,
    }


def back_substitution(found, count: int = 50) -> float:
    """The wall time of one back-substitution with the factors of the found net's D (the
    free nodes' matrix; what each product of the iterative steps costs three of)."""
    import numpy as np

    from catenet.formfind.fdm import Pattern
    from catenet.solver.linear import make_solver, resolve_backend

    p = Pattern(found.net)
    solver = make_solver(
        resolve_backend("auto"), p.indptr, p.indices, upper=True, dof_node=p.free_nodes, mtype=2
    )
    solver.factorize(p.values(found.q))
    b = np.random.default_rng(0).standard_normal(p.n_free)
    solver.solve(b)  # (the first, checked)
    start = time.perf_counter()
    for _ in range(count):
        solver.solve(b)
    return (time.perf_counter() - start) / count


@click.command(name="python benchmarks/targets.py")
@click.option(
    "-o",
    "--output",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=Path(__file__).resolve().parent / "results",
    show_default="benchmarks/results",
)
@click.option("--quick", is_flag=True, help="Smaller roofs (1e2 and 1e3 force densities).")
@click.option(
    "--direct",
    is_flag=True,
    help="Every damped step by the direct saddle-point factorisation (no conjugate "
    "residuals): the steps as they were before the iterations.",
)
@click.option(
    "--first-order",
    is_flag=True,
    help="The search by L-BFGS-B on adjoint gradients (one adjoint solve each) in place "
    "of Levenberg-Marquardt's damped steps.",
)
def main(out_dir: Path, quick: bool, direct: bool, first_order: bool) -> None:
    """The hypar on its surface: gradients and time per gradient against a Newton
    iteration."""
    from benchmarks.common import set_threads
    from catenet.formfind import design, krylov

    krylov.ENABLED = not direct
    if first_order:
        design._search = globals()["first_order"]
        design.DENSE = -1  # a gradient is one adjoint solve at every size

    set_threads(1)
    roof_row(16)  # (warm: Numba's caches, MKL, the imports of the sparse steps)
    rows = []
    for n, smooth in itertools.product(QUICK_SIZES if quick else SIZES, (False, True)):
        rows.append(roof_row(n, smooth))
        r = rows[-1]
        click.echo(
            f"{r['force_densities']:>6} force densities ({r['surface']}): "
            f"{r['gradients']} gradients "
            f"({'met' if r['met'] else 'NOT met'}: largest miss {r['largest_miss_m']:.1e} m), "
            f"{r['search_s']:.2f} s, "
            f"{r['per_gradient_s'] * 1e3:.0f} ms per gradient; damped step "
            f"{r['per_step_s'] * 1e3:.0f} ms ({r['cr_iterations']} CR iterations in "
            f"{r['steps']} steps, {r['steps_direct']} direct); Newton iteration "
            f"{r['per_newton_s'] * 1e3:.1f} ms: gradient / "
            f"Newton {r['gradient_over_newton']:.1f} (CPU; the search "
            f"{r['search_over_newton']:.0f} Newton iterations, {r['products']} products with "
            f"J or J^T, {r['d_solves']} solves with D), step / Newton "
            f"{r['step_over_newton']:.1f}; a back-substitution with D "
            f"{r['back_substitution_s'] * 1e3:.2f} ms (Newton / it "
            f"{r['newton_over_back_substitution']:.0f})"
        )
    out_dir.mkdir(parents=True, exist_ok=True)
    name = "targets-first-order" if first_order else "targets-direct" if direct else "targets"
    write_csv(rows, out_dir / f"{name}.csv")


if __name__ == "__main__":
    main()
