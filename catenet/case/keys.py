"""Declared case keys and the checker that reports every problem with its key path.

Each key of a section is a field of the section's frozen dataclass, declared once with
``real``, ``integer``, ``boolean``, ``choice``, ``text``, ``vec3``, ``node``, ``tables``
or ``key``: its check, default, accepted values, unit and one-line doc. ``parse_table``
checks a table against the declarations, ``Declared.to_dict`` writes a section back, and
catenet/case/readme.py renders the README table of keys from the same declarations.

Checks collect problems in a ``Checker`` as ``key.path = value: what is accepted`` and
return the clean value, or ``BAD`` when the value failed (its problem already recorded).
"""

from __future__ import annotations

import collections
import dataclasses
import datetime
import difflib
import math
import numbers
import re
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.case.written import WrittenFloat, WrittenInt, as_written_float
from catenet.model.limits import MAGNITUDE, MAX_COUNT, carried, too_large  # noqa: F401

if TYPE_CHECKING:  # the geometry kinds declare their keys here
    from catenet.case.kinds.base import GeometryConfig


class _Marker:
    def __init__(self, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return f"<{self.name}>"


#: A value that failed its check (the problem is already recorded).
BAD: Any = _Marker("bad")
#: The default of a key that must be given.
REQUIRED: Any = _Marker("required")
#: A section table that is absent.
MISSING: Any = _Marker("missing")


# --------------------------------------------------------------------------- values


def show(value: Any, limit: int = 72) -> str:
    """A value as it reads in a message: as written in the case file or --set (see
    catenet/case/written.py), else as TOML writes it (arrays in brackets, also where the
    checks made them tuples; true and false; dates), else repr (NumPy's values as
    Python's), shortened."""
    text = _text(value, limit)
    return text if len(text) <= limit else text[: limit - 4] + " ..."


def _text(value: Any, limit: int) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"  # as TOML writes them
    if isinstance(value, (datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, np.generic):
        return repr(value.item())
    if isinstance(value, np.ndarray):
        value = value.tolist() if value.size <= limit else value.ravel()[:limit].tolist()
    if isinstance(value, (list, tuple)) and not hasattr(value, "_fields"):
        inner = []
        for item in value[:limit]:  # (enough to fill the line)
            inner.append(_text(item, limit))
            if sum(map(len, inner)) > limit:
                break
        text = ", ".join(inner) + ("" if len(inner) == len(value) else ", ...")
        return f"[{text}]"  # a TOML array, also where the checks made it a tuple
    try:
        return repr(value)
    except Exception:  # a repr that fails must not hide the real problem
        return f"<{type(value).__name__}>"


def as_float(v: Any) -> float | None:
    """A real number (not a boolean) as float (huge integers become inf), else None."""
    if not isinstance(v, numbers.Real) or isinstance(v, (bool, np.bool_)):
        return None
    big: Any = v  # a huge integer (or fraction)
    try:
        if isinstance(v, (WrittenFloat, WrittenInt)):
            return as_written_float(v)  # quoted as written after the checks too
        if isinstance(v, (int, np.integer)):  # an integer for a float: quoted without ".0"
            return WrittenFloat(str(int(v)), float(big))
        return float(big)
    except OverflowError:
        return math.inf if big > 0 else -math.inf
    except (TypeError, ValueError):
        return None


def as_int(v: Any) -> int | None:
    """An integer, or an integral finite float, as int; else None."""
    if isinstance(v, (bool, np.bool_)):
        return None
    if isinstance(v, numbers.Integral):
        return int(v)
    f = as_float(v)
    if f is not None and math.isfinite(f) and f == int(f):
        return int(f)
    return None


def duplicates(values: Sequence[Any]) -> list[Any]:
    """The values that occur more than once, sorted."""
    counts = collections.Counter(values)
    return sorted(i for i, n in counts.items() if n > 1)


def _bounds(gt=None, ge=None, lt=None) -> str:
    cond = [f"{op} {b:g}" for op, b in ((">", gt), (">=", ge), ("<", lt)) if b is not None]
    return " and ".join(["finite", *cond])


# --------------------------------------------------------------------------- checker


class Checker:
    """Collects problems; each check returns the clean value or BAD."""

    def __init__(self) -> None:
        self.problems: list[str] = []

    def add(self, message: str) -> None:
        self.problems.append(message)

    def bad(self, path: str, value: Any, need: str) -> Any:
        self.add(f"{path} = {show(value)}: {need}")
        return BAD

    def first(self, bad: list[tuple[str, Any]], need: str, limit: int = 5) -> None:
        """Record up to ``limit`` bad items of one array and how many more there are."""
        for path, value in bad[:limit]:
            self.bad(path, value, need)
        if len(bad) > limit:
            self.add(f"{bad[0][0].split('[')[0]}: {len(bad) - limit} more entries like these")

    def table(self, value: Any, path: str) -> dict | None:
        if isinstance(value, Mapping):
            return dict(value)
        self.bad(path, value, "must be a table")
        return None

    def keys(self, tbl: Mapping, prefix: str, accepted: Sequence[str], what: str = "") -> None:
        """A problem for each key of ``tbl`` not in ``accepted``, with the closest match."""
        for key in tbl:
            if key in accepted:
                continue
            path = f"{prefix}.{key}" if prefix else str(key)
            hint = difflib.get_close_matches(str(key), accepted, n=1)
            mean = f"; did you mean {hint[0]!r}?" if hint else ""
            self.add(f"{path}: unknown key{what} (accepted: {', '.join(accepted)}){mean}")

    def real(self, v: Any, path: str, *, gt=None, ge=None, lt=None, need: str = "") -> Any:
        """A finite float within the bounds."""
        if v is BAD:
            return BAD
        need = need or _bounds(gt, ge, lt)
        f = as_float(v)
        if f is None:
            return self.bad(path, v, f"must be a number, {need}")
        ok = math.isfinite(f)
        ok = ok and (gt is None or f > gt) and (ge is None or f >= ge) and (lt is None or f < lt)
        if not ok:
            return self.bad(path, v, f"must be {need}")
        if abs(f) > MAGNITUDE:
            return self.bad(path, v, f"must be {need} and within {too_large()}")
        return f

    def integer(
        self, v: Any, path: str, *, ge: int, even: bool = False, le: int = MAX_COUNT
    ) -> Any:
        if v is BAD:
            return BAD
        i = as_int(v)
        if i is None or i < ge or (even and i % 2):
            return self.bad(path, v, f"must be an {'even ' if even else ''}integer >= {ge}")
        if i > le:
            return self.bad(path, v, f"must be at most {le:.0e}: more would never finish")
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
        out = [as_float(c) for c in v]
        values = [c for c in out if c is not None and math.isfinite(c)]
        if len(values) != 3:
            return self.bad(path, v, need)
        if any(abs(c) > MAGNITUDE for c in values):
            return self.bad(path, v, f"{need}, each within {too_large()}")
        return tuple(values)

    def sizes3(self, v: Any, path: str) -> Any:
        """[a, b, c]: 3 finite numbers > 0 (a box's half sizes)."""
        out = self.vec3(v, path)
        if out is BAD or all(c > 0 for c in out):
            return out
        return self.bad(path, v, "must be 3 numbers > 0")

    def node_ref(self, v: Any, path: str, kind: type[GeometryConfig] | None) -> Any:
        """A node index (checked against the node count later) or a node name of the
        geometry kind (its config class; None when the geometry is broken)."""
        names = kind.node_names if kind is not None else ()
        alts = f" or one of {', '.join(map(repr, names))}" if names else ""
        if kind is not None and kind.node_sets:  # (a set's name: checked later)
            alts += " or a node set's name"
        if isinstance(v, str):
            if kind is None:  # the geometry is broken: names cannot be checked
                return BAD
            if v in names:
                return v
            if kind.node_sets and v.strip():
                return v  # a node set of the geometry: checked against its topology
            return self.bad(path, v, f"must be a node index{alts} (geometry.kind = {kind.kind!r})")
        i = as_int(v)
        if i is None or i < 0:
            return self.bad(path, v, f"must be a node index (an integer >= 0){alts}")
        return i

    def array_of_tables(self, v: Any, path: str) -> list:
        if isinstance(v, (list, tuple)) and all(isinstance(t, Mapping) for t in v):
            return list(v)
        header = re.sub(r"\[\d+\]", "", path)  # TOML's header names no index
        under = f" after its [[{header.rsplit('.', 1)[0]}]]" if header != path else ""
        self.bad(path, v, f"must be an array of tables ([[{header}]]{under})")
        return []


# --------------------------------------------------------------------------- declarations


@dataclasses.dataclass(frozen=True)
class Context:
    """What a check may look at: the geometry kind (its config class, None while unknown)
    and the values of the keys checked before it in the same table."""

    kind: Any = None
    values: Mapping[str, Any] = dataclasses.field(default_factory=dict)


Check = Callable[[Checker, Any, str, Context], Any]


@dataclasses.dataclass(frozen=True)
class Key:
    """One key of a case table.

    ``default`` is the value when the key is absent (REQUIRED: a problem); ``computed``
    keys are absent as None and filled in by their section (the chord, the file name),
    so their dataclass field has no default. ``write`` says when ``to_dict`` writes the
    key: "always", "given" (not when None or empty), "changed" (not when it is the
    default: keys added later, so that older resolved cases read the same) or "never".
    ``missing`` is what the message for an absent required key asks for (its ``doc`` if
    not given); ``shown`` is the default as the README shows it, when it is not a plain
    value. A ``null`` key given as None (from Python or a JSON file) is as absent.
    """

    check: Check
    accepted: str
    default: Any = REQUIRED
    computed: bool = False
    shown: str | None = None
    unit: str = ""
    doc: str = ""
    missing: str = ""
    write: str = "always"
    null: bool = False
    name: str = ""  # the TOML key; filled in from the field name by declared()
    attr: str = ""  # the dataclass attribute; filled in by declared()
    section: Any = None  # the section class of an array of tables (``tables``)


def key(
    check: Check,
    accepted: str,
    default: Any = REQUIRED,
    *,
    compare: bool = True,
    **declaration: Any,
) -> Any:
    """A dataclass field declaring a key (see Key); its default is the key's default."""
    k = Key(check, accepted, default, **declaration)
    if default is REQUIRED or k.computed:
        return dataclasses.field(metadata={"key": k}, compare=compare)
    return dataclasses.field(default=default, metadata={"key": k}, compare=compare)


def real(default: Any = REQUIRED, *, gt=None, ge=None, lt=None, need: str = "", **kw) -> Any:
    """A finite number within the bounds; ``need`` replaces the bounds in messages."""
    need = need or _bounds(gt, ge, lt)

    def check(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
        return ck.real(v, path, gt=gt, ge=ge, lt=lt, need=need)

    return key(check, f"a number, {need}", default, **kw)


def integer(
    default: Any = REQUIRED, *, ge: int, even: bool = False, le: int = MAX_COUNT, **kw
) -> Any:
    def check(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
        return ck.integer(v, path, ge=ge, even=even, le=le)

    return key(check, f"an {'even ' if even else ''}integer >= {ge}", default, **kw)


def boolean(default: Any = REQUIRED, **kw) -> Any:
    return key(lambda ck, v, path, ctx: ck.boolean(v, path), "true or false", default, **kw)


def choice(default: Any, choices: Sequence[str], **kw) -> Any:
    choices = tuple(choices)

    def check(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
        return ck.string(v, path, choices=choices)

    return key(check, "one of " + ", ".join(map(repr, choices)), default, **kw)


def text(default: Any = REQUIRED, *, nonempty: bool = False, **kw) -> Any:
    def check(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
        return ck.string(v, path, nonempty=nonempty)

    return key(check, "a non-empty string" if nonempty else "a string", default, **kw)


def vec3(default: Any = REQUIRED, **kw) -> Any:
    check = lambda ck, v, path, ctx: ck.vec3(v, path)  # noqa: E731
    return key(check, "[x, y, z]: 3 finite numbers", default, **kw)


def sizes3(default: Any = REQUIRED, **kw) -> Any:
    """[a, b, c]: 3 finite numbers > 0, checked with the table's other keys (so that a
    problem elsewhere in the table does not hide it)."""
    check = lambda ck, v, path, ctx: ck.sizes3(v, path)  # noqa: E731
    return key(check, "[a, b, c]: 3 numbers > 0", default, **kw)


def node(default: Any = REQUIRED, **kw) -> Any:
    """A node index or a node name of the geometry kind."""
    check = lambda ck, v, path, ctx: ck.node_ref(v, path, ctx.kind)  # noqa: E731
    return key(check, "a node index (from 0) or a node name", default, **kw)


def tables(section: type, **kw) -> Any:
    """An array of tables, each a ``section`` (``[[load.point]]``); absent: none."""

    def check(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
        items = [
            parse_table(ck, t, section, f"{path}[{k}]", ctx)
            for k, t in enumerate(ck.array_of_tables(v, path))
        ]
        return BAD if BAD in items else tuple(items)

    kw.setdefault("write", "given")
    return key(check, "an array of tables", (), section=section, **kw)


_DECLARED: dict[type, tuple[Key, ...]] = {}


def declared(section: type) -> tuple[Key, ...]:
    """The keys of a section class, in the order of its fields (the order messages list
    accepted keys in); found once per class."""
    keys = _DECLARED.get(section)
    if keys is None:
        out = []
        for f in dataclasses.fields(section):
            k = f.metadata.get("key")
            if k is not None:
                out.append(dataclasses.replace(k, name=k.name or f.name, attr=f.name))
        keys = _DECLARED[section] = tuple(out)
    return keys


def names(section: type) -> tuple[str, ...]:
    return tuple(k.name for k in declared(section))


def value(ck: Checker, tbl: Mapping, k: Key, prefix: str, ctx: Context) -> Any:
    """The checked value of one key of ``tbl``: its default when absent (a computed
    default is None until its section fills it in), BAD when required and absent."""
    path = f"{prefix}.{k.name}" if prefix else k.name
    if k.name in tbl and not (k.null and tbl[k.name] is None):
        return k.check(ck, tbl[k.name], path, ctx)
    if k.default is REQUIRED:
        ck.add(f"{path}: missing: {k.missing or k.doc or k.accepted}")
        return BAD
    return None if k.computed else k.default


def parse_keys(
    ck: Checker, tbl: Mapping, section: type, prefix: str, ctx: Context, only: Sequence = ()
) -> dict[str, Any]:
    """Every declared key of ``section`` (or ``only`` these names) checked in order, by
    attribute name; each check sees the values before it."""
    values: dict[str, Any] = {}
    here = dataclasses.replace(ctx, values=values)
    for k in declared(section):
        if not only or k.name in only:
            values[k.attr] = value(ck, tbl, k, prefix, here)
    return values


def parse_table(ck: Checker, tbl: Any, section: type, prefix: str, ctx: Context) -> Any:
    """A table of a section with no rules beyond its keys: unknown keys reported, every
    key checked; the section's instance, or BAD."""
    t = ck.table(tbl, prefix)
    if t is None:
        return BAD
    ck.keys(t, prefix, names(section))
    values = parse_keys(ck, t, section, prefix, ctx)
    return BAD if BAD in values.values() else section(**values)


def plain(v: Any) -> Any:
    """A value as plain TOML types: tuples as lists, sections as tables."""
    if isinstance(v, (tuple, list)):
        return [plain(x) for x in v]
    if isinstance(v, Declared):
        return v.to_dict()
    return v


class Declared:
    """Base of the section dataclasses: ``to_dict`` from the declared keys."""

    def to_dict(self) -> dict:
        out = {}
        for k in declared(type(self)):
            v = getattr(self, k.attr)
            if k.write == "never" or (k.write == "given" and (v is None or v == ())):
                continue
            if k.write == "changed" and v == k.default:
                continue
            out[k.name] = plain(v)
        return out
