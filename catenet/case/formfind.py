"""The [formfind] table: how ``catenet formfind`` finds the shape of a case's net.

The force density method (``method = "linear"``) takes a force density q [N/m] per edge
(``force_density``: one number for every edge, one per edge, or a table by cable,
``{ "hang*" = q1, edges = q2 }``) and gives the shape in one sparse solve.
``method = "forces"`` and ``"lengths"`` adjust the force densities until every
edge carries its target tension ``force`` [N] or has its target length ``length`` [m], to
the relative tolerance ``tol``. ``catenet run`` refuses a case with this table (it would
analyse the unfound starting geometry): form-find it first, then run the case it writes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    as_float,
    carried,
    choice,
    integer,
    key,
    names,
    node,
    parse_keys,
    real,
    show,
    tables,
)

FORMFIND_METHODS = ("linear", "forces", "lengths", "elastic")

#: What the targets ([[target]]) vary: a force density (elastic: a rest-length factor) per
#: edge, or one per cable; elastic also the prestress of the cables that have one, or
#: its [[formfind.support]] offsets alone ("supports": the rest lengths kept).
VARY = ("edges", "cables", "prestress", "supports")

#: The offsets a [[formfind.support]] may give, one design variable each.
OFFSETS = ("dx", "dy", "dz")

#: The bounds of each kind of design variable: force densities, the elastic method's
#: rest-length factors and prestress.
BOUNDS = {
    "force_density": ("force_density_min", "force_density_max"),
    "rest_length_factor": ("rest_length_factor_min", "rest_length_factor_max"),
    "prestress": ("prestress_min", "prestress_max"),
}

#: What each method needs besides the force densities: its target key.
TARGETS = {"forces": "force", "lengths": "length"}


def _number_or_per_edge(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """One number > 0 (every edge), an array of them (one per edge, counted when the
    net is built) or a table of them by cable (names or patterns, ``edges`` for the
    graph's own edges: matched when the net is built)."""
    if isinstance(v, dict):
        if not v:
            return ck.bad(path, v, f"must name at least one cable: {BY_CABLE}")
        out = {}
        for name, x in v.items():
            f = as_float(x)
            if f is None or not (carried(f) and f > 0):
                return ck.bad(f"{path}.{name}", x, "must be a number, finite and > 0")
            out[str(name)] = f
        return out
    if isinstance(v, (list, tuple)):
        if not v:
            return ck.bad(path, v, "must be a number > 0 or a non-empty array, one per edge")
        vals = [as_float(x) for x in v]
        bad = [
            (f"{path}[{k}]", v[k])
            for k, x in enumerate(vals)
            if x is None or not (carried(x) and x > 0)
        ]
        ck.first(bad, "must be finite and > 0")
        return BAD if bad else tuple(vals)
    f = as_float(v)
    if f is None or not (carried(f) and f > 0):
        return ck.bad(path, v, "must be a number, finite and > 0, or an array of them per edge")
    return f


def _offset_range(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """[low, high], low < high, finite: how far a support may move along one axis."""
    if isinstance(v, (list, tuple)) and len(v) == 2:
        lo, hi = (as_float(c) for c in v)
        if lo is not None and hi is not None and carried(lo) and carried(hi) and lo < hi:
            return (lo, hi)
    return ck.bad(
        path, v, "must be [low, high] with low < high, both finite: how far the support may "
        "move along this axis from where it is given [m]"
    )  # fmt: skip


def _offset(axis: str) -> Any:
    return key(
        _offset_range,
        "[low, high]",
        None,
        write="given",
        unit="m",
        doc=(
            f"its offset along {axis} from where it is given, a design variable in the range given"
        ),
    )


@dataclass(frozen=True)
class SupportMoveConfig(Declared):
    """A support the target search may move ([[formfind.support]]): a
    fixed node (or a set of them, moved as one) and, per axis it may move along, the
    range of its offset from where it is given (one design variable per axis)."""

    node: Any = node(doc="the fixed node (index, name or node set: moved as one)")
    dx: Any = _offset("x")
    dy: Any = _offset("y")
    dz: Any = _offset("z")

    @property
    def axes(self) -> tuple[int, ...]:
        """The axes it moves along (0, 1, 2 for x, y, z)."""
        return tuple(c for c, k in enumerate(OFFSETS) if getattr(self, k) is not None)


#: The table form of a per-edge value, as messages show it.
BY_CABLE = '{ NAME or "PATTERN*" = value, edges = value (the graph\'s own edges) }'


def _per_edge(default: Any = None, **kw) -> Any:
    return key(
        _number_or_per_edge,
        "a number > 0, an array of them (one per edge), or a table by cable",
        default,
        write="given",
        **kw,
    )


@dataclass(frozen=True)
class FormfindConfig(Declared):
    """How to find the shape; see the module docstring."""

    method: str = choice(
        "linear",
        FORMFIND_METHODS,
        doc="linear: the force densities as given (with [[target]]: found); forces, "
        "lengths: meet the targets; elastic: the rest lengths that reach [[target]] in the "
        "elastic equilibrium",
    )
    force_density: float | tuple[float, ...] | None = _per_edge(
        shown="linear: required; else the start",
        unit="N/m",
        doc="q = tension / length of every edge (lengths without loads: their geometric mean)",
    )
    force: float | tuple[float, ...] | None = _per_edge(
        unit="N", doc='method = "forces": the tension of every edge'
    )
    length: float | tuple[float, ...] | None = _per_edge(
        unit="m", doc='method = "lengths": the length of every edge'
    )
    tol: float = real(
        1e-9,
        gt=0,
        lt=1,
        doc="forces, lengths, [[target]]: relative tolerance on the targets (a position's: "
        "of the net's size)",
    )
    max_iter: int = integer(
        100, ge=1, doc="forces, lengths, [[target]]: iterations (one factorisation each)"
    )
    vary: str | None = choice(
        None,
        VARY,
        write="given",
        shown='"edges" (elastic: "cables")',
        doc="[[target]]: the design variables: a force density (elastic: a rest-length "
        "factor) per edge, or one per cable (and per own edge of a graph; a net without "
        "named cables is one cable); elastic: "
        '"prestress", the prestress of each cable that has one; "supports": only the '
        "offsets of [[formfind.support]] (the force densities or rest lengths kept)",
    )
    force_density_min: float | None = real(
        None, gt=0, write="given", unit="N/m", doc="[[target]]: the least force density"
    )
    force_density_max: float | None = real(
        None, gt=0, write="given", unit="N/m", doc="[[target]]: the largest force density"
    )
    rest_length_factor_min: float | None = real(
        None, gt=0, write="given", doc="elastic: the least factor on the case's rest lengths"
    )
    rest_length_factor_max: float | None = real(
        None, gt=0, write="given", doc="elastic: the largest factor on the case's rest lengths"
    )
    prestress_min: float | None = real(
        None, gt=0, write="given", unit="N", doc='elastic, vary = "prestress": the least'
    )
    prestress_max: float | None = real(
        None, gt=0, write="given", unit="N", doc='elastic, vary = "prestress": the largest'
    )
    supports: tuple = tables(
        SupportMoveConfig,
        name="support",
        doc="[[target]]: supports the search moves (node, and dx, dy, dz ranges), besides "
        'the force densities, rest lengths or prestress (vary = "supports": alone)',
    )


def parse_formfind(
    ck: Checker, f_v: Any, ctx: Context, targets: bool = False
) -> FormfindConfig | Any:
    """The [formfind] table with the rules between its keys; ``targets``: the case has
    [[target]] tables (the force densities given are then the start)."""
    f = ck.table(f_v, "formfind")
    if f is None:
        return BAD
    ck.keys(f, "formfind", names(FormfindConfig))
    v = parse_keys(ck, f, FormfindConfig, "formfind", ctx)
    method = v["method"]
    if method == "elastic" and not targets:
        ck.add("formfind.method = 'elastic': finds rest lengths for [[target]] tables: add them")
    for k in ("force_density", "force_density_min", "force_density_max"):
        if method == "elastic" and k in f:
            ck.add(
                f"formfind.{k} = {show(f[k])}: method = 'elastic' varies the rest lengths "
                "(the geometry's are the start): remove it"
            )
    if targets and method not in ("linear", "elastic", BAD):
        ck.add(
            f"formfind.method = {method!r}: [[target]] varies the force densities itself: "
            "remove formfind.method (or the targets)"
        )
    _bounds(ck, f, v, method)
    _supports(ck, f, v, method, targets)
    if not targets:
        for k in ("vary", *(b for pair in BOUNDS.values() for b in pair)):
            if k in f:
                ck.add(f"formfind.{k} = {show(f[k])}: only with [[target]] tables (none given)")
    if method == "linear" and "force_density" not in f and not targets:
        ck.add(
            "formfind.force_density: missing: method = 'linear' needs the force density "
            "q [N/m] (one number, or one per edge)"
        )
    for m, target in TARGETS.items():
        if method is BAD:
            break
        if method == m and target not in f:
            ck.add(f"formfind.{target}: missing: method = {m!r} needs its targets")
        elif method != m and target in f:
            ck.add(
                f"formfind.{target} = {show(f[target])}: only with method = {m!r} "
                f"(this is {method!r})"
            )
    if BAD in v.values():
        return BAD
    return FormfindConfig(**v)


def _supports(ck: Checker, f: dict, v: dict, method: Any, targets: bool) -> None:
    """[[formfind.support]] only in a target search (method "elastic", or "linear" with
    [[target]]), each moving along some axis; vary = "supports" only with them."""
    moves = v["supports"]
    if moves is BAD or method is BAD:
        return
    if moves and method not in ("elastic", "linear"):
        ck.add(
            f"formfind.support = {show(f['support'])}: only in a search for [[target]] "
            f"(method = 'elastic' or 'linear'; this is {method!r})"
        )
    elif moves and method == "linear" and not targets:
        ck.add(
            f"formfind.support = {show(f['support'])}: the supports move to meet "
            "[[target]] tables: add them (form finding alone keeps its supports where the "
            "geometry puts them)"
        )
    for k, m in enumerate(moves):
        if not m.axes:
            ck.add(f"formfind.support[{k}]: needs dx, dy or dz: the range it may move along")
    if v["vary"] == "supports" and not moves:
        ck.add(
            "formfind.vary = 'supports': needs [[formfind.support]] tables (the supports that move)"
        )


def _bounds(ck: Checker, f: dict, v: dict, method: Any) -> None:
    """Each pair of bounds in order, and only with the variables they bound."""
    for low, high in BOUNDS.values():
        lo, hi = v[low], v[high]
        if lo not in (None, BAD) and hi not in (None, BAD) and not lo < hi:
            ck.add(f"formfind.{high} = {show(hi)}: must be > formfind.{low} ({show(lo)})")
    if method is BAD or v["vary"] is BAD:
        return
    elastic = method == "elastic"
    if not elastic and v["vary"] == "prestress":
        ck.add(
            "formfind.vary = 'prestress': only with method = 'elastic' (the force density "
            "method varies the force densities)"
        )
    varies = "" if v["vary"] == "supports" else "force_density"
    if elastic:
        varies = {"prestress": "prestress", "supports": ""}.get(v["vary"], "rest_length_factor")
    for kind, pair in BOUNDS.items():
        for k in pair:
            if k in f and kind != varies and not (kind == "force_density" and elastic):
                what = {
                    "force_density": "the force densities (method = 'linear' with [[target]])",
                    "rest_length_factor": "rest-length factors (method = 'elastic', vary = "
                    "'cables' or 'edges')",
                    "prestress": "prestress (method = 'elastic', vary = 'prestress')",
                }[kind]
                ck.add(f"formfind.{k} = {show(f[k])}: bounds {what}: not varied here")


def check_formfind_case(ck: Checker, data: Any) -> None:
    """Problems of the other sections that form finding cannot honour: the rest lengths
    it derives itself (method "elastic" starts from them), and support motions."""
    table = data.get("formfind")
    if isinstance(table, dict) and table.get("method") == "elastic":
        return
    geometry = data.get("geometry") if isinstance(data.get("geometry"), dict) else {}
    material = data.get("material") if isinstance(data.get("material"), dict) else {}
    supports = data.get("supports") if isinstance(data.get("supports"), dict) else {}
    for k in ("rest_length", "length", "prestrain", "prestress"):
        if k in geometry:
            ck.add(
                f"geometry.{k} = {show(geometry[k])}: form finding derives the rest lengths "
                "from the forces it finds: remove it (or remove [formfind])"
            )
    listed = geometry.get("cable")
    cables: list = listed if isinstance(listed, list) else []
    given = [
        (j, k, c[k])
        for j, c in enumerate(cables)
        for k in ("prestress", "rest_length")
        if isinstance(c, dict) and k in c
    ]
    if given:
        j, k, v = given[0]
        more = f" ({len(given) - 1} more cables give theirs)" if len(given) > 1 else ""
        ck.add(
            f"geometry.cable[{j}].{k} = {show(v)}: form finding gives every edge its "
            f"tension: remove it{more} (target tensions by cable: formfind.method = "
            "'forces' with formfind.force = { NAME = N, ... })"
        )
    if "prestress" in material:
        ck.add(
            f"material.prestress = {show(material['prestress'])}: form finding gives every "
            "edge its tension: remove it (target tensions: formfind.method = 'forces' with "
            "formfind.force)"
        )
    if "move" in supports:
        ck.add(
            "supports.move: form finding holds the fixed nodes where the geometry puts "
            "them: give them their final positions there"
        )


__all__ = ["BOUNDS", "FORMFIND_METHODS", "FormfindConfig", "check_formfind_case", "parse_formfind"]
