"""A sinusoidal support motion, ``[[supports.move]]`` ``sine = { ... }``: its keys and the
rules between a move's keys (``check_move``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from catenet.case.keys import Checker, Context, Declared, parse_table, real, vec3

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class SineConfig(Declared):
    """A sinusoidal support motion, amplitude r(t) sin(2 pi t / period + phase)."""

    amplitude: Vec3 = vec3(missing="[dx, dy, dz] [m]", unit="m", doc="its amplitude")
    period: float = real(gt=0, missing="its period [s]", unit="s", doc="its period")
    phase: float = real(0.0, unit="deg", doc="its phase at t = 0")
    ramp: float | None = real(
        None, ge=0, write="given", unit="s", doc="smooth start over this time (default: a period)"
    )


SINE = "a table { amplitude = [dx, dy, dz], period = T, phase = deg, ramp = s }"


def check_sine(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    return parse_table(ck, v, SineConfig, path, ctx)


def check_move(ck: Checker, mv: Any, path: str) -> None:
    """A move gives displacement or sine (one of them); a sine takes no history."""
    if mv.sine is None and mv.displacement is None:
        ck.add(f"{path}: missing: give displacement = [dx, dy, dz] or sine = {{ ... }}")
    elif mv.sine is not None and mv.displacement is not None:
        ck.add(f"{path}.sine: give displacement (with duration or history) or sine, not both")
    elif mv.sine is not None and (mv.history is not None or mv.duration > 0):
        ck.add(f"{path}.sine: a sine motion takes no history or duration (it has its ramp)")
