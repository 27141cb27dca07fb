"""What a dynamic run at fixed steps is told about its histories before it runs: a load's or
a motion's history is taken at the ends of the steps only (its factor at t + h), so a
piece of it shorter than a step can fall between two step ends and be stepped over whole.
A 20 ms force pulse on a hanging 10 kg weight, at fixed 50 ms steps: the weight never
moved and the run ended "converged". Steps chosen by accuracy land on every point of a
history (catenet/solver/adaptive.py, ``corners``) and are not warned. A sine motion
(a support's, a vessel's) is warned below PER_PERIOD fixed steps a period: its motion is
sampled, not resolved (at two steps a period a sine is not there at all)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from catenet.case.parse import Case

#: The fewest fixed steps a period of a prescribed sine motion is taken in unwarned.
PER_PERIOD = 10


def histories(case: Case) -> list[tuple[str, np.ndarray]]:
    """Every history of a case with its key path and the times of its points: the loads'
    and load cases', the supports' moves and twists, the vessels' motion tables and the
    obstacles' prescribed motions."""
    from catenet.case.timing import load_histories

    out: list[tuple[str, Any]] = [(f"{p}.history", h) for p, h in load_histories(case.load)]
    for k, load_case in enumerate(case.load_cases):
        out.extend((f"{p}.history", h) for p, h in load_histories(load_case, f"load_case[{k}]"))
    supports = case.supports
    out.extend((f"supports.move[{k}].history", m.history) for k, m in enumerate(supports.moves))
    out.extend((f"supports.twist[{k}].history", t.history) for k, t in enumerate(supports.twists))
    out.extend((f"supports.vessel[{k}].motion", v.motion) for k, v in enumerate(supports.vessels))
    out.extend(
        (f"obstacle[{k}].history", getattr(o, "history", None))
        for k, o in enumerate(case.obstacles)
    )
    return [
        (path, np.asarray([row[0] for row in points], dtype=np.float64))
        for path, points in out
        if points
    ]


def stepped_over(case: Case) -> list[str]:
    """Messages for the histories of a dynamic run at fixed steps (no ``solver.tolerance``)
    with a piece between two points, within the run, shorter than ``solver.dt``."""
    solver = case.solver
    if solver.method != "dynamic" or solver.tolerance is not None or not solver.dt:
        return []
    dt = float(solver.dt)
    t_end = solver.t_end if isinstance(solver.t_end, (int, float)) else np.inf
    out = _sines(case, dt)
    for path, times in histories(case):
        pieces = np.diff(times)
        inside = (times[1:] > 0.0) & (times[:-1] < t_end)
        short = np.flatnonzero(inside & (pieces < dt))
        if not len(short):
            continue
        k = int(short[np.argmin(pieces[short])])
        out.append(
            f"{path}: its points at t = {times[k]:.6g} and {times[k + 1]:.6g} s lie "
            f"{pieces[k]:.3g} s apart, less than solver.dt = {dt:g} s: fixed steps take "
            "the history at their ends only and can step over such a piece whole (a pulse "
            f"missed); give solver.dt <= {pieces[k]:.3g} s, or leave dt out and give "
            "solver.tolerance (steps chosen by accuracy land on every point)"
        )
    return out


def _sines(case: Case, dt: float) -> list[str]:
    """Messages for the prescribed sines with fewer than PER_PERIOD steps of ``dt`` a
    period."""
    periods = [
        (f"supports.move[{k}].sine.period", m.sine.period)
        for k, m in enumerate(case.supports.moves)
        if m.sine is not None
    ]
    periods += [
        (f"supports.vessel[{k}].sine[{j}].period", w.period)
        for k, v in enumerate(case.supports.vessels)
        for j, w in enumerate(v.sines)
    ]
    return [
        f"{path} = {period:g} s: {period / dt:.3g} steps of solver.dt = {dt:g} s a period, "
        f"fewer than {PER_PERIOD}: the motion is sampled, not followed; give solver.dt <= "
        f"{period / PER_PERIOD:.3g} s, or leave dt out and give solver.tolerance"
        for path, period in periods
        if period < PER_PERIOD * dt
    ]
