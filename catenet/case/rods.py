"""A case's rods: which edges bend (``material.EI``, per cable in a graph) and twist
(``material.GJ``), their natural curvature, the clamped rod ends (``supports.clamped``)
and the turned ones (``[[supports.twist]]``), as a ``Bending`` and a ``Twist`` term.

Rods bend along lines: a graph's cables ([[geometry.cable]]: each its own line; the
graph's own edges, geometry.edges, never bend), each cable of the square net, the
single cable. Clamped nodes are pinned too (a clamp holds the node and its tangent).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.case.keys import Checker, show
from catenet.case.kinds.base import expand
from catenet.case.kinds.cables import cable_materials
from catenet.case.kinds.warn import warn_once
from catenet.errors import ConfigError
from catenet.model.histories import History
from catenet.model.net import Net
from catenet.model.rods import Rods, build_rods, without_hinges

if TYPE_CHECKING:
    from catenet.case.parse import Case
    from catenet.model.torsion import Torsion
    from catenet.terms.bending import Bending
    from catenet.terms.joints import RigidJoints
    from catenet.terms.twist import Twist


#: Why a cable's twist is refused.
NO_RING = (
    "the cable is no twisting ring: a closed cable (its last node its first) of a rod with "
    "GJ > 0 and EI > 0 is closed with a twist (a rod between clamps is turned by "
    "[[supports.twist]])"
)


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


def _polar(mat: Any) -> float:
    """rho J_p [kg m] of a material, NaN where neither given nor from a section."""
    value = mat.rotational_inertia
    return math.nan if value is None else value


def _per_edge(case: Case, built: Any, net: Net, polar: bool = False) -> tuple[np.ndarray, ...]:
    """EI (M,), GJ (M,), the natural-curvature switch (M,) and the line (M,) of every
    edge (and with ``polar`` each edge's rho J_p (M,) [kg m], NaN where unknown)."""
    m = net.n_edges
    cables = getattr(case.geometry, "cables", ())
    if built.cables is not None and cables:
        line = np.asarray(built.cables.edge, dtype=np.int64)
        mats = cable_materials(Checker(), case.material, cables)
        ei = np.array([mat.bending_stiffness for mat in mats] + [0.0])
        gj = np.array([mat.torsional_stiffness for mat in mats] + [0.0])
        given = np.array([mat.natural_curvature == "given" for mat in mats] + [False])
        if polar:  # line -1 (the graph's own edges): the last
            rho_j = np.array([_polar(mat) for mat in mats] + [0.0])
            return ei[line], gj[line], given[line], line, rho_j[line]
        return ei[line], gj[line], given[line], line
    material = case.material
    if case.geometry.kind == "graph":  # a graph without cables: no lines
        line = np.full(m, -1, dtype=np.int64)
    elif built.lines is not None:
        line = np.asarray(built.lines, dtype=np.int64)
    else:
        line = np.zeros(m, dtype=np.int64)
    ei = np.full(m, material.bending_stiffness)
    gj = np.full(m, material.torsional_stiffness)
    given = np.full(m, material.natural_curvature == "given")
    if polar:
        return ei, gj, given, line, np.full(m, _polar(material))
    return ei, gj, given, line


def case_rods(case: Case, built: Any, net: Net, clamped: np.ndarray) -> Rods | None:
    """The rods of a built case (None: nothing bends and nothing is clamped); a line's
    hinge at a rigid joint is the joint's (``case_joints``)."""
    ei, _, given, line = _per_edge(case, built, net)
    springs = rotational_springs(case, built)
    joints = _joint_nodes(case, built)
    if joints.size and not (ei > 0.0).any():
        raise ConfigError(
            f"supports.rigid_joints = {show(list(case.supports.rigid_joints))}: no edge "
            "bends: a rigid joint joins rods: give material.EI > 0 (or a cable's)"
        )
    if not (ei > 0.0).any():
        if clamped.size:
            raise ConfigError(
                f"supports.clamped = {show(list(case.supports.clamped))}: no edge bends: "
                "a clamp holds a rod's end: give material.EI > 0 (or a cable's)"
            )
        if springs:
            raise ConfigError(
                "supports.rotational[0].nodes: no edge bends: a rotational spring holds a "
                "rod's end: give material.EI > 0 (or a cable's)"
            )
        return None
    rods = build_rods(net, ei, line, natural=given, clamped=clamped, springs=springs)
    if joints.size:
        rods = without_hinges(rods, joints)
    if not len(rods) and not joints.size:
        warn_once(
            "material.EI > 0, but no two bending edges of one cable meet and nothing is "
            "clamped: nothing bends (rods bend along cables: a graph's [[geometry.cable]], "
            "not its geometry.edges; a cable of one edge bends only where clamped)"
        )
    return rods


def _joint_nodes(case: Case, built: Any) -> np.ndarray:
    """The node indices of supports.rigid_joints (each once)."""
    refs = case.supports.rigid_joints
    nodes = [i for r in refs for i in expand(r, built.names, built.sets or {})]
    return np.unique(np.asarray(nodes, dtype=np.int64))


def case_joints(case: Case, built: Any, net: Net, n_nodes: int) -> RigidJoints | None:
    """The rods' rigid joints (``supports.rigid_joints``) as a ``RigidJoints`` term (None:
    none); a ConfigError for a node where fewer than two lines' rods meet."""
    nodes = _joint_nodes(case, built)
    if not nodes.size:
        return None
    from catenet.model.joints import build_joints
    from catenet.terms.joints import RigidJoints

    ei, _, _, line = _per_edge(case, built, net)
    return RigidJoints(build_joints(net, ei, line, nodes, "supports.rigid_joints"), n_nodes)


def rotational_springs(case: Case, built: Any) -> dict[int, float]:
    """Node -> the stiffness [N m/rad] of its rotational spring (``supports.rotational``);
    a ConfigError for a node on two."""
    out: dict[int, float] = {}
    for k, r in enumerate(case.supports.rotationals):
        for node in [i for ref in r.nodes for i in expand(ref, built.names, built.sets or {})]:
            if node in out:
                raise ConfigError(
                    f"supports.rotational[{k}].nodes: node {node} is on a rotational spring "
                    "already: one spring per rod end"
                )
            out[node] = float(r.stiffness)
    return out


def rod_end_springs(case: Case, built: Any, net: Net, clamped: np.ndarray) -> Any:
    """The rod ends on 6x6 springs (``[[supports.spring]]`` with a 6x6 stiffness) as an
    ``Elastic`` of ``catenet.model.rodends.RodEnds`` (None: none); a ConfigError for a
    node that is no rod end, clamped or on a rotational spring too, or a twist held on a
    rod that twists."""
    from catenet.case.supports import is_six
    from catenet.model.guides import Elastic
    from catenet.model.rodends import (
        RodEnds,
        end_stiffness,
        spring6_matrix,
        twist_coupled,
        twist_held,
    )
    from catenet.model.rods import rod_ends, rod_hinges

    given = [(k, s) for k, s in enumerate(case.supports.springs) if is_six(s.stiffness)]
    if not given:
        return None
    ei, gj, _, line = _per_edge(case, built, net)
    hinges = rod_hinges(net.edges, line, ei > 0.0)[:, 2:]
    total: dict[int, np.ndarray] = {}
    where: dict[int, str] = {}
    sprung = rotational_springs(case, built)
    for k, spring in given:
        path = f"supports.spring[{k}]"
        k6 = spring6_matrix([list(r) if isinstance(r, tuple) else r for r in spring.stiffness])
        if k6 is None:  # checked when the case was read
            raise ConfigError(f"{path}.stiffness: not a 6x6")
        for node in [i for r in spring.nodes for i in expand(r, built.names, built.sets or {})]:
            other = "supports.clamped" if node in clamped else None
            other = "supports.rotational" if node in sprung else other
            if other is not None:
                raise ConfigError(
                    f"{path}.nodes: node {node} is in {other} too: a rod end on a 6x6 "
                    "spring is held by it alone (its position and direction)"
                )
            total[node] = total.get(node, np.zeros((6, 6))) + k6
            where.setdefault(node, path)
    nodes = np.asarray(list(total), dtype=np.int64)
    found = [
        rod_ends(net, ei, hinges, nodes[i : i + 1], f"{where[int(n)]}.nodes", "a 6x6 spring's node")
        for i, n in enumerate(nodes)
    ]
    pairs, tangent, edge = (np.concatenate(part) for part in zip(*found, strict=True))
    stiffness = np.stack([total[int(n)] for n in nodes])
    for n, t, e, k6 in zip(nodes, tangent, edge, stiffness, strict=True):
        if gj[e] > 0.0 and twist_coupled(k6, t):
            raise ConfigError(
                f"{where[int(n)]}.stiffness: node {int(n)} is the end of a rod that twists "
                "(GJ > 0) and the 6x6 couples the twist about the rod's axis "
                f"({twist_held(k6, t):.6g} N m/rad) with its other rows: a spring holds a "
                "twisting rod's twist in series with it only where its row and column about "
                "the rod's axis hold nothing else (e.g. [kx, ky, kz, krx, kry, krz] with the "
                "rod along an axis): give that rod GJ = 0, or the 6x6 such a row"
            )
    series = np.stack(
        [
            end_stiffness(k6, t, ei[e], net.rest_length[e])
            for k6, t, e in zip(stiffness, tangent, edge, strict=True)
        ]
    )
    ends = RodEnds(pairs[:, 0].copy(), pairs[:, 1].copy(), tangent, stiffness, series)
    return Elastic.rod_ends(ends)


def bending_term(rods: Rods, n_nodes: int) -> Bending:
    """The rods' ``Bending`` term (its kernels load only for a case with rods)."""
    from catenet.terms.bending import Bending

    return Bending(rods, n_nodes)


def case_twist(
    case: Case, built: Any, net: Net, rods: Rods | None, n_nodes: int, joints: Any = None
) -> Twist | None:
    """The rods' ``Twist`` term (None: no rod twists): the chains of edges with GJ > 0
    held at both ends (clamped, or on a rigid joint of ``joints``) and the rings, each
    clamp of [[supports.twist]] turned."""
    twisted = case.supports.twists
    _, gj, _, line = _per_edge(case, built, net)
    if rods is None or not (gj > 0.0).any():
        if twisted:
            raise ConfigError(
                "supports.twist[0].nodes: no rod twists: a twist turns a clamped end of a rod "
                "with material.GJ > 0 (and EI > 0)"
            )
        for k, cable in enumerate(getattr(case.geometry, "cables", ())):
            if cable.twist is not None:
                raise ConfigError(f"geometry.cable[{k}].twist = {cable.twist!r}: {NO_RING}")
        return None
    from catenet.model.rodends import twist_ends
    from catenet.model.twist import build_twists, check_twist_ends
    from catenet.terms.twist import Twist

    rigid = rods.rigid  # a rotational spring holds no twist: the rod untwists there
    springs = twist_ends(None if net.springs is None else net.springs.ends)
    twists = build_twists(net, gj, line, rods.clamps[rigid], rods.tangent[rigid], joints, springs)
    clamped = set(rods.clamps[rigid, 0].tolist())
    imposed = []
    seen: dict[int, str] = {}
    for k, t in enumerate(twisted):
        path = f"supports.twist[{k}].nodes"
        nodes = [i for r in t.nodes for i in expand(r, built.names, built.sets or {})]
        check_twist_ends(twists, np.asarray(nodes), path, clamped)
        for node in dict.fromkeys(nodes):
            if node in seen:
                raise ConfigError(f"{path}: node {node} is turned by {seen[node]} already")
            seen[node] = path
            history = None if t.history is None else History(t.history)
            imposed.append((twists.segment_of(node)[0], t.angle, history))
    imposed += _ring_twists(case, twists, line)
    if not len(twists):
        warn_once(
            "material.GJ > 0, but no twisting rod is clamped at both ends (nor closed): "
            "nothing twists at rest (a rod with a free or pinned end untwists); catenet "
            "modes has its torsional modes"
        )
        return None
    x0 = np.zeros((n_nodes, 3))
    x0[: net.n_nodes] = net.nodes
    return Twist(twists, n_nodes, x0, imposed)


def _ring_twists(case: Case, twists: Any, line: np.ndarray) -> list:
    """(segment, twist, None) of every closed cable given a ``twist``; a ConfigError
    where such a cable is no twisting ring."""
    cables = getattr(case.geometry, "cables", ())
    rings = {int(line[twists.edges[twists.first[s]]]): s for s in np.flatnonzero(twists.closed)}
    out, problems = [], []
    for k, cable in enumerate(cables):
        if cable.twist is None:
            continue
        if k in rings:
            out.append((rings[k], cable.twist, None))
        else:
            problems.append(f"geometry.cable[{k}].twist = {cable.twist!r}: {NO_RING}")
    if problems:
        raise ConfigError(problems)
    return out


def case_torsion(
    case: Case, built: Any, net: Net, rods: Rods | None, twist: Twist | None, joints: Any = None
) -> Torsion | None:
    """The twisting chains with their twist angles as DOFs for ``catenet modes``
    (``catenet.model.torsion``; None: no rod twists). Where a twisting rod's rotational
    inertia is unknown (no radius, no ``polar_inertia``), its chains are left out and
    ``Torsion.missing`` says which key to give."""
    if rods is None:
        return None
    _, gj, _, line, polar = _per_edge(case, built, net, polar=True)
    if not (gj > 0.0).any():
        return None
    from dataclasses import replace

    from catenet.model.rodends import twist_ends
    from catenet.model.torsion import build_torsion

    rigid = rods.rigid
    known = np.where(np.isnan(polar), 0.0, polar)
    torsion = build_torsion(
        net, gj, known, line, rods.clamps[rigid], rods.tangent[rigid],
        None if twist is None else twist.twists, joints,
        twist_ends(None if net.springs is None else net.springs.ends),
    )  # fmt: skip
    unknown = (gj > 0.0) & np.isnan(polar)
    if not unknown.any():
        return torsion
    cables = getattr(case.geometry, "cables", ())
    where = sorted({int(c) for c in line[unknown] if c >= 0}) if cables else []
    paths = [f"geometry.cable[{c}].material" for c in where] or ["material"]
    missing = (
        f"{paths[0]}.polar_inertia: a rod that twists (GJ > 0) needs its rotational "
        "inertia for its modes: give the material a radius (rho J_p = density pi (r^4 - "
        "ri^4) / 2 of a round section or tube) or polar_inertia [kg m], the mass polar "
        "moment per length (0: no rotational inertia, the twist quasistatic)"
    )
    if torsion is None:
        from catenet.model.torsion import no_torsion

        torsion = no_torsion()
    return replace(torsion, missing=missing)
