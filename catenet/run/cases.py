"""Load cases and combinations of a case (``[[load_case]]``, ``[[combination]]``): each
solved from the base state (the equilibrium under ``[load]``: prestress, self-weight)
under the base loads plus its own, in ``solver.steps`` load steps of its own part, on the
base run's workspace (one sparsity pattern, one symbolic analysis); not superposed.

Results go to ``/cases/<name>/`` with the layout of ``/result`` (its attributes: the
summary's numbers, ``kind`` "load_case" or "combination", a combination's ``factors``),
and the envelopes over the cases solved to ``/envelope/``: ``tension_max``,
``tension_min`` (M,) [N], ``displacement_max`` (N,) [m], each with the index of the case
that governs (``*_case``, into the attribute ``cases``).
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import CatenetError, ConfigError
from catenet.model.summary import first_extreme
from catenet.scene import Scene

if TYPE_CHECKING:  # the solvers load when a case is run
    from catenet.solver.result import Result

log = logging.getLogger(__name__)

__all__ = ["CaseRun", "governing", "pick", "solve_cases", "write_cases"]


@dataclass
class CaseRun:
    """A load case or combination solved: its name, kind, the Result (None when it
    failed before any state), the summary's numbers and the error's text ("" when none)."""

    name: str
    combination: bool
    result: Result | None
    numbers: dict = field(default_factory=dict)
    error: str = ""

    @property
    def converged(self) -> bool:
        return self.result is not None and bool(self.result.converged) and not self.error


def pick(scene, only: str | None) -> tuple:
    """The scene's load cases to solve: every one, or the one named ``only`` (ConfigError
    naming the ones there are)."""
    if only is None:
        return scene.cases
    for c in scene.cases:
        if c.name == only:
            return (c,)
    names = ", ".join(repr(c.name) for c in scene.cases) or "none"
    raise ConfigError(
        f"--case {only!r}: no [[load_case]] or [[combination]] is named so (the case has: {names})"
    )


def solve_cases(scene, settings, ws, base, cases, interrupt=None) -> list[CaseRun]:
    """Solves each of ``cases`` (``catenet.case.scene.LoadCase``) from the base Result on
    the workspace ``ws``; a case that fails keeps its last good state and the others go on."""
    from catenet.model import summary
    from catenet.model.cases import Increment
    from catenet.run.advice import implausible, unit_slips
    from catenet.solver import path as sv
    from catenet.solver.newton import interruptible
    from catenet.solver.result import Outcome, finish
    from catenet.solver.stability import CollapseError

    case = scene.case
    slips = unit_slips(case, scene.net) if case is not None else []
    runs = []
    for c in cases:
        loads = Increment(base=scene.loads, added=c.force)
        problem = Scene(scene.net, loads, scene.terms)
        start = sv.Start(x=base.x)
        log.info("%s %s: solving from the base state", _kind(c), c.name)
        try:
            with interruptible(interrupt):
                r = sv.solve(problem, settings, workspace=ws, start=start)
            error = "" if r.converged else r.message
        except CatenetError as exc:
            if isinstance(exc, ConfigError):
                raise
            good = exc.last_good
            x = base.x if good is None or good.x is None else good.x
            r = finish(
                ws.system,
                loads,
                np.asarray(x, dtype=np.float64),
                1.0 if good is None else float(good.time),
                converged=False,
                iterations=0 if good is None else int(good.iterations),
                residual=float("inf"),
                time=0.0 if good is None else float(good.time),
                message=str(exc),
                outcome=Outcome.FAILED,
                stability=exc.verdict if isinstance(exc, CollapseError) else "",
            )
            error = str(exc)
            log.error("%s %s: %s", _kind(c), c.name, exc)
        if r.converged and not error:  # strains and displacements a cable can have
            what, extreme = implausible(scene.net, r.x, float(scene.size))
            if what and slips:  # the likely cause, named with each case
                what = f"{what}; {slips[0]}"
            if what:
                log.warning("%s %s: %s", _kind(c), c.name, what)
            if extreme:
                error = f"implausible (check units and supports): {what}"
        numbers = summary.summarize_result(scene, r, loads)
        runs.append(CaseRun(c.name, c.combination, r, numbers, error))
        if interrupt is not None and interrupt():  # a signal: the cases after it wait
            log.warning("interrupted: the load cases after %s are not solved", c.name)
            break
    return runs


def _kind(c) -> str:
    return "combination" if c.combination else "load case"


def write_cases(path, scene, case, runs: list[CaseRun]) -> None:
    """Adds /cases/<name>/ and /envelope/ to the closed result file at ``path``
    (OutputError when it cannot be written)."""
    from catenet.errors import OutputError
    from catenet.output.files import describe

    try:
        _write_cases(path, scene, case, runs)
    except OSError as exc:
        raise OutputError(
            f"{path}: writing the load cases (/cases, /envelope) failed: {describe(exc)}"
        ) from None


def _write_cases(path, scene, case, runs: list[CaseRun]) -> None:
    import h5py

    from catenet.output.result_group import write_result_group

    combos = {c.name: c.factors for c in case.combinations}
    with h5py.File(path, "a") as h5:
        for key in ("cases", "envelope"):
            if key in h5:
                del h5[key]
        for run in runs:
            if run.result is None:
                continue
            attrs = {"kind": "combination" if run.combination else "load_case"}
            if run.name in combos:
                attrs["factors"] = json.dumps(combos[run.name])
            if run.error:
                attrs["error"] = run.error
            write_result_group(
                h5,
                scene,
                run.result,
                run.result.tension,
                attrs,
                False,
                False,
                name=f"cases/{run.name}",
            )
        done = [r for r in runs if r.result is not None]
        if done:
            write_envelope(h5.create_group("envelope"), scene.net, done)


def envelope(net, runs: list[CaseRun]) -> dict[str, np.ndarray]:
    """Over the cases: each edge's largest and least tension [N], each node's largest
    displacement [m], and the index (into ``runs``: each with its Result) of the case
    that governs each."""
    results = [r.result for r in runs if r.result is not None]
    assert len(results) == len(runs), "the envelope is over the cases solved"
    t = np.array([np.asarray(r.tension) for r in results])
    u = np.array([np.linalg.norm(np.asarray(r.x) - net.nodes, axis=1) for r in results])
    return {
        "tension_max": t.max(axis=0),
        "tension_max_case": t.argmax(axis=0),
        "tension_min": t.min(axis=0),
        "tension_min_case": t.argmin(axis=0),
        "displacement_max": u.max(axis=0),
        "displacement_max_case": u.argmax(axis=0),
    }


def governing(net, runs: list[CaseRun]) -> dict:
    """The envelope's extremes and the cases that give them: ``tension_max`` [N] (edge,
    case), ``tension_min`` [N] (edge, case: the least tension, negative for a strut in
    compression), ``displacement_max`` [m] (node, case); {} without a case solved."""
    done = [r for r in runs if r.result is not None]
    if not done:
        return {}
    env = envelope(net, done)
    free = ~np.asarray(net.fixed, dtype=bool)
    free[net.n_net :] = False
    out = {}
    for key, largest, where in (
        ("tension_max", True, None),
        ("tension_min", False, None),
        ("displacement_max", True, free),
    ):
        values = env[key]
        idx = np.flatnonzero(where) if where is not None else np.arange(len(values))
        if idx.size == 0:
            continue
        k = first_extreme(values, idx, largest)  # ties at round-off: the first
        out[key] = {
            "value": float(values[k]),
            "at": k,
            "case": done[int(env[f"{key}_case"][k])].name,
        }
    return out


def write_envelope(group, net, runs: list[CaseRun]) -> None:
    for key, value in envelope(net, runs).items():
        group.create_dataset(key, data=value)
    import h5py

    group.attrs["cases"] = np.array([r.name for r in runs], dtype=h5py.string_dtype())
    group.attrs["converged"] = all(r.converged for r in runs)


def solve_from_base(scene, settings, ws, result, cases, path, interrupt) -> tuple[dict, dict]:
    """The load cases from the base state ``result``, written to /cases and /envelope;
    their summary numbers by name and the envelope (``governing``)."""
    if not result.converged:
        log.error("the base state did not converge: no load case is solved")
        return {}, {}
    if result.stable is False:
        log.error("the base state is an unstable equilibrium: no load case is solved")
        return {}, {}
    result.cases = solve_cases(scene, settings, ws, result, cases, interrupt)
    numbers = {
        r.name: {**r.numbers, "converged": r.converged, "error": r.error} for r in result.cases
    }
    envelope = governing(scene.net, result.cases)
    if path is not None:
        write_cases(path, scene, scene.case, result.cases)
    return numbers, envelope
