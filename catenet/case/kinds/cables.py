"""Cables and node sets of a graph case.

``[[geometry.cable]]`` is a named polyline through given nodes (joints are shared nodes,
named by index or by a node set of one node), with its own material (a table of
[material] keys overriding it), prestress and edge length: every segment between
consecutive polyline nodes is split into ``ceil(length / edge_length - 1e-9)`` equal edges,
whose new nodes are numbered after the given ones, cable after cable. ``[geometry.sets]``
names groups of given nodes for supports and loads (``name = [nodes]``).

``cable_mesh`` builds the nodes and edges; a point load at a position along a cable
(``load.point`` with ``cable`` and ``at``) becomes a break point of its segment, so that a
node sits exactly there.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    as_int,
    duplicates,
    key,
    names,
    parse_keys,
    plain,
    real,
    show,
    text,
)
from catenet.case.kinds.regions import Region, check_region, resolve
from catenet.case.material import MaterialConfig, parse_material

#: How close (as a fraction of a segment) a load position must be to a node to use it.
AT_TOL = 1e-9


# --------------------------------------------------------------------------- values


@dataclass(frozen=True)
class Overrides(Declared):
    """The [material] keys a cable gives, in the order given (written back as a table)."""

    items: tuple[tuple[str, Any], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        return dict(self.items)

    def to_dict(self) -> dict:
        return {k: plain(v) for k, v in self.items}


@dataclass(frozen=True)
class NodeSets(Declared):
    """Named groups of nodes, ``((name, (i, j, ...) or Region), ...)``: given nodes, or a
    region (catenet/case/kinds/regions.py) evaluated on nodes."""

    items: tuple[tuple[str, Any], ...] = ()

    def as_dict(self, xyz: np.ndarray | None = None) -> dict[str, tuple[int, ...]]:
        """Name -> node indices: regions evaluated on ``xyz`` (None: left out)."""
        if xyz is None:
            return {k: v for k, v in self.items if not isinstance(v, Region)}
        return resolve(self.items, xyz)

    @property
    def regions(self) -> bool:
        return any(isinstance(v, Region) for _, v in self.items)

    def to_dict(self) -> dict:
        return {k: (v.to_dict() if isinstance(v, Region) else list(v)) for k, v in self.items}


#: [material] keys that hold for the whole net, not per cable: the edges' contact radius
#: (``solver.edge_contact``: one capsule radius for every edge of the net)
NET_WIDE = ("contact_radius",)


def _material_names() -> tuple[str, ...]:
    return names(MaterialConfig)


def _check_material(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A table of [material] keys, each checked as [material] checks it."""
    t = ck.table(v, path)
    if t is None:
        return BAD
    ck.keys(t, path, _material_names(), " of [material]")
    for k in NET_WIDE:  # (a cable's was accepted and ignored)
        if k in t:
            ck.add(
                f"{path}.{k} = {show(t[k])}: the [material] table's key, for every cable of "
                f"the net (material.{k}), not a cable's"
            )
            return BAD
    given = tuple(k for k in t if k in _material_names())
    if not given:
        return Overrides()
    values = parse_keys(ck, t, MaterialConfig, path, Context(), only=given)
    if BAD in values.values():
        return BAD
    return Overrides(tuple((k, values[k]) for k in given))


