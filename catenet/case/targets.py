"""Targets of form finding (``[[target]]``): what ``catenet formfind`` varies the force
densities to reach.

A target is a node's coordinate (``node`` with ``x``, ``y``, ``z`` or ``point``; a node
set: each of its nodes, the value one for all or one per node), a surface the nodes lie
on (``surface``, a triangle mesh file taken as a height field, optionally ``within`` a
vertical distance of it) or a cable's tension
(``cable`` with ``tension``: every edge of the cable, or of each cable a pattern matches;
a number, or a range ``[low, high]``) or its length (``cable`` with ``length``: the sum
of its edges' lengths in the shape found, a number or a range), or a support's reaction
(``support``, a fixed node or a set of them, with ``reaction = [Rx, Ry, Rz]`` or any of
``reaction_x``, ``reaction_y``, ``reaction_z``: the force the support exerts on the net).
Each weighs
in the least squares with ``weight``; ``hard = true`` makes it a bound that must be met.
The nodes and cables are resolved on
the built net (``catenet.formfind.goals``), where a fixed node is refused.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    as_float,
    boolean,
    carried,
    key,
    node,
    parse_table,
    real,
    show,
    text,
)

#: The coordinates a node target may give.
AXES = ("x", "y", "z")

#: The reaction components a support target may give one by one.
REACTIONS = ("reaction_x", "reaction_y", "reaction_z")


def _coordinate(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A finite number (every node of the target) or an array of them (one per node)."""
    if isinstance(v, (list, tuple)):
        vals = [as_float(c) for c in v]
        if not v or any(c is None or not carried(c) for c in vals):
            return ck.bad(path, v, "must be a number or an array of numbers (one per node)")
        return tuple(vals)
    f = as_float(v)
    if f is None or not carried(f):
        return ck.bad(path, v, "must be a finite number, or an array of them (one per node)")
    return f


