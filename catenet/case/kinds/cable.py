"""geometry.kind = "cable": one cable pinned at both ends, nodes evenly on the chord."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from catenet.case.keys import BAD, Checker, Context, integer, parse_keys, real, vec3
from catenet.case.kinds.base import Built, GeometryConfig, Topology, refit
from catenet.model import builders as geo

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class SingleCableConfig(GeometryConfig):
    """A single cable: ``nodes`` nodes evenly on the chord from ``start`` to ``end``;
    ``length`` is the unstressed length (the chord when not given)."""

    kind: ClassVar[str] = "cable"
    summary: ClassVar[str] = "one cable pinned at both ends, its nodes evenly on the chord"
    node_names: ClassVar[tuple[str, ...]] = ("start", "end", "midpoint")
    default_supports: ClassVar[str] = "the two ends of the cable; supports.fixed sets others"

    start: Vec3 = vec3(missing="[x, y, z] of node 0", unit="m", doc="node 0, named start")
    end: Vec3 = vec3(
        missing="[x, y, z] of the last node",
        unit="m",
        doc="the last node, named end (not at start)",
    )
    length: float = real(
        None, gt=0, computed=True, null=True, shown="the chord", unit="m", doc="unstressed length"
    )
    nodes: int = integer(
        ge=2,
        missing="the number of nodes (an integer >= 2)",
        doc="node count; midpoint is node (nodes - 1) // 2",
    )

    @property
    def chord(self) -> float:
        return math.dist(self.start, self.end)

    @property
    def midpoint(self) -> int:
        """Node (nodes - 1) // 2: the middle node, or the one before the middle when
        ``nodes`` is even."""
        return (self.nodes - 1) // 2

    @classmethod
    def parse(cls, ck: Checker, g: dict, base_dir: Path) -> SingleCableConfig | None:
        v = parse_keys(ck, g, cls, "geometry", Context(kind=cls))
        if v["start"] is not BAD and v["end"] is not BAD:
            chord = math.dist(v["start"], v["end"])
            if not chord > 0:
                ck.bad("geometry.end", g["end"], "must differ from geometry.start")
                return None
            if not math.isfinite(chord):
                ck.bad(
                    "geometry.end", g["end"], "too far from geometry.start (the chord overflows)"
                )
                return None
            if v["length"] is None:
                v["length"] = chord
        return None if BAD in v.values() else cls(**v)

    def estimate_size(self) -> tuple[float, float, float, str]:
        n = float(self.nodes) if self.nodes < 2**1000 else math.inf  # float() overflows
        return n, n - 1.0, 0.0, "geometry.nodes"

    def _names(self) -> dict[str, int]:
        return {"start": 0, "end": self.nodes - 1, "midpoint": self.midpoint}

    def topology(self) -> Topology:
        return Topology(self.nodes, frozenset({0, self.nodes - 1}), self._names())

    def build(self, material: geo.Material, fixed: Any) -> Built:
        net = geo.cable(self.start, self.end, self.nodes, material, length=self.length)
        names = self._names()
        return Built(refit(net, names, fixed, 0.0), self.midpoint, self.chord, names)
