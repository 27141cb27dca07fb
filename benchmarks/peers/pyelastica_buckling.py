"""catenet and PyElastica on one strut: Euler buckling of a pinned-pinned rod under an
end load, against P_e = pi^2 EI / L^2.

The rod is the cantilever's (``pyelastica_cantilever.py``): L = 1 m, a solid circular
section of radius 1 cm, EI = 1 N m^2, EA = 4e4 N, density 1000 kg/m^3; one end pinned,
the other on a slider along the rod's axis, pushed towards the first by P. Euler's
strut is inextensible and without shear: both tools differ from it by the axial strain
(the bending moment EI dtheta/ds per unstretched length s, the strut shortened by P / EA:
P (1 - P / EA) = P_e, 2.5e-4 above P_e) and PyElastica also by its shear (G = E / 3, its
default).

- catenet: its stability verdict. The straight strut is an equilibrium under every load
  (its edges shortened by P / EA); ``catenet.solver.tangent.tangent``, the verdict a
  static run gives its equilibrium (``result.stable``; ``catenet run`` exits 1 where it
  is unstable), says whether it is stable. P_cr is found by bisection on that verdict to
  1e-7 of P_e, as ``catenet validate``'s Euler strut is.
- PyElastica 1.0 (``pip install pyelastica``) has no eigenvalue or stability analysis: its
  users load an imperfect strut and watch the lateral deflection. Here the imperfection
  is a small uniform lateral load q (``UniformForces``, q L = 1e-2 P_e), the end load P
  (``EndpointForces``, ramped over a quarter of the run) on a ``GeneralConstraint`` that
  holds the far end across the axis only, the near end's position held; damped to rest
  (``AnalyticalLinearDamper``, the first mode of the loaded strut critically damped:
  2 omega_1 sqrt(1 - P / P_e)), ``PositionVerlet`` at the cantilever's stable steps. The
  mid-span deflection at P = 0.8 P_e over that at P = 0 is the beam-column's
  amplification, 12 (2 sec u - 2 - u^2) / (5 u^4) with u = (pi / 2) sqrt(P / P_cr)
  (Timoshenko and Gere, Theory of Elastic Stability, 1.11): solved for P_cr. The runs
  last 1 s (P = 0) and 2.5 s (P = 0.8 P_e: 3 s changes the deflection by under 3e-5).
  catenet's static solves of the same two loads give its P_cr by the same route.

Usage: python benchmarks/peers/pyelastica_buckling.py [--edges 50,100]
prints, per resolution, P_cr / P_e - 1 of catenet's verdict, of catenet's and of
PyElastica's imperfect strut, and the CPU time of each (one thread; each tool's JIT
compiled or loaded before the timed runs).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import logging
import math
import sys
import time
from pathlib import Path

import numpy as np

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from benchmarks.peers.pyelastica_cantilever import (  # noqa: E402 (the rod of all three)
    DENSITY,
    EI,
    RADIUS,
    E,
    L,
    elastica_rod,
)

EULER = math.pi**2 * EI / L**2
LATERAL = 1e-2 * EULER  # N: the imperfection, q L
RATIO = 0.8  # P / P_e of the loaded imperfect strut
STEP = {50: 2.5e-5, 100: 1.25e-5}  # s: PyElastica's stable steps (the cantilever's)


def amplification(p: float) -> float:
    """Mid-span deflection of a pin-ended beam-column under a uniform lateral load and
    an axial compression P = p P_cr, over the one without P (Timoshenko and Gere 1.11)."""
    u = 0.5 * math.pi * math.sqrt(p)  # p >= 0.01: round-off 1e-16 / u^4 below 1e-12
    return 12.0 * (2.0 / math.cos(u) - 2.0 - u * u) / (5.0 * u**4)


def critical_from(ratio: float, load: float) -> float:
    """P_cr from the deflection ratio w(P) / w(0) observed at the compression ``load``."""
    from scipy.optimize import brentq

    p = brentq(lambda p: amplification(p) - ratio, 0.01, 1.0 - 1e-12, xtol=1e-15)
    return load / p


def strut_case(edges: int, load: float, lateral: float = 0.0) -> dict:
    """catenet's case: the strut pinned at node 0, on a slider along x at its far end,
    pushed by ``load`` [N], and the lateral load ``lateral`` [N] lumped on its nodes."""
    points = [{"node": edges, "force": [-load, 0.0, 0.0]}]
    points += [{"node": i, "force": [0.0, 0.0, -lateral / edges]} for i in range(1, edges)]
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [L, 0, 0], "nodes": edges + 1},
        "material": {"E": E, "radius": RADIUS, "EI": EI, "density": DENSITY},
        "supports": {"fixed": [0], "slider": [{"nodes": [edges], "direction": [1, 0, 0]}]},
        "load": {"point": points},
        "solver": {"rtol": 1e-10},
    }


def catenet_solve(case: dict):
    """catenet's static run of ``case``: its result, or None where the path collapses."""
    from catenet.case import build, parse_case
    from catenet.solver import path
    from catenet.solver.stability import CollapseError

    scene = build(parse_case(case))
    try:
        result = path.solve(scene, path.Settings.of(scene.case.solver))
    except CollapseError:
        return None
    if not result.converged:
        raise RuntimeError(result.message)
    return result


