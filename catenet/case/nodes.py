"""Node references (indices, names such as "center", a graph's node sets) and cable names
checked against the geometry: in range, known, supports listed once, only fixed nodes move
and each once."""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import BAD, Checker, duplicates, show
from catenet.case.kinds.base import GeometryConfig, Topology, expand, resolve, with_prefix
from catenet.case.kinds.graph import GraphConfig
from catenet.case.kinds.netfile import flag_note
from catenet.case.sections import (
    LoadConfig,
    NodeRef,
    OutputConfig,
    SupportsConfig,
)
from catenet.errors import ConfigError


def _needs_topology(g: GeometryConfig, supports: Any, load: Any, probe: Any = None) -> bool:
    """A kind whose topology needs a build (square nets) is built to check node
    references only when there are any."""
    if not g.lazy_topology:
        return True
    refs = [probe]
    if isinstance(supports, SupportsConfig):
        refs += list(supports.fixed or ()) + [m.node for m in supports.moves]
        refs += [r for v in supports.vessels for r in v.nodes]
        refs += list(supports.clamped) + list(supports.rigid_joints)
        refs += [r for t in supports.twists for r in t.nodes]
        refs += [r for _, _, part in partial_supports(supports) for r in part.nodes]
    if isinstance(load, LoadConfig):
        refs += [p.node for p in load.points if p.node is not None]
        for a in load.areas:
            refs += [a.nodes] if isinstance(a.nodes, str) else list(a.nodes or ())
        if any(p.cable is not None for p in load.points):
            return True
        if any(ln.cable is not None for ln in load.lines):
            return True
    return any(isinstance(r, int) for r in refs) or bool(
        isinstance(supports, SupportsConfig) and (supports.moves or supports.vessels)
    )


def check_nodes(
    ck: Checker,
    g: GeometryConfig,
    supports: Any,
    load: Any,
    output: Any = None,
    flies: bool = False,
    *,
    prefix: str = "load",
) -> None:
    """Every node reference of the supports, loads and output probe (each BAD when its
    section failed) against the geometry ``g``; ``flies``: a dynamic run, where the net
    may have no support; ``prefix``: the loads' key path (a load case's
    ``load_case[k]``: then its loads alone are checked, not the supports)."""
    probe = output.probe if isinstance(output, OutputConfig) else None
    if not _needs_topology(g, supports, load, probe):
        return
    try:
        topo = g.topology()
    except ConfigError as exc:  # the builder's own checks
        ck.problems.extend(with_prefix(p, "supports.fixed") for p in exc.problems)
        return
    refs = _Refs(ck, topo, g.file if isinstance(g, GraphConfig) else None)
    fixed = set(topo.default_fixed)
    fixed_key = g.default_supports
    before = len(ck.problems)
    if isinstance(supports, SupportsConfig):
        if supports.fixed is not None:
            fixed_key = "supports.fixed"
            fixed = _fixed_nodes(refs, supports.fixed)
        held = _check_partial(refs, supports, fixed, fixed_key)
        _check_moves(refs, _moved(supports), fixed, fixed_key, held)
        for k, r in enumerate(supports.clamped):
            if refs.known(r, f"supports.clamped[{k}]"):
                _check_clamp(refs, f"supports.clamped[{k}]", r, held, supports)
        for k, r in enumerate(supports.rigid_joints):
            refs.known(r, f"supports.rigid_joints[{k}]")
        for k, t in enumerate(supports.twists):
            for j, r in enumerate(t.nodes):
                refs.known(r, f"supports.twist[{k}].nodes[{j}]")
        fixed = fixed | set(held)
    if isinstance(load, LoadConfig):
        _check_loads(refs, load, g, prefix)
    if probe is not None:
        _check_probe(refs, probe)
    failed = supports is BAD  # its own problems are said; what it holds is unknown
    if len(ck.problems) == before and prefix == "load" and not failed:
        g.check_supports(ck, fixed, fixed_key, flies)


@dataclass(frozen=True)
class _Refs:
    """Node references checked against the topology ``topo``, problems added to ``ck``;
    ``file``: the net file the geometry was read from (None: none), which messages name."""

    ck: Checker
    topo: Topology
    file: str | None = None

    def known(self, ref: NodeRef, path: str) -> bool:
        """Whether ``ref`` is a node index in range, a named node or a node set (else a
        problem at ``path``)."""
        n = self.topo.n_nodes
        if isinstance(ref, int) and ref >= n:
            self.ck.bad(path, ref, f"must be a node index in 0..{n - 1} (or a named node)")
            return False
        if isinstance(ref, str) and ref not in self.topo.names and ref not in self.topo.sets:
            self.ck.add(_unknown_name(path, ref, self.topo) + flag_note(self.file))
            return False
        return True

    def nodes(self, ref: NodeRef) -> tuple[int, ...]:
        """The nodes a known reference stands for."""
        return expand(ref, self.topo.names, self.topo.sets)


