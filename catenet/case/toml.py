"""Case files as TOML: reading (errors name the file, line and column), ``--set``
overrides of the raw table, and writing a resolved case back (with tomli-w)."""

from __future__ import annotations

import copy
import re
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import tomli_w

from catenet.case.keys import show
from catenet.case.written import WrittenFloat, mark_integers, plain, written_value
from catenet.errors import ConfigError


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


def parse_toml(raw: bytes | str, source: str, *, written: bool = False) -> dict:
    """TOML text (bytes are decoded as UTF-8) to a dict; errors name source, line and column.
    ``written``: its numbers print as written in the text (catenet/case/written.py), for
    the messages of the checks."""
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
        data = tomllib.loads(text, parse_float=WrittenFloat if written else float)
    except RecursionError:
        raise ConfigError(f"{source}: nested too deeply to be a case file") from None
    except ValueError as exc:  # tomllib.TOMLDecodeError is a ValueError
        msg = str(exc)
        m = re.match(r"(?s)(.*) \(at line (\d+), column (\d+)\)$", msg)
        if m:
            reason, line, col = m.group(1), int(m.group(2)), int(m.group(3))
        else:
            line, col = _line_col(text)
            reason = re.sub(r" \(at end of document\)$", "", msg)
        reason = reason[:1].lower() + reason[1:]
        raise ConfigError(f"{source}: line {line}, column {col}: {reason}") from None
    deep = too_deep(data)
    if deep is not None:
        raise ConfigError(
            f"{source}: {deep}: nested more than {MAX_DEPTH} levels deep: not a case file"
        )
    if written:
        mark_integers(data, text)
    return data


#: The deepest nesting of tables and arrays a case file or a --set key path may have.
MAX_DEPTH = 32


def too_deep(data: Any) -> str | None:
    """The key path (shortened) at which ``data`` nests deeper than MAX_DEPTH, else None;
    walked without recursion."""
    stack: list[tuple[Any, tuple]] = [(data, ())]
    while stack:
        value, path = stack.pop()
        if len(path) > MAX_DEPTH:
            shown = ".".join(map(str, path[:4]))
            return f"{shown}... ({len(path)}+ levels)"
        if isinstance(value, dict):
            stack.extend((v, (*path, k)) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, (*path, i)) for i, v in enumerate(value))
    return None


def _line_col(text: str) -> tuple[int, int]:
    """Line and column (both from 1) just after ``text``."""
    lines = text.split("\n")
    return len(lines), len(lines[-1]) + 1


#: An index written in brackets after a key (``obstacle[1]``) in a --set key path.
_INDEX = re.compile(r"\[\s*(\d+)\s*\](?=\.|$)")


def apply_overrides(
    data: dict, overrides: Sequence[str], *, written: bool = False, added: list | None = None
) -> dict:
    """A copy of ``data`` with every ``key.path=value`` set. The value is read as a TOML
    value (``3``, ``0.5``, ``[1, 2, 3]``, ``true``, ``"text"``), else taken as a plain
    string. A number as a path part indexes an array of tables (the next free index
    appends a table), as ``name.1`` or ``name[1]``. ``written``: numbers print as the
    text gave them (``1e12``). ``added`` collects (path, tables before) of every table an
    override appended to an array of tables (``obstacle[2]`` where the case has two)."""
    out = copy.deepcopy(dict(data))
    problems: list[str] = []
    for ov in overrides:
        if not isinstance(ov, str) or "=" not in ov:
            problems.append(f"override {ov!r}: must be key.path=value (e.g. solver.method=dynamic)")
            continue
        key, _, text = ov.partition("=")
        key = _INDEX.sub(r".\1", key.strip())  # obstacle[1].friction: obstacle.1.friction
        parts = [p.strip() for p in key.split(".")]
        if len(parts) > MAX_DEPTH:
            problems.append(
                f"override {show(ov, 60)}: key path of {len(parts)} parts: a case nests at "
                f"most {MAX_DEPTH} levels deep"
            )
            continue
        if not all(parts):
            problems.append(
                f"override {ov!r}: key path {key.strip()!r}: empty part: must be like a.b.c"
            )
            continue
        value = _override_value(text.strip(), written)
        problem = _set_path(out, parts, value, added)
        if problem:
            problems.append(f"override {ov!r}: {problem}")
    if problems:
        raise ConfigError(problems)
    return out


def _override_value(text: str, written: bool = False) -> Any:
    try:
        parsed = tomllib.loads(f"v = {text}", parse_float=WrittenFloat if written else float)
    except (ValueError, RecursionError):
        return text
    if set(parsed) != {"v"} or too_deep(parsed) is not None:
        return text
    return written_value(text, parsed["v"]) if written else parsed["v"]


def _set_path(root: dict, parts: list[str], value: Any, added: list | None = None) -> str | None:
    cur: Any = root
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        here = ".".join(parts[:depth]) or "<top>"
        if isinstance(cur, list):
            if not part.isdigit() or int(part) > len(cur):
                last_one = f"{here}[{len(cur) - 1}]" if cur else "none"
                return (
                    f"{here} is an array of {len(cur)} table{'s' if len(cur) != 1 else ''}: "
                    f"{'.'.join(parts[: depth + 1])} needs an index 0..{len(cur)} (the case's "
                    f"last is {last_one}; {here}[{len(cur)}] adds a new one)"
                )
            i = int(part)
            if i == len(cur):
                if added is not None and i > 0:  # a case's own array: one more table
                    added.append((".".join(parts[:depth]), i))
                cur.append({})
            if last:
                cur[i] = value
                return None
            if not isinstance(cur[i], (dict, list)):
                cur[i] = {}
            cur = cur[i]
            continue
        if not isinstance(cur, dict):
            return f"{here} = {show(cur)} is not a table: cannot set {'.'.join(parts)}"
        if last:
            cur[part] = value
            return None
        if part not in cur:  # a new table, or a new array of tables before an index
            cur[part] = [] if parts[depth + 1].isdigit() else {}
        cur = cur[part]
    return None


#: An array tomli-w wrote one item per line whose items hold no bracket: a flat array.
_FLAT_ARRAY = re.compile(r"\[\n((?:[ \t]+[^\[\]\n]+,\n)+)[ \t]*\]")


def dumps_toml(data: Mapping) -> str:
    """TOML text of a table of tables, arrays of tables, strings, numbers, booleans and
    (nested) arrays: enough for a resolved case. Floats are written with repr (nan and
    inf as such), so they read back bit for bit. tomli-w puts every array item on its own
    line; flat arrays that fit in a line of 100 characters are joined onto one, so a node
    reads ``[0.0, 1.5, 2.0]`` and a net of 10^4 nodes takes 10^4 lines, not 5 10^4."""
    text = tomli_w.dumps(plain(data))

    def join(match: re.Match) -> str:
        items = [line.strip().rstrip(",") for line in match.group(1).splitlines()]
        inline = "[" + ", ".join(items) + "]"
        start = text.rfind("\n", 0, match.start()) + 1
        return inline if match.start() - start + len(inline) <= 100 else match.group(0)

    return _FLAT_ARRAY.sub(join, text)
