"""The sweep and its jobs: a base case, its parameters, and one job per combination of
the non-load keys, whose load levels (the product of the load keys' values) are solved
as one continuation. ``load_sweep`` and ``make_sweep`` validate every combination as a
case before anything runs."""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from catenet.errors import CatenetError, ConfigError
from catenet.sweep.params import Param, params_from_table, parse_param

log = logging.getLogger(__name__)

# catenet.model.summary.COLUMNS (not imported here: it loads NumPy; a test checks them)
SUMMARY_COLUMNS = (
    "max_displacement",
    "max_displacement_node",
    "max_tension",
    "max_tension_edge",
    "max_compression",
    "max_strain_edge",
    "max_reaction",
    "max_reaction_node",
    "reaction_resultant_x",
    "reaction_resultant_y",
    "reaction_resultant_z",
    "contact_resultant_x",
    "contact_resultant_y",
    "contact_resultant_z",
    "peak_tension",
    "peak_tension_time",
    "peak_displacement",
    "probe",
)
RESULT_COLUMNS = (
    "delta",
    "delta_over_L",
    "F_bar",
    "max_strain",
    "slack_edges",
    *SUMMARY_COLUMNS,
    "iterations",
    "wall_time",
    "converged",
    "error",
    "attempts",
    "run_file",
)
# the utilisation's columns, where a material of the sweep gives material.breaking_load
DESIGN_COLUMNS = (
    "max_utilisation",
    "max_utilisation_edge",
    "max_utilisation_cable",
    "peak_utilisation",
)
MAX_VALIDATED = 5_000  # combinations checked as cases before a sweep starts


def toml_literal(value) -> str:
    """A value as TOML text for ``apply_overrides`` (floats round-trip exactly)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_literal(v) for v in value) + "]"
    if isinstance(value, dict):
        items = (f"{json.dumps(k)} = {toml_literal(v)}" for k, v in value.items())
        return "{" + ", ".join(items) + "}"
    raise ConfigError(f"{value!r}: cannot be written as a TOML value")


def overrides(settings: Iterable[tuple[str, Any]]) -> list[str]:
    """``key=value`` texts for ``catenet.case.apply_overrides``."""
    return [f"{k}={toml_literal(v)}" for k, v in settings]


def case_api():
    """The module ``catenet.case`` (imported when a sweep is made or run)."""
    try:
        from catenet import case
    except ImportError as exc:  # pragma: no cover - during development only
        raise CatenetError(f"catenet.case is not available: {exc}") from exc
    return case


@dataclass(frozen=True)
class Job:
    """One combination of the non-load keys and its load levels (a continuation)."""

    index: int
    settings: tuple[tuple[str, Any], ...]
    levels: tuple[tuple[tuple[str, Any], ...], ...]

    @property
    def key(self) -> str:
        return json.dumps([list(s) for s in self.settings])

    def describe(self) -> str:
        return ", ".join(f"{k}={v!r}" for k, v in self.settings) or "base case"


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: the base case data (without ``[sweep]``), its parameters and jobs."""

    source: str
    base_dir: str
    base: dict
    params: tuple[Param, ...]
    base_toml: str = ""
    base_resolved: dict = field(default_factory=dict)
    modes: int = 0  # the lowest natural frequencies per row, columns f1..fK [Hz]
    load_case: str | None = None  # the [[load_case]] or [[combination]] each row reports
    design: bool = False  # a material gives breaking_load: the utilisation's columns

    @property
    def keys(self) -> list[str]:
        return [p.key for p in self.params]

    @property
    def columns(self) -> list[str]:
        design = list(DESIGN_COLUMNS) if self.design else []
        return self.keys + list(RESULT_COLUMNS) + design + mode_columns(self.modes)

    @property
    def jobs(self) -> list[Job]:
        other = [p for p in self.params if not p.is_load]
        load = [p for p in self.params if p.is_load]
        levels = tuple(
            tuple(zip([p.key for p in load], combo, strict=True))
            for combo in itertools.product(*[p.values for p in load])
        )
        return [
            Job(i, tuple(zip([p.key for p in other], combo, strict=True)), levels)
            for i, combo in enumerate(itertools.product(*[p.values for p in other]))
        ]

    @property
    def n_rows(self) -> int:
        return math.prod(len(p.values) for p in self.params)

    @property
    def fingerprint(self) -> str:
        """Identity of the sweep for resuming: the resolved base case and the parameters."""
        blob = json.dumps(
            {
                "base": self.base_resolved or self.base,
                "params": [[p.key, list(p.values)] for p in self.params],
                **({"modes": self.modes} if self.modes else {}),
                **({"load_case": self.load_case} if self.load_case else {}),
            },
            sort_keys=True,
            default=str,
        )
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def row_values(self, job: Job, level: int) -> dict:
        values = dict(job.settings)
        if job.levels:
            values.update(dict(job.levels[level]))
        return {k: values[k] for k in self.keys}


def mode_columns(count: int) -> list[str]:
    """The columns of the lowest natural frequencies: f1, f2, ... [Hz]."""
    return [f"f{k}" for k in range(1, count + 1)]


