"""What the arithmetic carries: the largest magnitude of a number in a model and the
largest count a run may be asked for (checked where input comes in: case keys, the
builders, ``Net.from_arrays``)."""

from __future__ import annotations

import math

#: The largest magnitude of a number in a case: EA, loads, coordinates and their products
#: must stay far below the 1.8e308 of double precision (squares of forces, energies).
MAGNITUDE = 1e100
#: The largest count (steps, iterations, threads, nodes asked for by number) a key takes:
#: beyond it a run would not finish.
MAX_COUNT = 10**9


def carried(f: float) -> bool:
    """A float the arithmetic carries: finite and within +-MAGNITUDE."""
    return math.isfinite(f) and abs(f) <= MAGNITUDE


def too_large() -> str:
    """What a number must stay within, as messages say it."""
    return f"+-{MAGNITUDE:.0e} (beyond, the arithmetic of forces and energies overflows)"
