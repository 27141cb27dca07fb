"""geometry.kind = "square_net": the paper's square net (contract §2)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from catenet.case.keys import integer, real
from catenet.case.kinds.base import Built, GeometryConfig, Topology, refit
from catenet.case.kinds.warn import angle_warning, warn_once
from catenet.model import builders as geo


@dataclass(frozen=True)
class SquareNetConfig(GeometryConfig):
    """The paper's square net (contract §2); ``prestrain`` shortens every rest length
    to initial / (1 + prestrain)."""

    kind: ClassVar[str] = "square_net"
    summary: ClassVar[str] = "the paper's square net (Sec. 3.2), both ends of every cable pinned"
    node_names: ClassVar[tuple[str, ...]] = ("center",)
    default_supports: ClassVar[str] = "both ends of every cable; supports.fixed sets others"
    pressure: ClassVar[bool] = True
    lazy_topology: ClassVar[bool] = True

    n: int = integer(
        ge=2,
        even=True,
        missing="the number of cables (an even integer >= 2)",
        doc="cables in all, n/2 per family",
    )
    alpha: float = real(
        need="finite (radians)", missing="the angle in radians", unit="rad", doc="angle"
    )
    size: float = real(gt=0, missing="the side L [m] (> 0)", unit="m", doc="side L")
    edge_length: float = real(
        gt=0,
        missing="the edge length [m] (> 0)",
        unit="m",
        doc="longest edge after splitting the pieces between joints",
    )
    prestrain: float = real(0.0, gt=-1, doc="rest lengths = initial / (1 + prestrain)")

    @classmethod
    def parse(cls, ck, g, base_dir):
        """The keys, and a warning for an angle that looks like degrees (45 taken as 45 rad
        is a valid but surely unintended net)."""
        config = super().parse(ck, g, base_dir)
        if config is not None:
            message = angle_warning("geometry.alpha", config.alpha)
            if message:
                warn_once(message)
        return config

    def estimate_size(self) -> tuple[float, float, float, str]:
        """Every cable's length inside the square over edge_length, plus one edge per
        piece between crossings (at worst)."""
        m = self.n // 2
        if m * m > geo.MAX_NODES:  # do not even loop over the cables
            big = float(m * m) if m < 10**150 else math.inf
            return big, 2 * big, big, "geometry.n"
        crossings = float(m * m)
        pieces = float(self.n * (m + 1))
        half = 0.5 * self.size
        d = self.size / (m + 1)
        u = (math.cos(self.alpha), math.sin(self.alpha))
        v = (-math.sin(self.alpha), math.cos(self.alpha))
        total = 0.0
        for k in range(m):
            ck = (k - (m - 1) / 2) * d
            total += _clip_length((ck * v[0], ck * v[1]), u, half)
            total += _clip_length((-ck * u[0], -ck * u[1]), v, half)
        along = total / self.edge_length
        edges = along + pieces
        key = "geometry.edge_length" if along >= pieces else "geometry.n"
        return edges + self.n, edges, crossings, key

    def topology(self) -> Topology:
        return _topology(self.n, self.alpha, self.size, self.edge_length)

    def build(self, material: geo.Material, fixed: Any) -> Built:
        sq = geo.square_net(self.n, self.alpha, self.size, self.edge_length, material)
        names = {"center": sq.center}
        net = refit(sq.net, names, fixed, self.prestrain)
        return Built(net, sq.center, self.size, names, lines=sq.cable)

    def area_force(self, net, pressure: float, size: float) -> Any:
        """The paper's pressure (contract §2): p L^2 over the square, shared equally by
        the N nodes, so that [[load.area]] on the whole net is load.pressure (the net is
        flat: on plan and normal to it alike)."""
        return geo.pressure_force(net, pressure, size)


def _clip_length(p: tuple[float, float], w: tuple[float, float], half: float) -> float:
    """Length of the line p + t w inside the square [-half, half]^2."""
    lo, hi = -math.inf, math.inf
    for axis in range(2):
        if abs(w[axis]) < 1e-15:
            if abs(p[axis]) > half:
                return 0.0
            continue
        a = (-half - p[axis]) / w[axis]
        b = (half - p[axis]) / w[axis]
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    return max(hi - lo, 0.0)


@functools.lru_cache(maxsize=8)
def _topology(n: int, alpha: float, size: float, edge_length: float) -> Topology:
    sq = geo.square_net(n, alpha, size, edge_length, geo.Material(EA=1.0))
    fixed = frozenset(np.flatnonzero(sq.net.fixed).tolist())
    return Topology(sq.net.n_nodes, fixed, {"center": sq.center})