def _point(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """[x, y, z] (every node of the target) or an array of them (one per node)."""
    if isinstance(v, (list, tuple)) and v and all(isinstance(p, (list, tuple)) for p in v):
        out = [ck.vec3(p, f"{path}[{k}]") for k, p in enumerate(v)]
        return BAD if BAD in out else tuple(out)
    return ck.vec3(v, path)


def _tension(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A tension > 0, or a range [low, high] with 0 <= low < high."""
    return _positive_or_range(ck, v, path, "a tension > 0 [N]")


def _length(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A length > 0, or a range [low, high] with 0 <= low < high."""
    return _positive_or_range(ck, v, path, "a length > 0 [m]")


def _positive_or_range(ck: Checker, v: Any, path: str, what: str) -> Any:
    """A number > 0 (``what``), or a range [low, high] with 0 <= low < high."""
    need = f"must be {what} or a range [low, high] with 0 <= low < high"
    if isinstance(v, (list, tuple)):
        vals = [as_float(c) for c in v]
        if len(v) != 2 or any(c is None or not carried(c) for c in vals):
            return ck.bad(path, v, need)
        low, high = vals
        if not (low is not None and high is not None and 0 <= low < high):
            return ck.bad(path, v, need)
        return (low, high)
    f = as_float(v)
    if f is None or not (carried(f) and f > 0):
        return ck.bad(path, v, need)
    return f


_node_key = node  # (the class's own field ``node`` shadows the declaration's name there)


def _reaction(axis: str) -> Any:
    return real(
        None,
        write="given",
        unit="N",
        doc=f"support: the {axis} component of the force it exerts on the net",
    )


def _coord(axis: str) -> Any:
    return key(
        _coordinate,
        "a number or one per node",
        None,
        write="given",
        unit="m",
        doc=f"node: the {axis} it reaches",
    )


@dataclass(frozen=True)
class TargetConfig(Declared):
    """One target of form finding; see the module docstring."""

    node: Any = node(
        None,
        write="given",
        doc="the node (index, name or node set) to place; with surface, none: every free node",
    )
    cable: str | None = text(
        None,
        nonempty=True,
        write="given",
        doc='the cable (name or pattern "guy*") whose tension or length is asked',
    )
    x: Any = _coord("x")
    y: Any = _coord("y")
    z: Any = _coord("z")
    point: Any = key(
        _point,
        "[x, y, z] or one per node",
        None,
        write="given",
        unit="m",
        doc="node: the point it reaches",
    )
    surface: str | None = text(
        None,
        nonempty=True,
        write="given",
        doc="node: a triangle mesh file (.stl, .obj, ...; relative to the case file), a "
        "height field z = f(x, y) the nodes lie on",
    )
    within: float | None = real(
        None,
        ge=0,
        write="given",
        unit="m",
        doc="surface: how far above or below it the nodes may lie (default: on it)",
    )
    smooth: bool = boolean(
        False,
        write="given",
        doc="surface: a smooth height field through the mesh's vertices (C1: cubic on each "
        "triangle, its slopes continuous) instead of its flat triangles",
    )
    tension: Any = key(
        _tension,
        "a number > 0 or a range [low, high]",
        None,
        write="given",
        unit="N",
        doc="cable: the tension of each of its edges (or the range it stays in)",
    )
    length: Any = key(
        _length,
        "a number > 0 or a range [low, high]",
        None,
        write="given",
        unit="m",
        doc="cable: its length in the shape found, the sum of its edges' (of each cable a "
        "pattern matches), or the range it stays in",
    )
    support: Any = _node_key(
        None,
        write="given",
        doc="the fixed node (index, name or node set) whose reaction is asked",
    )
    reaction: Any = key(
        lambda ck, v, path, ctx: ck.vec3(v, path),
        "[Rx, Ry, Rz]",
        None,
        write="given",
        unit="N",
        doc="support: the force it exerts on the net (as /result/reaction)",
    )
    reaction_x: float | None = _reaction("x")
    reaction_y: float | None = _reaction("y")
    reaction_z: float | None = _reaction("z")
    weight: float = real(1.0, gt=0, doc="its weight in the least squares (misses scaled first)")
    hard: bool = boolean(False, doc="a bound: the force densities must meet it (to formfind.tol)")

    @property
    def kind(self) -> str:
        """'x', 'y', 'z', 'point', 'surface', 'tension', 'length', 'reaction' or
        'reaction_x' ... (the first given)."""
        for k in (*AXES, "point", "surface", "tension", "length", "reaction", *REACTIONS):
            if getattr(self, k) is not None:
                return k
        return ""

    @property
    def axes(self) -> tuple[str, ...]:
        """The coordinates a node target gives (x, y, z in order)."""
        return tuple(a for a in AXES if getattr(self, a) is not None)

    @property
    def components(self) -> tuple[int, ...]:
        """A support target's reaction components (0, 1, 2 for x, y, z)."""
        if self.reaction is not None:
            return (0, 1, 2)
        return tuple(c for c, k in enumerate(REACTIONS) if getattr(self, k) is not None)

    def reaction_of(self, c: int) -> float:
        """A support target's reaction component c [N]."""
        if self.reaction is not None:
            return float(self.reaction[c])
        return float(getattr(self, REACTIONS[c]))

    def describe(self) -> str:
        """``node 'center' z`` or ``cable 'guy*' tension``: what the target is about."""
        if self.support is not None:
            what = (
                "reaction"
                if self.reaction is not None
                else " ".join(REACTIONS[c] for c in self.components)
            )
            return f"support {self.support!r} {what}"
        if self.cable is not None:
            return f"cable {self.cable!r} {'length' if self.length is not None else 'tension'}"
        what = "point" if self.point is not None else " ".join(self.axes)
        if self.surface is not None:
            what = f"on {Path(self.surface).name}{' (smooth)' if self.smooth else ''}"
            if self.node is None:
                return f"free nodes {what}"
        return f"node {self.node!r} {what}"


def parse_targets(ck: Checker, value: Any, ctx: Context, base_dir: Path) -> tuple | Any:
    """The ``[[target]]`` array of tables (absent: none) with the rules between keys; a
    surface's file made absolute (from ``base_dir``, the case file's folder)."""
    if value is None:
        return ()
    out = []
    for k, t in enumerate(ck.array_of_tables(value, "target")):
        path = f"target[{k}]"
        tgt = parse_table(ck, t, TargetConfig, path, ctx)
        if tgt is not BAD and not _consistent(ck, tgt, t, path):
            tgt = BAD
        if tgt is not BAD and tgt.surface is not None:
            file = Path(tgt.surface)
            full = (file if file.is_absolute() else base_dir / file).resolve()
            if not full.is_file():
                ck.add(f"{path}.surface = {tgt.surface!r}: no such file ({full})")
                tgt = BAD
            else:
                tgt = dataclasses.replace(tgt, surface=str(full))
        out.append(tgt)
    return BAD if BAD in out else tuple(out)


def _consistent(ck: Checker, tgt: TargetConfig, raw: dict, path: str) -> bool:
    """The rules between a target's keys: a node, a cable or a support; what each needs."""
    given = [k for k in ("reaction", *REACTIONS) if getattr(tgt, k) is not None]
    if tgt.support is not None or given:
        return _support(ck, tgt, raw, path, given)
    node_keys = [k for k in (*AXES, "point", "surface") if getattr(tgt, k) is not None]
    if tgt.within is not None and tgt.surface is None:
        ck.add(f"{path}.within = {show(raw['within'])}: only with surface")
        return False
    if "smooth" in raw and tgt.surface is None:
        ck.add(f"{path}.smooth = {str(bool(tgt.smooth)).lower()}: only with surface")
        return False
    if tgt.node is None and tgt.cable is None and tgt.surface is not None:
        return True  # (every free node)
    if (tgt.node is None) == (tgt.cable is None):
        both = tgt.node is not None
        ck.add(
            f"{path}: {'gives both node and cable' if both else 'gives neither node nor cable'}"
            ": give node (with x, y, z, point or surface), cable (with tension or length) "
            "or support (with reaction), or surface alone (every free node)"
        )
        return False
    if tgt.node is not None:
        for one in ("tension", "length"):
            if getattr(tgt, one) is not None:
                ck.add(f"{path}.{one} = {show(raw[one])}: a cable's target: give cable")
                return False
        if not node_keys:
            ck.add(
                f"{path}: node = {show(tgt.node)} needs x, y, z, point or surface: what it reaches"
            )
            return False
        for one in ("point", "surface"):
            if getattr(tgt, one) is not None and len(node_keys) > 1:
                ck.add(f"{path}.{one} = {show(raw[one])}: give {one} alone, not with x, y, z")
                return False
        return True
    if node_keys:
        ck.add(f"{path}.{node_keys[0]} = {show(raw[node_keys[0]])}: a node's target: give node")
        return False
    if tgt.tension is None and tgt.length is None:
        ck.add(
            f"{path}: cable = {tgt.cable!r} needs tension or length: a number > 0 or [low, high]"
        )
        return False
    if tgt.tension is not None and tgt.length is not None:
        ck.add(
            f"{path}.length = {show(raw['length'])}: give a cable's tension and its length "
            "in targets of their own"
        )
        return False
    return True


def _support(ck: Checker, tgt: TargetConfig, raw: dict, path: str, given: list) -> bool:
    """A support target: support with reaction or its components, nothing else."""
    if tgt.support is None:
        ck.add(f"{path}.{given[0]} = {show(raw[given[0]])}: a support's target: give support")
        return False
    other = [
        k for k in ("node", "cable", *AXES, "point", "surface", "tension", "length") if k in raw
    ]
    if other:
        ck.add(
            f"{path}.{other[0]} = {show(raw[other[0]])}: support takes reaction (or "
            "reaction_x, reaction_y, reaction_z) only: give it in a target of its own"
        )
        return False
    if not given:
        ck.add(
            f"{path}: support = {show(tgt.support)} needs reaction = [Rx, Ry, Rz] or any of "
            "reaction_x, reaction_y, reaction_z"
        )
        return False
    if tgt.reaction is not None and len(given) > 1:
        ck.add(f"{path}.{given[1]} = {show(raw[given[1]])}: give reaction or its components")
        return False
    return True


__all__ = ["AXES", "REACTIONS", "TargetConfig", "parse_targets"]
