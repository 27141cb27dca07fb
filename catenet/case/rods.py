"""A case's rods: which edges bend (``material.EI``, per cable in a graph), their natural
curvature and the clamped rod ends (``supports.clamped``), as a ``Bending`` term.

Rods bend along lines: a graph's cables ([[geometry.cable]]: each its own line; the
graph's own edges, geometry.edges, never bend), each cable of the square net, the
single cable. Clamped nodes are pinned too (a clamp holds the node and its tangent).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.case.keys import Checker, show
from catenet.case.kinds.base import expand
from catenet.case.kinds.cables import cable_materials
from catenet.case.kinds.warn import warn_once
from catenet.errors import ConfigError
from catenet.model.net import Net
from catenet.model.rods import Rods, build_rods

if TYPE_CHECKING:
    from catenet.case.parse import Case
    from catenet.terms.bending import Bending


def clamped_nodes(case: Case, built: Any) -> np.ndarray:
    """The node indices of supports.clamped (each once)."""
    refs = case.supports.clamped
    nodes = [i for r in refs for i in expand(r, built.names, built.sets or {})]
    return np.unique(np.asarray(nodes, dtype=np.int64))


def with_clamps(net: Net, clamped: np.ndarray) -> Net:
    """The net with its clamped nodes pinned."""
    if not clamped.size or net.fixed[clamped].all():
        return net
    fixed = net.fixed.copy()
    fixed[clamped] = True
    return net.replace(fixed=fixed)


def _per_edge(case: Case, built: Any, net: Net) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EI (M,), the natural-curvature switch (M,) and the line (M,) of every edge."""
    m = net.n_edges
    cables = getattr(case.geometry, "cables", ())
    if built.cables is not None and cables:
        line = np.asarray(built.cables.edge, dtype=np.int64)
        mats = cable_materials(Checker(), case.material, cables)
        ei = np.array([mat.bending_stiffness for mat in mats] + [0.0])
        given = np.array([mat.natural_curvature == "given" for mat in mats] + [False])
        return ei[line], given[line], line  # line -1 (the graph's own edges): the last
    material = case.material
    if case.geometry.kind == "graph":  # a graph without cables: no lines
        line = np.full(m, -1, dtype=np.int64)
    elif built.lines is not None:
        line = np.asarray(built.lines, dtype=np.int64)
    else:
        line = np.zeros(m, dtype=np.int64)
    ei = np.full(m, material.bending_stiffness)
    given = np.full(m, material.natural_curvature == "given")
    return ei, given, line


def case_rods(case: Case, built: Any, net: Net, clamped: np.ndarray) -> Rods | None:
    """The rods of a built case (None: nothing bends and nothing is clamped)."""
    ei, given, line = _per_edge(case, built, net)
    if not (ei > 0.0).any():
        if clamped.size:
            raise ConfigError(
                f"supports.clamped = {show(list(case.supports.clamped))}: no edge bends: "
                "a clamp holds a rod's end: give material.EI > 0 (or a cable's)"
            )
        return None
    rods = build_rods(net, ei, line, natural=given, clamped=clamped)
    if not len(rods):
        warn_once(
            "material.EI > 0, but no two bending edges of one cable meet and nothing is "
            "clamped: nothing bends (rods bend along cables: a graph's [[geometry.cable]], "
            "not its geometry.edges; a cable of one edge bends only where clamped)"
        )
    return rods


def bending_term(rods: Rods, n_nodes: int) -> Bending:
    """The rods' ``Bending`` term (its kernels load only for a case with rods)."""
    from catenet.terms.bending import Bending

    return Bending(rods, n_nodes)
