"""Case files: TOML -> validated frozen dataclasses -> a scene (net and loads) to solve.

``load_case`` reads a TOML file (or the bundled default), applies ``--set`` overrides to the
raw table and hands it to ``parse_case``, which checks every key before anything is
computed and reports all problems at once in one ``ConfigError``, each as
``key.path = value: what is accepted``. ``build`` turns a ``Case`` into a ``Scene``: the
``Net``, its ``Loads``, the probe node whose deflection is reported and the length scale.

A guard estimates the size of the net and the memory a solve needs before any array is
made, and refuses cases that would not fit in this machine's memory.
"""

from __future__ import annotations

import copy
import datetime
import difflib
import functools
import json
import logging
import math
import numbers
import os
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from catenet import geometry as geo
from catenet.errors import ConfigError
from catenet.net import Loads, Net

log = logging.getLogger(__name__)

KINDS = ("cable", "square_net", "graph")
METHODS = ("static", "dynamic")
LINEAR = ("auto", "pardiso", "scipy")

#: No case may have more nodes than this, whatever the memory (checked before building).
MAX_NODES = 50_000_000
#: Share of the physical memory a case may need.
MEMORY_SHARE = 0.8

# Named nodes per geometry kind (besides plain indices).
NODE_NAMES = {
    "cable": ("start", "end", "midpoint"),
    "square_net": ("center",),
    "graph": ("center",),
}

_TOP_KEYS = ("title", "geometry", "material", "supports", "load", "solver", "output")
_GEOMETRY_KEYS = {
    "square_net": ("kind", "n", "alpha", "size", "edge_length", "prestrain"),
    "cable": ("kind", "start", "end", "length", "nodes"),
    "graph": ("kind", "nodes", "edges", "rest_length", "EA", "fixed", "prestrain", "file"),
}
_GRAPH_DATA_KEYS = ("nodes", "edges", "rest_length", "EA", "fixed")
_MATERIAL_KEYS = ("E", "radius", "area", "EA", "density", "tension_only")
_SUPPORTS_KEYS = ("fixed", "move")
_MOVE_KEYS = ("node", "displacement", "duration")
_LOAD_KEYS = ("pressure", "gravity", "point")
_POINT_KEYS = ("node", "force")
_SOLVER_KEYS = (
    "method",
    "dt",
    "damping",
    "t_end",
    "rtol",
    "linear",
    "threads",
    "max_iter",
    "steps",
)
_OUTPUT_KEYS = ("file", "every", "xdmf")

Vec3 = tuple[float, float, float]
NodeRef = int | str


# --------------------------------------------------------------------------- dataclasses


class GeometryConfig:
    """Base of the three geometry kinds; ``kind`` names the builder."""

    kind: ClassVar[str] = ""

    def to_dict(self) -> dict:
        raise NotImplementedError


@dataclass(frozen=True)
class CableConfig(GeometryConfig):
    """A single cable: ``nodes`` nodes evenly on the chord from ``start`` to ``end``;
    ``length`` is the unstressed length (the chord when not given)."""

    kind: ClassVar[str] = "cable"
    start: Vec3
    end: Vec3
    nodes: int
    length: float

    @property
    def chord(self) -> float:
        return math.dist(self.start, self.end)

    @property
    def midpoint(self) -> int:
        """Node (nodes - 1) // 2: the middle node, or the one before the middle when
        ``nodes`` is even."""
        return (self.nodes - 1) // 2

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "start": list(self.start),
            "end": list(self.end),
            "length": self.length,
            "nodes": self.nodes,
        }


@dataclass(frozen=True)
class SquareNetConfig(GeometryConfig):
    """The paper's square net (SPEC section 2); ``prestrain`` shortens every rest length
    to initial / (1 + prestrain)."""

    kind: ClassVar[str] = "square_net"
    n: int
    alpha: float
    size: float
    edge_length: float
    prestrain: float = 0.0

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "n": self.n,
            "alpha": self.alpha,
            "size": self.size,
            "edge_length": self.edge_length,
            "prestrain": self.prestrain,
        }


@dataclass(frozen=True)
class GraphConfig(GeometryConfig):
    """An explicit net. ``fixed`` are its default supports; ``rest_length`` and ``EA``
    (per edge) are optional. ``file`` records where the data came from (not compared, and
    the resolved case holds the data itself)."""

    kind: ClassVar[str] = "graph"
    nodes: tuple[Vec3, ...]
    edges: tuple[tuple[int, int], ...]
    fixed: tuple[int, ...] = ()
    rest_length: tuple[float, ...] | None = None
    EA: tuple[float, ...] | None = None
    prestrain: float = 0.0
    file: str | None = field(default=None, compare=False)

    def to_dict(self) -> dict:
        d: dict[str, Any] = {
            "kind": self.kind,
            "nodes": [list(p) for p in self.nodes],
            "edges": [list(e) for e in self.edges],
            "fixed": list(self.fixed),
        }
        if self.rest_length is not None:
            d["rest_length"] = list(self.rest_length)
        if self.EA is not None:
            d["EA"] = list(self.EA)
        d["prestrain"] = self.prestrain
        return d


@dataclass(frozen=True)
class MaterialConfig:
    """Either E with radius or area, or EA directly; density needs radius or area."""

    E: float | None = None
    radius: float | None = None
    area: float | None = None
    EA: float | None = None
    density: float = 0.0
    tension_only: bool = True

    @property
    def cross_section(self) -> float | None:
        """Area A [m^2] from radius or area, None when only EA is given."""
        if self.area is not None:
            return self.area
        if self.radius is not None:
            return math.pi * self.radius**2
        return None

    @property
    def axial_stiffness(self) -> float | None:
        """EA [N]: E * A, or EA as given (None for a graph with EA per edge only)."""
        if self.EA is not None:
            return self.EA
        if self.E is not None and self.cross_section is not None:
            return self.E * self.cross_section
        return None

    @property
    def line_density(self) -> float:
        """rho * A [kg/m]."""
        a = self.cross_section
        return 0.0 if a is None else self.density * a

    def to_dict(self) -> dict:
        d: dict[str, Any] = {}
        for key in ("E", "radius", "area", "EA"):
            if getattr(self, key) is not None:
                d[key] = getattr(self, key)
        d["density"] = self.density
        d["tension_only"] = self.tension_only
        return d


@dataclass(frozen=True)
class MoveConfig:
    """A support that moves by ``displacement`` over ``duration`` seconds."""

    node: NodeRef
    displacement: Vec3
    duration: float = 0.0

    def to_dict(self) -> dict:
        return {
            "node": self.node,
            "displacement": list(self.displacement),
            "duration": self.duration,
        }


@dataclass(frozen=True)
class SupportsConfig:
    """``fixed``: the pinned nodes, replacing the geometry's default supports (None: the
    defaults); ``moves``: prescribed motions of pinned nodes."""

    fixed: tuple[NodeRef, ...] | None = None
    moves: tuple[MoveConfig, ...] = ()

    def to_dict(self) -> dict:
        d: dict[str, Any] = {}
        if self.fixed is not None:
            d["fixed"] = list(self.fixed)
        if self.moves:
            d["move"] = [m.to_dict() for m in self.moves]
        return d