def catenet_verdict(edges: int, rtol: float = 1e-7) -> tuple[float, float, int]:
    """(P_cr [N], CPU seconds, verdicts): bisection on the stability verdict of the
    straight strut, the equilibrium under every load (its nodes moved in by P / EA)."""
    from catenet.case import build, parse_case
    from catenet.solver.tangent import STABLE, tangent
    from catenet.solver.workspace import Workspace

    start = time.process_time()
    scene = build(parse_case(strut_case(edges, EULER)))
    ws = Workspace(scene.net, terms=scene.terms)
    axial = E * math.pi * RADIUS**2

    def stable(load: float) -> bool:
        x = scene.net.nodes * np.array([1.0 - load / axial, 1.0, 1.0])
        tension = ws.system.tension(x)
        if not np.allclose(tension, -load, rtol=1e-9):
            raise ArithmeticError("the straight strut does not carry the load")
        return tangent(ws.system, ws.solver, x).verdict == STABLE

    low, high, runs = 0.9 * EULER, 1.1 * EULER, 0
    while high - low > rtol * EULER:
        mid = 0.5 * (low + high)
        runs += 1
        low, high = (mid, high) if stable(mid) else (low, mid)
    return 0.5 * (low + high), time.process_time() - start, runs


def catenet_imperfect(edges: int) -> tuple[float, float]:
    """(P_cr [N], CPU seconds) from catenet's deflections of the imperfect strut."""
    start = time.process_time()
    w = []
    for load in (0.0, RATIO * EULER):
        result = catenet_solve(strut_case(edges, load, LATERAL))
        w.append(-result.x[edges // 2, 2])
    return critical_from(w[1] / w[0], RATIO * EULER), time.process_time() - start


def pyelastica_deflection(edges: int, load: float, dt: float, final_time: float):
    """(mid-span deflection [m], CPU seconds, steps) of PyElastica's imperfect strut."""
    import elastica as ea

    class Strut(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    sim = Strut()
    rod = elastica_rod(ea, edges)
    sim.append(rod)
    held, across = np.array([True, True, True]), np.array([False, True, True])
    sim.constrain(rod).using(ea.GeneralConstraint, constrained_position_idx=(0,),
                             translational_constraint_selector=held)  # fmt: skip
    sim.constrain(rod).using(ea.GeneralConstraint, constrained_position_idx=(-1,),
                             translational_constraint_selector=across)  # fmt: skip
    sim.add_forcing_to(rod).using(ea.EndpointForces, np.zeros(3), np.array([-load, 0.0, 0.0]),
                                  ramp_up_time=0.25 * final_time)  # fmt: skip
    sim.add_forcing_to(rod).using(ea.UniformForces, LATERAL, np.array([0.0, 0.0, -1.0]))
    # the loaded strut's first mode critically damped: omega_1 = pi^2 sqrt(EI / (rho A L^4))
    omega = math.pi**2 * math.sqrt(EI / (DENSITY * math.pi * RADIUS**2 * L**4))
    omega *= math.sqrt(1.0 - load / EULER)
    sim.dampen(rod).using(
        ea.AnalyticalLinearDamper, uniform_damping_constant=2.0 * omega, time_step=dt
    )
    sim.finalize()
    steps = int(round(final_time / dt))
    start = time.process_time()
    with contextlib.redirect_stdout(io.StringIO()):
        ea.integrate(ea.PositionVerlet(), sim, final_time, steps, progress_bar=False)
    spent = time.process_time() - start
    return -float(rod.position_collection[2, edges // 2]), spent, steps


def pyelastica_imperfect(edges: int, dt: float) -> tuple[float, float, int]:
    """(P_cr [N], CPU seconds, steps) from PyElastica's deflections."""
    w0, t0, n0 = pyelastica_deflection(edges, 0.0, dt, 1.0)
    w1, t1, n1 = pyelastica_deflection(edges, RATIO * EULER, dt, 2.5)
    return critical_from(w1 / w0, RATIO * EULER), t0 + t1, n0 + n1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--edges", default="50,100")
    args = parser.parse_args()
    logging.getLogger("catenet").setLevel(logging.ERROR)  # the unstable tries' warnings
    print(f"strut: L = {L} m, EI = {EI} N m^2, EA = {E * math.pi * RADIUS**2:.4g} N, "
          f"P_e = {EULER:.6f} N; imperfection q L = {LATERAL:.4g} N, P = {RATIO} P_e")  # fmt: skip
    catenet_solve(strut_case(10, 0.5 * EULER, LATERAL))  # JITs compiled or loaded
    pyelastica_deflection(10, 0.0, 2.5e-5, 10 * 2.5e-5)
    axial = E * math.pi * RADIUS**2  # the extensible strut: P (1 - P / EA) = P_e
    extensible = 0.5 * axial * (1.0 - math.sqrt(1.0 - 4.0 * EULER / axial)) / EULER
    print(f"{'edges':>5} {'tool':<30} {'P_cr/P_e - 1':>13} {'CPU s':>8}")
    for edges in (int(n) for n in args.edges.split(",")):
        discrete = (math.sin(math.pi / (2 * edges)) / (math.pi / (2 * edges))) ** 2 - 1.0
        print(f"{edges:5d} {'discrete rod, inextensible':<30} {discrete:13.2e}")
        print(f"{edges:5d} {'continuum, extensible':<30} {extensible - 1.0:13.2e}")
        p, spent, runs = catenet_verdict(edges)
        print(f"{edges:5d} {'catenet: stability verdict':<30} {p / EULER - 1:13.2e} "
              f"{spent:8.3f}  ({runs} verdicts)")  # fmt: skip
        p, spent = catenet_imperfect(edges)
        print(f"{edges:5d} {'catenet: imperfect strut':<30} {p / EULER - 1:13.2e} {spent:8.3f}")
        p, spent, steps = pyelastica_imperfect(edges, STEP[edges])
        print(f"{edges:5d} {'PyElastica: imperfect strut':<30} {p / EULER - 1:13.2e} "
              f"{spent:8.3f}  ({steps} steps)")  # fmt: skip


if __name__ == "__main__":
    main()
