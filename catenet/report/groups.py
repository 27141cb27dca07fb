"""The parts of a net a report names: its cables (a graph's named cables, the square
net's A0 .. B(m-1), a single cable's "cable"; "other edges" for edges of no cable) and
its support sets (node sets whose every node is pinned)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.output.states import States

OTHER = "other edges"


@dataclass(frozen=True)
class Groups:
    """``cable`` (M,): each edge's index into ``names``; ``sets``: the file's node sets
    (name -> nodes); ``supports``: those of them whose every node is pinned."""

    cable: np.ndarray
    names: tuple[str, ...]
    sets: dict[str, np.ndarray]
    supports: dict[str, np.ndarray]

    def edges(self, k: int) -> np.ndarray:
        return np.flatnonzero(self.cable == k)


def groups(states: States) -> Groups:
    """The cables and support sets of a result file's net."""
    m = len(states.mesh.edges)
    cable, names = _cables(states, m)
    if (cable < 0).any():  # edges of no cable: one group of their own
        cable = np.where(cable < 0, len(names), cable)
        names = (*names, OTHER)
    fixed = states.mesh.fixed
    n = len(states.mesh.nodes)
    sets = {k: v for k, v in states.sets.items() if v.size and v.min() >= 0 and v.max() < n}
    supports = {}
    if fixed is not None:
        supports = {k: v for k, v in sets.items() if bool(np.all(fixed[v]))}
    return Groups(cable, names, sets, supports)


def _cables(states: States, m: int) -> tuple[np.ndarray, tuple[str, ...]]:
    """Each edge's cable index and the names: the file's cables; the square net's
    rebuilt from the case (when it gives the file's edges); one cable for a "cable"
    case; else every edge in one group."""
    if states.cable is not None:
        return states.cable, tuple(states.cable_names)
    geometry = states.case.get("geometry", {}) if states.case else {}
    kind = geometry.get("kind")
    if kind == "square_net":
        found = _square_net(geometry, states.mesh.edges)
        if found is not None:
            return found
    if kind == "cable":
        return np.zeros(m, dtype=np.int64), ("cable",)
    return np.full(m, -1, dtype=np.int64), ()


def _square_net(geometry: dict, edges: np.ndarray) -> tuple[np.ndarray, tuple[str, ...]] | None:
    """The square net's cables, built again from its keys (None where they do not make
    the file's edges)."""
    from catenet.errors import ConfigError
    from catenet.model import builders as geo

    try:
        sq = geo.square_net(
            int(geometry["n"]),
            float(geometry["alpha"]),
            float(geometry["size"]),
            float(geometry["edge_length"]),
            geo.Material(EA=1.0),
        )
    except (ConfigError, KeyError, TypeError, ValueError):
        return None
    if sq.cable is None or sq.net.edges.shape != edges.shape:
        return None
    if not np.array_equal(sq.net.edges, edges):
        return None
    return sq.cable, geo.square_net_cables(sq.n)
