"""The checks of a graph case's array keys (``catenet.case.kinds.graph``): node
coordinates, edges as index pairs, one value per edge, node index lists."""

from __future__ import annotations

from typing import Any

import numpy as np

from catenet.case.keys import (
    BAD,
    MAGNITUDE,
    Checker,
    Context,
    as_float,
    as_int,
    carried,
    duplicates,
)


def finite(c: Any) -> float | None:
    f = as_float(c)
    return f if f is not None and carried(f) else None


def index(c: Any) -> int | None:
    i = as_int(c)
    return i if i is not None and i >= 0 else None


def _array(ck: Checker, v: Any, path: str, shape: tuple[int, int], convert, need: str) -> Any:
    """An array of at least shape[0] items, each shape[1] values that ``convert`` accepts;
    ``need`` describes one item."""
    least, width = shape
    if not isinstance(v, (list, tuple)) or len(v) < least:
        some = f"at least {least} " if least else ""
        return ck.bad(path, v, f"must be an array of {some}{need.split(':')[0]}")
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


def points(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    need = f"[x, y, z]: 3 finite numbers, each within +-{MAGNITUDE:.0e}"
    return _array(ck, v, path, (2, 3), finite, need)


def pairs(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    return _array(ck, v, path, (0, 2), index, "[i, j]: two node indices (integers >= 0)")


def per_edge_of(what: str, convert, need: str):
    """A check of one value per edge (of geometry.edges): ``convert`` gives the clean
    value or None, ``need`` says what one must be."""

    def check(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
        if not isinstance(v, (list, tuple)):
            return ck.bad(path, v, f"must be an array with one {what} per edge")
        vals = [convert(x) for x in v]
        ck.first([(f"{path}[{k}]", v[k]) for k, x in enumerate(vals) if x is None], need)
        edges = ctx.values.get("edges")
        if edges is not None and edges is not BAD and len(v) != len(edges):
            return ck.bad(
                path,
                v,
                f"has {len(v)} values: must have one per edge ({len(edges)}) of geometry.edges",
            )
        return BAD if None in vals else tuple(vals)

    return check


def positive(x: Any) -> float | None:
    f = finite(x)
    return f if f is not None and f > 0 else None


def boolean(x: Any) -> bool | None:
    return bool(x) if isinstance(x, (bool, np.bool_)) else None


per_edge = per_edge_of("number > 0", positive, "must be finite and > 0")


def index_list(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
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