def _fixed_nodes(refs: _Refs, fixed: tuple[NodeRef, ...]) -> set[int]:
    """The nodes supports.fixed pins (none while a reference is bad); a problem for a
    node listed twice."""
    ok = [refs.known(r, f"supports.fixed[{k}]") for k, r in enumerate(fixed)]
    if not all(ok):
        return set()
    single = [r for r in fixed if r not in refs.topo.sets]
    dups = duplicates([resolve(r, refs.topo.names) for r in single])
    if dups:
        refs.ck.bad(
            "supports.fixed",
            list(fixed),
            f"node {dups[0]} appears more than once: list each node once",
        )
    return {i for r in fixed for i in refs.nodes(r)}


def partial_supports(supports: SupportsConfig) -> list[tuple[str, int, Any]]:
    """(kind, index, table) of every roller, slider and spring of ``supports``."""
    out: list[tuple[str, int, Any]] = []
    for kind, tables in (
        ("roller", supports.rollers),
        ("slider", supports.sliders),
        ("spring", supports.springs),
    ):
        out += [(kind, k, t) for k, t in enumerate(tables)]
    return out


def _check_partial(
    refs: _Refs, supports: SupportsConfig, fixed: set[int], fixed_key: str
) -> dict[int, str]:
    """Problems of the rollers', sliders' and springs' nodes: unknown, fixed as well
    (``fixed``, named by ``fixed_key``), on two guides; the supported nodes, each with
    the key that holds it."""
    guided: dict[int, str] = {}
    held: dict[int, str] = {}
    for kind, k, part in partial_supports(supports):
        here = f"supports.{kind}[{k}].nodes"
        for j, ref in enumerate(part.nodes):
            path = here if len(part.nodes) == 1 else f"{here}[{j}]"
            if not refs.known(ref, path):
                continue
            for i in refs.nodes(ref):
                shown = ref if isinstance(ref, int) else f"{ref!r} (node {i})"
                if i in fixed and _turns(part):
                    refs.ck.add(
                        f"{path} = {shown}: node {i} is fixed already ({fixed_key}): its "
                        "position is held, and a 6x6 spring there would hold its rotation "
                        "alone: give that as [[supports.rotational]] (a rod end's direction "
                        "held by a rotational spring), or leave the node out of the fixed "
                        "nodes (supports.fixed) for the spring to hold both"
                    )
                elif i in fixed:
                    refs.ck.add(
                        f"{path} = {shown}: node {i} is fixed already ({fixed_key}): a fixed "
                        f"node is held in every direction, a {kind} there would hold nothing: "
                        "leave it out of the fixed nodes (supports.fixed) or of this support"
                    )
                elif kind != "spring" and i in guided:
                    refs.ck.add(
                        f"{path} = {shown}: node {i} is on {guided[i]} already: one roller or "
                        "slider per node (a node held in every direction is a fixed node)"
                    )
                elif kind != "spring":
                    guided[i] = f"supports.{kind}[{k}]"
                held.setdefault(i, f"supports.{kind}[{k}]")
    return held


def _turns(part) -> bool:
    """Whether a support table is a spring with rotational rows (a 6x6 or six entries)."""
    stiffness = getattr(part, "stiffness", ())
    return np.size(() if stiffness is None else stiffness) in (6, 36)


def _check_clamp(
    refs: _Refs, path: str, ref: NodeRef, held: dict[int, str], supports: SupportsConfig
) -> None:
    """A clamped rod end on a roller, slider or a spring along x, y, z: a clamp holds it
    in place (a 6x6 spring there: its own message, catenet.model.rods)."""
    springs = enumerate(supports.springs)  # a 6x6's stiffness: 6 or 36 numbers
    six = {f"supports.spring[{k}]" for k, t in springs if np.size(t.stiffness) in (6, 36)}
    for i in refs.nodes(ref):
        if i not in held or held[i] in six:
            continue
        shown = ref if isinstance(ref, int) else f"{ref!r} (node {i})"
        what = held[i]
        if what.startswith("supports.spring"):
            hint = f"leave it out of {what} (a clamped end does not move), or hold its "
            hint += "direction by a 6x6 spring (stiffness with six rows) instead of the clamp"
        else:
            hint = f"for an end that slides with its direction held, keep it on {what} "
            hint += "and hold its direction by a stiff [[supports.rotational]]"
        refs.ck.add(
            f"{path} = {shown}: node {i} is on {what} too: a clamp holds a rod end in "
            f"place as well as its direction; {hint} (docs/howto/rods.md)"
        )


