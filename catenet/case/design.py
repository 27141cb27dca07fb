"""The [design] section: the partial factors of the utilisation of tension components
(``catenet.model.design``: EN 1993-1-11's cable resistance), and the per-edge design
data of a built case (each edge's material's breaking and proof loads)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import Declared, node, real, show, tables
from catenet.errors import ConfigError
from catenet.model import design as rule


@dataclass(frozen=True)
class SupportCapacityConfig(Declared):
    """The capacity of supports: the anchor or fitting at each node of ``node`` resists a
    reaction |R| up to ``capacity``; its utilisation is |R| / capacity."""

    node: int | str = node(
        missing="the supported node or node set", doc="a support, or a node set of supports"
    )
    capacity: float = real(
        gt=0, missing="its resistance [N] (> 0)", unit="N", doc="each node's resistance"
    )


@dataclass(frozen=True)
class DesignConfig(Declared):
    """Partial factors of the utilisation F_Ed / F_Rd of every edge whose material gives
    material.breaking_load: F_Rd = min(k_e F_min / (breaking_factor gamma_R),
    F_k / gamma_R), F_Ed = load_factor x tension (EN 1993-1-11, section 6)."""

    gamma_R: float = real(
        rule.GAMMA_R,
        gt=0,
        write="changed",
        unit="-",
        doc="partial factor of the tension resistance (EN 1993-1-11 recommends 0.90 where "
        "measures limit bending at the anchorages, 1.00 where none are taken; a national "
        "annex may set others)",
    )
    breaking_factor: float = real(
        rule.BREAKING_FACTOR,
        gt=0,
        write="changed",
        unit="-",
        doc="the factor on the breaking strength in F_uk / (breaking_factor gamma_R)",
    )
    k_e: float = real(
        rule.K_E,
        gt=0,
        write="changed",
        unit="-",
        doc="loss factor of the end terminations: F_uk = k_e breaking_load (1.0: metal "
        "or resin sockets)",
    )
    load_factor: float = real(
        rule.LOAD_FACTOR,
        gt=0,
        write="changed",
        unit="-",
        doc="gamma_F: design tension = load_factor x tension, in every state (1 where "
        "the combinations carry the load factors)",
    )
    supports: tuple[SupportCapacityConfig, ...] = tables(
        SupportCapacityConfig,
        name="support",
        doc="capacities of anchors and fittings: each support's utilisation |R| / capacity",
    )


def edge_design(case: Any, net: Any, built: Any) -> rule.Design:
    """The ``catenet.model.design.Design`` of a built case (its ``net`` and the
    geometry's ``Built``: cables, node names and sets): each edge's breaking and proof
    load from its material ([material], or its cable's in a graph), the supports'
    capacities and the factors of [design]."""
    from catenet.case.keys import Checker
    from catenet.case.kinds.cables import cable_materials

    config = case.design if case.design is not None else DesignConfig()
    factors = {
        "gamma_R": config.gamma_R,
        "breaking_factor": config.breaking_factor,
        "k_e": config.k_e,
        "load_factor": config.load_factor,
    }
    n_edges, cables = net.n_edges, built.cables
    mats = [case.material]
    owner = np.full(n_edges, -1, dtype=np.int64)  # -1: the case's [material]
    own_cables = getattr(case.geometry, "cables", ())
    if cables is not None and own_cables:
        mats += cable_materials(Checker(), case.material, own_cables)
        owner = np.asarray(cables.edge, dtype=np.int64)
    breaking = np.array([_value(m.breaking_load) for m in mats])
    proof = np.array([_value(m.proof_load) for m in mats])
    capacity = _capacities(config.supports, net, built) if config.supports else None
    return rule.Design(breaking[owner + 1], proof[owner + 1], capacity=capacity, **factors)


def _capacities(supports, net: Any, built: Any) -> np.ndarray:
    """Each node's support capacity [N] (N,), NaN where none is given; ConfigError for a
    reference that names no node or a node that is no support."""
    from catenet.case.kinds.base import expand

    out = np.full(net.n_nodes, np.nan)
    for k, s in enumerate(supports):
        path = f"design.support[{k}].node = {show(s.node)}"
        try:
            nodes = expand(s.node, built.names, built.sets or {})
        except KeyError:
            raise ConfigError(f"{path}: names no node or node set of the geometry") from None
        for i in nodes:
            if not (0 <= i < net.n_nodes and net.fixed[i]):
                raise ConfigError(f"{path}: node {i} is not a support (fixed node)")
            out[i] = s.capacity
    return out


def _value(v: float | None) -> float:
    return np.nan if v is None else float(v)
