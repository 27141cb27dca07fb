"""The unit names of a case's ``units`` system (top-level ``units``: "SI", "kN-m",
"N-mm"). catenet computes in whatever consistent units the case is written in; only the
labels of what it prints, plots and reports change: kN-m reads N as kN, Pa as kPa, kg as
t and J as kJ; N-mm reads m as mm, Pa as MPa, kg as t and J as mJ (N mm). Compound
units follow from their parts (``N/m`` -> ``kN/m``, ``m/s^2`` -> ``mm/s^2``)."""

from __future__ import annotations

import re

SYSTEMS = ("SI", "kN-m", "N-mm")

#: Each system's name for an SI base name; a name not listed stays.
TOKENS: dict[str, dict[str, str]] = {
    "kN-m": {"N": "kN", "Pa": "kPa", "kg": "t", "J": "kJ"},
    "N-mm": {"m": "mm", "Pa": "MPa", "kg": "t", "J": "mJ"},
}

_UNIT = "N m|N/m|1/m|m/s\\^2|m/s|m\\^2|m|N|kg|Pa|J"
_AFTER_NUMBER = re.compile(rf"(?<=[\d\])]) ({_UNIT})(?=$|[\s,;:)(])(?! in SI)")
_BRACKETED = re.compile(r"\[([A-Za-z][A-Za-z0-9/^ ]*)\]")
_NAME = re.compile(r"[A-Za-z]+")


def system(units: object) -> str:
    """``units`` if it names a system, else "SI"."""
    return units if isinstance(units, str) and units in SYSTEMS else "SI"


def unit_in(unit: str, units: str) -> str:
    """An SI unit as written in ``units`` (``N/m`` -> ``kN/m`` in kN-m)."""
    table = TOKENS.get(units, {})
    return _NAME.sub(lambda m: table.get(m.group(0), m.group(0)), unit)


def relabel(lines: list[str], units: str) -> list[str]:
    """``lines`` with each unit name after a number or a vector (``1.5 m``, ``[0, 0, 1] m``)
    and each bracketed unit (``[N]``, ``[N/m]``) named as in ``units``; a value that says
    it is in SI (``9.81 m/s^2 in SI``) stays as it is."""
    if units not in TOKENS:
        return lines

    def after(m: re.Match) -> str:
        return " " + unit_in(m.group(1), units)

    def bracketed(m: re.Match) -> str:
        return "[" + unit_in(m.group(1), units) + "]"

    return [_BRACKETED.sub(bracketed, _AFTER_NUMBER.sub(after, line)) for line in lines]
