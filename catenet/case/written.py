"""Numbers as the user wrote them: a case file's floats (``1e12``, ``1_000.5``, ``+inf``)
and integers (``0x10``, ``1_000``) and ``--set`` values keep their source text, so that a
message quoting one shows it as written, not as Python prints the number
(``1000000000000.0``). They are a ``float`` and an ``int`` in every other respect; the
checks keep a float's text in the case's settings (``catenet.case.guard`` quotes them
after parsing) and give plain integers; the resolved case (``Case.to_dict``, the TOML in a
result file) holds plain numbers only (``plain``).

tomllib gives a float's text to ``parse_float``; an integer's text is found again by
scanning the ``key = integer`` lines of the source (an integer inside an array or an
inline table keeps Python's spelling)."""

from __future__ import annotations

import re
from typing import Any


class WrittenFloat(float):
    """A float that prints as its source text."""

    text: str

    def __new__(cls, text: str, value: float | None = None) -> WrittenFloat:
        self = super().__new__(cls, float(text) if value is None else value)
        self.text = text
        return self

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__

    def __reduce__(self):
        return (WrittenFloat, (self.text, float(self)))


class WrittenInt(int):
    """An int that prints as its source text."""

    text: str

    def __new__(cls, value: int, text: str) -> WrittenInt:
        self = super().__new__(cls, value)
        self.text = text
        return self

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__

    def __reduce__(self):
        return (WrittenInt, (int(self), self.text))


def as_written_float(v: WrittenFloat | WrittenInt) -> WrittenFloat:
    """A written number as a float that keeps its text."""
    return v if isinstance(v, WrittenFloat) else WrittenFloat(v.text, float(v))


def plain(data: Any) -> Any:
    """``data`` (nested dicts, lists, tuples) with every written number a plain one."""
    if isinstance(data, WrittenFloat):
        return float(data)
    if isinstance(data, WrittenInt):
        return int(data)
    if isinstance(data, dict):
        return {k: plain(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return type(data)(plain(v) for v in data)
    return data


def written_value(text: str, value: Any) -> Any:
    """``value`` (parsed from the TOML value ``text``) with its text when it is an integer
    spelt otherwise than Python prints it (a float keeps its own already)."""
    if type(value) is int and text != str(value):
        return WrittenInt(value, text)
    return value


_PART = r"""(?:[A-Za-z0-9_-]+|"[^"\\]*"|'[^']*')"""
_KEY = rf"{_PART}(?:\s*\.\s*{_PART})*"
_HEADER = rf"^\s*(\[\[?)\s*({_KEY})\s*\]\]?\s*(?:#.*)?$"
_INT = r"[+-]?(?:0x[0-9A-Fa-f_]+|0o[0-7_]+|0b[01_]+|[0-9_]+)"
_INT_LINE = rf"^\s*({_KEY})\s*=\s*({_INT})\s*(?:#.*)?$"


def _parts(key: str) -> tuple[str, ...]:
    return tuple(p.strip("\"'") for p in re.findall(_PART, key))


def mark_integers(data: dict, text: str) -> None:
    """Give the integers of ``key = integer`` lines of the TOML source ``text`` (parsed
    into ``data``) their source text where it differs from Python's."""
    if re.search(r"=\s*(?:\+|[+-]?0[xob]|[+-]?\d+_)", text) is None:
        return  # no integer spelt otherwise (the common case: no scan)
    table: tuple[str, ...] = ()
    index: dict[tuple, int] = {}  # the current item of each array of tables
    for line in text.splitlines():
        header = re.match(_HEADER, line)  # (re caches the compiled patterns)
        if header:
            table = _parts(header.group(2))
            if header.group(1) == "[[":
                index[table] = index.get(table, -1) + 1
                for k in [k for k in index if k[: len(table)] == table and k != table]:
                    del index[k]  # a new item: its own arrays of tables start again
            continue
        m = re.match(_INT_LINE, line)
        if m is None:
            continue
        literal = m.group(2)
        if literal.lstrip("+-").isdigit() and not literal.startswith("+"):
            continue  # as Python prints it
        _mark(data, (*table, *_parts(m.group(1))), literal, index)


def _mark(data: dict, path: tuple, literal: str, index: dict) -> None:
    cur: Any = data
    for i, part in enumerate(path[:-1]):
        if not isinstance(cur, dict) or part not in cur:
            return
        cur = cur[part]
        if isinstance(cur, list):
            k = index.get(path[: i + 1], len(cur) - 1)
            if not (isinstance(k, int) and 0 <= k < len(cur)):
                return
            cur = cur[k]
    last = path[-1]
    if isinstance(cur, dict) and type(cur.get(last)) is int:
        try:
            value = int(literal.replace("_", ""), 0)
        except ValueError:
            return
        if value == cur[last]:
            cur[last] = WrittenInt(value, literal)