@dataclass(frozen=True)
class PointLoadConfig:
    """A constant force [N] on one node."""

    node: NodeRef
    force: Vec3

    def to_dict(self) -> dict:
        return {"node": self.node, "force": list(self.force)}


@dataclass(frozen=True)
class LoadConfig:
    """Pressure p [Pa] (square_net), gravity [m/s^2] (None: none) and point loads."""

    pressure: float = 0.0
    gravity: Vec3 | None = None
    points: tuple[PointLoadConfig, ...] = ()

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"pressure": self.pressure}
        if self.gravity is not None:
            d["gravity"] = list(self.gravity)
        if self.points:
            d["point"] = [p.to_dict() for p in self.points]
        return d


@dataclass(frozen=True)
class SolverConfig:
    """How to solve: see docs/DESIGN.md (solver section) for the meaning of each key."""

    method: str = "static"
    dt: float = 1e-2
    damping: float = 1.0
    t_end: float = 10.0
    rtol: float = 1e-8
    linear: str = "auto"
    threads: int = 1
    max_iter: int = 200
    steps: int = 1

    def to_dict(self) -> dict:
        return {key: getattr(self, key) for key in _SOLVER_KEYS}


@dataclass(frozen=True)
class OutputConfig:
    """Result file, trajectory stride (0: final state only) and XDMF sidecar switch."""

    file: str
    every: int = 1
    xdmf: bool = True

    def to_dict(self) -> dict:
        return {"file": self.file, "every": self.every, "xdmf": self.xdmf}


@dataclass(frozen=True)
class Case:
    """A validated case; ``source`` (the file it came from) is not compared."""

    title: str
    geometry: CableConfig | SquareNetConfig | GraphConfig
    material: MaterialConfig
    supports: SupportsConfig
    load: LoadConfig
    solver: SolverConfig
    output: OutputConfig
    source: str = field(default="<dict>", compare=False)

    def to_dict(self) -> dict:
        """The resolved case: every default filled in, plain TOML types only."""
        load = self.load.to_dict()
        if self.geometry.kind != "square_net":
            load.pop("pressure")
        return {
            "title": self.title,
            "geometry": self.geometry.to_dict(),
            "material": self.material.to_dict(),
            "supports": self.supports.to_dict(),
            "load": load,
            "solver": self.solver.to_dict(),
            "output": self.output.to_dict(),
        }

    def to_toml(self) -> str:
        """The resolved case as TOML text; ``parse_case(tomllib.loads(text))`` gives it back."""
        return dumps_toml(self.to_dict())


@dataclass(frozen=True, eq=False)
class Scene:
    """A case built: the net, its loads, the probe node (whose z-deflection is "delta")
    and the length scale L of delta/L."""

    case: Case
    net: Net
    loads: Loads
    probe: int
    size: float


# --------------------------------------------------------------------------- loading


def load_case(path: str | Path | None, overrides: Sequence[str] = ()) -> Case:
    """Read, override and validate a case file; ``None`` is the bundled default case."""
    if path is None:
        resource = resources.files("catenet") / "data" / "default.toml"
        source = "catenet/data/default.toml"
        raw = resource.read_bytes()
        base_dir = Path.cwd()
    else:
        p = Path(path)
        source = str(p)
        raw = read_case_bytes(p)
        base_dir = p.parent
    data = parse_toml(raw, source)
    sweep = data.pop("sweep", None)  # the grid of `catenet sweep`; a single run ignores it
    if sweep is not None and not isinstance(sweep, dict):
        raise ConfigError(
            f"sweep = {sweep!r}: must be a table of key.path = [values] (read by catenet sweep)"
        )
    if overrides:
        data = apply_overrides(data, overrides)
    return parse_case(data, source=source, base_dir=base_dir)


def read_case_bytes(path: Path) -> bytes:
    """The bytes of a case file; ConfigError naming the path when it cannot be read."""
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such case file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a directory, not a case file") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the case file: {exc.strerror or exc}") from None


def parse_toml(raw: bytes | str, source: str) -> dict:
    """TOML text (bytes are decoded as UTF-8) to a dict; errors name source, line and column."""
    if isinstance(raw, bytes):
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            line, col = _line_col(raw[: exc.start].decode("utf-8", "replace"))
            raise ConfigError(
                f"{source}: line {line}, column {col}: not UTF-8 text (a TOML file must be UTF-8)"
            ) from None
    else:
        text = raw
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise ConfigError(f"{source}: nested too deeply to be a case file") from None
    except ValueError as exc:  # tomllib.TOMLDecodeError is a ValueError
        msg = str(exc)
        m = re.match(r"(?s)(.*) \(at line (\d+), column (\d+)\)$", msg)
        if m:
            reason, line, col = m.group(1), m.group(2), m.group(3)
        else:
            line, col = _line_col(text)
            reason = re.sub(r" \(at end of document\)$", "", msg)
        reason = reason[:1].lower() + reason[1:]
        raise ConfigError(f"{source}: line {line}, column {col}: {reason}") from None


def _line_col(text: str) -> tuple[int, int]:
    """Line and column (both from 1) just after ``text``."""
    lines = text.split("\n")
    return len(lines), len(lines[-1]) + 1


def apply_overrides(data: dict, overrides: Sequence[str]) -> dict:
    """A copy of ``data`` with every ``key.path=value`` set. The value is read as a TOML
    value (``3``, ``0.5``, ``[1, 2, 3]``, ``true``, ``"text"``), else taken as a plain
    string. A number as a path part indexes an array of tables (the next free index
    appends a table)."""
    out = copy.deepcopy(dict(data))
    problems: list[str] = []
    for ov in overrides:
        if not isinstance(ov, str) or "=" not in ov:
            problems.append(f"override {ov!r}: must be key.path=value (e.g. solver.method=dynamic)")
            continue
        key, _, text = ov.partition("=")
        parts = [p.strip() for p in key.strip().split(".")]
        if not all(parts):
            problems.append(
                f"override {ov!r}: key path {key.strip()!r}: empty part: must be like a.b.c"
            )
            continue
        value = _override_value(text.strip())
        problem = _set_path(out, parts, value)
        if problem:
            problems.append(f"override {ov!r}: {problem}")
    if problems:
        raise ConfigError(problems)
    return out


def _override_value(text: str) -> Any:
    try:
        parsed = tomllib.loads(f"v = {text}")
    except (ValueError, RecursionError):
        return text
    if set(parsed) != {"v"}:
        return text
    return parsed["v"]


