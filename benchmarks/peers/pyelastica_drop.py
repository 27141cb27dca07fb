"""catenet and PyElastica on one rod falling onto a rigid plane: the time of first
contact against free fall, the energy the impact keeps, the deepest penetration, the
height and sag at rest, and the CPU per simulated second.

The rod is the cantilever's (``pyelastica_cantilever.py``): L = 1 m, a solid circular
section of radius r = 1 cm, EI = 1 N m^2, EA = 4e4 N, density 1000 kg/m^3 (0.314 kg),
free, horizontal, its axis r + H above the plane z = 0 (H = 5 cm: its underside H above
it), released at rest under gravity g = 9.81 m/s^2, no air and no friction. Closed
forms: the underside meets the plane at t = sqrt(2 H / g) = 0.10096 s at sqrt(2 g H) =
0.990 m/s; the rod falls flat, so it does not bend, and a frictionless elastic contact
gives it all its energy back (it rises to H again); at rest it lies on its underside
(its axis at r), straight.

- catenet: a dynamic run (``solver.method = "dynamic"``, no mass damping: ``damping =
  0``), the rod a ``graph`` of one cable (nothing fixed), ``material.EI``, a ``[[obstacle]]
  kind = "plane"`` with ``solver.edge_contact = true`` (every edge a capsule of the
  rod's radius: its underside meets the plane), the barrier's defaults, its default
  steps (bdf2, steps chosen by accuracy, ``solver.tolerance`` 3e-3) and smaller
  tolerances. The barrier acts within its activation distance d (default 1e-4 of the
  edge length, 2e-6 m here): the first contact is the first step the barrier acts in,
  and the rod rests with its underside between 0 and d above the plane, never in it.
  At rest: the same run with ``solver.t_end = "rest"`` and its default mass damping
  (1 /s), dynamic relaxation until the rod lies still.
- PyElastica 1.0 (``pip install pyelastica``), as its contact docs set a rod on a plane
  up: a ``CosseratRod.straight_rod`` of 50 elements, ``GravityForces``, a ``Plane`` and
  ``RodPlaneContact`` with the docs' k = 1e4 N/m and nu = 10 N s/m (per element: a
  spring and a dashpot on the element's penetration below its radius, and a reaction
  that cancels the element's other forces towards the plane while within 1e-4 m of it),
  and with nu = 0 (the elastic contact the closed form has), ``PositionVerlet`` at the
  cantilever's stable step 2.5e-5 s. The first contact is the first step an element's
  centre is within r of the plane; the state is read at every step (a callback).

Energy: E = sum m_i (|v_i|^2 / 2 + g (z_i - r)) over the nodes' lumped masses (the same
lumping in both), against M g H before the fall; the impact's share kept is E at t =
0.2 s (after the rebound, before any second contact) over M g H.

Usage: python benchmarks/peers/pyelastica_drop.py [--tolerances 3e-3,1e-3,1e-4,1e-5]
prints one row per run (one thread; each tool's JIT compiled or loaded before the
timed runs).
"""

from __future__ import annotations

import argparse
import contextlib
import io
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

HEIGHT = 0.05  # m: the underside above the plane
GRAVITY = 9.81
EDGES = 50
T_END = 0.35  # s: the fall, the impact, the rebound and (elastic) the second impact
T_AFTER = 0.2  # s: the impact's energy read here, in the rebound's flight
STEP = 2.5e-5  # s: PyElastica's stable step at 50 elements
CONTACT_K = 1e4  # N/m: RodPlaneContact's docs
CONTACT_NU = 10.0  # N s/m: RodPlaneContact's docs


def masses(edges: int = EDGES) -> np.ndarray:
    """The nodes' lumped masses [kg] (rho A l / 2 from each edge), as both tools lump."""
    m = np.full(edges + 1, DENSITY * math.pi * RADIUS**2 * L / edges)
    m[[0, -1]] *= 0.5
    return m


def energy(z: np.ndarray, v: np.ndarray) -> float:
    """The rod's mechanical energy above its rest level [J] (positions z (N,), velocities
    v (N, 3)); its bending and stretching are nil in a flat fall."""
    return float(
        np.sum(masses(len(z) - 1) * (0.5 * np.sum(v * v, axis=1) + GRAVITY * (z - RADIUS)))
    )


