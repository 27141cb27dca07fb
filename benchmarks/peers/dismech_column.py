"""catenet and dismech-newton on a buckled column: the rod of ``dismech_cantilever.py``
(L = 1 m, radius 1 cm, EI = 1 N m^2, EA = 4e4 N), clamped at its foot, under an axial end
load P above Euler's P_cr = pi^2 EI / (4 L^2) with a lateral nudge of 1e-4 P at the tip,
against the elastica of the buckled cantilever column (Timoshenko and Gere, 2.7):

    K(k) = (pi / 2) sqrt(P / P_cr),   the tip's lateral deflection 2 k L / K(k),
    its distance from the foot along the axis (2 E(k) / K(k) - 1) L,

with K, E the complete elliptic integrals of modulus k = sin(theta_tip / 2). The nudge
moves the answer by about 1e-4 of L, within both tools' errors here.

- catenet: its discrete elastic rod, clamped at the foot, one static solve through load
  steps (``column_tip``).
- dismech-newton 0.1.0.post2 (as ``dismech_cantilever.py`` sets it up: ``fix_segment`` on
  the first edge, the load on the tip particle, implicit Euler without damping until
  the tip moves less than 1e-7 L in a step).

Usage: python benchmarks/peers/dismech_column.py [--ratios 1.1,1.5] [--edges 50,100]
prints, per load ratio and resolution, the tip of both tools against the elastica and
the CPU time of each (one thread; both compiled or loaded before the timed runs).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

if __name__ == "__main__":  # one thread for every tool, set before NumPy, MKL and Numba
    # start theirs; never on import (a test process's threads are set already)
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

from benchmarks.peers.dismech_cantilever import dismech_end_load  # noqa: E402
from benchmarks.peers.pyelastica_cantilever import EI, L, catenet_end_load  # noqa: E402

NUDGE = 1e-4  # the lateral load at the tip, a share of P
P_CR = math.pi**2 * EI / (4.0 * L**2)


def elastica_column(ratio: float) -> tuple[float, float]:
    """(axial, lateral) tip position / L of the buckled cantilever column at P = ratio
    P_cr (module docstring)."""
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipk

    target = 0.5 * math.pi * math.sqrt(ratio)
    m = brentq(lambda m: ellipk(m) - target, 0.0, 1.0 - 1e-15)  # m = k^2
    K, Ek = ellipk(m), ellipe(m)
    return 2.0 * Ek / K - 1.0, 2.0 * math.sqrt(m) / K


def _load(ratio: float) -> np.ndarray:
    P = ratio * P_CR
    return np.array([-P, 0.0, -NUDGE * P])


def column_tip(ratio: float, edges: int) -> tuple[np.ndarray, float]:
    """(tip (axial, lateral) / L, CPU seconds) of catenet's column at P = ratio P_cr: one
    static solve in 20 load steps (``pyelastica_cantilever.catenet_end_load``)."""
    return catenet_end_load(_load(ratio), edges, 20)


def dismech_column_tip(
    ratio: float, edges: int, dt: float = 0.2, max_steps: int = 20000
) -> tuple[np.ndarray, float, int]:
    """(tip (axial, lateral) / L, CPU seconds, steps) of dismech-newton's column at
    P = ratio P_cr, run to rest (``dismech_cantilever.dismech_end_load``)."""
    return dismech_end_load(_load(ratio), edges, dt, max_steps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ratios", default="1.1,1.5")
    parser.add_argument("--edges", default="50,100")
    parser.add_argument("--dt", type=float, default=0.2, help="dismech-newton's step, 50 edges")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each; the least CPU")
    args = parser.parse_args()
    print(f"column: L = {L} m, EI = {EI} N m^2, P_cr = {P_CR:.6g} N, nudge {NUDGE:g} P; "
          f"dismech-newton dt = {args.dt:g} s x 50 / edges, to rest")  # fmt: skip
    column_tip(1.1, 10)  # both tools compiled (or loaded) before the timed runs
    dismech_column_tip(1.1, 10, args.dt)
    print(f"{'P/P_cr':>7} {'edges':>6} {'tool':<14} {'axial/L':>10} {'lateral/L':>10} "
          f"{'|err|':>9} {'CPU s':>8}")  # fmt: skip
    for ratio in (float(r) for r in args.ratios.split(",")):
        exact = np.array(elastica_column(ratio))
        print(f"{ratio:7g} {'':>6} {'elastica':<14} {exact[0]:10.6f} {exact[1]:10.6f}")
        for edges in (int(n) for n in args.edges.split(",")):
            runs = [column_tip(ratio, edges) for _ in range(args.repeat)]
            tip, spent = runs[0][0], min(r[1] for r in runs)
            err = float(np.abs(tip - exact).max())
            print(f"{ratio:7g} {edges:6d} {'catenet':<14} {tip[0]:10.6f} {tip[1]:10.6f} "
                  f"{err:9.2e} {spent:8.3f}")  # fmt: skip
            ran = [
                dismech_column_tip(ratio, edges, args.dt * 50 / edges) for _ in range(args.repeat)
            ]
            (tip, _, steps), spent = ran[0], min(r[1] for r in ran)
            err = float(np.abs(tip - exact).max())
            print(f"{ratio:7g} {edges:6d} {'dismech-newton':<14} {tip[0]:10.6f} {tip[1]:10.6f} "
                  f"{err:9.2e} {spent:8.3f}  ({steps} steps)")  # fmt: skip


if __name__ == "__main__":
    main()
