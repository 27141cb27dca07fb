"""Node sets by region in ``[geometry.sets]``: ``name = { box = [[x0, y0, z0], [x1, y1,
z1]] }`` (every node inside the box, faces included, the nodes that split cables too) and
``name = { near = [x, y, z] }`` (the node nearest the point). A region is evaluated on
the built net's nodes for supports and loads, and on the given nodes where a cable passes
through a node set (a cable's nodes are given ones).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from catenet.case.keys import BAD, Checker, show

#: Tolerance of a box's faces, relative to the net's extent.
BOX_TOL = 1e-9

REGIONS = ("box", "near")


@dataclass(frozen=True)
class Region:
    """A box (two opposite corners) or a point whose nearest node is meant."""

    box: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    near: tuple[float, float, float] | None = None
    given: Any = field(default=None, compare=False)  # as written, for messages

    def select(self, xyz: np.ndarray) -> tuple[int, ...]:
        """The nodes of ``xyz`` (N, 3) in the region."""
        if self.near is not None:
            d = np.linalg.norm(xyz - np.asarray(self.near), axis=1)
            return (int(np.argmin(d)),)
        box = self._box()
        lo, hi = np.minimum(*box), np.maximum(*box)
        extent = float(np.linalg.norm(np.ptp(xyz, axis=0))) if len(xyz) else 0.0
        tol = BOX_TOL * max(extent, float(np.max(np.abs(box))), 1e-300)
        inside = np.all((xyz >= np.asarray(lo) - tol) & (xyz <= np.asarray(hi) + tol), axis=1)
        return tuple(np.flatnonzero(inside).tolist())

    def to_dict(self) -> dict:
        if self.near is not None:
            return {"near": list(self.near)}
        return {"box": [list(c) for c in self._box()]}

    def _box(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """The box of a region that is not ``near`` (``check_region`` gives one of them)."""
        assert self.box is not None, "a Region has a box or a near point"
        return self.box


def check_region(ck: Checker, v: Any, path: str) -> Any:
    """A table with one key, ``box`` (two corners) or ``near`` (a point)."""
    t = ck.table(v, path)
    if t is None:
        return BAD
    given = [k for k in t if k in REGIONS]
    ck.keys(t, path, REGIONS, " of a region")
    if len(given) != 1:
        return ck.bad(
            path, v, "a region gives one of box = [[x0, y0, z0], [x1, y1, z1]] or near = [x, y, z]"
        )
    (name,) = given
    if name == "near":
        p = ck.vec3(t["near"], f"{path}.near")
        return BAD if p is BAD else Region(near=p, given=t["near"])
    box = t["box"]
    need = "must be [[x0, y0, z0], [x1, y1, z1]]: two opposite corners, finite"
    if not isinstance(box, (list, tuple)) or len(box) != 2:
        return ck.bad(f"{path}.box", box, need)
    sub = Checker()
    corners = [sub.vec3(c, f"{path}.box[{k}]") for k, c in enumerate(box)]
    if sub.problems:
        return ck.bad(f"{path}.box", box, need)
    return Region(box=(corners[0], corners[1]), given=box)


def resolve(items, xyz: np.ndarray) -> dict[str, tuple[int, ...]]:
    """Node sets ``(name, nodes or Region)`` as name -> node indices of ``xyz``."""
    return {
        name: (nodes.select(xyz) if isinstance(nodes, Region) else tuple(nodes))
        for name, nodes in items
    }


def empty_boxes(ck: Checker, items, xyz: np.ndarray, where: str = "geometry.sets") -> None:
    """A problem for every box that holds no node of ``xyz``."""
    for name, nodes in items:
        if isinstance(nodes, Region) and nodes.box is not None and not nodes.select(xyz):
            lo = np.min(xyz, axis=0).tolist() if len(xyz) else []
            hi = np.max(xyz, axis=0).tolist() if len(xyz) else []
            ck.add(
                f"{where}.{name}.box = {show(nodes.given or [list(c) for c in nodes.box])}: "
                "holds no node "
                f"(the net's nodes span {show(lo)} to {show(hi)}): a box must hold at least "
                "one node"
            )
