"""The keys of supports that hold a node in some directions only: ``[[supports.roller]]``,
``[[supports.slider]]`` and ``[[supports.spring]]`` (``catenet.model.guides``), the turned
rod ends ``[[supports.twist]]`` (``catenet.model.twist``), the moving supports
``[[supports.move]]``, the node lists every support key takes and the time histories of
loads and support motions."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from catenet.case.keys import BAD, Checker, Context, Declared, key, node, real, vec3
from catenet.case.sine import SINE, SineConfig, check_sine
from catenet.errors import ConfigError
from catenet.model.histories import NEED, history_problem
from catenet.model.net import Net

Vec3 = tuple[float, float, float]
NodeRef = int | str


def _check_history(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A time history [[t, factor], ...] (catenet/model/histories.py) as a tuple of pairs."""
    problem = history_problem(v)
    if problem:
        return ck.bad(path, v, problem)
    duration = ctx.values.get("duration")
    if duration not in (None, BAD, 0.0):
        return ck.bad(
            path,
            v,
            f"give duration (a linear ramp, here {duration!r} s) or history, not both",
        )
    return tuple((float(t), float(f)) for t, f in v)


def history_key(doc: str) -> Any:
    """The ``history`` key of a load or support motion."""
    return key(_check_history, NEED, None, write="given", shown="none", unit="s, -", doc=doc)


@dataclass(frozen=True)
class MoveConfig(Declared):
    """A support that moves by ``displacement`` over ``duration`` seconds, or by
    factor(t) times it along a ``history``, or along a ``sine`` (dynamic runs)."""

    node: NodeRef = node(missing="the fixed node to move", doc="the fixed node that moves")
    displacement: Vec3 | None = vec3(
        None, write="given", unit="m", doc="its displacement (dx, dy, dz) (or sine)"
    )
    duration: float = real(
        0.0, ge=0, unit="s", doc="ramp time in dynamic runs (static runs: reached at once)"
    )
    history: tuple | None = history_key(
        "dynamic: displacement times factor(t), instead of a ramp over duration"
    )
    sine: SineConfig | None = key(
        check_sine,
        SINE,
        None,
        write="given",
        doc="dynamic: amplitude r(t) sin(2 pi t / period + phase), r a smooth start from 0 "
        "to 1 over ramp (default one period; 0: none), instead of displacement; static "
        "runs and an equilibrium start take it at t = 0",
    )