def drop_case(edges: int = EDGES, steps: dict | None = None, rest: bool = False) -> dict:
    """catenet's case: the free rod above the plane, ``steps`` the [solver] keys of its
    steps (None: the defaults; ``rest``: relaxed to rest)."""
    z = RADIUS + HEIGHT
    solver: dict = {"method": "dynamic", "edge_contact": True}
    if rest:
        solver["t_end"] = "rest"
    else:
        solver.update(t_end=T_END, damping=0.0)
    solver.update(steps or {})
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, z], [L, 0.0, z]],
            "cable": [{"name": "rod", "nodes": [0, 1], "edge_length": L / edges}],
        },
        "material": {"E": E, "radius": RADIUS, "EI": EI, "density": DENSITY},
        "load": {"gravity": [0.0, 0.0, -GRAVITY]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}],
        "solver": solver,
    }


def catenet_drop(steps: dict | None, t_after: float = T_AFTER) -> dict:
    """catenet's fall: first contact (the step before and the first in contact), the
    energy kept, the least gap of the underside, CPU seconds and steps."""
    from catenet.case import build, parse_case
    from catenet.errors import ConvergenceError
    from catenet.solver import path

    states: list[tuple[float, float, float, float]] = []  # t, least gap, E, contact energy

    def seen(step) -> None:
        contact = float(step.energy[2]) if step.energy is not None else 0.0
        gap = float(step.x[:, 2].min()) - RADIUS
        states.append((step.time, gap, energy(step.x[:, 2], step.v), contact))

    start = time.process_time()
    scene = build(parse_case(drop_case(steps=steps)))
    try:
        result = path.solve(scene, path.Settings.of(scene.case.solver), on_step=seen)
    except ConvergenceError as exc:
        return dict(failed=str(exc).split(":")[0].split(",")[0], steps=len(states))
    spent = time.process_time() - start
    if not result.converged:
        raise RuntimeError(result.message)
    a = np.array(states)
    touching = np.flatnonzero(a[:, 3] > 0.0)
    first = int(touching[0])
    flight = a[(a[:, 0] <= t_after) & (a[:, 0] > a[first, 0]) & (a[:, 3] == 0.0)]
    kept = flight[-1, 2] if len(flight) else math.nan
    return dict(
        before=a[first - 1, 0],
        contact=a[first, 0],
        kept=kept / energy(np.full(EDGES + 1, RADIUS + HEIGHT), np.zeros((EDGES + 1, 3))),
        gap=float(a[:, 1].min()),
        cpu=spent,
        steps=len(a),
    )


def catenet_rest() -> dict:
    """catenet's rod at rest on the plane: the underside's height and the sag."""
    from catenet.case import build, parse_case
    from catenet.solver import path

    start = time.process_time()
    scene = build(parse_case(drop_case(rest=True)))
    result = path.solve(scene, path.Settings.of(scene.case.solver))
    spent = time.process_time() - start
    if not result.converged:
        raise RuntimeError(result.message)
    z = result.x[:, 2]
    return dict(height=float(z.mean()) - RADIUS, sag=float(z.max() - z.min()), cpu=spent)


