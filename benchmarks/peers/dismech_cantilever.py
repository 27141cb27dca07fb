"""catenet and dismech-newton on one rod: the cantilever of ``pyelastica_cantilever.py``
(L = 1 m, radius 1 cm, EI = 1 N m^2, EA = 4e4 N, density 1000 kg/m^3) under a transverse
end load, against the elastica (Bisshopp and Drucker's closed form,
``catenet.validate.rods.elastica_tip``).

- catenet: its discrete elastic rod, clamped at the root, one static solve
  (``pyelastica_cantilever.catenet_tip``).
- dismech-newton 0.1.0.post2 (``pip install dismech-newton==0.1.0.post2``: implicit
  discrete elastic rods on NVIDIA's Newton and Warp, run here on the CPU; its latest
  release, 0.1.0.post4, does not import on Python 3.11): ``newton.Rod`` with the same
  section rigidities (the shear rigidity, which its discrete elastic rods do not use,
  set high), ``add_rod`` without capsule proxies, ``fix_segment`` on the first edge (the
  clamp: both its nodes and its twist held), the end load on the tip particle
  (``State.particle_f``), ``DiSMechSolver`` (implicit Euler, Newton to its default
  tolerance 1e-6) stepped without damping until the tip moves less than 1e-7 L in a step
  (implicit Euler's steps, long beside the rod's first period, damp the motion). The
  step is ``--dt`` at 50 edges and shorter in proportion on finer rods: dismech-newton
  assembles and solves in single precision (Warp's ``float``), and at 0.2 s or 1 s
  on 200 edges SciPy's LU finds its matrix exactly singular (the inertia's
  M / h^2 keeps it regular).

Usage: python benchmarks/peers/dismech_cantilever.py [--loads 1,3] [--edges 50,100]
prints, per load and resolution, the tip of both tools against the elastica and the CPU
time of each, the least of ``--repeat`` runs (one thread; Warp's kernels compiled or
loaded and catenet's JIT loaded before the timed runs).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path

if __name__ == "__main__":  # one thread for every tool (benchmarks/peers/README.md), set
    # before NumPy, MKL and Numba start their threads; never on import: a test process's
    # threads are set already, and catenet's own setting then fails
    for _name in (
        "MKL_NUM_THREADS",
        "OMP_NUM_THREADS",
        "OPENBLAS_NUM_THREADS",
        "NUMBA_NUM_THREADS",
    ):
        os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from benchmarks.peers.pyelastica_cantilever import (  # noqa: E402 (the rod of both)
    DENSITY,
    EI,
    RADIUS,
    SHEAR_FACTOR,
    E,
    L,
    catenet_tip,
)

SETTLE = 1e-7  # the tip at rest: it moves less than this times L in a step


def dismech_tip(
    alpha: float, edges: int, dt: float = 0.2, max_steps: int = 5000
) -> tuple[np.ndarray, float, int]:
    """(tip (x, y) / L, CPU seconds, steps) of dismech-newton's cantilever at
    P L^2 / EI = alpha, run to rest (module docstring)."""
    return dismech_end_load([0.0, 0.0, -alpha * EI / L**2], edges, dt, max_steps)


def dismech_end_load(force, edges: int, dt: float, max_steps: int) -> tuple[np.ndarray, float, int]:
    """(tip (x, -z) / L, CPU seconds, steps) of dismech-newton's rod along +x, its first
    edge held (``fix_segment``), under ``force`` [N] at its tip particle, stepped without
    damping until the tip moves less than SETTLE L in a step (module docstring)."""
    import newton
    import warp as wp
    from dismech_newton import DiSMechSolver, add_rod, fix_segment

    wp.config.quiet = True  # type: ignore[attr-defined]
    area, inertia = math.pi * RADIUS**2, math.pi * RADIUS**4 / 4.0
    points = np.column_stack([np.linspace(0.0, L, edges + 1), np.zeros((edges + 1, 2))])
    rod = newton.Rod(
        points,
        radius=RADIUS,
        stretch_rigidity=E * area,
        shear_rigidity=1e6 * E * area,  # not a discrete elastic rod's: held stiff
        bend_rigidity=E * inertia,
        twist_rigidity=SHEAR_FACTOR * E * 2.0 * inertia,
    )
    with warnings.catch_warnings():  # Newton's scalar gravity is deprecated: none here
        warnings.simplefilter("ignore", DeprecationWarning)
        builder = newton.ModelBuilder(gravity=0.0)
    builder.default_shape_cfg.density = DENSITY
    segments = add_rod(builder, rod, proxies=False)
    fix_segment(builder, edge=segments[0])
    start = time.process_time()
    model = builder.finalize(device="cpu")
    solver = DiSMechSolver(model)
    now, after = model.state(), model.state()
    loads = np.zeros((edges + 1, 3), dtype=np.float32)
    loads[-1] = force
    last, steps = None, 0
    while True:
        assert now.particle_f is not None
        now.particle_f.assign(loads)
        solver.step(now, after, None, None, dt)
        now, after = after, now
        steps += 1
        assert now.particle_q is not None
        tip = now.particle_q.numpy()[-1].astype(np.float64)
        if last is not None and np.abs(tip - last).max() < SETTLE * L:
            break
        if steps >= max_steps:
            raise RuntimeError(f"dismech-newton: not at rest after {max_steps} steps")
        last = tip
    spent = time.process_time() - start
    return np.array([tip[0], -tip[2]]) / L, spent, steps


def main() -> None:
    from catenet.validate.rods import elastica_tip

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loads", default="1,3")
    parser.add_argument("--edges", default="50,100")
    parser.add_argument("--dt", type=float, default=0.2, help="dismech-newton's step, 50 edges")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each; the least CPU")
    args = parser.parse_args()
    print(f"rod: L = {L} m, EI = {EI} N m^2, EA = {E * math.pi * RADIUS**2:.4g} N; "
          f"dismech-newton dt = {args.dt:g} s x 50 / edges, to rest")  # fmt: skip
    catenet_tip(1.0, 10)  # both tools compiled (or loaded) before the timed runs
    dismech_tip(1.0, 10, args.dt)
    print(f"{'PL^2/EI':>8} {'edges':>6} {'tool':<14} {'x/L':>10} {'y/L':>10} {'|err|':>9} "
          f"{'CPU s':>8}")  # fmt: skip
    for alpha in (float(a) for a in args.loads.split(",")):
        _, x, y = elastica_tip(alpha)
        exact = np.array([x, y])
        print(f"{alpha:8g} {'':>6} {'elastica':<14} {x:10.6f} {y:10.6f}")
        for edges in (int(n) for n in args.edges.split(",")):
            runs = [catenet_tip(alpha, edges) for _ in range(args.repeat)]
            tip, spent = runs[0][0], min(r[1] for r in runs)
            err = float(np.abs(tip - exact).max())
            print(f"{alpha:8g} {edges:6d} {'catenet':<14} {tip[0]:10.6f} {tip[1]:10.6f} "
                  f"{err:9.2e} {spent:8.3f}")  # fmt: skip
            ran = [dismech_tip(alpha, edges, args.dt * 50 / edges) for _ in range(args.repeat)]
            (tip, _, steps), spent = ran[0], min(r[1] for r in ran)
            err = float(np.abs(tip - exact).max())
            print(f"{alpha:8g} {edges:6d} {'dismech-newton':<14} {tip[0]:10.6f} {tip[1]:10.6f} "
                  f"{err:9.2e} {spent:8.3f}  ({steps} steps)")  # fmt: skip


if __name__ == "__main__":
    main()
