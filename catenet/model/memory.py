"""Memory a solve needs, estimated from the size of its net before any array is made,
and the machine's physical memory: the case loader's guard (``catenet.case.guard``) and
the builders (``catenet.model.builders``) refuse nets that cannot fit."""

from __future__ import annotations

import os

#: Share of the physical memory a case may need.
MEMORY_SHARE = 0.8


def physical_memory() -> int | None:
    """Bytes of physical memory of this machine, None where the OS does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


#: Resident memory of a process that has loaded NumPy, Numba and MKL (Linux x86-64).
PROCESS_BYTES = 180.0 * 2**20
#: Bytes per node and per edge of the size estimate, fitted to the peak resident memory
#: of static solves of square nets from 1e3 to 1e7 DOF (``python -m benchmarks scale``: the
#: estimate is 0.99 to 1.06 times the measured peak there).
PER_ITEM_BYTES = 1300.0


def estimate_memory(nodes: float, edges: float, junctions: float = 0.0) -> float:
    """Bytes the process of a solve of a net of this size needs at its peak.

    The process itself (PROCESS_BYTES), then per node and edge (PER_ITEM_BYTES, about
    1.3 KiB): the net's arrays and its builder's transients (~0.15 KiB), per edge the 36
    Hessian values and their positions in the matrix (2 * 36 * 8 bytes), the matrix (9 (N +
    M) entries of 12 bytes), PARDISO's factor and work arrays (about 0.5 KiB per DOF at
    1e6 DOF). The factor's fill-in grows like log K with the K ``junctions`` (nested
    dissection of their 2D grid), but by 1e7 DOF it adds less than the size estimates
    count on the safe side (about 20 % more nodes than the nets have), so the measured
    peaks need no term of their own for it: ``junctions`` is accepted for callers that
    know it and not used.
    """
    del junctions
    return PROCESS_BYTES + PER_ITEM_BYTES * (nodes + edges)


def fits(nodes: float, edges: float, share: float = 1.0) -> tuple[bool, float, int | None]:
    """(whether a solve of this size needs at most ``share`` of the physical memory, the
    bytes it needs, the machine's bytes or None where the OS does not say)."""
    total = physical_memory()
    need = estimate_memory(nodes, edges)
    return total is None or need <= share * total, need, total
