"""The memory guard: the size of the net and the memory a solve needs, estimated from
the case alone, before any array is made."""

from __future__ import annotations

import math
import os

from catenet.case.keys import Checker, show
from catenet.case.kinds import GeometryConfig
from catenet.geometry import MAX_NODES

#: Share of the physical memory a case may need.
MEMORY_SHARE = 0.8


def physical_memory() -> int | None:
    """Bytes of physical memory of this machine, None where the OS does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def estimate_size(geometry: GeometryConfig) -> tuple[float, float, float, str]:
    """(nodes, edges, junctions, key path of what drives the size), estimated from the
    parameters alone (see each kind's ``estimate_size``)."""
    return geometry.estimate_size()


def estimate_memory(nodes: float, edges: float, junctions: float = 0.0) -> float:
    """Bytes a solve of a net of this size needs, roughly and on the safe side.

    Per edge a 6x6 Hessian block of float64 values and its int64 scatter map (2 * 36 * 8);
    ten vectors of 3N float64; the CSR matrix, 9 (N + M) entries of 12 bytes (value and
    column index); the sparse factor, measured at about twice the matrix for the chains
    between joints plus 24 K log2 K entries for the K joints (nested dissection of a 2D
    grid); and the builders' Python objects, about 400 bytes per node and edge.
    """
    nnz = 9.0 * (nodes + edges)
    factor = 2.0 * nnz + 24.0 * junctions * math.log2(junctions + 2.0)
    return 2 * 36 * 8 * edges + 10 * 24 * nodes + 12 * (nnz + factor) + 400 * (nodes + edges)


def guard_size(ck: Checker, geometry: GeometryConfig) -> None:
    """A problem when the net would have more than MAX_NODES nodes or need more than
    MEMORY_SHARE of this machine's memory; it names the key that drives the size."""
    nodes, edges, junctions, key = estimate_size(geometry)
    value = getattr(geometry, key.removeprefix("geometry."), None)
    shown = value is not None and not isinstance(value, (tuple, list))
    where = f"{key} = {show(value)}" if shown else key
    if not nodes <= MAX_NODES:
        ck.add(
            f"{where}: the net would have about {nodes:.2g} nodes; catenet builds at most "
            f"{MAX_NODES:.0e} nodes"
        )
        return
    total = physical_memory()
    need = estimate_memory(nodes, edges, junctions)
    if total is not None and not need <= MEMORY_SHARE * total:
        gib = 2.0**30
        ck.add(
            f"{where}: the net would have about {edges:.2g} edges and need about "
            f"{need / gib:.2g} GiB; this machine has {total / gib:.0f} GiB (at most "
            f"{MEMORY_SHARE:.0%} of it may be used)"
        )
