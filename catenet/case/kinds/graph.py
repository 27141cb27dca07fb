"""geometry.kind = "graph": an explicit net, inline or from a JSON file."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from catenet import geometry as geo
from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    as_float,
    as_int,
    declared,
    duplicates,
    key,
    names,
    parse_keys,
    real,
    text,
    value,
)
from catenet.case.kinds.base import Built, GeometryConfig, Topology, resolve, with_prefix
from catenet.errors import ConfigError
from catenet.net import Net

Vec3 = tuple[float, float, float]


def _finite(c: Any) -> float | None:
    f = as_float(c)
    return f if f is not None and math.isfinite(f) else None


def _index(c: Any) -> int | None:
    i = as_int(c)
    return i if i is not None and i >= 0 else None


def _array(ck: Checker, v: Any, path: str, shape: tuple[int, int], convert, need: str) -> Any:
    """An array of at least shape[0] items, each shape[1] values that ``convert`` accepts;
    ``need`` describes one item."""
    least, width = shape
    if not isinstance(v, (list, tuple)) or len(v) < least:
        return ck.bad(path, v, f"must be an array of at least {least} {need.split(':')[0]}")
    out, bad = [], []
    for i, q in enumerate(v):
        item = None
        if isinstance(q, (list, tuple)) and len(q) == width:
            item = tuple(convert(c) for c in q)
            if None in item:
                item = None
        if item is None:
            bad.append((f"{path}[{i}]", q))
        out.append(item)
    ck.first(bad, f"must be {need}")
    return BAD if bad else tuple(out)


def _points(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    return _array(ck, v, path, (2, 3), _finite, "[x, y, z]: 3 finite numbers")


def _pairs(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    return _array(ck, v, path, (1, 2), _index, "[i, j]: two node indices (integers >= 0)")


def _per_edge(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """One number > 0 per edge."""
    if not isinstance(v, (list, tuple)):
        return ck.bad(path, v, "must be an array with one number > 0 per edge")
    vals = [as_float(x) for x in v]
    bad = [
        (f"{path}[{k}]", v[k])
        for k, x in enumerate(vals)
        if x is None or not (math.isfinite(x) and x > 0)
    ]
    ck.first(bad, "must be finite and > 0")
    edges = ctx.values.get("edges")
    if edges is not None and edges is not BAD and len(v) != len(edges):
        return ck.bad(path, v, f"has {len(v)} values: must have one per edge ({len(edges)})")
    return BAD if bad else tuple(vals)


def _index_list(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    if not isinstance(v, (list, tuple)):
        return ck.bad(path, v, "must be an array of node indices")
    out, bad = [], []
    for k, x in enumerate(v):
        i = as_int(x)
        if i is None or i < 0:
            bad.append((f"{path}[{k}]", x))
        out.append(i)
    ck.first(bad, "must be a node index (an integer >= 0)")
    if bad:
        return BAD
    dup = duplicates(out)
    if dup:
        return ck.bad(path, v, f"node {dup[0]} appears more than once: list each node once")
    return tuple(out)


@dataclass(frozen=True)
class GraphConfig(GeometryConfig):
    """An explicit net. ``fixed`` are its default supports; ``rest_length`` and ``EA``
    (per edge) are optional. ``file`` records where the data came from (not compared, and
    the resolved case holds the data itself)."""

    kind: ClassVar[str] = "graph"
    summary: ClassVar[str] = "an explicit net, inline or from a JSON file"
    node_names: ClassVar[tuple[str, ...]] = ("center",)
    default_supports: ClassVar[str] = "geometry.fixed"

    nodes: tuple[Vec3, ...] = key(
        _points,
        "an array of at least 2 [x, y, z]",
        missing="[[x, y, z], ...] (at least 2 nodes)",
        unit="m",
        doc="node positions; center is the node nearest the bounding box's centre",
    )
    edges: tuple[tuple[int, int], ...] = key(
        _pairs,
        "an array of at least 1 [i, j] (node indices)",
        missing="[[i, j], ...] (at least 1 edge)",
        doc="the edges, each joining two distinct nodes once",
    )
    rest_length: tuple[float, ...] | None = key(
        _per_edge,
        "an array with one number > 0 per edge",
        None,
        write="given",
        null=True,
        shown="the initial lengths",
        unit="m",
        doc="unstressed length of each edge",
    )
    EA: tuple[float, ...] | None = key(
        _per_edge,
        "an array with one number > 0 per edge",
        None,
        write="given",
        null=True,
        shown="from [material]",
        unit="N",
        doc="axial stiffness of each edge",
    )
    fixed: tuple[int, ...] = key(
        _index_list,
        "an array of node indices",
        (),
        doc="default supports (required unless supports.fixed)",
    )
    prestrain: float = real(
        0.0, gt=-1, doc="rest lengths = initial / (1 + prestrain); not with rest_length"
    )
    file: str | None = text(
        None,
        nonempty=True,
        write="never",
        compare=False,
        doc="a JSON file (relative to the case file) of nodes, edges, rest_length, EA, fixed",
    )

    @classmethod
    def parse(cls, ck: Checker, g: dict, base_dir: Path) -> GraphConfig | None:
        ctx = Context(kind=cls)
        by_name = {k.name: k for k in declared(cls)}
        pre = value(ck, g, by_name["prestrain"], "geometry", ctx)
        file = None
        src: Any = g
        suffix = ""
        if "file" in g:
            file = value(ck, g, by_name["file"], "geometry", ctx)
            if file is BAD:
                return None
            inline = [k for k in _DATA if k in g]
            if inline:
                ck.add(
                    f"geometry.{inline[0]}: give the graph in geometry.file or inline, not both "
                    f"(geometry.file = {file!r} holds {', '.join(_DATA)})"
                )
                return None
            src = _read_graph_file(ck, file, base_dir)
            if src is None:
                return None
            suffix = f" (in geometry.file = {file!r})"
        sub = Checker()
        if file is not None:
            sub.keys(src, "geometry", _DATA, " in a graph file")
        data = _parse_data(sub, src, pre)
        ck.problems.extend(msg + suffix for msg in sub.problems)
        if data is None or sub.problems or pre is BAD:
            return None
        return cls(**data, prestrain=pre, file=file)

    @classmethod
    def gives_stiffness(cls, geometry: GeometryConfig | None) -> bool:
        return geometry is None or geometry.EA is not None  # None: unknown, do not insist

    def estimate_size(self) -> tuple[float, float, float, str]:
        n, m = len(self.nodes), len(self.edges)
        degree = np.bincount(np.array(self.edges, dtype=np.int64).ravel(), minlength=n)
        key = "geometry.file" if self.file else "geometry.nodes"
        return float(n), float(m), float(np.count_nonzero(degree > 2)), key

    def topology(self) -> Topology:
        return Topology(len(self.nodes), frozenset(self.fixed), {"center": _center(self.nodes)})

    def check_supports(self, ck: Checker, fixed: set[int], fixed_key: str) -> None:
        if not fixed:
            ck.add(
                "geometry.fixed: missing or empty: a graph needs supports "
                "(geometry.fixed or supports.fixed)"
            )
            return
        try:
            Net.from_arrays(
                self.nodes, self.edges, EA=1.0, fixed=sorted(fixed), rest_length=self.rest_length
            )
        except ConfigError as exc:
            ck.problems.extend(with_prefix(p, fixed_key) for p in exc.problems)

    def build(self, material: geo.Material, fixed: Any) -> Built:
        probe = _center(self.nodes)
        names = {"center": probe}
        pinned = list(self.fixed) if fixed is None else [resolve(r, names) for r in fixed]
        rest = self.rest_length
        if self.prestrain:
            xyz = np.asarray(self.nodes, dtype=np.float64)
            e = np.asarray(self.edges, dtype=np.int64)
            rest = np.linalg.norm(xyz[e[:, 1]] - xyz[e[:, 0]], axis=1) / (1.0 + self.prestrain)
        net = geo.graph(self.nodes, self.edges, pinned, material, rest_length=rest, EA=self.EA)
        size = float(np.linalg.norm(net.nodes.max(axis=0) - net.nodes.min(axis=0)))
        return Built(net, probe, size, names)


#: The keys that give the net (inline, or in the JSON file of geometry.file).
_DATA = tuple(n for n in names(GraphConfig) if n not in ("prestrain", "file"))


def _center(nodes) -> int:
    """The node nearest the centre of the bounding box."""
    xyz = np.asarray(nodes, dtype=np.float64)
    mid = 0.5 * (xyz.min(axis=0) + xyz.max(axis=0))
    return int(np.argmin(np.linalg.norm(xyz - mid, axis=1)))


def _read_graph_file(ck: Checker, file: str, base_dir: Path) -> dict | None:
    path = Path(file) if Path(file).is_absolute() else base_dir / file
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        ck.add(f"geometry.file = {file!r}: no such file ({path})")
        return None
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        ck.add(f"geometry.file = {file!r}: cannot read {path}: {reason}")
        return None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        ck.add(
            f"geometry.file = {file!r}: not valid JSON: {exc.msg} at line {exc.lineno}, "
            f"column {exc.colno}"
        )
        return None
    except (ValueError, RecursionError) as exc:
        ck.add(f"geometry.file = {file!r}: not valid JSON: {exc}")
        return None
    if not isinstance(obj, dict):
        ck.add(
            f"geometry.file = {file!r}: must hold a JSON object with keys "
            f"{', '.join(_DATA)}, not {type(obj).__name__}"
        )
        return None
    return obj


def _parse_data(ck: Checker, g: dict, pre: Any) -> dict | None:
    """The net's keys checked, then its topology: indices, loops, duplicates, zero or
    overflowing lengths."""
    v = parse_keys(ck, g, GraphConfig, "geometry", Context(kind=GraphConfig), only=_DATA)
    if v["rest_length"] not in (None, BAD) and pre not in (BAD, 0.0):
        ck.add(
            f"geometry.prestrain = {pre!r}: give geometry.rest_length or geometry.prestrain, "
            "not both"
        )
    if BAD in v.values():
        return None
    nodes, edges, fixed = v["nodes"], v["edges"], v["fixed"]
    n = len(nodes)
    bad_idx = [(f"geometry.edges[{k}]", list(e)) for k, e in enumerate(edges) if max(e) >= n]
    ck.first(bad_idx, f"node indices must be in 0..{n - 1}")
    bad_fixed = [(f"geometry.fixed[{k}]", i) for k, i in enumerate(fixed) if i >= n]
    ck.first(bad_fixed, f"must be a node index in 0..{n - 1}")
    if bad_idx or bad_fixed:
        return None
    e_arr = np.array(edges, dtype=np.int64)
    xyz = np.array(nodes, dtype=np.float64)
    loops = np.flatnonzero(e_arr[:, 0] == e_arr[:, 1])
    ck.first(
        [(f"geometry.edges[{k}]", list(edges[k])) for k in loops],
        "an edge must join two different nodes",
    )
    key = np.sort(e_arr, axis=1)
    _, counts = np.unique(key, axis=0, return_counts=True)
    seen: dict[tuple[int, int], int] = {}
    dups = []
    if (counts > 1).any():
        for k, pair in enumerate(map(tuple, key.tolist())):
            if pair in seen:
                dups.append((f"geometry.edges[{k}]", list(edges[k]), seen[pair]))
            else:
                seen[pair] = k
    for path, bad, k0 in dups[:5]:
        ck.bad(path, bad, f"repeats geometry.edges[{k0}]: edges must be unique")
    if len(dups) > 5:
        ck.add(f"geometry.edges: {len(dups) - 5} more repeated edges")
    with np.errstate(all="ignore"):
        length = np.linalg.norm(xyz[e_arr[:, 1]] - xyz[e_arr[:, 0]], axis=1)
    is_loop = set(loops.tolist())
    zero = [k for k in np.flatnonzero(~(length > 0)).tolist() if k not in is_loop]
    ck.first(
        [(f"geometry.edges[{k}]", list(edges[k])) for k in zero],
        "zero length: the nodes of an edge must be distinct points",
    )
    huge = np.flatnonzero(~np.isfinite(length))
    ck.first(
        [(f"geometry.edges[{k}]", list(edges[k])) for k in huge],
        "its length overflows: coordinates too large",
    )
    return v
