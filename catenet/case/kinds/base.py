"""What a geometry kind is: a frozen dataclass whose fields declare its keys, and whose
methods parse them, estimate the size of the net, name its nodes and build it.

A new kind subclasses ``GeometryConfig`` in its own module and is registered in
catenet/case/kinds/__init__.py.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, NamedTuple

from catenet.case.keys import BAD, Checker, Context, Declared, parse_keys
from catenet.model.net import Net


@dataclass(frozen=True)
class Topology:
    """What node references are checked against: the node count, the nodes pinned
    unless supports.fixed says otherwise, the named nodes, the node sets (a name for
    several nodes, ``[geometry.sets]``) and the names of the cables."""

    n_nodes: int
    default_fixed: frozenset[int]
    names: dict[str, int]
    sets: Mapping[str, tuple[int, ...]] = field(default_factory=dict)
    cables: tuple[str, ...] = ()


class Built(NamedTuple):
    """A geometry built: the net (with its supports and rest lengths, under the case's
    material: its law and prestress), the probe node whose z-deflection is reported, the
    length scale L of delta/L and the named nodes; ``sets`` are its node sets, ``cables``
    its cables (a ``catenet.case.kinds.cables.CableIndex``, None: none) and ``at_nodes``
    the node of each load.point given by a position along a cable (by its index);
    ``lines`` (M,) the line (cable) of every edge where ``cables`` does not say it (the
    square net's; None: one line, or the graph's cables), along which rods bend."""

    net: Net
    probe: int
    size: float
    names: dict[str, int]
    sets: Mapping[str, tuple[int, ...]] = {}
    cables: Any = None
    at_nodes: Mapping[int, int] = {}
    lines: Any = None


def resolve(ref: int | str, names: Mapping[str, int]) -> int:
    """A node index from an index or a node name."""
    return names[ref] if isinstance(ref, str) else ref


def expand(ref: int | str, names: Mapping[str, int], sets: Mapping) -> tuple[int, ...]:
    """The nodes a reference stands for: an index or a node name (one node), or the name
    of a node set (each of its nodes)."""
    if isinstance(ref, str) and ref in sets:
        return tuple(sets[ref])
    return (resolve(ref, names),)


def refit(net: Net, names: dict[str, int], fixed: Any, prestrain: float) -> Net:
    """The net with the supports ``fixed`` (node references; None: its own) and every
    rest length divided by 1 + prestrain."""
    if fixed is None and not prestrain:
        return net
    mask = net.fixed if fixed is None else sorted(resolve(r, names) for r in fixed)
    # none pinned: rollers, sliders or springs hold it (checked when they are added)
    flies = net.flies or (fixed is not None and not fixed)
    return net.replace(fixed=mask, rest_length=net.rest_length / (1.0 + prestrain), flies=flies)


def with_prefix(message: str, fixed_key: str = "geometry.fixed") -> str:
    """A Net builder message with the case key path of what it names."""
    sections = ("geometry", "supports", "material", "load", "solver", "obstacle", "mass")
    if message.startswith(sections):
        return message
    if message.startswith("nodes "):  # "nodes [3, 4]: ..." lists node indices
        return "geometry: " + message
    for name, key in (
        ("nodes", "geometry.nodes"),
        ("edges", "geometry.edges"),
        ("rest_length", "geometry.rest_length"),
        ("EA", "geometry.EA"),
        ("line_density", "material.density (line density)"),
        ("fixed", fixed_key),
    ):
        if re.match(rf"{name}[\[:= ]", message):
            return key + message[len(name) :]
    return "geometry: " + message


class GeometryConfig(Declared):
    """Base of the geometry kinds; ``kind`` is the name ``geometry.kind`` gives.

    Class attributes: ``summary`` (a line for the README), ``node_names`` (names a node
    reference may use besides indices),
    ``default_supports`` (what is pinned without supports.fixed, as messages say it),
    ``pressure`` (whether load.pressure applies), ``lazy_topology`` (the topology needs
    a build: check node references only when there are any), ``node_sets`` (node
    references may name node sets and cables of the instance, checked with its topology).
    """

    kind: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    node_names: ClassVar[tuple[str, ...]] = ()
    default_supports: ClassVar[str] = ""
    pressure: ClassVar[bool] = False
    lazy_topology: ClassVar[bool] = False
    node_sets: ClassVar[bool] = False

    @classmethod
    def parse(cls, ck: Checker, g: dict, base_dir: Path) -> GeometryConfig | None:
        """The kind's keys of the [geometry] table (unknown keys are checked before);
        None when any is bad (the problems are in ``ck``)."""
        values = parse_keys(ck, g, cls, "geometry", Context(kind=cls))
        return None if BAD in values.values() else cls(**values)

    @classmethod
    def gives_stiffness(cls, geometry: GeometryConfig | None) -> bool:
        """Whether the geometry (None: given but broken) sets EA, so that the material
        need not."""
        return False

    def estimate_size(self) -> tuple[float, float, float, str]:
        """(nodes, edges, junctions, key path of what drives the size), estimated from
        the parameters alone, before anything is built."""
        raise NotImplementedError

    def topology(self) -> Topology:
        raise NotImplementedError

    def check_supports(
        self, ck: Checker, fixed: set[int], fixed_key: str, flies: bool = False
    ) -> None:
        """Problems of the supports ``fixed`` (named by ``fixed_key``) once every node
        reference is sound; ``flies``: a dynamic run, where a net may have none."""

    def build(self, material: Any, fixed: Any) -> Built:
        """The net under ``material`` (a catenet.model.builders.Material: its law and
        prestress; the builders apply both) pinned at the node references ``fixed``
        (None: the kind's default supports)."""
        raise NotImplementedError

    def check_material(self, ck: Checker, material: Any) -> None:
        """Problems of the case's [material] (a sound ``MaterialConfig``) with this
        geometry (a graph's cables override it)."""

    def build_case(self, case: Any, material: Any) -> Built:
        """The net of a whole case (``material``: the catenet.model.builders.Material of its
        [material], ``catenet.case.material.model_material``); kinds that need more of the
        case than the supports override it."""
        return self.build(material, case.supports.fixed)

    def area_force(self, net: Net, pressure: float, size: float) -> Any:
        """The nodal forces (N, 3) of an area load over the whole net when the kind
        lumps it its own way (the square net: the paper's pressure), else None
        (tributary areas, catenet/model/areas.py)."""
        return None

    def given_nodes(self, net: Net) -> int:
        """How many of the built net's first nodes the case gives (the rest split
        cables)."""
        return net.n_nodes

    def to_dict(self) -> dict:
        return {"kind": self.kind, **super().to_dict()}
