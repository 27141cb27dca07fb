"""Obstacle shapes, one module per kind, each a class of the ``Shape`` protocol
(``catenet.scene.shapes.base``): the module's name is the kind's name in a case file
(``[[obstacle]] kind = "box"``) and its ``SHAPE`` the class. A new shape is its kernel
(``catenet.kernels``), its module here and its declared keys (``catenet.case.shapes``):
nothing else names the kinds.

A kind's module is imported when a scene uses it, so that a run loads only the kernels
of the shapes it has.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Mapping
from functools import cache
from typing import Any

from catenet.scene.shapes.base import MassProperties, Outline, Shape, solid_width

__all__ = [
    "MassProperties",
    "Outline",
    "Shape",
    "kinds",
    "shape_class",
    "shape_of",
    "solid_width",
]


@cache
def kinds() -> tuple[str, ...]:
    """The kinds of shape there are (the modules of this package)."""
    return tuple(sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name != "base"))


def shape_class(kind: str) -> type[Shape]:
    """The class of shape ``kind``; ValueError naming the kinds there are."""
    if kind not in kinds():
        raise ValueError(f"unknown obstacle kind {kind!r}: one of {', '.join(kinds())}")
    shape: type[Shape] = importlib.import_module(f"{__name__}.{kind}").SHAPE
    return shape


def shape_of(table: Mapping[str, Any]) -> Shape:
    """The shape of an ``[[obstacle]]`` table (its ``kind`` and geometry keys, as the
    resolved case or a result file's stored case gives them)."""
    return shape_class(str(table.get("kind"))).from_table(table)
