"""Warnings of case loading: values that are valid but surely not meant (an angle in
degrees), logged once per process (a sweep parses its case for every combination)."""

from __future__ import annotations

import logging
import math

log = logging.getLogger("catenet.case")

_WARNED: set[str] = set()  # warnings of case loading given in this process (sweeps load often)


def warn_once(message: str) -> None:
    """Logs a warning about a case once per process: a sweep parses its case for every
    combination, and one warning is enough."""
    if message in _WARNED:
        return
    if len(_WARNED) < 10_000:
        _WARNED.add(message)
    log.warning("%s", message)


def angle_warning(path: str, value: float) -> str | None:
    """A message for an angle [rad] outside [0, 2 pi] (naming the radians it would be
    if it looks like degrees), else None."""
    if 0.0 <= value <= 2.0 * math.pi or not math.isfinite(value):
        return None
    text = f"{path} = {value!r}: angles are in radians and {value!r} rad is outside [0, 2 pi]"
    if abs(value) <= 360.0:
        rad = math.radians(value)
        return (
            f"{text}; it looks like degrees: {value!r} degrees is {rad:.6g} rad ({path} = {rad!r})"
        )
    return f"{text}; it is taken as {math.fmod(value, 2.0 * math.pi):.6g} rad modulo 2 pi"
