"""catenet and dismech-newton on one rod falling onto a rigid plane: the scene of
``pyelastica_drop.py`` (the cantilever's rod, L = 1 m, radius 1 cm, EI = 1 N m^2,
EA = 4e4 N, 0.314 kg, free and horizontal, its underside H = 5 cm above the plane z = 0,
released at rest under gravity, frictionless). Free fall puts the first contact at
sqrt(2 H / g) = 0.10096 s; the rod falls flat and does not bend; at rest it lies on its
underside, straight.

- catenet: as in ``pyelastica_drop.py`` (its default steps, smaller tolerances; at rest
  ``t_end = "rest"``).
- dismech-newton 0.1.0.post2 (``pip install dismech-newton==0.1.0.post2``, run on the
  CPU) as its contact solver is meant to be used: ``ADMMDiSMechSolver`` (implicit discrete
  elastic rods with contact and friction by ADMM; its defaults: implicit Euler,
  ``theta = 1``, ADMM to its tolerance 1e-4 of the mean edge length, friction 0 here as the
  scene is frictionless), the rod added with capsule proxies
  (``ADMMDiSMechSolver.add_rod``: ``add_colliding_rod``), Newton's ground plane
  (``ModelBuilder.add_ground_plane``) and a ``newton.CollisionPipeline`` with
  ``soft_contact_max = 0`` (the solver's docstring) colliding the state before each step,
  at fixed steps ``--dts``. Its contact is a projection within an implicit Euler step: the
  rod stops at the plane (its contact inelastic by construction). With ``theta = 1/2``
  (its docstring: "needs a small tol") the rod bounced with 1.2 m/s after meeting the plane
  at 0.99 m/s and went 0.13 mm into it at 1 ms steps: energy gained, so not used.

Measured as in ``pyelastica_drop.py``: "contact in" the last step before the first in
contact (dismech-newton: the underside within 1e-5 m of the plane) and that step; "E kept"
the energy at 0.2 s over M g H; the least gap of the underside over the run; at the end of
the 0.35 s the underside's height and the sag (dismech-newton's rod at rest by then).

Usage: python benchmarks/peers/dismech_drop.py [--dts 1e-3,5e-4,2.5e-4]
(one thread; each tool's kernels compiled or loaded before the timed runs: Warp compiles
dismech-newton's in about a minute the first time).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path

if __name__ == "__main__":  # one thread for every tool (benchmarks/peers/README.md)
    for _name in ("MKL", "OMP", "OPENBLAS", "NUMBA"):
        os.environ.setdefault(f"{_name}_NUM_THREADS", "1")

import numpy as np  # noqa: E402

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from benchmarks.peers.pyelastica_cantilever import (  # noqa: E402 (the rod of all)
    DENSITY,
    EI,
    RADIUS,
    SHEAR_FACTOR,
    E,
    L,
)
from benchmarks.peers.pyelastica_drop import (  # noqa: E402 (the scene of both)
    EDGES,
    GRAVITY,
    HEIGHT,
    T_AFTER,
    T_END,
    catenet_drop,
    energy,
    print_rows,
)

TOUCH = 1e-5  # m: dismech-newton's underside this near the plane counts as contact


def dismech_drop(dt: float, final_time: float = T_END, t_after: float = T_AFTER) -> dict:
    """dismech-newton's fall at fixed steps dt (module docstring): first contact, energy
    kept, least gap, CPU seconds, steps, and the underside's height and sag at the end."""
    import newton
    import warp as wp
    from dismech_newton import ADMMDiSMechSolver

    wp.config.quiet = True  # type: ignore[attr-defined]
    area, inertia = math.pi * RADIUS**2, math.pi * RADIUS**4 / 4.0
    z0 = RADIUS + HEIGHT
    points = np.column_stack(
        [np.linspace(0.0, L, EDGES + 1), np.zeros(EDGES + 1), np.full(EDGES + 1, z0)]
    )
    rod = newton.Rod(
        points,
        radius=RADIUS,
        stretch_rigidity=E * area,
        shear_rigidity=1e6 * E * area,  # not a discrete elastic rod's: held stiff
        bend_rigidity=EI,
        twist_rigidity=SHEAR_FACTOR * E * 2.0 * inertia,
    )
    with warnings.catch_warnings():  # Newton's scalar gravity is deprecated, not gone
        warnings.simplefilter("ignore", DeprecationWarning)
        builder = newton.ModelBuilder(gravity=-GRAVITY)
    builder.default_shape_cfg.density = DENSITY
    ADMMDiSMechSolver.add_rod(builder, rod)
    builder.add_ground_plane()
    start = time.process_time()
    model = builder.finalize(device="cpu")
    solver = ADMMDiSMechSolver(model, friction=0.0)
    pipeline = newton.CollisionPipeline(model, soft_contact_max=0)
    contacts = pipeline.contacts()
    now, after = model.state(), model.state()
    steps = int(round(final_time / dt))
    states = []  # t, least gap of the underside, E
    for k in range(steps):
        pipeline.collide(now, contacts)
        solver.step(now, after, None, contacts, dt)
        now, after = after, now
        assert now.particle_q is not None and now.particle_qd is not None
        q = now.particle_q.numpy().astype(np.float64)
        v = now.particle_qd.numpy().astype(np.float64)
        states.append(((k + 1) * dt, float(q[:, 2].min()) - RADIUS, energy(q[:, 2], v)))
    spent = time.process_time() - start
    a = np.array(states)
    if not np.any(a[:, 1] < TOUCH):
        return {}  # a warm-up, no contact
    first = int(np.flatnonzero(a[:, 1] < TOUCH)[0])
    after_k = int(np.searchsorted(a[:, 0], t_after - 0.5 * dt))
    start_energy = energy(np.full(EDGES + 1, z0), np.zeros((EDGES + 1, 3)))
    return dict(
        before=a[first - 1, 0],
        contact=a[first, 0],
        kept=a[after_k, 2] / start_energy,
        gap=float(a[:, 1].min()),
        cpu=spent,
        steps=steps,
        height=float(q[:, 2].mean()) - RADIUS,
        sag=float(q[:, 2].max() - q[:, 2].min()),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tolerances", default="3e-3,1e-4", help="catenet's, adaptive")
    parser.add_argument("--dts", default="1e-3,5e-4,2.5e-4", help="dismech-newton's, fixed")
    args = parser.parse_args()
    print(f"rod: L = {L} m, r = {RADIUS} m, EI = {EI} N m^2, {EDGES} edges, underside "
          f"{HEIGHT} m above the plane; {T_END} s simulated; free fall meets it at "
          f"{math.sqrt(2.0 * HEIGHT / GRAVITY):.5f} s")  # fmt: skip
    catenet_drop({})  # both tools' kernels compiled (or loaded) before the timed runs
    dismech_drop(1e-3, 0.01)
    print(f"{'tool':<34} {'contact in [s]':>19} {'E kept':>7} {'least gap [m]':>14} "
          f"{'CPU s':>7} {'CPU/sim s':>9} {'steps':>6}")  # fmt: skip
    runs = [
        (f"catenet bdf2, tolerance {tol:g}", catenet_drop({"tolerance": tol}))
        for tol in (float(t) for t in args.tolerances.split(","))
    ]
    rests = []
    for dt in (float(t) for t in args.dts.split(",")):
        r = dismech_drop(dt)
        runs.append((f"dismech-newton ADMM, dt {dt:g}", r))
        rests.append((dt, r))
    print_rows(runs)
    for dt, r in rests:
        print(f"at {T_END} s: dismech-newton dt {dt:g}: underside {r['height']:.3e} m above "
              f"the plane, sag {r['sag']:.2e} m")  # fmt: skip


if __name__ == "__main__":
    main()
