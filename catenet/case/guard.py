"""The memory guard: the size of the net and the memory a solve needs, estimated from
the case alone, before any array is made."""

from __future__ import annotations

from catenet.case.keys import Checker, show
from catenet.case.kinds import GeometryConfig
from catenet.model.builders import MAX_NODES
from catenet.model.memory import (  # noqa: F401  (re-exported)
    MEMORY_SHARE,
    PER_ITEM_BYTES,
    PROCESS_BYTES,
    estimate_memory,
    physical_memory,
)


def estimate_size(geometry: GeometryConfig) -> tuple[float, float, float, str]:
    """(nodes, edges, junctions, key path of what drives the size), estimated from the
    parameters alone (see each kind's ``estimate_size``)."""
    return geometry.estimate_size()


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
