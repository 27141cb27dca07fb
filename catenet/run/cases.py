"""Load cases and combinations of a case (``[[load_case]]``, ``[[combination]]``): each
solved from the base state (the equilibrium under ``[load]``: prestress, self-weight)
under the base loads plus its own, in ``solver.steps`` load steps of its own part, on the
base run's workspace (one sparsity pattern, one symbolic analysis); not superposed. Each
is watched for edges in solids and steps through them as the base run is
(``catenet.run.crossings``).

Results go to ``/cases/<name>/`` with the layout of ``/result`` (its attributes: the
summary's numbers, ``kind`` "load_case" or "combination", a combination's ``factors``),
and the envelopes over the cases solved to ``/envelope/``: ``tension_max``,
``tension_min`` (M,) [N], ``displacement_max`` (N,) [m], ``utilisation_max`` (M,) (NaN
where no breaking load is given), each with the index of the case that governs
(``*_case``, into the attribute ``cases``).
"""

from __future__ import annotations

import contextlib
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
    failed before any state), the summary's numbers, the error's text ("" when none)
    and the warnings and errors logged while it was solved."""

    name: str
    combination: bool
    result: Result | None
    numbers: dict = field(default_factory=dict)
    error: str = ""
    warnings: list[str] = field(default_factory=list)

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
    the workspace ``ws``; a case that fails keeps its last good state and the others go
    on. Every warning and error logged while a case is solved names it, and is kept
    with it (``CaseRun.warnings``)."""
    from catenet.run.advice import unit_slips

    case = scene.case
    slips = unit_slips(case, scene.net) if case is not None else []
    runs = []
    for c in cases:
        log.info("%s %s: solving from the base state", _kind(c), c.name)
        with heard(f"{_kind(c)} {c.name}") as got:
            run = _solve_one(scene, settings, ws, base, c, interrupt, slips)
        run.warnings = list(got.messages)
        runs.append(run)
        if interrupt is not None and interrupt():  # a signal: the cases after it wait
            log.warning("interrupted: the load cases after %s are not solved", c.name)
            break
    return runs


def _solve_one(scene, settings, ws, base, c, interrupt, slips) -> CaseRun:
    """One load case or combination ``c`` solved from the base Result (its messages
    logged without its name: ``heard`` adds it)."""
    from catenet.model import summary
    from catenet.model.cases import Increment
    from catenet.run.advice import implausible
    from catenet.run.crossings import EdgeWatch
    from catenet.solver import path as sv
    from catenet.solver.newton import interruptible
    from catenet.solver.result import Outcome, finish
    from catenet.solver.stability import CollapseError

    loads = Increment(base=scene.loads, added=c.force)
    problem = Scene(scene.net, loads, scene.terms)
    start = sv.Start(x=base.x)
    crossed = EdgeWatch(scene, ws.system.terms)  # edges into solids, steps through them
    crossed.see(0.0, base.x)

    def on_step(step) -> bool:
        crossed.see(step.time, step.x)
        return False

    try:
        with interruptible(interrupt):
            r = sv.solve(problem, settings, workspace=ws, start=start, on_step=on_step)
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
        log.error("%s", exc)
    crossed.see(r.time, r.x)
    for message in crossed.warnings():
        log.warning("%s", message)
    if r.converged and not error:  # strains and displacements a cable can have
        what, extreme = implausible(scene.net, r.x, float(scene.size))
        if what and slips:  # the likely cause, named with each case
            what = f"{what}; {slips[0]}"
        if what:
            log.warning("%s", what)
        if extreme:
            error = f"implausible (check units and supports): {what}"
    numbers = summary.summarize_result(scene, r, loads)
    return CaseRun(c.name, c.combination, r, numbers, error)


