"""The successful rows of a square-net sweep as arrays (``load_data``), and the helpers
that group them by n, alpha and p."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ALPHA_TOL = 1e-6


@dataclass
class SweepData:
    """The successful rows of a square-net sweep, as arrays."""

    n: np.ndarray
    alpha: np.ndarray
    pressure: np.ndarray
    F_bar: np.ndarray
    delta_bar: np.ndarray
    rows: int
    failed: int
    keys: list[str]
    kind: str
    base: dict

    def select(self, mask) -> SweepData:
        return SweepData(
            self.n[mask],
            self.alpha[mask],
            self.pressure[mask],
            self.F_bar[mask],
            self.delta_bar[mask],
            int(np.count_nonzero(mask)),
            0,
            self.keys,
            self.kind,
            self.base,
        )


def _base_value(base: dict, key: str):
    cur = base
    for part in key.split("."):
        if not isinstance(cur, dict) or part not in cur:
            return None
        cur = cur[part]
    return cur


def load_data(directory: Path) -> SweepData:
    from catenet.sweep import read_journal, read_table

    keys, columns, table = read_table(directory)
    header, _ = read_journal(directory)
    base = (header or {}).get("base") or {}
    total = len(table.get("delta", []))

    def column(key: str, default=np.nan):
        if key in table:
            return np.array([_num(v) for v in table[key]], dtype=float)
        value = _base_value(base, key)
        value = default if value is None else _num(value)
        return np.full(total, value, dtype=float)

    error = table.get("error", [""] * total)
    conv = table.get("converged", [True] * total)
    ok = np.array([(not e) and bool(c) for e, c in zip(error, conv, strict=True)], dtype=bool)
    data = SweepData(
        n=column("geometry.n"),
        alpha=column("geometry.alpha"),
        pressure=column("load.pressure"),
        F_bar=column("F_bar"),
        delta_bar=column("delta_over_L"),
        rows=total,
        failed=int(np.count_nonzero(~ok)),
        keys=keys,
        kind=str(
            _base_value(base, "geometry.kind")
            or ("square_net" if "geometry.n" in keys else "unknown")
        ),
        base=base,
    )
    good = data.select(ok & np.isfinite(data.delta_bar))
    good.rows, good.failed = total, data.failed
    return good


def _num(v) -> float:
    if isinstance(v, bool):
        return float(v)
    if isinstance(v, int | float):
        return float(v)
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def unique(values: np.ndarray) -> np.ndarray:
    values = np.sort(values[np.isfinite(values)])
    if values.size == 0:
        return values
    keep = np.concatenate([[True], np.diff(values) > ALPHA_TOL])
    return values[keep]


def alpha_label(a: float) -> str:
    for num, den, text in (
        (1, 4, "π/4"),
        (1, 6, "π/6"),
        (1, 8, "π/8"),
        (1, 3, "π/3"),
        (1, 2, "π/2"),
    ):
        if abs(a - num * math.pi / den) < ALPHA_TOL:
            return f"α = {text}"
    return f"α = {a:.2f}"


def near(values: np.ndarray, target: float, tol: float = ALPHA_TOL) -> np.ndarray:
    return np.abs(values - target) <= tol * max(1.0, abs(target))
