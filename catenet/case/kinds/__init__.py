"""The geometry kinds, registered by the name ``geometry.kind`` gives.

Each kind is one module holding its config dataclass (its keys, declared once), its
parsing, size estimate, named nodes and build (see base.py). A new kind is a new module
here and one line in the registration below.
"""

from __future__ import annotations

from catenet.case.kinds.base import GeometryConfig
from catenet.case.kinds.cable import SingleCableConfig
from catenet.case.kinds.graph import GraphConfig
from catenet.case.kinds.square_net import SquareNetConfig

#: geometry.kind -> its config class, in the order messages and the README list them.
KINDS: dict[str, type[GeometryConfig]] = {
    cls.kind: cls
    for cls in (
        SingleCableConfig,
        SquareNetConfig,
        GraphConfig,
    )
}

__all__ = ["KINDS", "SingleCableConfig", "GeometryConfig", "GraphConfig", "SquareNetConfig"]