class Heard(logging.Handler):
    """Collects the warnings and errors catenet logs (each message once, in order)."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = record.getMessage()
        except (TypeError, ValueError):
            text = str(record.msg)
        if text not in self.messages:
            self.messages.append(text)


@contextlib.contextmanager
def heard(what: str = ""):
    """Inside the block, the warnings and errors catenet logs go to the yielded ``Heard``
    as well; with ``what`` (a load case's "load case NAME"), each starts with ``what: ``
    unless it names it already, so that the solver's warnings say which case they
    concern."""
    make = logging.getLogRecordFactory()
    lead = f"{what}: "

    def factory(*args, **kwargs):
        record = make(*args, **kwargs)
        own = record.name == "catenet" or record.name.startswith("catenet.")
        if own and record.levelno >= logging.WARNING and not str(record.msg).startswith(lead):
            text = lead.replace("%", "%%") if record.args else lead
            record.msg = text + str(record.msg)
        return record

    handler = Heard()
    own = logging.getLogger("catenet")
    level, shown = own.level, own.getEffectiveLevel()
    mute = _Below(shown)  # what the log did not show (-q: errors only) it still does not
    outputs = logging.getLogger().handlers if shown > logging.WARNING else []
    if outputs:
        own.setLevel(logging.WARNING)  # made, so that they are kept
    for out in outputs:
        out.addFilter(mute)
    own.addHandler(handler)
    if what:
        logging.setLogRecordFactory(factory)
    try:
        yield handler
    finally:
        own.removeHandler(handler)
        for out in outputs:
            out.removeFilter(mute)
        if outputs:
            own.setLevel(level)
        if what:
            logging.setLogRecordFactory(make)


@contextlib.contextmanager
def spoken_in(units: str):
    """Inside the block, the warnings and errors catenet logs name lengths, forces and
    masses as the case's ``units`` do (``catenet.model.units.relabel``: 2.5 mm in an N-mm
    case, where the solver writes 2.5 m), in every output: the terminal, the log file and
    the result file's warnings. SI (or no system): nothing changes."""
    from catenet.model.units import TOKENS, relabel

    if units not in TOKENS:
        yield
        return
    make = logging.getLogRecordFactory()

    def factory(*args, **kwargs):
        record = make(*args, **kwargs)
        own = record.name == "catenet" or record.name.startswith("catenet.")
        if own and record.levelno >= logging.WARNING:
            try:
                text = record.getMessage()
            except (TypeError, ValueError):
                return record
            record.msg, record.args = relabel([text], units)[0], ()
        return record

    logging.setLogRecordFactory(factory)
    try:
        yield
    finally:
        logging.setLogRecordFactory(make)


class _Below(logging.Filter):
    """Drops catenet's records below ``level`` (the level the log showed)."""

    def __init__(self, level: int) -> None:
        super().__init__()
        self.level = level

    def filter(self, record: logging.LogRecord) -> bool:
        own = record.name == "catenet" or record.name.startswith("catenet.")
        return not own or record.levelno >= self.level


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
            attrs: dict = {"kind": "combination" if run.combination else "load_case"}
            if run.name in combos:
                attrs["factors"] = json.dumps(combos[run.name])
            if run.error:  # (an implausible equilibrium too: its state is no answer)
                attrs["error"] = run.error
                attrs.update(converged=False, outcome="failed", message=run.error)
            attrs["warnings"] = "\n".join(run.warnings)  # one a line, "" when none
            applied = run.numbers.get("applied_resultant")  # the case's loads, not the base's
            if applied is not None:
                attrs.update(
                    {
                        f"applied_resultant_{a}": float(v)
                        for a, v in zip("xyz", applied, strict=True)
                    }
                )
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
            write_envelope(h5.create_group("envelope"), scene.net, done, scene.design)