def load_sweep(
    path: str | Path,
    params: Sequence[str] = (),
    modes: int = 0,
    load_case: str | None = None,
) -> Sweep:
    """The sweep of a case file: its ``[sweep]`` table (``key.path = [values]``), if any,
    with the ``params`` (``"key.path=v1,v2"``) added; a key given in both takes the
    command line's values. Every combination is validated as a case (ConfigError listing
    the problems) before anything runs. ``modes`` K > 0: every row also gets the K
    lowest natural frequencies about its equilibrium (columns f1..fK [Hz]).
    ``load_case``: each row reports that load case or combination of the case, solved
    from the row's base state."""
    from catenet.case import parse_toml, read_case_bytes

    path = Path(path)
    data = parse_toml(read_case_bytes(path), str(path))
    table = data.pop("sweep", None)
    merged: dict[str, Param] = {}
    if table is not None:
        if not isinstance(table, dict):
            raise ConfigError(f"{path}: sweep = {table!r}: must be a table of key.path = [values]")
        for p in params_from_table(table):
            merged[p.key] = p
    seen: set[str] = set()
    for text in params:
        p = parse_param(text)
        if p.key in seen:
            raise ConfigError(f"--param {text}: {p.key} is given twice")
        seen.add(p.key)
        merged[p.key] = p
    return make_sweep(
        data,
        list(merged.values()),
        source=str(path),
        base_dir=path.parent,
        modes=modes,
        load_case=load_case,
    )


def make_sweep(
    base: dict,
    params: Sequence[Param],
    *,
    source: str = "<dict>",
    base_dir: Path | str = ".",
    modes: int = 0,
    load_case: str | None = None,
) -> Sweep:
    """A sweep from base case data (a dict as read from TOML) and parameters; validates
    the base case and every combination with ``catenet.case.parse_case``; ``modes``: see
    ``load_sweep``."""
    if isinstance(modes, bool) or not isinstance(modes, int) or modes < 0:
        raise ConfigError(f"--modes = {modes!r}: must be an integer >= 0")
    if not params:
        raise ConfigError(
            "no parameters to sweep: give --param key.path=v1,v2,... or a [sweep] table "
            "in the case file"
        )
    keys = [p.key for p in params]
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise ConfigError(f"parameters: {', '.join(dup)} given more than once")
    case = case_api()
    base_dir = Path(base_dir)
    base_case = case.parse_case(base, source=source, base_dir=base_dir)
    from catenet.run.runner import refuse_formfind

    refuse_formfind(base_case)
    if load_case is not None:
        names = [c.name for c in (*base_case.load_cases, *base_case.combinations)]
        if load_case not in names:
            listed = ", ".join(map(repr, names)) or "none"
            raise ConfigError(
                f"--case {load_case!r}: no [[load_case]] or [[combination]] is named so "
                f"(the case has: {listed})"
            )
    sweep = Sweep(
        source=source,
        base_dir=str(base_dir.resolve()),
        base=base,
        params=tuple(params),
        base_toml=base_case.to_toml(),
        base_resolved=base_case.to_dict(),
        modes=modes,
        load_case=load_case,
        design=_breaking_load(base_case.to_dict()) or any(_breaking_load(p.key) for p in params),
    )
    problems: list[str] = []
    for param in params:  # each value on its own first: one message per bad value
        for value in param.values:
            _validate(case, base, [(param.key, value)], source, base_dir, problems)
    if not problems:  # then the combinations (a few ms each: the first MAX_VALIDATED)
        combos = (
            list(job.settings) + list(level)
            for job in sweep.jobs
            for level in (job.levels or ((),))
        )
        for settings in itertools.islice(combos, MAX_VALIDATED):
            _validate(case, base, settings, source, base_dir, problems)
            if len(problems) >= 20:
                break
        if sweep.n_rows > MAX_VALIDATED:
            log.info("validated the first %d of %d combinations", MAX_VALIDATED, sweep.n_rows)
    if problems:
        raise ConfigError(problems)
    return sweep


def _validate(case, base, settings, source, base_dir, problems) -> None:
    try:
        data = case.apply_overrides(base, overrides(settings), written=True)
        case.parse_case(data, source=source, base_dir=base_dir)
    except ConfigError as exc:
        where = ", ".join(f"{k}={toml_literal(v)}" for k, v in settings)
        for line in exc.problems:
            msg = f"--param {where}: {line}" if len(settings) == 1 else f"[{where}] {line}"
            if msg not in problems:
                problems.append(msg)


def _breaking_load(data: Any) -> bool:
    """Whether a resolved case (or a swept key's path) gives a material.breaking_load."""
    if isinstance(data, str):
        return data.endswith("breaking_load")
    if isinstance(data, dict):
        if data.get("breaking_load") is not None:
            return True
        return any(_breaking_load(v) for v in data.values() if isinstance(v, dict | list))
    if isinstance(data, list):
        return any(_breaking_load(v) for v in data if isinstance(v, dict | list))
    return False