def node_list(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A non-empty array of node references (indices, names, node sets)."""
    if not isinstance(v, (list, tuple)) or not v:
        return ck.bad(path, v, "must be a non-empty array of nodes")
    refs = [ck.node_ref(x, f"{path}[{k}]", ctx.kind) for k, x in enumerate(v)]
    return BAD if BAD in refs else tuple(refs)


def fixed_list(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """``supports.fixed``: a non-empty array of nodes, or [] (no node pinned: the
    rollers, sliders and springs hold the net; ``check_fixed`` says where there are
    none)."""
    if isinstance(v, (list, tuple)) and not v:
        return ()
    return node_list(ck, v, path, ctx)


def check_fixed(ck: Checker, supports: Any, flight: bool = False) -> None:
    """``supports.fixed = []`` only where clamps, rollers, sliders or springs hold the
    net, or in a dynamic run (``flight``: a net may fly free). (A clamped rod end is held
    in place: a cantilever needs no fixed node beside its clamp.)"""
    partial = supports.clamped or supports.rollers or supports.sliders or supports.springs
    if supports.fixed == () and not partial and not flight:
        ck.bad(
            "supports.fixed",
            [],
            "must be a non-empty array of nodes ([] only where supports.clamped, "
            "[[supports.roller]], [[supports.slider]] or [[supports.spring]] hold the "
            "net, or in a dynamic run: a net flying free)",
        )


def _node_refs(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """One node reference (an index, a name, a node set) or a non-empty array of them."""
    if isinstance(v, (list, tuple)):
        return node_list(ck, v, path, ctx)
    ref = ck.node_ref(v, path, ctx.kind)
    return BAD if ref is BAD else (ref,)


def _direction(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A direction [x, y, z]: three finite numbers, not all zero."""
    vec = ck.vec3(v, path)
    if vec is BAD:
        return BAD
    if not any(vec):
        return ck.bad(path, v, "must not be [0, 0, 0]: it names a direction")
    return vec


def _stiffness(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """[kx, ky, kz] >= 0 (not all 0), or a symmetric positive semidefinite 3x3 [N/m]; at
    a rod end also a 6x6 or [kx, ky, kz, krx, kry, krz] (``catenet.model.rodends``)."""
    from catenet.model.guides import spring_matrix
    from catenet.model.rodends import spring6_matrix

    try:
        if spring6_matrix(v, path) is None:
            spring_matrix(v, path)
    except ConfigError as exc:
        ck.problems.extend(exc.problems)
        return BAD
    rows = [tuple(float(c) for c in r) for r in v] if isinstance(v[0], (list, tuple)) else None
    return tuple(rows) if rows is not None else tuple(float(c) for c in v)


def _guide_nodes(what: str) -> Any:
    return key(
        _node_refs,
        "a node (index, name or node set) or an array of them",
        missing=f"the nodes {what}",
        doc=f"the nodes {what}: an index, a name, a node set or an array of them",
    )


@dataclass(frozen=True)
class RollerConfig(Declared):
    """Nodes held along ``normal`` only: free to move in the plane across it."""

    nodes: tuple[NodeRef, ...] = _guide_nodes("on the roller")
    normal: Vec3 = key(
        _direction,
        "[nx, ny, nz], not zero",
        missing="[nx, ny, nz]: the direction the nodes are held in",
        doc="the held direction (any length, any orientation)",
    )


@dataclass(frozen=True)
class SliderConfig(Declared):
    """Nodes free along ``direction`` only: held in the two directions across it."""

    nodes: tuple[NodeRef, ...] = _guide_nodes("on the slider")
    direction: Vec3 = key(
        _direction,
        "[dx, dy, dz], not zero",
        missing="[dx, dy, dz]: the direction the nodes slide along",
        doc="the free direction (any length, any orientation)",
    )


@dataclass(frozen=True)
class SpringConfig(Declared):
    """Elastic supports: each node held toward its given position by a linear spring."""

    nodes: tuple[NodeRef, ...] = _guide_nodes("on springs")
    stiffness: Any = key(
        _stiffness,
        "[kx, ky, kz] >= 0, not all 0, or a symmetric positive semidefinite 3x3; at a rod "
        "end also a 6x6 or [kx, ky, kz, krx, kry, krz]",
        missing="[kx, ky, kz] [N/m]",
        unit="N/m",
        doc="per node: kx, ky, kz along x, y and z, or a 3x3 matrix of rows (kxx, kxy, kxz) "
        "...; at a rod end (EI > 0) a 6x6 of rows for x, y, z, rx, ry, rz (N/m, N/rad, "
        "N m/rad: translation and rotation coupled) or its diagonal",
    )


@dataclass(frozen=True)
class RotationalConfig(Declared):
    """Rod ends whose tangent a rotational spring holds toward its given direction: the
    moment k sin(theta) for a turn theta (k theta while it is small); the node's position
    and the rod's twist are held by whatever else holds them."""

    nodes: tuple[NodeRef, ...] = _guide_nodes("on rotational springs (each the end of a rod)")
    stiffness: float = real(
        gt=0,
        missing="[N m/rad]: the spring's moment per turn of the rod end",
        unit="N m/rad",
        doc="the moment per radian of the end tangent's turn from its given direction",
    )


@dataclass(frozen=True)
class TwistConfig(Declared):
    """Clamped rod ends turned about the rod's axis: each by ``angle``, right-handed about
    the tangent pointing out of the rod at that end (``catenet.model.twist``)."""

    nodes: tuple[NodeRef, ...] = _guide_nodes("turned (each a clamped end of a twisting rod)")
    angle: float = real(
        missing="[rad]: the end's turn about the rod's axis",
        unit="rad",
        doc="the end's turn, right-handed about the outward tangent: a positive angle at "
        "either end twists the rod right-handed; a rod's twist is the sum of its two ends'",
    )
    history: tuple | None = history_key(
        "dynamic: angle times factor(t) (none: the whole angle from the start); static "
        "runs: the whole angle"
    )


def is_six(stiffness: Any) -> bool:
    """Whether a sound ``supports.spring`` stiffness is a rod end's 6x6 (or its diagonal)."""
    return len(stiffness) == 6


def with_partial_supports(
    supports: Any,
    net: Net,
    names: Mapping,
    sets: Mapping,
    flies: bool = False,
    ends: Any = None,
) -> Net:
    """The net with the case's rollers, sliders and springs (``supports``, a sound
    ``SupportsConfig``; node references resolved by ``names`` and ``sets``; ``ends`` the
    rod ends on 6x6 springs, an ``Elastic``, ``catenet.case.rods.rod_end_springs``),
    every part of it supported (``flies``: a dynamic run, where none need be)."""
    from catenet.case.kinds.base import expand
    from catenet.model.guides import Elastic, Guides

    def nodes(refs: tuple[NodeRef, ...]) -> list[int]:
        return [i for r in refs for i in expand(r, names, sets)]

    guides = [
        Guides.roller(nodes(t.nodes), t.normal, f"supports.roller[{k}].normal")
        for k, t in enumerate(supports.rollers)
    ]
    guides += [
        Guides.slider(nodes(t.nodes), t.direction, f"supports.slider[{k}].direction")
        for k, t in enumerate(supports.sliders)
    ]
    springs = [
        Elastic.of(nodes(t.nodes), t.stiffness, f"supports.spring[{k}].stiffness")
        for k, t in enumerate(supports.springs)
        if not is_six(t.stiffness)
    ]
    if ends is not None:
        springs.append(ends)
    if guides:
        net = net.with_guides(*guides)
    if springs:
        net = net.with_springs(*springs)
    if net.flies != flies:  # supported now, with the rollers and springs
        net = net.replace(flies=flies)
    return net