def envelope(net, runs: list[CaseRun], design=None) -> dict[str, np.ndarray]:
    """Over the cases: each edge's largest and least tension [N], each node's largest
    displacement [m], each edge's largest utilisation (``design``, a
    ``catenet.model.design.Design``; NaN where no breaking load is given), and the index
    (into ``runs``: each with its Result) of the case that governs each (0 where no
    utilisation is known)."""
    results = [r.result for r in runs if r.result is not None]
    assert len(results) == len(runs), "the envelope is over the cases solved"
    t = np.array([np.asarray(r.tension) for r in results])
    u = np.array([np.linalg.norm(np.asarray(r.x) - net.nodes, axis=1) for r in results])
    use = np.full_like(t, np.nan) if design is None else design.utilisation(t)
    known = np.isfinite(use).any(axis=0)
    extra = {}
    if design is not None and design.anchored:  # each support's largest |R| / capacity
        zero = np.zeros_like(net.nodes)
        r = np.array([zero if res.reaction is None else res.reaction for res in results])
        su = np.nan_to_num(design.support_utilisation(r), nan=-np.inf)
        extra = {
            "support_utilisation_max": np.where(
                np.isfinite(design.capacity), su.max(axis=0), np.nan
            ),
            "support_utilisation_max_case": su.argmax(axis=0),
        }
    return {
        "tension_max": t.max(axis=0),
        "tension_max_case": t.argmax(axis=0),
        "tension_min": t.min(axis=0),
        "tension_min_case": t.argmin(axis=0),
        "displacement_max": u.max(axis=0),
        "displacement_max_case": u.argmax(axis=0),
        "utilisation_max": np.where(known, np.nan_to_num(use, nan=-np.inf).max(axis=0), np.nan),
        "utilisation_max_case": np.nan_to_num(use, nan=-np.inf).argmax(axis=0),
        **extra,
    }


def governing(net, runs: list[CaseRun], design=None) -> dict:
    """The envelope's extremes and the cases that give them: ``tension_max`` [N] (edge,
    case), ``tension_min`` [N] (edge, case: the least tension, negative for a strut in
    compression), ``displacement_max`` [m] (node, case), ``utilisation_max`` (edge,
    case; only where a breaking load is given); {} without a case solved."""
    done = [r for r in runs if r.result is not None]
    if not done:
        return {}
    env = envelope(net, done, design)
    free = ~np.asarray(net.fixed, dtype=bool)
    free[net.n_net :] = False
    out = {}
    for key, largest, where in (
        ("tension_max", True, None),
        ("tension_min", False, None),
        ("displacement_max", True, free),
        ("utilisation_max", True, np.isfinite(env["utilisation_max"])),
        ("support_utilisation_max", True, np.isfinite(env.get("support_utilisation_max", []))),
    ):
        if key not in env:
            continue
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


def write_envelope(group, net, runs: list[CaseRun], design=None) -> None:
    for key, value in envelope(net, runs, design).items():
        group.create_dataset(key, data=value)
    import h5py

    group.attrs["cases"] = np.array([r.name for r in runs], dtype=h5py.string_dtype())
    group.attrs["converged"] = all(r.converged for r in runs)


def write_warnings(path, messages: list[str], failure: str = "") -> None:
    """The base state's warnings as /result's attribute ``warnings`` (one a line, ""
    when none) of the closed result file ``path`` (OutputError when it cannot be);
    ``failure``: why the state the solve reached is no answer, /result then marked
    failed (``converged`` false, ``outcome`` failed, ``message`` the failure)."""
    import h5py

    from catenet.errors import OutputError
    from catenet.output.files import describe

    try:
        with h5py.File(path, "a") as h5:
            if "result" in h5:
                attrs = h5["result"].attrs
                attrs["warnings"] = "\n".join(dict.fromkeys(messages))
                if failure:
                    attrs["converged"], attrs["outcome"] = False, "failed"
                    attrs["message"] = failure
    except OSError as exc:
        raise OutputError(f"{path}: writing /result's warnings failed: {describe(exc)}") from None


def solve_from_base(scene, settings, ws, result, cases, path, interrupt) -> tuple[dict, dict]:
    """The load cases from the base state ``result``, written to /cases and /envelope;
    their summary numbers by name and the envelope (``governing``)."""
    if not result.converged:
        why = "is implausible" if result.message.startswith("implausible") else "did not converge"
        log.error("the base state %s: no load case is solved", why)
        return {}, {}
    if result.stable is False:
        log.error("the base state is an unstable equilibrium: no load case is solved")
        return {}, {}
    result.cases = solve_cases(scene, settings, ws, result, cases, interrupt)
    numbers = {
        r.name: {**r.numbers, "converged": r.converged, "error": r.error} for r in result.cases
    }
    envelope = governing(scene.net, result.cases, scene.design)
    if path is not None:
        write_cases(path, scene, scene.case, result.cases)
    return numbers, envelope
