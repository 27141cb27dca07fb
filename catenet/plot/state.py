"""Which state of a result file ``catenet plot`` draws: the final one (the default), a
load case, a combination or the envelope over them (``--case NAME``), or a stored frame
of the trajectory (``--time T``: the nearest one, ``--frame K``).

``select(res, case=, time=, frame=)`` returns the ``ResultFile`` with that state's
positions, tensions and reactions in place of the final ones, and a ``Shown`` that says
what it is (the figure's title, the colour bar, the plan view's colours, the frame marked
on the time panel). Names and values the file does not have are a ConfigError that lists
what it has.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.output.reader import ResultFile

__all__ = ["BASE", "ENVELOPE", "Shown", "select", "state_output"]

BASE = "base"  # --case base: the base state (the file's /result)
ENVELOPE = "envelope"  # --case envelope: the largest values over the cases


@dataclass(frozen=True)
class Shown:
    """What a figure draws besides the final state: ``label`` (said in the title, e.g.
    "combination ULS" or "frame 12, t = 0.36 s"), ``tension`` (the colour bar's
    quantity), ``displacement`` (N,) [m] the plan view's colours where they are not
    |x - X| (the envelope's largest displacement over the cases), ``marker`` the time or
    load factor marked on the time panel (a frame's)."""

    label: str
    tension: str = "tension"
    displacement: np.ndarray | None = None
    marker: float | None = None
    key: str = ""  # in the default file name: RESULT-<key>.png


def state_output(path: str | Path, shown: Shown) -> Path:
    """RESULT-<key>.png beside RESULT.h5 (the key made safe for a file name)."""
    path = Path(path)
    key = re.sub(r"[^A-Za-z0-9_.-]+", "_", shown.key).strip("._") or "state"
    return path.with_name(f"{path.stem}-{key}.png")


def select(
    res: ResultFile,
    *,
    case: str | None = None,
    time: float | None = None,
    frame: int | None = None,
) -> tuple[ResultFile, Shown | None, str]:
    """(the result with the chosen state in place, what it is, a note for the user: the
    frame that --time found, "" otherwise). All None: ``res`` itself."""
    given = [
        n for n, v in (("--case", case), ("--time", time), ("--frame", frame)) if v is not None
    ]
    if len(given) > 1:
        raise ConfigError(f"{' and '.join(given)}: give one of them")
    if case is not None:
        return (*_case(res, case), "")
    if time is not None:
        k, note = _nearest(res, time)
        out, shown = _frame(res, k)
        return out, shown, note
    if frame is not None:
        n = res.n_frames
        if n == 0:
            raise ConfigError(_no_frames(res, "--frame"))
        if not -n <= frame < n:
            raise ConfigError(
                f"--frame {frame}: {res.path.name} has {n} stored frames: give 0 to {n - 1} "
                f"(or -{n} to -1, counted from the end)"
            )
        return (*_frame(res, frame % n), "")
    return res, None, ""


def _no_frames(res: ResultFile, option: str) -> str:
    return (
        f"{option}: {res.path.name} stores no trajectory frames (a run without output.every "
        "frames, or a single state): plot it without " + option
    )


def _unit(res: ResultFile) -> str:
    return "pseudo-time" if res.to_rest else "t"


def _nearest(res: ResultFile, t: float) -> tuple[int, str]:
    """The stored frame nearest to time ``t`` and the note that says which it is."""
    if not math.isfinite(t):
        raise ConfigError(f"--time {t!r}: must be a finite number of seconds")
    times = res.times
    if len(times) == 0:
        raise ConfigError(_no_frames(res, "--time"))
    if res.method == "static":
        shown = ", ".join(f"{v:g}" for v in times[:12]) + (", ..." if len(times) > 12 else "")
        raise ConfigError(
            f"--time {t:g}: {res.path.name} is a static run: its {len(times)} frames are load "
            f"steps (load factors {shown}), not times: give --frame K (0 to {len(times) - 1})"
        )
    lo, hi = float(times.min()), float(times.max())
    slack = 1e-9 * max(abs(lo), abs(hi), 1e-300)
    if not lo - slack <= t <= hi + slack:
        raise ConfigError(
            f"--time {t:g}: beyond the stored frames of {res.path.name}: they span "
            f"{_unit(res)} = {lo:g} to {hi:g} s ({len(times)} frames)"
        )
    k = int(np.argmin(np.abs(times - t)))
    if abs(float(times[k]) - t) <= slack:
        return k, ""
    at = f"{_unit(res)} = {times[k]:g} s"
    return k, f"--time {t:g} s: drawn at the nearest stored frame, {k} ({at})"


def _frame(res: ResultFile, k: int) -> tuple[ResultFile, Shown]:
    """The result at trajectory frame ``k``: its positions and tensions, the reactions of
    the history's step at that time (a dynamic run keeps every step's), none otherwise."""
    f = res.frame(k)
    static = res.method == "static"
    what = "load factor" if static else _unit(res)
    label = f"frame {k}, {what} = {f.t:g}" + ("" if static else " s")
    attrs = {**res.result_attrs, "time": f.t}
    out = dataclasses.replace(
        res,
        x=f.x,
        tension=f.tension,
        reaction=_history_reaction(res, f.t),
        result_attrs=attrs,
        from_trajectory=False,
    )
    return out, Shown(label, marker=f.t, key=f"frame{k}")


def _history_reaction(res: ResultFile, t: float) -> np.ndarray | None:
    """(N, 3) the reactions of the history's step at time t (zero at free nodes); None
    where the file has no history step at that time."""
    from catenet.output.history import read_history

    hist = read_history(res.path)
    if hist is None or len(hist.time) == 0 or hist.reaction.size == 0:
        return None
    j = int(np.argmin(np.abs(hist.time - t)))
    if abs(float(hist.time[j]) - t) > 1e-9 * max(abs(t), 1.0):
        return None
    out = np.zeros((len(res.mesh.nodes), 3))
    out[np.asarray(hist.reaction_nodes, dtype=np.int64)] = hist.reaction[j]
    return out


def _case(res: ResultFile, name: str) -> tuple[ResultFile, Shown | None]:
    """The result in the load case, combination or envelope ``name``."""
    from catenet.output.states import read_states

    states = read_states(res.path)
    by_name = {s.name: s for s in states.states[1:]}
    if name in by_name:
        s = by_name[name]
        kind = "combination" if s.kind == "combination" else "load case"
        converged = s.attrs.get("converged")
        out = dataclasses.replace(
            res,
            x=s.x,
            tension=s.get("tension"),
            reaction=s.get("reaction"),
            converged=None if converged is None else bool(converged),
            series_t=None,
            series_delta=None,
            series_u=None,
            from_trajectory=False,
        )
        return out, Shown(f"{kind} {name}", key=name)
    if name == BASE:
        return res, None
    if name == ENVELOPE and states.envelope:
        env = states.envelope
        out = dataclasses.replace(
            res,
            tension=env.get("tension_max"),
            reaction=None,
            series_t=None,
            series_delta=None,
            series_u=None,
        )
        count = len(states.envelope_cases)
        shown = Shown(
            f"envelope over {count} cases, drawn on the base state",
            tension="largest tension of the cases",
            displacement=env.get("displacement_max"),
            key=ENVELOPE,
        )
        return out, shown
    accepted = [BASE, *by_name, *([ENVELOPE] if states.envelope else [])]
    if len(accepted) == 1:
        raise ConfigError(
            f"--case {name!r}: {res.path.name} holds no load case or combination (its case "
            "has no [[load_case]]): plot it without --case"
        )
    raise ConfigError(
        f"--case {name!r}: {res.path.name} has no state of that name: give one of "
        + ", ".join(accepted)
    )