def _set_path(root: dict, parts: list[str], value: Any) -> str | None:
    cur: Any = root
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        here = ".".join(parts[:depth]) or "<top>"
        if isinstance(cur, list):
            if not part.isdigit() or int(part) > len(cur):
                return (
                    f"{here} is an array of {len(cur)} tables: "
                    f"{'.'.join(parts[: depth + 1])} needs an index 0..{len(cur)}"
                )
            i = int(part)
            if i == len(cur):
                cur.append({})
            if last:
                cur[i] = value
                return None
            if not isinstance(cur[i], (dict, list)):
                cur[i] = {}
            cur = cur[i]
            continue
        if not isinstance(cur, dict):
            return f"{here} = {_show(cur)} is not a table: cannot set {'.'.join(parts)}"
        if last:
            cur[part] = value
            return None
        if part not in cur:  # a new table, or a new array of tables before an index
            cur[part] = [] if parts[depth + 1].isdigit() else {}
        cur = cur[part]
    return None


# --------------------------------------------------------------------------- checking


class _Bad:
    """Marks a value that failed its check (the problem is already recorded)."""

    def __repr__(self) -> str:
        return "<bad>"


BAD: Any = _Bad()
_MISSING: Any = object()


def _show(value: Any, limit: int = 72) -> str:
    """A value as it reads in a message: repr, TOML-like for dates, shortened."""
    if isinstance(value, (datetime.date, datetime.time)):
        text = value.isoformat()
    elif isinstance(value, np.generic):
        text = repr(value.item())
    else:
        try:
            text = repr(value)
        except Exception:  # a repr that fails must not hide the real problem
            text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 4] + " ..."


def _is_real(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


def _as_float(v: Any) -> float | None:
    """A real number as float (huge integers become inf), else None."""
    if not _is_real(v):
        return None
    try:
        return float(v)
    except OverflowError:
        return math.inf if v > 0 else -math.inf
    except (TypeError, ValueError):
        return None


def _as_int(v: Any) -> int | None:
    """An integer, or an integral finite float, as int; else None."""
    if isinstance(v, (bool, np.bool_)):
        return None
    if isinstance(v, numbers.Integral):
        return int(v)
    f = _as_float(v)
    if f is not None and math.isfinite(f) and f == int(f):
        return int(f)
    return None


class _Checker:
    """Collects problems; each check returns the clean value or BAD."""

    def __init__(self) -> None:
        self.problems: list[str] = []

    def add(self, message: str) -> None:
        self.problems.append(message)

    def bad(self, path: str, value: Any, need: str) -> Any:
        self.add(f"{path} = {_show(value)}: {need}")
        return BAD

    def table(self, value: Any, path: str) -> dict | None:
        if isinstance(value, Mapping):
            return dict(value)
        self.bad(path, value, "must be a table")
        return None

    def keys(self, tbl: Mapping, prefix: str, accepted: Sequence[str], what: str = "") -> None:
        for key in tbl:
            if key in accepted:
                continue
            path = f"{prefix}.{key}" if prefix else str(key)
            hint = difflib.get_close_matches(str(key), accepted, n=1)
            mean = f"; did you mean {hint[0]!r}?" if hint else ""
            self.add(f"{path}: unknown key{what} (accepted: {', '.join(accepted)}){mean}")

    def get(self, tbl: Mapping, prefix: str, key: str, default: Any, need: str) -> Any:
        """The value, the default, or (required and absent) BAD with a problem."""
        if key in tbl:
            return tbl[key]
        if default is _MISSING:
            self.add(f"{prefix}.{key}: missing: {need}")
            return BAD
        return default

    def real(self, v: Any, path: str, *, gt=None, ge=None, lt=None, need: str = "") -> Any:
        """A finite float within the bounds."""
        if v is BAD:
            return BAD
        cond = []
        if gt is not None:
            cond.append(f"> {gt:g}")
        if ge is not None:
            cond.append(f">= {ge:g}")
        if lt is not None:
            cond.append(f"< {lt:g}")
        need = need or " and ".join(["finite", *cond])
        f = _as_float(v)
        if f is None:
            return self.bad(path, v, f"must be a number, {need}")
        ok = math.isfinite(f)
        ok = ok and (gt is None or f > gt) and (ge is None or f >= ge) and (lt is None or f < lt)
        if not ok:
            return self.bad(path, v, f"must be {need}")
        return f

    def integer(self, v: Any, path: str, *, ge: int, even: bool = False) -> Any:
        if v is BAD:
            return BAD
        need = f"an {'even ' if even else ''}integer >= {ge}"
        i = _as_int(v)
        if i is None or i < ge or (even and i % 2):
            return self.bad(path, v, f"must be {need}")
        return i

    def boolean(self, v: Any, path: str) -> Any:
        if v is BAD:
            return BAD
        if isinstance(v, (bool, np.bool_)):
            return bool(v)
        return self.bad(path, v, "must be true or false")

    def string(
        self, v: Any, path: str, *, choices: Sequence[str] | None = None, nonempty: bool = False
    ) -> Any:
        if v is BAD:
            return BAD
        if choices is not None:
            if isinstance(v, str) and v in choices:
                return v
            return self.bad(path, v, "must be one of " + ", ".join(map(repr, choices)))
        if not isinstance(v, str) or (nonempty and not v.strip()):
            return self.bad(
                path, v, "must be a non-empty string" if nonempty else "must be a string"
            )
        try:
            v.encode("utf-8")
        except UnicodeEncodeError:  # lone surrogates, e.g. from undecodable arguments
            return self.bad(path, v, "must be valid Unicode text")
        return v

    def vec3(self, v: Any, path: str) -> Any:
        if v is BAD:
            return BAD
        need = "must be [x, y, z]: 3 finite numbers"
        if not isinstance(v, (list, tuple)) or len(v) != 3:
            return self.bad(path, v, need)
        out = [_as_float(c) for c in v]
        if any(c is None or not math.isfinite(c) for c in out):
            return self.bad(path, v, need)
        return tuple(out)

    def node_ref(self, v: Any, path: str, kind: str | None) -> Any:
        """A node index (checked against the node count later) or a name of this kind."""
        names = NODE_NAMES.get(kind or "", ())
        alts = f" or one of {', '.join(map(repr, names))}" if names else ""
        if isinstance(v, str):
            if kind is None:  # the geometry is broken: names cannot be checked
                return BAD
            if v in names:
                return v
            where = f" (geometry.kind = {kind!r})" if kind else ""
            return self.bad(path, v, f"must be a node index{alts}{where}")
        i = _as_int(v)
        if i is None or i < 0:
            return self.bad(path, v, f"must be a node index (an integer >= 0){alts}")
        return i

    def array_of_tables(self, v: Any, path: str) -> list:
        if isinstance(v, (list, tuple)) and all(isinstance(t, Mapping) for t in v):
            return list(v)
        self.bad(path, v, f"must be an array of tables ([[{path}]])")
        return []


# --------------------------------------------------------------------------- parsing


def parse_case(data: dict, *, source: str = "<dict>", base_dir: Path | None = None) -> Case:
    """Validate a case table (as read from TOML) and resolve every default.

    Raises ConfigError listing every problem. ``source`` names the case in messages and
    gives the default output file ``out/<stem>.h5``; ``base_dir`` (default: the current
    directory) is where ``geometry.file`` is looked up.
    """
    base_dir = Path.cwd() if base_dir is None else Path(base_dir)
    ck = _Checker()
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source}: the case must be a table of sections, not {_show(data)}")
    ck.keys(data, "", _TOP_KEYS)

    title = ck.string(data.get("title", ""), "title")

    geometry, kind = _parse_geometry(ck, data, base_dir)
    material = _parse_material(ck, data.get("material", _MISSING), kind, geometry)
    supports = _parse_supports(ck, data.get("supports", {}), kind)
    load = _parse_load(ck, data.get("load", {}), kind)
    solver = _parse_solver(ck, data.get("solver", {}))
    output = _parse_output(ck, data.get("output", {}), source)

    # Cross checks between sections.
    if isinstance(material, MaterialConfig):
        dens = material.density
        if isinstance(solver, SolverConfig) and solver.method == "dynamic" and dens == 0:
            ck.add(
                f"material.density = {dens!r}: solver.method = 'dynamic' needs mass: "
                "must be > 0 (with material.radius or material.area)"
            )
        if isinstance(load, LoadConfig) and load.gravity is not None and dens == 0:
            ck.add(
                f"load.gravity = {_show(data['load']['gravity'])}: gravity needs mass: "
                "set material.density > 0 (with material.radius or material.area)"
            )
    if isinstance(solver, SolverConfig) and solver.method == "dynamic" and solver.dt > solver.t_end:
        ck.add(f"solver.dt = {solver.dt!r}: must be <= solver.t_end = {solver.t_end!r}")

    # Node references need the node count (and, for square nets, the built topology):
    # only once the geometry itself is sound.
    if geometry is not None:
        _check_nodes(ck, geometry, supports, load)

    if ck.problems:
        raise ConfigError(ck.problems)
    return Case(
        title=title,
        geometry=geometry,
        material=material,
        supports=supports,
        load=load,
        solver=solver,
        output=output,
        source=source,
    )