def _check_polyline(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """At least two nodes: indices (>= 0) or names (node sets of one node)."""
    if not isinstance(v, (list, tuple)) or len(v) < 2:
        return ck.bad(path, v, "must be an array of at least 2 nodes (indices or node sets)")
    out: list[int | str] = []
    bad = []
    for k, x in enumerate(v):
        i = as_int(x)
        if isinstance(x, str) and x.strip():
            out.append(x)
        elif i is not None and i >= 0:
            out.append(i)
        else:
            bad.append((f"{path}[{k}]", x))
    ck.first(bad, "must be a node index (an integer >= 0) or the name of a node set of one node")
    return BAD if bad else tuple(out)


def _check_lengths(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """Numbers > 0 (one per edge of the cable: checked when it is split); not with
    prestress."""
    if not isinstance(v, (list, tuple)) or not v:
        return ck.bad(path, v, "must be an array of numbers > 0, one per edge of the cable")
    out = [ck.real(x, f"{path}[{k}]", gt=0.0) for k, x in enumerate(v)]
    if BAD in out:
        return BAD
    if ctx.values.get("prestress") is not None:
        return ck.bad(path, v, "gives the rest lengths: give it or prestress, not both")
    return tuple(out)


def _check_sets(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A table of name = [node indices] (each non-empty and listing each node once) or
    name = { box = ... } or { near = ... }."""
    t = ck.table(v, path)
    if t is None:
        return BAD
    taken = ctx.kind.node_names if ctx.kind is not None else ()
    items, before = [], len(ck.problems)
    for name, nodes in t.items():
        here = f"{path}.{name}"
        if name in taken or str(name).startswith("cable:"):
            ck.bad(here, nodes, f"{name!r} names a node already: choose another set name")
        elif isinstance(nodes, dict):
            region = check_region(ck, nodes, here)
            items.append((str(name), region))
        elif not isinstance(nodes, (list, tuple)) or not nodes:
            ck.bad(here, nodes, "names no node: must be a non-empty array of node indices")
        else:
            idx = [as_int(x) for x in nodes]
            bad = [(f"{here}[{k}]", nodes[k]) for k, i in enumerate(idx) if i is None or i < 0]
            ck.first(bad, "must be a node index (an integer >= 0)")
            dup = [] if bad else duplicates(idx)
            if dup:
                ck.bad(here, nodes, f"node {dup[0]} appears more than once: list each once")
            items.append((str(name), tuple(i for i in idx if i is not None)))
    return BAD if len(ck.problems) > before else NodeSets(tuple(items))


def sets_key() -> Any:
    return key(
        _check_sets,
        "a table of name = [node indices], { box = [[x0, y0, z0], [x1, y1, z1]] } or "
        "{ near = [x, y, z] }",
        None,
        write="given",
        shown="none",
        doc="node sets: a name usable wherever a node is (supports, loads, cable nodes)",
    )


@dataclass(frozen=True, kw_only=True)
class CableConfig(Declared):
    """A cable: a named polyline through given nodes, split into edges no longer than its
    ``edge_length``, of [material] with ``material``'s keys overriding it."""

    name: str = text(nonempty=True, missing="the cable's name", doc="its name (unique)")
    nodes: tuple[int | str, ...] = key(
        _check_polyline,
        "an array of at least 2 nodes (indices or node sets of one node)",
        missing="[i, j, ...]: the given nodes it passes through, in order",
        doc="the polyline through given nodes; joints are shared nodes",
    )
    edge_length: float | None = real(
        None,
        gt=0,
        write="given",
        shown="geometry.edge_length",
        unit="m",
        doc="longest edge after splitting its segments",
    )
    prestress: float | None = real(
        None,
        write="given",
        shown="material's",
        unit="N",
        doc="its tension in the given geometry (rest lengths derived from it)",
    )
    rest_length: tuple[float, ...] | None = key(
        _check_lengths,
        "an array of numbers > 0, one per edge of the cable (after splitting)",
        None,
        write="given",
        shown="from prestress, else the given lengths",
        unit="m",
        doc="unstressed length of each of its edges, in order (as catenet formfind writes)",
    )
    material: Overrides | None = key(
        _check_material,
        "a table of [material] keys",
        None,
        write="given",
        shown="[material]",
        doc="[material] keys that differ for this cable (E, radius, area, EA, density, ...)",
    )
    twist: float | None = real(
        None,
        write="given",
        shown="none",
        unit="rad",
        doc="a closed cable of a twisting rod (GJ > 0, a ring): the twist it was closed with, "
        "the turn of one end against the other where they were joined",
    )


# --------------------------------------------------------------------------- checks


def polylines(
    ck: Checker,
    cables: Sequence[CableConfig],
    xyz: np.ndarray,
    edges: Sequence,
    sets: Mapping[str, tuple[int, ...]],
    named: Mapping[str, int],
) -> list[tuple[int, ...]] | None:
    """The node indices of every cable, checked: names unique, nodes known, no
    zero-length segment, no segment twice (in two cables, or a cable and an edge). None
    when any is bad (the problems are in ``ck``)."""
    n = len(xyz)
    before = len(ck.problems)
    for name, nodes in sets.items():
        bad = [(f"geometry.sets.{name}[{k}]", i) for k, i in enumerate(nodes) if i >= n]
        ck.first(bad, f"names no node: must be a node index in 0..{n - 1}")
    if len(ck.problems) > before:
        return None
    seen_names: dict[str, int] = {}
    out = []
    for c, cable in enumerate(cables):
        path = f"geometry.cable[{c}]"
        if cable.name in seen_names:
            ck.add(
                f"{path}.name = {cable.name!r}: also the name of geometry.cable"
                f"[{seen_names[cable.name]}]: cable names must be unique"
            )
        seen_names.setdefault(cable.name, c)
        out.append(
            tuple(
                _node(ck, ref, f"{path}.nodes[{k}]", n, sets, named)
                for k, ref in enumerate(cable.nodes)
            )
        )
    if len(ck.problems) > before:
        return None
    segments: dict[tuple[int, int], str] = {
        tuple(sorted(e)): f"geometry.edges[{k}]" for k, e in enumerate(edges)
    }
    for c, line in enumerate(out):
        for k, (i, j) in enumerate(zip(line[:-1], line[1:], strict=True)):
            path = f"geometry.cable[{c}].nodes[{k}:{k + 2}]"
            if i == j or not np.linalg.norm(xyz[j] - xyz[i]) > 0:
                ck.bad(
                    path,
                    [i, j],
                    "zero-length segment: consecutive nodes of a cable must be distinct points",
                )
                continue
            pair = (min(i, j), max(i, j))
            if pair in segments:
                ck.bad(
                    path,
                    [i, j],
                    f"repeats the segment of {segments[pair]}: cables share nodes, not segments",
                )
            segments.setdefault(pair, path.split(".nodes")[0])
    return None if len(ck.problems) > before else out


def _node(
    ck: Checker, ref: int | str, path: str, n: int, sets: Mapping, named: Mapping
) -> int | Any:
    """The index of one polyline node (an index, a node name or a node set of one node)."""
    if isinstance(ref, int):
        if ref >= n:
            return ck.bad(path, ref, f"is no node: must be a node index in 0..{n - 1}")
        return ref
    if ref in named:
        return named[ref]
    if ref in sets:
        if len(sets[ref]) != 1:
            return ck.bad(
                path, ref, f"names {len(sets[ref])} nodes: a cable passes through one node each"
            )
        return sets[ref][0]
    known = ", ".join(map(repr, [*named, *sets]))
    return ck.bad(path, ref, f"no such node set or named node (accepted: an index, or {known})")


# --------------------------------------------------------------------------- the mesh


@dataclass(frozen=True, eq=False)
class CableIndex:
    """Which cable each edge belongs to: ``edge`` (M,) its index in ``names``, -1 for the
    graph's own edges."""

    names: tuple[str, ...]
    edge: np.ndarray


@dataclass(frozen=True, eq=False)
class CableMesh:
    """Nodes (given ones first) and edges (the graph's own first, then each cable's),
    the cable of each edge (-1: none) and the node of each point load along a cable."""

    nodes: np.ndarray
    edges: np.ndarray
    cable: np.ndarray
    at_nodes: dict[int, int]


def split_count(length: np.ndarray, h: float | None) -> np.ndarray:
    """Edges per piece: as the square net's pieces (contract §2); one without h."""
    if h is None:
        return np.ones(len(length), dtype=np.int64)
    return np.minimum(_counts(length, h), 2.0**62).astype(np.int64)  # beyond: refused anyway


def _counts(length: np.ndarray, h: float) -> np.ndarray:
    return np.maximum(np.ceil(length / h - 1e-9), 1.0)


def estimate(xyz: np.ndarray, lines: Sequence[Sequence[int]], hs: Sequence) -> tuple[float, float]:
    """(new nodes, edges) the cables add, from their segment lengths, in floating point (a
    cable 1e99 m long in edges of 0.5 m is 2e99 edges: the size guard refuses it)."""
    nodes = edges = 0.0
    for line, h in zip(lines, hs, strict=True):
        p = xyz[np.asarray(line, dtype=np.int64)]
        length = np.linalg.norm(np.diff(p, axis=0), axis=1)
        k = _counts(length, h) if h is not None else np.ones(len(length))
        nodes += float(np.sum(k - 1))
        edges += float(np.sum(k))
    return nodes, edges


def cable_mesh(
    xyz: np.ndarray,
    edges: np.ndarray,
    lines: Sequence[Sequence[int]],
    hs: Sequence,
    at: Mapping[int, Sequence[tuple[float, int]]] | None = None,
) -> CableMesh:
    """The net's nodes and edges with every cable split; ``at[c]`` lists (fraction of
    cable c's length, load index) of the point loads along it."""
    at = at or {}
    points = [np.asarray(xyz, dtype=np.float64)]
    count = len(xyz)
    pieces = [np.asarray(edges, dtype=np.int64).reshape(-1, 2)]
    owner = [np.full(len(pieces[0]), -1, dtype=np.int64)]
    at_nodes: dict[int, int] = {}
    for c, (polyline, h) in enumerate(zip(lines, hs, strict=True)):
        line = np.asarray(polyline, dtype=np.int64)
        seg = np.linalg.norm(np.diff(xyz[line], axis=0), axis=1)
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        breaks: dict[int, list[tuple[float, int]]] = {}
        for frac, k in at.get(c, ()):
            s = frac * cum[-1]
            j = int(np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1))
            t = (s - cum[j]) / seg[j]
            if t <= AT_TOL:
                at_nodes[k] = int(line[j])
            elif t >= 1.0 - AT_TOL:
                at_nodes[k] = int(line[j + 1])
            else:
                breaks.setdefault(j, []).append((t, k))
        chain: list[int] = [int(line[0])]
        for j in range(len(seg)):
            a, b = xyz[line[j]], xyz[line[j + 1]]
            ts, ends = [0.0], [int(line[j])]
            for t, k in sorted(breaks.get(j, ())):
                if t - ts[-1] > AT_TOL:  # a new node there (else the last one carries it)
                    ts.append(t)
                    points.append((a + t * (b - a))[None, :])
                    ends.append(count)
                    count += 1
                at_nodes[k] = ends[-1]
            ts.append(1.0)
            ends.append(int(line[j + 1]))
            t = np.asarray(ts)
            for q, m in enumerate(split_count(np.diff(t) * seg[j], h)):
                if m > 1:
                    s = t[q] + (t[q + 1] - t[q]) * np.arange(1, m) / m
                    points.append(a[None, :] + s[:, None] * (b - a)[None, :])
                    chain.extend(range(count, count + m - 1))
                    count += m - 1
                chain.append(ends[q + 1])
        ids = np.asarray(chain, dtype=np.int64)
        pieces.append(np.column_stack([ids[:-1], ids[1:]]))
        owner.append(np.full(len(ids) - 1, c, dtype=np.int64))
    return CableMesh(
        nodes=np.ascontiguousarray(np.concatenate(points)),
        edges=np.ascontiguousarray(np.concatenate(pieces)),
        cable=np.concatenate(owner),
        at_nodes=at_nodes,
    )


# --------------------------------------------------------------------------- materials


#: Keys of [material] that a cable's key replaces (a cable giving EA drops E, ...): a
#: cable's own section (radius or area) drops the case's tube (inner_radius), unless it
#: gives one itself (a solid tie beside tubes was refused as "a tube needs its outer
#: radius").
_REPLACES = {
    "E": ("EA", "table"),
    "EA": ("E", "table"),
    "radius": ("area", "inner_radius"),
    "area": ("radius", "inner_radius"),
    "table": ("E", "EA"),
}


def merged_material(base: dict, over: Mapping[str, Any]) -> dict:
    """The raw [material] table of a cable: ``base`` (the case's, as written) with the
    cable's keys over it; a key replaces those it excludes (EA replaces E and a table, a
    law other than "table" drops the table)."""
    out = dict(base)
    for k, v in over.items():
        for other in _REPLACES.get(k, ()):
            if other not in over:  # (the case's key, not one the cable gives too)
                out.pop(other, None)
        if k == "law" and v != "table":
            out.pop("table", None)
        if k == "law" and v == "table":
            out.pop("E", None)
            out.pop("EA", None)
        out[k] = plain(v)
    if out.get("law", "linear") != "table":
        out.pop("table", None)
    return out


def cable_materials(ck: Checker, base: Any, cables: Sequence[CableConfig]) -> list:
    """The MaterialConfig of every cable (``base`` where it overrides nothing), checked
    as [material] is; problems name the cable's keys. BAD entries where a cable's is bad."""
    out = []
    raw = base.to_dict()
    for c, cable in enumerate(cables):
        over = cable.material.as_dict() if cable.material is not None else {}
        if cable.prestress is not None:
            over["prestress"] = cable.prestress
        if over.get("EI", 0.0) != 0.0 and "tension_only" not in over:
            over["tension_only"] = False  # a rod carries compression (unless it says)
        if not over:
            out.append(base)
            continue
        path = f"geometry.cable[{c}]"
        if cable.prestress is not None and cable.material is not None:
            if "prestress" in cable.material.as_dict():
                ck.add(
                    f"{path}.prestress = {cable.prestress!r}: give {path}.prestress or "
                    f"{path}.material.prestress, not both"
                )
                out.append(BAD)
                continue
        sub = Checker()
        mat = parse_material(sub, merged_material(raw, over), Context(), None)
        for msg in sub.problems:
            if msg.startswith("material.prestress") and cable.prestress is not None:
                ck.add(f"{path}.prestress" + msg[len("material.prestress") :])
            elif msg.startswith("material.") and msg[9:].split(" ")[0].split(":")[0] in over:
                ck.add(f"{path}.{msg}")
            else:
                ck.add(f"{path} (its [material] with the cable's keys over it): {msg}")
        out.append(BAD if sub.problems else mat)
    return out


def line_force(net, on: np.ndarray, force, out: np.ndarray | None = None) -> np.ndarray:
    """Nodal forces (N, 3) of a force per unit unstressed length [N/m] along the edges
    ``on`` (a mask), lumped as the self-weight is: half of each edge's f l0 to each end;
    added to ``out`` when given."""
    out = np.zeros((net.n_nodes, 3)) if out is None else out
    half = 0.5 * net.rest_length[on][:, None] * np.asarray(force, dtype=np.float64)[None, :]
    np.add.at(out, net.edges[on, 0], half)
    np.add.at(out, net.edges[on, 1], half)
    return out


__all__ = [
    "CableConfig",
    "CableIndex",
    "CableMesh",
    "NodeSets",
    "Overrides",
    "cable_materials",
    "cable_mesh",
    "estimate",
    "line_force",
    "merged_material",
    "polylines",
    "sets_key",
]
