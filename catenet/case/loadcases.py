"""Load cases and combinations: ``[[load_case]]`` (a name and any keys ``[load]`` takes)
and ``[[combination]]`` (a name and ``factors = { case = factor, ... }``).

The base ``[load]`` (prestress, self-weight) is solved once; each load case and each
combination is then solved from that base state under the base loads plus its own (a
combination's: the sum of its cases' loads times their factors), in ``solver.steps`` load
steps of its own part: a nonlinear analysis, not a superposition (``catenet.run.cases``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from catenet.case.keys import BAD, Checker, Context, Declared, as_float, key, parse_table, show
from catenet.case.sections import LoadConfig, SolverConfig

#: A name usable as an HDF5 group (/cases/<name>) and a file name part.
NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+-]*$")
NAME_NEED = "must be a name of letters, digits and _ . + - (it names the group /cases/<name>)"


def _name(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    s = ck.string(v, path, nonempty=True)
    if s is BAD:
        return BAD
    if not NAME.match(s) or s in (".", ".."):
        return ck.bad(path, v, NAME_NEED)
    return s


@dataclass(frozen=True, kw_only=True)
class LoadCaseConfig(LoadConfig):
    """A load case: its name and the loads it adds to the base ``[load]`` (every key of
    ``[load]``: point loads, line loads, gravity, pressure)."""

    name: str = key(
        _name,
        "a name: letters, digits, _ . + -",
        missing="the case's name",
        doc="the case's name: its results are in /cases/<name>",
    )

    def to_dict(self) -> dict:
        out = {"name": self.name, **{k: v for k, v in super().to_dict().items() if k != "name"}}
        if out.get("pressure") == 0.0:
            out.pop("pressure")
        return out


def _factors(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A non-empty table of load case names and finite factors."""
    t = ck.table(v, path)
    if t is None:
        return BAD
    if not t:
        return ck.bad(path, v, "must name at least one load case: { case_name = factor }")
    out = {}
    for name, f in t.items():
        x = as_float(f)
        if x is None or not math.isfinite(x):
            ck.bad(f"{path}.{name}", f, "must be a finite number (the load case's factor)")
            return BAD
        out[str(name)] = x
    return out


@dataclass(frozen=True)
class CombinationConfig(Declared):
    """A combination of load cases: the sum of their loads times their factors, solved
    from the base state as a load case of its own."""

    name: str = key(
        _name,
        "a name: letters, digits, _ . + -",
        missing="the combination's name",
        doc="the combination's name: its results are in /cases/<name>",
    )
    factors: dict = key(
        _factors,
        "a table: load case name = factor",
        missing="{ case_name = factor, ... }",
        doc="the load cases it combines and their factors",
    )


def parse_load_cases(ck: Checker, value: Any, ctx: Context) -> tuple | Any:
    """The ``[[load_case]]`` array of tables (absent: none), names unique."""
    if value is None:
        return ()
    out = []
    for k, t in enumerate(ck.array_of_tables(value, "load_case")):
        path = f"load_case[{k}]"
        lc = parse_table(ck, t, LoadCaseConfig, path, ctx)
        out.append(lc)
        if lc is BAD:
            continue
        timed = [(path, lc.history)]
        timed += [(f"{path}.point[{j}]", p.history) for j, p in enumerate(lc.points)]
        timed += [(f"{path}.line[{j}]", p.history) for j, p in enumerate(lc.lines)]
        timed += [(f"{path}.area[{j}]", a.history) for j, a in enumerate(lc.areas)]
        for where, history in timed:
            if history is not None:
                ck.add(
                    f"{where}.history: a load case is a static analysis from the base state: "
                    "its loads take no history (give time histories in [load])"
                )
                out[-1] = BAD
    _unique(ck, out, "load_case", {})
    return BAD if BAD in out else tuple(out)


def parse_combinations(ck: Checker, value: Any, ctx: Context, cases: Any) -> tuple | Any:
    """The ``[[combination]]`` array of tables: names unique (among the load cases too),
    every factor naming a load case."""
    if value is None:
        return ()
    out = []
    known = [c.name for c in cases if c is not BAD] if isinstance(cases, tuple) else None
    for k, t in enumerate(ck.array_of_tables(value, "combination")):
        path = f"combination[{k}]"
        combo = parse_table(ck, t, CombinationConfig, path, ctx)
        out.append(combo)
        if combo is BAD or known is None:
            continue
        for name, f in combo.factors.items():
            if name not in known:
                listed = ", ".join(map(repr, known)) if known else "none"
                nested = any(isinstance(t, Mapping) and t.get("name") == name for t in value)
                why = " (a combination: combinations combine load cases, not combinations)"
                ck.add(
                    f"{path}.factors.{name} = {show(f)}: no [[load_case]] is named {name!r}"
                    f"{why if nested else ''} (the load cases: {listed})"
                )
                out[-1] = BAD
    if isinstance(cases, tuple):
        _unique(ck, out, "combination", {c.name: f"load_case[{j}]" for j, c in enumerate(cases)})
    return BAD if BAD in out else tuple(out)


def _unique(ck: Checker, items: list, what: str, taken: Mapping[str, str]) -> None:
    """A problem for each name given before (in ``taken`` or an earlier item)."""
    seen = dict(taken)
    for k, item in enumerate(items):
        if item is BAD:
            continue
        path = f"{what}[{k}].name"
        if item.name in seen:
            ck.add(f"{path} = {item.name!r}: already names {seen[item.name]}: give each its own")
            items[k] = BAD
        else:
            seen[item.name] = f"{what}[{k}]"


def check_method(ck: Checker, cases: Any, combos: Any, solver: Any, density: Any) -> None:
    """Load cases are static analyses from the base state; gravity in one needs mass."""
    dynamic = isinstance(solver, SolverConfig) and solver.method == "dynamic"
    if (cases or combos) and dynamic:
        ck.add(
            "solver.method = 'dynamic': [[load_case]] and [[combination]] are static "
            "analyses from the base state: set solver.method = 'static'"
        )
    for k, lc in enumerate(cases if isinstance(cases, tuple) else ()):
        if lc.gravity is not None and any(g != 0.0 for g in lc.gravity) and density == 0:
            ck.add(  # ([0, 0, 0] is no load: it needs no mass)
                f"load_case[{k}].gravity = {show(lc.gravity)}: gravity needs mass: set "
                "material.density > 0 (with material.radius or material.area)"
            )


__all__ = [
    "CombinationConfig",
    "LoadCaseConfig",
    "check_method",
    "parse_combinations",
    "parse_load_cases",
]