def _parse_geometry(ck: _Checker, data: Mapping, base_dir: Path):
    if "geometry" not in data:
        ck.add(
            "geometry: missing: the case needs a [geometry] table with kind = "
            + " | ".join(map(repr, KINDS))
        )
        return None, None
    g = ck.table(data["geometry"], "geometry")
    if g is None:
        return None, None
    kind = ck.string(
        ck.get(g, "geometry", "kind", _MISSING, "one of " + ", ".join(map(repr, KINDS))),
        "geometry.kind",
        choices=KINDS,
    )
    if kind is BAD:
        return None, None
    ck.keys(g, "geometry", _GEOMETRY_KEYS[kind], f" for kind {kind!r}")
    before = len(ck.problems)
    if kind == "square_net":
        cfg = _parse_square_net(ck, g)
    elif kind == "cable":
        cfg = _parse_cable(ck, g)
    else:
        cfg = _parse_graph(ck, g, base_dir)
    if len(ck.problems) > before or cfg is None:
        return None, kind
    _guard_size(ck, cfg)
    return (cfg if len(ck.problems) == before else None), kind


def _parse_square_net(ck: _Checker, g: Mapping) -> SquareNetConfig | None:
    p = "geometry"
    n = ck.integer(
        ck.get(g, p, "n", _MISSING, "the number of cables (an even integer >= 2)"),
        "geometry.n",
        ge=2,
        even=True,
    )
    alpha = ck.real(
        ck.get(g, p, "alpha", _MISSING, "the angle in radians"),
        "geometry.alpha",
        need="finite (radians)",
    )
    size = ck.real(ck.get(g, p, "size", _MISSING, "the side L [m] (> 0)"), "geometry.size", gt=0)
    el = ck.real(
        ck.get(g, p, "edge_length", _MISSING, "the edge length [m] (> 0)"),
        "geometry.edge_length",
        gt=0,
    )
    pre = ck.real(g.get("prestrain", 0.0), "geometry.prestrain", gt=-1)
    if BAD in (n, alpha, size, el, pre):
        return None
    return SquareNetConfig(n=n, alpha=alpha, size=size, edge_length=el, prestrain=pre)


def _parse_cable(ck: _Checker, g: Mapping) -> CableConfig | None:
    p = "geometry"
    start = ck.vec3(ck.get(g, p, "start", _MISSING, "[x, y, z] of node 0"), "geometry.start")
    end = ck.vec3(ck.get(g, p, "end", _MISSING, "[x, y, z] of the last node"), "geometry.end")
    nodes = ck.integer(
        ck.get(g, p, "nodes", _MISSING, "the number of nodes (an integer >= 2)"),
        "geometry.nodes",
        ge=2,
    )
    length = g.get("length", None)
    if length is not None:
        length = ck.real(length, "geometry.length", gt=0)
    if start is not BAD and end is not BAD:
        chord = math.dist(start, end)
        if not chord > 0:
            ck.bad("geometry.end", g["end"], "must differ from geometry.start")
            return None
        if not math.isfinite(chord):
            ck.bad("geometry.end", g["end"], "too far from geometry.start (the chord overflows)")
            return None
        if length is None:
            length = chord
    if BAD in (start, end, nodes, length):
        return None
    return CableConfig(start=start, end=end, nodes=nodes, length=length)


def _parse_graph(ck: _Checker, g: Mapping, base_dir: Path) -> GraphConfig | None:
    file = None
    src: Mapping = g
    suffix = ""
    pre = ck.real(g.get("prestrain", 0.0), "geometry.prestrain", gt=-1)
    if "file" in g:
        file = ck.string(g["file"], "geometry.file", nonempty=True)
        if file is BAD:
            return None
        inline = [k for k in _GRAPH_DATA_KEYS if k in g]
        if inline:
            ck.add(
                f"geometry.{inline[0]}: give the graph in geometry.file or inline, not both "
                f"(geometry.file = {file!r} holds {', '.join(_GRAPH_DATA_KEYS)})"
            )
            return None
        src = _read_graph_file(ck, file, base_dir)
        if src is None:
            return None
        suffix = f" (in geometry.file = {file!r})"
    sub = _Checker()
    if file is not None:
        sub.keys(src, "geometry", _GRAPH_DATA_KEYS, " in a graph file")
    cfg = _parse_graph_data(sub, src, pre)
    ck.problems.extend(msg + suffix for msg in sub.problems)
    if cfg is None or sub.problems or pre is BAD:
        return None
    return GraphConfig(
        nodes=cfg[0],
        edges=cfg[1],
        fixed=cfg[2],
        rest_length=cfg[3],
        EA=cfg[4],
        prestrain=pre,
        file=file,
    )


def _read_graph_file(ck: _Checker, file: str, base_dir: Path) -> Mapping | None:
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
            f"{', '.join(_GRAPH_DATA_KEYS)}, not {type(obj).__name__}"
        )
        return None
    return obj


def _first(ck: _Checker, bad: list[tuple[str, Any]], need: str, limit: int = 5) -> None:
    """Record up to ``limit`` bad items of one array and how many more there are."""
    for path, value in bad[:limit]:
        ck.bad(path, value, need)
    if len(bad) > limit:
        ck.add(f"{bad[0][0].split('[')[0]}: {len(bad) - limit} more entries like these")