def _moved(supports: SupportsConfig) -> list[tuple[str, NodeRef]]:
    """(key path, node) of every support that moves: supports.move's and the vessels'."""
    out = [(f"supports.move[{k}].node", mv.node) for k, mv in enumerate(supports.moves)]
    for k, vessel in enumerate(supports.vessels):
        out += [(f"supports.vessel[{k}].nodes", r) for r in vessel.nodes]
    return out


def _check_moves(
    refs: _Refs,
    moves: list[tuple[str, NodeRef]],
    fixed: set[int],
    fixed_key: str,
    held: dict[int, str] | None = None,
) -> None:
    """Problems of supports.move: a node that is not fixed (``fixed``, named by
    ``fixed_key``; ``held``: the nodes on rollers, sliders and springs), a node that
    moves twice."""
    seen: dict[int, str] = {}
    held = held or {}
    for path, ref in moves:
        if not refs.known(ref, path):
            continue
        for i in refs.nodes(ref):
            if i in held:
                refs.ck.add(
                    f"{path} = {show(ref)}: node {i} is on {held[i]}: a roller, slider or "
                    "spring does not move (supports.move moves fixed nodes only)"
                )
            elif fixed and i not in fixed:
                shown = ref if isinstance(ref, int) else f"{ref!r} (node {i})"
                refs.ck.add(
                    f"{path} = {shown}: is not a fixed node: only supports move "
                    f"(fixed: {fixed_key})"
                )
            if i in seen and seen[i] != path:
                refs.ck.add(
                    f"{path} = {show(ref)}: node {i} already moves in "
                    f"{seen[i].rsplit('.', 1)[0]}: one move per node"
                )
            seen[i] = path


def _check_loads(refs: _Refs, load: LoadConfig, g: GeometryConfig, prefix: str) -> None:
    """Problems of the loads' nodes and cables (under the key path ``prefix``)."""
    for k, pt in enumerate(load.points):
        if pt.node is not None:
            refs.known(pt.node, f"{prefix}.point[{k}].node")
        else:
            _known_cable(refs.ck, f"{prefix}.point[{k}].cable", pt.cable, g, refs.topo)
    for k, ln in enumerate(load.lines):
        if ln.cable is not None:
            _known_cable(refs.ck, f"{prefix}.line[{k}].cable", ln.cable, g, refs.topo)
    for k, ar in enumerate(load.areas):
        if isinstance(ar.nodes, str):
            refs.known(ar.nodes, f"{prefix}.area[{k}].nodes")
        elif ar.nodes is not None:
            for j, r in enumerate(ar.nodes):
                refs.known(r, f"{prefix}.area[{k}].nodes[{j}]")


def _check_probe(refs: _Refs, probe: NodeRef) -> None:
    """A problem unless output.probe names one node."""
    if not refs.known(probe, "output.probe"):
        return
    many = refs.nodes(probe)
    if len(many) != 1:
        refs.ck.add(
            f"output.probe = {probe!r}: the node set has {len(many)} nodes: "
            "the probe must be one node (an index, a node name or a set of one node)"
        )


def _unknown_name(path: str, ref: str, topo: Topology) -> str:
    """The message for a string that names no node and no node set."""
    cables = [k for k in topo.sets if k.startswith("cable:")]
    if ref.startswith("cable:"):
        hint = difflib.get_close_matches(ref, cables, n=1)
        mean = f"; did you mean {hint[0]!r}?" if hint else ""
        have = ", ".join(map(repr, cables)) if cables else "none: the geometry has no cables"
        return f"{path} = {ref!r}: no such cable (the nodes of a cable: {have}){mean}"
    known = [*topo.names, *(k for k in topo.sets if k not in cables)]
    hint = difflib.get_close_matches(ref, known, n=1)
    mean = f"; did you mean {hint[0]!r}?" if hint else ""
    return (
        f"{path} = {ref!r}: must be a node index or one of {', '.join(map(repr, known))} "
        f"(named nodes and the node sets of [geometry.sets]){mean}"
    )


def _known_cable(
    ck: Checker, path: str, name: str | None, g: GeometryConfig, topo: Topology
) -> None:
    """A problem unless ``name`` is one of the geometry's cables."""
    if name in topo.cables:
        return
    if not topo.cables:
        ck.add(
            f"{path} = {name!r}: this geometry has no cables (geometry.kind = {g.kind!r}; "
            "cables are a graph's [[geometry.cable]])"
        )
        return
    hint = difflib.get_close_matches(str(name), topo.cables, n=1)
    mean = f"; did you mean {hint[0]!r}?" if hint else ""
    ck.add(
        f"{path} = {name!r}: no such cable (accepted: {', '.join(map(repr, topo.cables))}){mean}"
    )
