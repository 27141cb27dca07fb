"""Node references (indices and names such as "center") checked against the geometry:
in range, supports listed once, only fixed nodes move and each once."""

from __future__ import annotations

from typing import Any

from catenet.case.keys import Checker, duplicates, show
from catenet.case.kinds.base import GeometryConfig, with_prefix
from catenet.case.sections import LoadConfig, SupportsConfig
from catenet.errors import ConfigError


def _needs_topology(g: GeometryConfig, supports: Any, load: Any) -> bool:
    """A kind whose topology needs a build (square nets) is built to check node
    references only when there are any."""
    if not g.lazy_topology:
        return True
    refs = []
    if isinstance(supports, SupportsConfig):
        refs += list(supports.fixed or ()) + [m.node for m in supports.moves]
    if isinstance(load, LoadConfig):
        refs += [p.node for p in load.points]
    return any(isinstance(r, int) for r in refs) or bool(
        isinstance(supports, SupportsConfig) and supports.moves
    )


def check_nodes(ck: Checker, g: GeometryConfig, supports: Any, load: Any) -> None:
    """Every node reference of the supports and loads (each BAD when its section failed)
    against the geometry ``g``."""
    if not _needs_topology(g, supports, load):
        return
    try:
        topo = g.topology()
    except ConfigError as exc:  # the builder's own checks
        ck.problems.extend(with_prefix(p, "supports.fixed") for p in exc.problems)
        return
    n = topo.n_nodes

    def in_range(ref, path) -> bool:
        if isinstance(ref, int) and ref >= n:
            ck.bad(path, ref, f"must be a node index in 0..{n - 1} (or a named node)")
            return False
        return True

    def resolve(ref) -> int:
        return topo.names[ref] if isinstance(ref, str) else ref

    fixed = set(topo.default_fixed)
    fixed_key = g.default_supports
    before = len(ck.problems)
    if isinstance(supports, SupportsConfig):
        if supports.fixed is not None:
            fixed_key = "supports.fixed"
            ok = [in_range(r, f"supports.fixed[{k}]") for k, r in enumerate(supports.fixed)]
            if all(ok):
                resolved = [resolve(r) for r in supports.fixed]
                dups = duplicates(resolved)
                if dups:
                    ck.bad(
                        "supports.fixed",
                        list(supports.fixed),
                        f"node {dups[0]} appears more than once: list each node once",
                    )
                fixed = set(resolved)
            else:
                fixed = set()
        seen: dict[int, int] = {}
        for k, mv in enumerate(supports.moves):
            path = f"supports.move[{k}].node"
            if not in_range(mv.node, path):
                continue
            i = resolve(mv.node)
            if fixed and i not in fixed:
                shown = mv.node if isinstance(mv.node, int) else f"{mv.node!r} (node {i})"
                ck.add(
                    f"{path} = {shown}: is not a fixed node: only supports move "
                    f"(fixed: {fixed_key})"
                )
            if i in seen:
                ck.add(
                    f"{path} = {show(mv.node)}: node {i} already moves in "
                    f"supports.move[{seen[i]}]: one move per node"
                )
            seen[i] = k
    if isinstance(load, LoadConfig):
        for k, pt in enumerate(load.points):
            in_range(pt.node, f"load.point[{k}].node")
    if len(ck.problems) == before:
        g.check_supports(ck, fixed, fixed_key)
