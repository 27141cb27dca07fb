"""A vessel's rigid motion carrying several supports at once, ``[[supports.vessel]]``
(``catenet.model.motions.Vessel``): its keys, their rules and its model.

```toml
[[supports.vessel]]
nodes = "fairleads"            # the supports it carries (fixed nodes)
reference = [0.0, 0.0, 0.0]    # the point its rotations are about [m]
motion = [[0.0, 0, 0, 0, 0, 0, 0], [60.0, 20.0, 0, 0, 0, 0, 5.0]]  # t, surge, sway,
                               # heave [m], roll, pitch, yaw [deg]
[[supports.vessel.sine]]
amplitude = [5.0, 0, 1.0, 0, 2.0, 0]   # surge, sway, heave [m], roll, pitch, yaw [deg]
period = 12.0
phase = [0, 0, 90.0, 0, 90.0, 0]       # [deg]: one for all, or one per motion
```
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import BAD, Checker, Context, Declared, key, real, tables, vec3
from catenet.case.supports import NodeRef, _guide_nodes
from catenet.model.limits import carried
from catenet.model.motions import DOFS, Vessel

SIX = "[surge, sway, heave, roll, pitch, yaw]: six finite numbers [m, m, m, deg, deg, deg]"
MOTION = (
    "[[t, surge, sway, heave, roll, pitch, yaw], ...]: rows of seven finite numbers "
    "[s, m, m, m, deg, deg, deg], times strictly increasing"
)
MAX_ANGLE = 180.0  # deg: a motion's largest angle (beyond, the angle is ambiguous)


def _number(v: Any) -> float | None:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    f = float(v)
    return f if carried(f) else None


def _six(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """Six motions (three lengths, three angles within +-MAX_ANGLE deg)."""
    vals = [_number(a) for a in v] if isinstance(v, (list, tuple)) and len(v) == 6 else None
    if vals is None or None in vals:
        return ck.bad(path, v, f"must be {SIX}")
    return _angles(ck, tuple(vals), path, v)


def _angles(ck: Checker, vals: tuple, path: str, shown: Any) -> Any:
    big = [DOFS[3 + k] for k, a in enumerate(vals[3:]) if abs(a) > MAX_ANGLE]
    if big:
        return ck.bad(path, shown, f"{big[0]} beyond +-{MAX_ANGLE:g} deg")
    return vals


def _phase(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """One phase for all six motions or one each [deg]."""
    one = _number(v)
    if one is not None:
        return (one,) * 6
    vals = [_number(a) for a in v] if isinstance(v, (list, tuple)) and len(v) == 6 else None
    if vals is None or None in vals:
        return ck.bad(path, v, "must be a phase [deg] or six of them (one per motion)")
    return tuple(vals)


def _motion(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A motion table: rows (t, six motions), times strictly increasing."""
    if not isinstance(v, (list, tuple)) or not v:
        return ck.bad(path, v, f"must be {MOTION}")
    rows: list[tuple[float, ...]] = []
    for k, row in enumerate(v):
        got = [_number(a) for a in row] if isinstance(row, (list, tuple)) else [None]
        vals = [a for a in got if a is not None]
        if len(vals) != 7 or len(got) != 7:
            return ck.bad(f"{path}[{k}]", row, f"must be [t, {SIX[1:]}")
        if rows and not vals[0] > rows[-1][0]:
            return ck.bad(f"{path}[{k}]", row, f"t = {vals[0]:g} does not follow the row before")
        if _angles(ck, tuple(vals[1:]), f"{path}[{k}]", row) is BAD:
            return BAD
        rows.append(tuple(vals))
    return tuple(rows)


@dataclass(frozen=True)
class VesselSineConfig(Declared):
    """One frequency of a vessel's motion: six amplitudes and phases at one period."""

    amplitude: tuple = key(_six, SIX, missing=SIX, unit="m, deg", doc="the six amplitudes")
    period: float = real(gt=0, missing="its period [s]", unit="s", doc="its period")
    phase: tuple = key(
        _phase,
        "a phase or six (one per motion)",
        (0.0,) * 6,
        write="given",
        unit="deg",
        shown="0",
        doc="its phase at t = 0: a sin(2 pi t / period + phase)",
    )


@dataclass(frozen=True)
class VesselConfig(Declared):
    """A vessel whose rigid motion (surge, sway, heave, roll, pitch, yaw about
    ``reference``) carries the supports ``nodes`` (dynamic runs; static: at t = 0)."""

    nodes: tuple[NodeRef, ...] = _guide_nodes("the vessel carries (fixed nodes)")
    reference: tuple = vec3(
        (0.0, 0.0, 0.0), unit="m", doc="the point its rotations are about, in the given geometry"
    )
    heading: float = real(
        0.0, unit="deg", doc="its surge axis, from +x toward +y (0: surge along +x)"
    )
    motion: tuple | None = key(
        _motion,
        MOTION,
        None,
        write="given",
        shown="none",
        unit="s, m, deg",
        doc="the six motions against time, linear between the rows (added to the sines)",
    )
    sines: tuple[VesselSineConfig, ...] = tables(
        VesselSineConfig, name="sine", doc="sinusoidal motions, added together"
    )
    ramp: float | None = real(
        None,
        ge=0,
        write="given",
        unit="s",
        shown="the longest sine's period; a motion table alone: a tenth of its time span",
        doc="smooth start over this time: every motion times (1 - cos(pi t / ramp)) / 2 (0: none)",
    )


def check_vessel(ck: Checker, vessel: VesselConfig, path: str) -> None:
    """A [[supports.vessel]] moves by a motion table, sines, or both."""
    if vessel.motion is None and not vessel.sines:
        ck.add(f"{path}: missing: give motion = [[t, surge, ..., yaw], ...] or [[{path}.sine]]")


def default_ramp(config: VesselConfig) -> float:
    """The ramp a vessel takes where its table does not give one."""
    if config.ramp is not None:
        return config.ramp
    if config.sines:
        return max(s.period for s in config.sines)
    assert config.motion is not None  # check_vessel
    return 0.1 * (config.motion[-1][0] - config.motion[0][0])


def vessel_model(config: VesselConfig) -> Vessel:
    """The ``catenet.model.motions.Vessel`` of a [[supports.vessel]] table."""
    table = None
    if config.motion is not None:
        table = np.array(config.motion, dtype=np.float64)
        table[:, 4:] = np.radians(table[:, 4:])
    sines = [
        [s.period, *s.amplitude[:3], *np.radians(s.amplitude[3:]), *np.radians(s.phase)]
        for s in config.sines
    ]
    return Vessel(
        config.reference, math.radians(config.heading), table, sines, default_ramp(config)
    )
