"""catenet and PyElastica on one rod: a cantilever under a transverse end load, against
the elastica (Bisshopp and Drucker's closed form, ``catenet.validate.rods.elastica_tip``).

The rod: L = 1 m, a solid circular section of radius 1 cm, EI = 1 N m^2 (E = 4 / (pi
r^4)), EA = E pi r^2 = 4e4 N, density 1000 kg/m^3. Both tools see the same rod; the
elastica is inextensible and without shear, so both differ from it by the axial strain
(P / EA <= 2.5e-4 here) and PyElastica also by its shear (a Cosserat rod, G = E / 3, its
default: EI / (k G A L^2) = 8e-5, the share of the deflection from shear).

- catenet: its discrete elastic rod (``material.EI``), clamped at the root, the load on
  the tip, one static solve (Newton, load steps to P L^2 / EI).
- PyElastica 1.0 (``pip install pyelastica``), as its Timoshenko-beam and cantilever
  examples set it up: a ``CosseratRod.straight_rod`` of N elements, ``OneEndFixedBC`` at
  the root, ``EndpointForces`` ramped over half the run, ``AnalyticalLinearDamper``
  (``uniform_damping_constant`` 2 omega_1: the first mode critically damped, the way
  its docs advise for reaching a static state) and the ``PositionVerlet`` stepper at a
  stable step (2.5e-5 s at 50 elements, 1.25e-5 s at 100; with G = 1e4 E it diverged);
  3 s of simulated time, the tip settled to 1e-6 (8 s gives the same tip).

Usage: python benchmarks/peers/pyelastica_cantilever.py [--loads 1,3] [--edges 50]
prints, per load, the tip of both tools against the elastica and the CPU time of each
(one thread; each tool's JIT compiled or loaded before the timed runs).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

L = 1.0
RADIUS = 0.01
EI = 1.0
E = 4.0 * EI / (math.pi * RADIUS**4)
DENSITY = 1000.0
SHEAR_FACTOR = 1.0 / 3.0  # G = E / (2 (1 + nu)), nu = 0.5: PyElastica's default


def catenet_tip(alpha: float, edges: int) -> tuple[np.ndarray, float]:
    """(tip (x, y) / L, CPU seconds) of catenet's cantilever at P L^2 / EI = alpha."""
    return catenet_end_load([0.0, 0.0, -alpha * EI / L**2], edges, max(1, int(alpha) // 2))


def catenet_end_load(force, edges: int, steps: int) -> tuple[np.ndarray, float]:
    """(tip (x, -z) / L, CPU seconds) of catenet's rod along +x, clamped at x = 0, under
    ``force`` [N] at its tip: one static solve in ``steps`` load steps."""
    from catenet.case import build, parse_case
    from catenet.solver import path

    case = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [L, 0, 0], "nodes": edges + 1},
        "material": {"E": E, "radius": RADIUS, "EI": EI, "density": DENSITY},
        "supports": {"fixed": [0], "clamped": [0]},
        "load": {"point": [{"node": edges, "force": [float(f) for f in force]}]},
        "solver": {"rtol": 1e-10, "steps": steps},
    }
    start = time.process_time()
    scene = build(parse_case(case))
    result = path.solve(scene, path.Settings.of(scene.case.solver))
    spent = time.process_time() - start
    if not result.converged:
        raise RuntimeError(result.message)
    tip = result.x[edges]
    return np.array([tip[0], -tip[2]]) / L, spent


def elastica_rod(ea, edges: int, start=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0)):
    """PyElastica's ``CosseratRod`` of this rod (the cantilever's, the buckling strut's and
    the falling rod's): ``edges`` elements along +x from ``start``."""
    return ea.CosseratRod.straight_rod(
        edges,
        np.asarray(start, dtype=np.float64),
        np.array([1.0, 0.0, 0.0]),
        np.asarray(normal, dtype=np.float64),
        L,
        RADIUS,
        DENSITY,
        youngs_modulus=E,
        shear_modulus=SHEAR_FACTOR * E,
    )


def pyelastica_tip(alpha: float, edges: int, dt: float, final_time: float):
    """(tip (x, y) / L, CPU seconds, steps) of PyElastica's cantilever."""
    import elastica as ea

    class Cantilever(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    sim = Cantilever()
    rod = elastica_rod(ea, edges)
    sim.append(rod)
    sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                             constrained_director_idx=(0,))  # fmt: skip
    force = np.array([0.0, 0.0, -alpha * EI / L**2])
    sim.add_forcing_to(rod).using(ea.EndpointForces, 0.0 * force, force,
                                  ramp_up_time=0.5 * final_time)  # fmt: skip
    # critical damping of the first mode: 2 omega_1 with omega_1 = 3.516 sqrt(EI / (rho A L^4))
    omega = 3.516 * math.sqrt(EI / (DENSITY * math.pi * RADIUS**2 * L**4))
    sim.dampen(rod).using(
        ea.AnalyticalLinearDamper, uniform_damping_constant=2.0 * omega, time_step=dt
    )
    sim.finalize()
    steps = int(round(final_time / dt))
    start = time.process_time()
    ea.integrate(ea.PositionVerlet(), sim, final_time, steps, progress_bar=False)
    spent = time.process_time() - start
    tip = rod.position_collection[:, -1]
    return np.array([tip[0], -tip[2]]) / L, spent, steps


def main() -> None:
    from catenet.validate.rods import elastica_tip

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loads", default="1,3")
    parser.add_argument("--edges", type=int, default=50)
    parser.add_argument("--dt", type=float, default=2.5e-5)
    parser.add_argument("--time", type=float, default=10.0, help="PyElastica's run [s]")
    args = parser.parse_args()
    print(f"rod: L = {L} m, EI = {EI} N m^2, EA = {E * math.pi * RADIUS**2:.4g} N, "
          f"{args.edges} edges; PyElastica dt = {args.dt:g} s for {args.time:g} s")  # fmt: skip
    catenet_tip(1.0, 10)  # both tools' JIT compiled (or loaded) before the timed runs
    pyelastica_tip(1.0, 10, args.dt, 10 * args.dt)
    print(f"{'PL^2/EI':>8} {'tool':<11} {'x/L':>10} {'y/L':>10} {'|err|':>9} {'CPU s':>8}")
    for alpha in (float(a) for a in args.loads.split(",")):
        _, x, y = elastica_tip(alpha)
        exact = np.array([x, y])
        print(f"{alpha:8g} {'elastica':<11} {x:10.6f} {y:10.6f}")
        tip, spent = catenet_tip(alpha, args.edges)
        err = float(np.abs(tip - exact).max())
        print(f"{alpha:8g} {'catenet':<11} {tip[0]:10.6f} {tip[1]:10.6f} {err:9.2e} {spent:8.3f}")
        tip, spent, steps = pyelastica_tip(alpha, args.edges, args.dt, args.time)
        err = float(np.abs(tip - exact).max())
        print(f"{alpha:8g} {'PyElastica':<11} {tip[0]:10.6f} {tip[1]:10.6f} {err:9.2e} "
              f"{spent:8.3f}  ({steps} steps)")  # fmt: skip


if __name__ == "__main__":
    main()