def pyelastica_drop(
    nu: float, final_time: float = T_END, dt: float = STEP, t_after: float = T_AFTER
) -> dict:
    """PyElastica's fall with the contact damper ``nu``: the same quantities, and the
    underside's height and sag at the end."""
    import elastica as ea

    class Drop(ea.BaseSystemCollection, ea.Forcing, ea.Contact, ea.CallBacks):
        pass

    sim = Drop()
    rod = elastica_rod(ea, EDGES, start=(0.0, 0.0, RADIUS + HEIGHT), normal=(0.0, 0.0, 1.0))
    sim.append(rod)
    plane = ea.Plane(plane_origin=np.zeros(3), plane_normal=np.array([0.0, 0.0, 1.0]))
    sim.append(plane)
    sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -GRAVITY]))
    sim.detect_contact_between(rod, plane).using(ea.RodPlaneContact, k=CONTACT_K, nu=nu)
    states: list[tuple[float, float, float]] = []  # t, least gap of the underside, E

    class Watch(ea.CallBackBaseClass):
        def make_callback(self, system, time, current_step) -> None:
            z = system.position_collection[2]
            states.append((time, float(z.min()) - RADIUS, energy(z, system.velocity_collection.T)))

    sim.collect_diagnostics(rod).using(Watch)
    sim.finalize()
    steps = int(round(final_time / dt))
    start = time.process_time()
    with contextlib.redirect_stdout(io.StringIO()):
        ea.integrate(ea.PositionVerlet(), sim, final_time, steps, progress_bar=False)
    spent = time.process_time() - start
    a = np.array(states)
    if not np.any(a[:, 1] < 0.0):
        return {}  # a warm-up, no contact
    first = int(np.flatnonzero(a[:, 1] < 0.0)[0])
    after = int(np.searchsorted(a[:, 0], t_after - 0.5 * dt))
    z = rod.position_collection[2]
    return dict(
        before=a[first - 1, 0],
        contact=a[first, 0],
        kept=a[after, 2] / energy(np.full(EDGES + 1, RADIUS + HEIGHT), np.zeros((EDGES + 1, 3))),
        gap=float(a[:, 1].min()),
        cpu=spent,
        steps=steps,
        height=float(z.mean()) - RADIUS,
        sag=float(z.max() - z.min()),
    )


def print_rows(runs: list[tuple[str, dict]]) -> None:
    """The table's rows (a run that failed says where), then catenet's rod at rest."""
    for name, r in runs:
        if "failed" in r:
            print(f"{name:<34} failed after {r['steps']} steps: {r['failed']}")
            continue
        per = r["cpu"] / T_END
        print(f"{name:<34} {r['before']:9.5f}-{r['contact']:.5f} {r['kept']:7.4f} "
              f"{r['gap']:14.3e} {r['cpu']:7.2f} {per:9.2f} {r['steps']:6d}")  # fmt: skip
    rest = catenet_rest()
    print(f"at rest: catenet (t_end = rest, damping 1 /s): underside {rest['height']:.3e} m "
          f"above the plane, sag {rest['sag']:.2e} m ({rest['cpu']:.2f} s CPU)")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tolerances", default="3e-3,1e-3,1e-4,1e-5", help="catenet's, adaptive")
    parser.add_argument("--dts", default="2.5e-4,1.25e-4,1e-4,6.25e-5", help="catenet's, fixed")
    parser.add_argument("--rest-time", type=float, default=1.0, help="PyElastica's run [s]")
    args = parser.parse_args()
    t_free = math.sqrt(2.0 * HEIGHT / GRAVITY)
    print(f"rod: L = {L} m, r = {RADIUS} m, EI = {EI} N m^2, EA = {E * math.pi * RADIUS**2:.4g} N, "
          f"{EDGES} edges, underside {HEIGHT} m above the plane; {T_END} s simulated")  # fmt: skip
    print(f"free fall: first contact at {t_free:.5f} s, {math.sqrt(2 * GRAVITY * HEIGHT):.4f} m/s")
    catenet_drop({})  # both tools' JIT compiled (or loaded) before the timed runs
    pyelastica_drop(CONTACT_NU, 10 * STEP)
    print(f"{'tool':<34} {'contact in [s]':>19} {'E kept':>7} {'least gap [m]':>14} "
          f"{'CPU s':>7} {'CPU/sim s':>9} {'steps':>6}")  # fmt: skip
    runs = []
    for tol in (float(t) for t in args.tolerances.split(",")):
        runs.append((f"catenet bdf2, tolerance {tol:g}", catenet_drop({"tolerance": tol})))
    for dt in (float(t) for t in args.dts.split(",")):
        runs.append((f"catenet bdf2, dt {dt:g}", catenet_drop({"dt": dt, "integrator": "bdf2"})))
    for nu in (CONTACT_NU, 0.0):
        runs.append((f"PyElastica k = {CONTACT_K:g}, nu = {nu:g}", pyelastica_drop(nu)))
    print_rows(runs)
    settled = pyelastica_drop(CONTACT_NU, args.rest_time)
    print(f"at rest: PyElastica nu = {CONTACT_NU:g} at {args.rest_time:g} s: underside "
          f"{settled['height']:.3e} m above the plane, sag {settled['sag']:.2e} m "
          f"({settled['cpu']:.2f} s CPU)")  # fmt: skip


if __name__ == "__main__":
    main()
