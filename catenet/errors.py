"""Exception hierarchy. The CLI maps these to exit codes (ConfigError -> 2, the rest -> 1)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar


@dataclass
class LastGood:
    """What a failed or interrupted run keeps: its last good state, never an unconverged
    iterate. ``x`` (N, 3) the positions of the last equilibrium of a static run (a load
    step's or a cut-back sub-step's; the start at load factor 0 before any) or of the
    last accepted time step; ``time`` its load factor or time [s]; ``steps`` the load or
    time steps done; ``iterations`` the Newton iterations spent in all; ``v`` (N, 3) and
    ``a`` (N, 3) a dynamic run's velocities and newmark acceleration state (else None)."""

    x: Any
    time: float = 0.0
    steps: int = 0
    iterations: int = 0
    v: Any = None
    a: Any = None


class CatenetError(Exception):
    """Base class of every error catenet raises on purpose. ``last_good``: the last good
    state of the run it ended (``LastGood``), where the solve path knows one; ``output``:
    the result file that holds it (``catenet.run.runner.run_case``; None: none does)."""

    last_good: LastGood | None = None
    output: Path | None = None
    iterations: int = 0  # the Newton iterations the failing solve spent (where counted)


Error = TypeVar("Error", bound=CatenetError)


def with_last_good(exc: Error, good: LastGood) -> Error:
    """``exc`` holding ``good`` as the last good state of the run it ends: the solve path
    sets it (``catenet.solver``), its callers read it."""
    exc.last_good = good
    return exc


class ConfigError(CatenetError, ValueError):
    """Bad input: a case file, a command-line value or an argument of the Python API.

    ``problems`` lists every problem found (key path, value, what is accepted), so that
    a case file with several mistakes is reported in one go.
    """

    def __init__(self, problems: str | list[str]):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        super().__init__("\n".join(self.problems))


class ConvergenceError(CatenetError):
    """Newton (or the time stepping) did not converge.

    ``history`` holds the residual norms of the failing iteration, ``state`` the start of
    the failing solve (N, 3) when there is one (never an unconverged iterate); the solve
    path adds the run's ``last_good`` (``with_last_good``), or raises it with one.
    """

    def __init__(
        self,
        message: str,
        *,
        iterations: int = 0,
        history=None,
        state=None,
        last_good: LastGood | None = None,
    ):
        super().__init__(message)
        self.iterations = iterations
        self.history = list(history or [])
        self.state = state
        self.last_good = last_good
        # a static load step's cut-back ladder was tried and failed (True: dynamic
        # relaxation to rest too; the load path then adds its advice): else None
        self.ladder: bool | None = None


class Interrupted(ConvergenceError):
    """A solve stopped on request (a signal) between two Newton iterations; like
    ConvergenceError it carries the last good state once the solve path has added it."""


class SingularSystemError(ConvergenceError):
    """A linear solve gave non-finite values or a large residual: a mechanism.

    ``nodes`` are the nodes that lack stiffness (or, failing that, move the most).
    """

    def __init__(self, message: str, *, nodes=(), **kwargs):
        self.nodes = [int(n) for n in nodes]
        if self.nodes:
            shown = ", ".join(map(str, self.nodes[:10]))
            more = f" and {len(self.nodes) - 10} more" if len(self.nodes) > 10 else ""
            message = f"{message}; nodes concerned: {shown}{more}"
        super().__init__(message, **kwargs)


class OutputError(CatenetError):
    """A result file could not be written. ``result``: the Result that was to be written
    (kept in memory), ``saved_to``: the temporary file it was saved to instead (None:
    nowhere)."""

    result: Any = None
    saved_to: Path | None = None
