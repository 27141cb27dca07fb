"""The same case at longer edges (``coarse_case``): the coarse net of a nested start
(``catenet.solver.nested``), built from the case as the user wrote it with every edge
length times a factor.

Only nets discretised by an edge length have one: ``geometry.kind = "square_net"`` and a
graph with cables that give ``edge_length`` (``geometry.edge_length`` or a cable's own).
A case that names a node by its index where refinement renumbers the nodes (every node
of a square net; a graph's nodes after the given ones) would put a support or a load
elsewhere on the coarse net: it has none either.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from catenet.case.kinds.base import GeometryConfig
from catenet.case.kinds.graph import GraphConfig
from catenet.case.kinds.square_net import SquareNetConfig
from catenet.case.parse import Case


def coarse_case(case: Case, factor: float) -> Case | None:
    """``case`` with every edge length times ``factor`` (> 1), or None where it has no
    edge length to lengthen or names renumbered nodes by index (module docstring)."""
    g = case.geometry
    geometry: GeometryConfig
    if not (math.isfinite(factor) and factor > 1.0):
        return None
    if isinstance(g, SquareNetConfig):
        stable = 0  # no node keeps its index
        geometry = dataclasses.replace(g, edge_length=g.edge_length * factor)
    elif isinstance(g, GraphConfig) and g.cables:
        if g.edge_length is None and all(c.edge_length is None for c in g.cables):
            return None
        if any(c.rest_length is not None for c in g.cables):
            return None  # rest lengths per edge of the split cable
        stable = len(g.nodes)  # the given nodes come first, in every refinement
        cables = tuple(
            c
            if c.edge_length is None
            else dataclasses.replace(c, edge_length=c.edge_length * factor)
            for c in g.cables
        )
        longer = None if g.edge_length is None else g.edge_length * factor
        geometry = dataclasses.replace(g, edge_length=longer, cables=cables)
    else:
        return None
    if any(ref >= stable for ref in node_indices(case)):
        return None
    return dataclasses.replace(case, geometry=geometry)


def node_indices(case: Case) -> list[int]:
    """Every node the case names by its index where supports, loads and masses are set."""
    refs: list[Any] = []
    s, load = case.supports, case.load
    refs += list(s.fixed or ())
    refs += [m.node for m in s.moves]
    refs += [r for vessel in s.vessels for r in vessel.nodes]
    refs += [r for roller in s.rollers for r in roller.nodes]
    refs += [r for slider in s.sliders for r in slider.nodes]
    refs += [r for spring in s.springs for r in spring.nodes]
    refs += [p.node for p in load.points if p.node is not None]
    for area in load.areas:
        nodes = area.nodes
        refs += list(nodes) if isinstance(nodes, (list, tuple)) else [nodes]
    refs += [m.node for m in case.masses]
    return [r for r in refs if isinstance(r, int) and not isinstance(r, bool)]
