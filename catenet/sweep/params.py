"""Sweep parameters: a key path and its values, from the command line or a ``[sweep]`` table.

A value is a TOML scalar (``10``, ``0.5``, ``true``, ``"text"``, ``[0, 0, -9.81]``), an
arithmetic expression of ``pi`` (``pi/4``, ``radians(30)``), an inclusive range
``start:step:stop`` or a bare word (``scipy``).
"""

from __future__ import annotations

import ast
import math
import operator
import tomllib
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from typing import Any

from catenet.case.written import WrittenFloat
from catenet.errors import ConfigError

LOAD_PREFIX = "load."
MAX_VALUES = 100_000


def _power(a, b):
    """a ** b, in floating point unless both are integers with a result of at most
    MAX_BITS bits (so that ``9**9**9`` is an overflow, not hours of big-integer work)."""
    if type(a) is int and type(b) is int and b >= 0:
        if a in (0, 1, -1) or b * math.log2(abs(a)) <= MAX_BITS:
            return a**b
    return math.pow(a, b)


MAX_BITS = 1024  # the largest integer an expression makes (about 1e308)

_OPS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: _power,
    ast.USub: operator.neg,
    ast.UAdd: operator.pos,
}
_NAMES = {"pi": math.pi, "e": math.e, "tau": math.tau}
_FUNCS = {
    "sqrt": math.sqrt,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "radians": math.radians,
    "degrees": math.degrees,
}