def _parse_graph_data(ck: _Checker, g: Mapping, pre: Any):
    p = "geometry"
    nodes_v = ck.get(g, p, "nodes", _MISSING, "[[x, y, z], ...] (at least 2 nodes)")
    edges_v = ck.get(g, p, "edges", _MISSING, "[[i, j], ...] (at least 1 edge)")
    nodes = edges = BAD
    if nodes_v is not BAD:
        if not isinstance(nodes_v, (list, tuple)) or len(nodes_v) < 2:
            ck.bad("geometry.nodes", nodes_v, "must be an array of at least 2 [x, y, z]")
        else:
            out, bad = [], []
            for i, q in enumerate(nodes_v):
                xyz = None
                if isinstance(q, (list, tuple)) and len(q) == 3:
                    xyz = tuple(_as_float(c) for c in q)
                    if any(c is None or not math.isfinite(c) for c in xyz):
                        xyz = None
                if xyz is None:
                    bad.append((f"geometry.nodes[{i}]", q))
                out.append(xyz)
            _first(ck, bad, "must be [x, y, z]: 3 finite numbers")
            if not bad:
                nodes = tuple(out)
    if edges_v is not BAD:
        if not isinstance(edges_v, (list, tuple)) or len(edges_v) < 1:
            ck.bad("geometry.edges", edges_v, "must be an array of at least 1 [i, j]")
        else:
            out, bad = [], []
            for k, e in enumerate(edges_v):
                ij = None
                if isinstance(e, (list, tuple)) and len(e) == 2:
                    ij = tuple(_as_int(c) for c in e)
                    if any(c is None or c < 0 for c in ij):
                        ij = None
                if ij is None:
                    bad.append((f"geometry.edges[{k}]", e))
                out.append(ij)
            _first(ck, bad, "must be [i, j]: two node indices (integers >= 0)")
            if not bad:
                edges = tuple(out)
    m = len(edges) if edges is not BAD else None
    rest = _per_edge(ck, g.get("rest_length"), "geometry.rest_length", m)
    ea = _per_edge(ck, g.get("EA"), "geometry.EA", m)
    fixed: Any = ()
    if "fixed" in g:
        fixed = _index_list(ck, g["fixed"], "geometry.fixed")
    if rest not in (None, BAD) and pre not in (BAD, 0.0):
        ck.add(
            f"geometry.prestrain = {pre!r}: give geometry.rest_length or geometry.prestrain, "
            "not both"
        )
    if BAD in (nodes, edges, rest, ea, fixed):
        return None
    n = len(nodes)
    # Topology: indices, loops, duplicates, zero or overflowing lengths.
    bad_idx = [(f"geometry.edges[{k}]", list(e)) for k, e in enumerate(edges) if max(e) >= n]
    _first(ck, bad_idx, f"node indices must be in 0..{n - 1}")
    bad_fixed = [(f"geometry.fixed[{k}]", i) for k, i in enumerate(fixed) if i >= n]
    _first(ck, bad_fixed, f"must be a node index in 0..{n - 1}")
    if bad_idx or bad_fixed:
        return None
    e_arr = np.array(edges, dtype=np.int64)
    xyz = np.array(nodes, dtype=np.float64)
    loops = np.flatnonzero(e_arr[:, 0] == e_arr[:, 1])
    _first(
        ck,
        [(f"geometry.edges[{k}]", list(edges[k])) for k in loops],
        "an edge must join two different nodes",
    )
    key = np.sort(e_arr, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    seen: dict[tuple[int, int], int] = {}
    dups = []
    if (counts > 1).any():
        for k, pair in enumerate(map(tuple, key.tolist())):
            if pair in seen:
                dups.append((f"geometry.edges[{k}]", list(edges[k]), seen[pair]))
            else:
                seen[pair] = k
    for path, value, k0 in dups[:5]:
        ck.bad(path, value, f"repeats geometry.edges[{k0}]: edges must be unique")
    if len(dups) > 5:
        ck.add(f"geometry.edges: {len(dups) - 5} more repeated edges")
    with np.errstate(all="ignore"):
        length = np.linalg.norm(xyz[e_arr[:, 1]] - xyz[e_arr[:, 0]], axis=1)
    is_loop = set(loops.tolist())
    zero = [k for k in np.flatnonzero(~(length > 0)).tolist() if k not in is_loop]
    _first(
        ck,
        [(f"geometry.edges[{k}]", list(edges[k])) for k in zero],
        "zero length: the nodes of an edge must be distinct points",
    )
    huge = np.flatnonzero(~np.isfinite(length))
    _first(
        ck,
        [(f"geometry.edges[{k}]", list(edges[k])) for k in huge],
        "its length overflows: coordinates too large",
    )
    return nodes, edges, tuple(fixed), rest, ea


def _per_edge(ck: _Checker, v: Any, path: str, m: int | None) -> Any:
    if v is None:
        return None
    if not isinstance(v, (list, tuple)):
        return ck.bad(path, v, "must be an array with one number > 0 per edge")
    vals = [_as_float(x) for x in v]
    bad = [
        (f"{path}[{k}]", v[k])
        for k, x in enumerate(vals)
        if x is None or not (math.isfinite(x) and x > 0)
    ]
    _first(ck, bad, "must be finite and > 0")
    if m is not None and len(v) != m:
        return ck.bad(path, v, f"has {len(v)} values: must have one per edge ({m})")
    return BAD if bad else tuple(vals)


def _index_list(ck: _Checker, v: Any, path: str) -> Any:
    if not isinstance(v, (list, tuple)):
        return ck.bad(path, v, "must be an array of node indices")
    out, bad = [], []
    for k, x in enumerate(v):
        i = _as_int(x)
        if i is None or i < 0:
            bad.append((f"{path}[{k}]", x))
        out.append(i)
    _first(ck, bad, "must be a node index (an integer >= 0)")
    if bad:
        return BAD
    dup = _dups(out)
    if dup:
        return ck.bad(path, v, f"node {dup[0]} appears more than once: list each node once")
    return tuple(out)


def _dups(values: list[int]) -> list[int]:
    seen: set[int] = set()
    return sorted({i for i in values if i in seen or seen.add(i)})


def _parse_material(ck: _Checker, m_v: Any, kind: str | None, geom) -> MaterialConfig | Any:
    if m_v is _MISSING:
        ck.add(
            "material: missing: the case needs a [material] table (E with radius or area, or EA)"
        )
        return BAD
    m = ck.table(m_v, "material")
    if m is None:
        return BAD
    ck.keys(m, "material", _MATERIAL_KEYS)
    vals = {}
    for key in ("E", "radius", "area", "EA"):
        vals[key] = ck.real(m[key], f"material.{key}", gt=0) if key in m else None
    density = ck.real(m.get("density", 0.0), "material.density", ge=0)
    tension_only = ck.boolean(m.get("tension_only", True), "material.tension_only")
    E, radius, area, EA = vals["E"], vals["radius"], vals["area"], vals["EA"]
    given = {k for k in ("E", "radius", "area", "EA") if k in m}
    per_edge_ea = isinstance(geom, GraphConfig) and geom.EA is not None
    per_edge_ea = per_edge_ea or (kind == "graph" and geom is None)  # unknown: do not insist
    if {"radius", "area"} <= given:
        ck.add(
            f"material.area = {_show(m['area'])}: give material.radius or material.area, not both"
        )
    if "E" in given and "EA" in given:
        ck.add(
            f"material.EA = {_show(m['EA'])}: give material.E (with radius or area) or "
            "material.EA, not both"
        )
    elif "E" in given and not given & {"radius", "area"}:
        ck.add(
            f"material.E = {_show(m['E'])}: needs a cross-section: give material.radius or "
            "material.area (or give material.EA instead of E)"
        )
    elif not given & {"E", "EA"} and not per_edge_ea:
        ck.add("material: missing stiffness: give E with radius or area, or EA")
    if density not in (BAD, 0.0) and "EA" in given and not given & {"radius", "area"}:
        ck.add(
            f"material.density = {density!r}: mass needs a cross-section: give "
            "material.radius or material.area (EA alone has no area)"
        )
    if BAD in (E, radius, area, EA, density, tension_only):
        return BAD
    return MaterialConfig(
        E=E, radius=radius, area=area, EA=EA, density=density, tension_only=tension_only
    )


def _parse_supports(ck: _Checker, s_v: Any, kind: str | None) -> SupportsConfig | Any:
    s = ck.table(s_v, "supports")
    if s is None:
        return BAD
    ck.keys(s, "supports", _SUPPORTS_KEYS)
    fixed: Any = None
    if "fixed" in s:
        v = s["fixed"]
        if not isinstance(v, (list, tuple)) or not v:
            fixed = ck.bad("supports.fixed", v, "must be a non-empty array of nodes")
        else:
            refs = [ck.node_ref(x, f"supports.fixed[{k}]", kind) for k, x in enumerate(v)]
            fixed = BAD if BAD in refs else tuple(refs)
    moves = []
    ok = True
    for k, t in enumerate(ck.array_of_tables(s.get("move", []), "supports.move")):
        p = f"supports.move[{k}]"
        ck.keys(t, p, _MOVE_KEYS)
        node = ck.node_ref(
            ck.get(t, p, "node", _MISSING, "the fixed node to move"), f"{p}.node", kind
        )
        disp = ck.vec3(
            ck.get(t, p, "displacement", _MISSING, "[dx, dy, dz] [m]"), f"{p}.displacement"
        )
        dur = ck.real(t.get("duration", 0.0), f"{p}.duration", ge=0)
        if BAD in (node, disp, dur):
            ok = False
        else:
            moves.append(MoveConfig(node=node, displacement=disp, duration=dur))
    if fixed is BAD or not ok:
        return BAD
    return SupportsConfig(fixed=fixed, moves=tuple(moves))


def _parse_load(ck: _Checker, l_v: Any, kind: str | None) -> LoadConfig | Any:
    ld = ck.table(l_v, "load")
    if ld is None:
        return BAD
    ck.keys(ld, "load", _LOAD_KEYS)
    pressure = ck.real(ld.get("pressure", 0.0), "load.pressure")
    if pressure not in (BAD, 0.0) and kind not in (None, "square_net"):
        ck.add(
            f"load.pressure = {pressure!r}: only for geometry.kind = 'square_net' "
            f"(this is {kind!r}): use [[load.point]] or load.gravity"
        )
    gravity = None
    if "gravity" in ld:
        gravity = ck.vec3(ld["gravity"], "load.gravity")
    points = []
    ok = True
    for k, t in enumerate(ck.array_of_tables(ld.get("point", []), "load.point")):
        p = f"load.point[{k}]"
        ck.keys(t, p, _POINT_KEYS)
        node = ck.node_ref(ck.get(t, p, "node", _MISSING, "the loaded node"), f"{p}.node", kind)
        force = ck.vec3(ck.get(t, p, "force", _MISSING, "[fx, fy, fz] [N]"), f"{p}.force")
        if BAD in (node, force):
            ok = False
        else:
            points.append(PointLoadConfig(node=node, force=force))
    if BAD in (pressure, gravity) or not ok:
        return BAD
    return LoadConfig(pressure=pressure, gravity=gravity, points=tuple(points))


def _parse_solver(ck: _Checker, s_v: Any) -> SolverConfig | Any:
    s = ck.table(s_v, "solver")
    if s is None:
        return BAD
    ck.keys(s, "solver", _SOLVER_KEYS)
    d = SolverConfig()
    vals = {
        "method": ck.string(s.get("method", d.method), "solver.method", choices=METHODS),
        "dt": ck.real(s.get("dt", d.dt), "solver.dt", gt=0),
        "damping": ck.real(s.get("damping", d.damping), "solver.damping", ge=0),
        "t_end": ck.real(s.get("t_end", d.t_end), "solver.t_end", gt=0),
        "rtol": ck.real(s.get("rtol", d.rtol), "solver.rtol", gt=0, lt=1),
        "linear": ck.string(s.get("linear", d.linear), "solver.linear", choices=LINEAR),
        "threads": ck.integer(s.get("threads", d.threads), "solver.threads", ge=1),
        "max_iter": ck.integer(s.get("max_iter", d.max_iter), "solver.max_iter", ge=1),
        "steps": ck.integer(s.get("steps", d.steps), "solver.steps", ge=1),
    }
    if vals["linear"] == "pardiso":
        from catenet.linsolve import resolve_backend

        try:
            resolve_backend("pardiso")
        except ConfigError as exc:
            ck.problems.extend(exc.problems)
    if BAD in vals.values():
        return BAD
    return SolverConfig(**vals)


def _parse_output(ck: _Checker, o_v: Any, source: str) -> OutputConfig | Any:
    o = ck.table(o_v, "output")
    if o is None:
        return BAD
    ck.keys(o, "output", _OUTPUT_KEYS)
    stem = "case" if source.startswith("<") else (Path(source).stem or "case")
    file = ck.string(o.get("file", f"out/{stem}.h5"), "output.file", nonempty=True)
    every = ck.integer(o.get("every", 1), "output.every", ge=0)
    xdmf = ck.boolean(o.get("xdmf", True), "output.xdmf")
    if BAD in (file, every, xdmf):
        return BAD
    return OutputConfig(file=file, every=every, xdmf=xdmf)


# --------------------------------------------------------------------------- size guard


def physical_memory() -> int | None:
    """Bytes of physical memory of this machine, None where the OS does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def estimate_size(geometry: GeometryConfig) -> tuple[float, float, float, str]:
    """(nodes, edges, junctions, key path of what drives the size), estimated from the
    parameters alone. Square nets: every cable's length inside the square over
    edge_length, plus one edge per piece between crossings (at worst)."""
    if isinstance(geometry, CableConfig):
        return float(geometry.nodes), float(geometry.nodes - 1), 0.0, "geometry.nodes"
    if isinstance(geometry, GraphConfig):
        n, m = len(geometry.nodes), len(geometry.edges)
        degree = np.bincount(np.array(geometry.edges, dtype=np.int64).ravel(), minlength=n)
        key = "geometry.file" if geometry.file else "geometry.nodes"
        return float(n), float(m), float(np.count_nonzero(degree > 2)), key
    g = geometry
    m = g.n // 2
    if m * m > MAX_NODES:  # do not even loop over the cables
        big = float(m * m) if m < 10**150 else math.inf
        return big, 2 * big, big, "geometry.n"
    crossings = float(m * m)
    pieces = float(g.n * (m + 1))
    half = 0.5 * g.size
    d = g.size / (m + 1)
    u = (math.cos(g.alpha), math.sin(g.alpha))
    v = (-math.sin(g.alpha), math.cos(g.alpha))
    total = 0.0
    for k in range(m):
        ck = (k - (m - 1) / 2) * d
        total += _clip_length((ck * v[0], ck * v[1]), u, half)
        total += _clip_length((-ck * u[0], -ck * u[1]), v, half)
    along = total / g.edge_length
    edges = along + pieces
    key = "geometry.edge_length" if along >= pieces else "geometry.n"
    return edges + g.n, edges, crossings, key


def _clip_length(p: tuple[float, float], w: tuple[float, float], half: float) -> float:
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


def estimate_memory(nodes: float, edges: float, junctions: float = 0.0) -> float:
    """Bytes a solve of a net of this size needs, roughly and on the safe side.

    Per edge a 6x6 Hessian block of float64 values and its int64 scatter map (2 * 36 * 8);
    ten vectors of 3N float64; the CSR matrix, 9 (N + M) entries of 12 bytes (value and
    column index); the sparse factor, measured at about twice the matrix for the chains
    between joints plus 24 K log2 K entries for the K joints (nested dissection of a 2D
    grid); and the builders' Python objects, about 400 bytes per node and edge.
    """
    nnz = 9.0 * (nodes + edges)
    factor = 2.0 * nnz + 24.0 * junctions * math.log2(junctions + 2.0)
    return 2 * 36 * 8 * edges + 10 * 24 * nodes + 12 * (nnz + factor) + 400 * (nodes + edges)


def _guard_size(ck: _Checker, geometry: GeometryConfig) -> None:
    nodes, edges, junctions, key = estimate_size(geometry)
    value = {
        "geometry.nodes": getattr(geometry, "nodes", None) if geometry.kind == "cable" else None,
        "geometry.edge_length": getattr(geometry, "edge_length", None),
        "geometry.n": getattr(geometry, "n", None),
        "geometry.file": getattr(geometry, "file", None),
    }.get(key)
    where = f"{key} = {_show(value)}" if value is not None else key
    if not nodes <= MAX_NODES:
        ck.add(
            f"{where}: the net would have about {nodes:.2g} nodes; catenet builds at most "
            f"{MAX_NODES:.0e} nodes"
        )
        return
    total = physical_memory()
    need = estimate_memory(nodes, edges, junctions)
    if total is not None and not need <= MEMORY_SHARE * total:
        gib = 2.0**30
        ck.add(
            f"{where}: the net would have about {edges:.2g} edges and need about "
            f"{need / gib:.2g} GiB; this machine has {total / gib:.0f} GiB (at most "
            f"{MEMORY_SHARE:.0%} of it may be used)"
        )


# --------------------------------------------------------------------------- node references


@dataclass(frozen=True)
class _Topology:
    n_nodes: int
    default_fixed: frozenset[int]
    names: dict[str, int]


@functools.lru_cache(maxsize=8)
def _square_topology(n: int, alpha: float, size: float, edge_length: float) -> _Topology:
    sq = geo.square_net(n, alpha, size, edge_length, geo.Material(EA=1.0))
    fixed = frozenset(np.flatnonzero(sq.net.fixed).tolist())
    return _Topology(sq.net.n_nodes, fixed, {"center": sq.center})


def _topology(g: GeometryConfig) -> _Topology:
    if isinstance(g, CableConfig):
        n = g.nodes
        return _Topology(
            n, frozenset({0, n - 1}), {"start": 0, "end": n - 1, "midpoint": g.midpoint}
        )
    if isinstance(g, GraphConfig):
        return _Topology(len(g.nodes), frozenset(g.fixed), {"center": _graph_center(g.nodes)})
    return _square_topology(g.n, g.alpha, g.size, g.edge_length)


def _graph_center(nodes) -> int:
    """The node nearest the centre of the bounding box."""
    xyz = np.asarray(nodes, dtype=np.float64)
    mid = 0.5 * (xyz.min(axis=0) + xyz.max(axis=0))
    return int(np.argmin(np.linalg.norm(xyz - mid, axis=1)))


def _needs_topology(g: GeometryConfig, supports: Any, load: Any) -> bool:
    """Square nets are built to check node references only when there are any."""
    if not isinstance(g, SquareNetConfig):
        return True
    refs = []
    if isinstance(supports, SupportsConfig):
        refs += list(supports.fixed or ()) + [m.node for m in supports.moves]
    if isinstance(load, LoadConfig):
        refs += [p.node for p in load.points]
    return any(isinstance(r, int) for r in refs) or bool(
        isinstance(supports, SupportsConfig) and supports.moves
    )


def _resolve(ref: NodeRef, topo: _Topology) -> int:
    return topo.names[ref] if isinstance(ref, str) else ref


def _check_nodes(ck: _Checker, g: GeometryConfig, supports: Any, load: Any) -> None:
    if not _needs_topology(g, supports, load):
        return
    try:
        topo = _topology(g)
    except ConfigError as exc:  # the builder's own checks
        ck.problems.extend(_with_prefix(p, "supports.fixed") for p in exc.problems)
        return
    n = topo.n_nodes

    def in_range(ref, path) -> bool:
        if isinstance(ref, int) and ref >= n:
            ck.bad(path, ref, f"must be a node index in 0..{n - 1} (or a named node)")
            return False
        return True

    fixed = set(topo.default_fixed)
    fixed_key = {
        "graph": "geometry.fixed",
        "cable": "the two ends of the cable; supports.fixed sets others",
        "square_net": "both ends of every cable; supports.fixed sets others",
    }[g.kind]
    before = len(ck.problems)
    if isinstance(supports, SupportsConfig):
        if supports.fixed is not None:
            fixed_key = "supports.fixed"
            ok = [in_range(r, f"supports.fixed[{k}]") for k, r in enumerate(supports.fixed)]
            if all(ok):
                resolved = [_resolve(r, topo) for r in supports.fixed]
                dups = _dups(resolved)
                if dups:
                    dup = dups[0]
                    ck.bad(
                        "supports.fixed",
                        list(supports.fixed),
                        f"node {dup} appears more than once: list each node once",
                    )
                fixed = set(resolved)
            else:
                fixed = set()
        seen: dict[int, int] = {}
        for k, mv in enumerate(supports.moves):
            path = f"supports.move[{k}].node"
            if not in_range(mv.node, path):
                continue
            i = _resolve(mv.node, topo)
            if fixed and i not in fixed:
                shown = mv.node if isinstance(mv.node, int) else f"{mv.node!r} (node {i})"
                ck.add(
                    f"{path} = {shown}: is not a fixed node: only supports move "
                    f"(fixed: {fixed_key})"
                )
            if i in seen:
                ck.add(
                    f"{path} = {_show(mv.node)}: node {i} already moves in "
                    f"supports.move[{seen[i]}]: one move per node"
                )
            seen[i] = k
    if isinstance(load, LoadConfig):
        for k, pt in enumerate(load.points):
            in_range(pt.node, f"load.point[{k}].node")
    if isinstance(g, GraphConfig) and len(ck.problems) == before:
        if not fixed:
            ck.add(
                "geometry.fixed: missing or empty: a graph needs supports "
                "(geometry.fixed or supports.fixed)"
            )
            return
        try:
            Net.from_arrays(
                g.nodes, g.edges, EA=1.0, fixed=sorted(fixed), rest_length=g.rest_length
            )
        except ConfigError as exc:
            ck.problems.extend(_with_prefix(p, fixed_key) for p in exc.problems)


def _with_prefix(message: str, fixed_key: str = "geometry.fixed") -> str:
    """A Net builder message with the case key path of what it names."""
    if message.startswith(("geometry", "supports", "material", "load", "solver")):
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


# --------------------------------------------------------------------------- building


def build(case: Case) -> Scene:
    """The net, loads, probe node and length scale of a case."""
    try:
        return _build(case)
    except ConfigError as exc:
        key = "supports.fixed" if case.supports.fixed is not None else "geometry.fixed"
        raise ConfigError([_with_prefix(p, key) for p in exc.problems]) from None


def _build(case: Case) -> Scene:
    g, mat = case.geometry, case.material
    ea = mat.axial_stiffness
    material = geo.Material(
        EA=1.0 if ea is None else ea,  # None only for a graph with EA per edge
        line_density=mat.line_density,
        tension_only=mat.tension_only,
    )
    fixed_refs = case.supports.fixed
    if isinstance(g, GraphConfig):
        probe = _graph_center(g.nodes)
        topo = _Topology(len(g.nodes), frozenset(g.fixed), {"center": probe})
        fixed = list(g.fixed) if fixed_refs is None else [_resolve(r, topo) for r in fixed_refs]
        rest = g.rest_length
        if g.prestrain:
            xyz = np.asarray(g.nodes, dtype=np.float64)
            e = np.asarray(g.edges, dtype=np.int64)
            rest = np.linalg.norm(xyz[e[:, 1]] - xyz[e[:, 0]], axis=1) / (1.0 + g.prestrain)
        net = geo.graph(g.nodes, g.edges, fixed, material, rest_length=rest, EA=g.EA)
        size = float(np.linalg.norm(net.nodes.max(axis=0) - net.nodes.min(axis=0)))
        return Scene(case, net, _loads(case, net, topo, size), int(probe), size)
    if isinstance(g, CableConfig):
        net = geo.cable(g.start, g.end, g.nodes, material, length=g.length)
        probe, size, prestrain = g.midpoint, g.chord, 0.0
        names = {"start": 0, "end": g.nodes - 1, "midpoint": g.midpoint}
    else:
        sq = geo.square_net(g.n, g.alpha, g.size, g.edge_length, material)
        net, probe, size, prestrain = sq.net, sq.center, g.size, g.prestrain
        names = {"center": sq.center}
    topo = _Topology(net.n_nodes, frozenset(), names)
    if fixed_refs is not None or prestrain:
        fixed = net.fixed
        if fixed_refs is not None:
            fixed = sorted(_resolve(r, topo) for r in fixed_refs)
        net = Net.from_arrays(
            net.nodes,
            net.edges,
            EA=net.EA,
            fixed=fixed,
            rest_length=net.rest_length / (1.0 + prestrain),
            line_density=net.line_density,
            tension_only=net.tension_only,
        )
    return Scene(case, net, _loads(case, net, topo, size), int(probe), float(size))


def _loads(case: Case, net: Net, topo: _Topology, size: float) -> Loads:
    ld = case.load
    force = None
    if isinstance(case.geometry, SquareNetConfig) and ld.pressure != 0.0:
        force = geo.pressure_force(net, ld.pressure, size)
    for k, pt in enumerate(ld.points):
        i = _resolve(pt.node, topo)
        if not 0 <= i < net.n_nodes:
            raise ConfigError(
                f"load.point[{k}].node = {_show(pt.node)}: must be a node index in "
                f"0..{net.n_nodes - 1}"
            )
        if force is None:
            force = np.zeros((net.n_nodes, 3))
        force[i] += pt.force
    gravity = None if ld.gravity is None else np.array(ld.gravity, dtype=np.float64)
    disp = ramp = None
    if case.supports.moves:
        disp = np.zeros((net.n_nodes, 3))
        ramp = np.zeros(net.n_nodes)
        for k, mv in enumerate(case.supports.moves):
            i = _resolve(mv.node, topo)
            if not (0 <= i < net.n_nodes and net.fixed[i]):
                raise ConfigError(
                    f"supports.move[{k}].node = {_show(mv.node)}: must be a fixed node"
                )
            disp[i] = mv.displacement
            ramp[i] = mv.duration
    return Loads(force=force, gravity=gravity, support_displacement=disp, ramp_time=ramp)


# --------------------------------------------------------------------------- TOML writer

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def dumps_toml(data: Mapping) -> str:
    """TOML text of a table of tables, arrays of tables, strings, numbers, booleans and
    (nested) arrays: enough for a resolved case. Floats are written with repr, so they
    read back bit for bit."""
    lines: list[str] = []
    _write_table(data, [], lines, header=None)
    return "\n".join(lines).strip("\n") + "\n"


def _write_table(tbl: Mapping, path: list[str], lines: list[str], header: str | None) -> None:
    if header is not None:
        if lines:
            lines.append("")
        lines.append(header)
    subtables, arrays = [], []
    for key, value in tbl.items():
        if isinstance(value, Mapping):
            subtables.append((key, value))
        elif _is_table_array(value):
            arrays.append((key, value))
        else:
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in subtables:
        sub = [*path, _key(key)]
        _write_table(value, sub, lines, header=f"[{'.'.join(sub)}]")
    for key, value in arrays:
        sub = [*path, _key(key)]
        for item in value:
            _write_table(item, sub, lines, header=f"[[{'.'.join(sub)}]]")


def _is_table_array(value: Any) -> bool:
    return (
        isinstance(value, (list, tuple))
        and bool(value)
        and all(isinstance(v, Mapping) for v in value)
    )


def _key(key: Any) -> str:
    key = str(key)
    return key if _BARE_KEY.match(key) else _string(key)


def _string(s: str) -> str:
    out = []
    for ch in s:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _value(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, numbers.Real):
        f = float(v)
        if math.isnan(f):
            return "nan"
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return repr(f)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, (list, tuple)):
        items = [_value(x) for x in v]
        if any(isinstance(x, (list, tuple)) for x in v) and len(v) > 1:
            return "[\n" + "".join(f"  {s},\n" for s in items) + "]"
        return "[" + ", ".join(items) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (datetime.date, datetime.time)):
        return v.isoformat()
    raise TypeError(f"cannot write {type(v).__name__} as TOML")