def evaluate(text: str) -> float | int:
    """An arithmetic expression of numbers, ``pi``, ``e``, ``tau``, ``+ - * / **`` and
    ``sqrt sin cos tan radians degrees`` (``pi/4``, ``2*pi/3``, ``radians(30)``).
    Raises ValueError when ``text`` is not such an expression."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"not an expression: {text!r}") from exc

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return node.value
        if isinstance(node, ast.Name) and node.id in _NAMES:
            return _NAMES[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.operand))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _FUNCS
            and len(node.args) == 1
            and not node.keywords
        ):
            return _FUNCS[node.func.id](ev(node.args[0]))
        raise ValueError(f"not an expression of numbers and pi: {text!r}")

    try:
        value = ev(tree)
        finite = not isinstance(value, complex) and math.isfinite(value)
    except (ZeroDivisionError, OverflowError, ValueError, RecursionError, MemoryError) as exc:
        reason = str(exc) or type(exc).__name__
        raise ValueError(f"{text!r}: {reason}") from None
    if not finite:
        raise ValueError(f"{text!r}: not a finite real number")
    return value


def _toml_scalar(text: str):
    """``text`` read as a TOML value (a float keeps its text for messages: ``-1e0``, not
    ``-1.0``); raises ValueError when it is not one."""
    try:
        value = tomllib.loads(f"v = {text}", parse_float=WrittenFloat)["v"]
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(str(exc)) from exc
    if _has_datetime(value):
        raise ValueError(f"{text!r}: dates and times are not parameter values")
    return value


def _show(value) -> str:
    """A value as the user wrote it in TOML (dates in ISO form)."""
    import datetime as dt

    if isinstance(value, (dt.date, dt.time, dt.datetime)):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    return repr(value)


def _has_datetime(value) -> bool:
    import datetime as dt

    if isinstance(value, (dt.date, dt.time, dt.datetime)):
        return True
    if isinstance(value, list):
        return any(_has_datetime(v) for v in value)
    if isinstance(value, dict):
        return any(_has_datetime(v) for v in value.values())
    return False


def _number(text: str):
    """A number from a TOML literal or an expression; ValueError otherwise."""
    try:
        value = _toml_scalar(text)
    except ValueError:
        return evaluate(text)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{text!r}: not a number")
    return value


def _decimal(text: str) -> Decimal | None:
    try:
        return Decimal(text.strip().replace("_", ""))
    except InvalidOperation:
        return None


def expand_range(text: str) -> list:
    """``start:step:stop``, inclusive of ``stop`` when the steps land on it (within
    1e-9 of a step): ``0:0.25:0.75`` -> [0.0, 0.25, 0.5, 0.75], ``10:8:34`` ->
    [10, 18, 26, 34], ``0:pi/8:pi/4``. Integers stay integers; decimal literals are
    stepped exactly (no 0.30000000000000004)."""
    parts = text.split(":")
    if len(parts) != 3 or not all(p.strip() for p in parts):
        raise ValueError(f"{text!r}: a range is start:step:stop (e.g. 0:0.25:0.75)")
    try:
        start, step, stop = (_number(p) for p in parts)
    except ValueError as exc:
        raise ValueError(f"{text!r}: a range is start:step:stop of numbers ({exc})") from None
    try:
        finite = all(math.isfinite(v) for v in (start, step, stop))
    except OverflowError:  # an integer beyond floating point
        finite = False
    if not finite:
        raise ValueError(f"{text!r}: start, step and stop must be finite numbers")
    if step == 0:
        raise ValueError(f"{text!r}: the step must not be 0")
    span = (stop - start) / step
    if not math.isfinite(span):
        raise ValueError(f"{text!r}: more than {MAX_VALUES} values")
    if span < -1e-9:
        raise ValueError(f"{text!r}: the step goes away from stop (check its sign)")
    count = math.floor(span + 1e-9) + 1
    if count > MAX_VALUES:
        shown = f"{count}" if count < 10**9 else f"about {float(count):.3g}"
        raise ValueError(f"{text!r}: {shown} values: at most {MAX_VALUES}")
    if all(type(v) is int for v in (start, step, stop)):
        return [start + k * step for k in range(count)]
    decimals = [d for d in map(_decimal, parts) if d is not None and d.is_finite()]
    if len(decimals) == len(parts):
        d0, ds, _ = decimals
        return [float(d0 + k * ds) for k in range(count)]
    values = [float(start + k * step) for k in range(count)]
    if abs(values[-1] - stop) <= 1e-9 * abs(step):
        values[-1] = float(stop)
    return values


def _split_top(text: str) -> list[str]:
    """Split at commas outside brackets, braces, parentheses and quotes."""
    items, depth, quote, cur = [], 0, "", []
    for ch in text:
        if quote:
            cur.append(ch)
            if ch == quote:
                quote = ""
            continue
        if ch in "\"'":
            quote = ch
        elif ch in "[{(":
            depth += 1
        elif ch in "]})":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    items.append("".join(cur))
    return items


def parse_value(text: str) -> list:
    """One item of a value list: a list of one value, or of many for a range.

    In order: a TOML value (``10``, ``0.5``, ``true``, ``"text"``, ``[0, 0, -9.81]``);
    a range ``start:step:stop``; an expression such as ``pi/4``; a bare word (a string,
    as in ``solver.linear=scipy``). Raises ValueError otherwise."""
    item = text.strip()
    if not item:
        raise ValueError("empty value (two commas in a row, or a comma at the end?)")
    try:
        return [_toml_scalar(item)]
    except ValueError:
        pass
    if ":" in item:
        return expand_range(item)
    try:
        return [evaluate(item)]
    except ValueError:
        pass
    if item.replace("-", "_").isidentifier():
        return [item]
    raise ValueError(
        f"{item!r}: not a number, a range start:step:stop, an expression of pi, "
        "a TOML value or a word"
    )


@dataclass(frozen=True)
class Param:
    """A swept key and its values (TOML types)."""

    key: str
    values: tuple

    @property
    def is_load(self) -> bool:
        return self.key.startswith(LOAD_PREFIX)


def _check_key(key: str, where: str) -> str:
    key = key.strip()
    parts = key.split(".")
    if not key or not all(p.strip() and p == p.strip() for p in parts) or len(parts) < 2:
        raise ConfigError(
            f"{where}: key {key!r}: must be a key path such as geometry.n or load.pressure"
        )
    return key


def parse_param(text: str) -> Param:
    """``key.path=v1,v2,...`` (each item a value or a range; see ``parse_value``)."""
    where = f"--param {text}"
    if "=" not in text:
        raise ConfigError(f"{where}: must be key.path=v1,v2,... (e.g. geometry.n=10,18)")
    key, _, rest = text.partition("=")
    key = _check_key(key, where)
    if not rest.strip():
        raise ConfigError(f"{where}: no values after '='")
    values: list = []
    for item in _split_top(rest):
        try:
            values.extend(parse_value(item))
        except ValueError as exc:
            raise ConfigError(f"{where}: {exc}") from None
    return Param(key, tuple(values))


def params_from_table(table: dict) -> list[Param]:
    """The parameters of the ``[sweep]`` table of a case file: each key path's list of
    values (strings in it may be expressions or ranges: ``"pi/4"``, ``"0:0.25:0.75"``)
    or one string as on the command line (``"10, 18, 22"``)."""
    return [_param_from_table(key, raw) for key, raw in _flatten(table)]


def _param_from_table(key: str, raw) -> Param:
    where = f"sweep.{key}"
    if isinstance(raw, str):
        return parse_param(f"{key}={raw}")
    if not isinstance(raw, list) or not raw:
        raise ConfigError(f"{where} = {raw!r}: must be a non-empty list of values")
    values: list = []
    for item in raw:
        if _has_datetime(item):
            raise ConfigError(f"{where}: {_show(item)}: dates and times are not parameter values")
        if isinstance(item, str):
            try:
                values.extend(_string_item(item))
            except ValueError as exc:
                raise ConfigError(f"{where}: {exc}") from None
        else:
            values.append(item)
    return Param(key, tuple(values))


def _string_item(item: str) -> list:
    text = item.strip()
    if ":" in text:
        return expand_range(text)
    try:
        return [evaluate(text)]
    except ValueError:
        return [item]


def _flatten(table: dict, prefix: str = "") -> list[tuple[str, Any]]:
    out = []
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.extend(_flatten(v, key + "."))
        else:
            out.append((key, v))
    return out
