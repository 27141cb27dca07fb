"""How to solve: the settings of the one solve path, declared here once; the case's
``[solver]`` keys (``catenet.case.sections.SolverConfig``) take their defaults from them."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from catenet.errors import ConfigError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance
from catenet.solver.adaptive import FIRST_SHARE
from catenet.solver.integrators import INTEGRATORS, RHO_INF
from catenet.solver.relax import MAX_STEPS, REST

METHODS = ("static", "dynamic")
DT = 1e-2  # solver.dt's default with fixed steps
STARTS = ("auto", "stretched", "nested")  # static: where Newton starts (solver.nested)
INITIAL_STATES = ("given", "equilibrium")  # dynamic: where a run starts (solver.initial_state)
STATIC_MAX_ITER = 200  # solver.max_iter not given: Newton iterations of a static solve
STEP_MAX_ITER = 25  # ... and of one time step of a dynamic run (at fixed steps to a time,
#                    a step still converging there goes on: ``newton.EXTEND``)
MAX_ITER_SHOWN = (  # (case keys)
    f"`{STATIC_MAX_ITER}` (static), `{STEP_MAX_ITER}` (a time step; at fixed steps to a "
    "time, one still converging goes on, up to 4 times that)"
)


class Steps(Protocol):
    """The keys that decide a dynamic run's steps (Settings, a case's SolverConfig)."""

    @property
    def t_end(self) -> float | str | None: ...
    @property
    def tolerance(self) -> float | None: ...
    @property
    def dt_max(self) -> float | None: ...


def steps_given(dt: float | None, integrator: str | None, keys: Steps) -> tuple[float, str]:
    """(dt, integrator) where not given (None): with a tolerance and a number for t_end,
    the first step FIRST_SHARE of t_end (at most dt_max) and bdf2 (steps chosen by
    accuracy, ``catenet.solver.adaptive``); else DT and implicit Euler (fixed steps)."""
    t_end = keys.t_end if isinstance(keys.t_end, (int, float)) else None
    adaptive = keys.tolerance is not None and t_end is not None
    if dt is None and adaptive and t_end is not None:
        dt = min(keys.dt_max or math.inf, FIRST_SHARE * float(t_end))
    return DT if dt is None else dt, integrator or ("bdf2" if adaptive else "implicit_euler")


@dataclass(frozen=True)
class Settings:
    """How to solve: the [solver] keys (contract §3) that a solve uses."""

    method: str = "static"
    dt: float = math.nan  # not given: 0.01, or with a tolerance t_end / 1000 (__post_init__)
    damping: float = 1.0
    t_end: float | str = 10.0  # or "rest" (a case's default when nothing depends on time)
    max_steps: int = MAX_STEPS  # t_end = "rest": the most time steps
    rtol: float = 1e-8
    max_iter: int | None = None  # not given: STATIC_MAX_ITER, or STEP_MAX_ITER a time step
    steps: int = 1
    linear: str = "auto"
    integrator: str = ""  # not given: "implicit_euler", or with a tolerance "bdf2"
    reuse: bool = False
    rho_inf: float = RHO_INF
    start: str = "auto"  # static: "auto", "stretched" or "nested" (catenet.solver.nested)
    initial_state: str = "given"  # dynamic: "given" or "equilibrium" (at rest at t0)
    post_collapse: bool = False  # static: follow a collapsing path through (else exit 1)
    energy_tolerance: float = 1e-2  # dynamic: energy created, a share of the largest
    tolerance: float | None = None  # dynamic: steps chosen by accuracy (catenet.solver.adaptive)
    dt_max: float | None = None  # ... the longest step (None: t_end - t0)
    dt_min: float | None = None  # ... the shortest

    @property
    def static_iterations(self) -> int:
        """Newton iterations of one static solve: ``max_iter``, else STATIC_MAX_ITER."""
        return STATIC_MAX_ITER if self.max_iter is None else self.max_iter

    def _resolve_steps(self) -> None:
        """dt and integrator where not given (``steps_given``)."""
        dt = None if math.isnan(self.dt) else self.dt
        dt, integrator = steps_given(dt, self.integrator or None, self)
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "integrator", integrator)

    @classmethod
    def of(cls, config: DataclassInstance, **changes: Any) -> Settings:
        """The settings in a dataclass with these fields (a case's SolverConfig; its other
        fields ignored, a None the default here: not given, e.g. a static case's t_end)."""
        names = {f.name for f in dataclasses.fields(cls)}
        given = dataclasses.asdict(config)
        values = {n: v for n, v in given.items() if n in names and v is not None}
        return cls(**{**values, **changes})

    def __post_init__(self) -> None:
        self._resolve_steps()
        if self.method not in METHODS:
            raise ConfigError(
                f"solver.method = {self.method!r}: must be one of {', '.join(METHODS)}"
            )
        if self.integrator not in INTEGRATORS:
            raise ConfigError(
                f"solver.integrator = {self.integrator!r}: must be one of {', '.join(INTEGRATORS)}"
            )
        if not 0.0 <= self.rho_inf <= 1.0:
            raise ConfigError(f"solver.rho_inf = {self.rho_inf!r}: must be in [0, 1]")
        if isinstance(self.t_end, str) and self.t_end != REST:
            raise ConfigError(f"solver.t_end = {self.t_end!r}: must be a number or {REST!r}")
        if self.start not in STARTS:
            raise ConfigError(f"solver.start = {self.start!r}: must be one of {', '.join(STARTS)}")
        if self.start == "nested" and self.method == "dynamic":
            raise ConfigError(
                'solver.start = "nested": is for static runs (solver.method = "static"); '
                'a dynamic run starts from the reference positions: use "auto"'
            )
        if self.tolerance is not None and not 0.0 < self.tolerance < 1.0:
            raise ConfigError(f"solver.tolerance = {self.tolerance!r}: must be in (0, 1)")
        for name, value in (("dt_max", self.dt_max), ("dt_min", self.dt_min)):
            if value is not None and not value > 0.0:
                raise ConfigError(f"solver.{name} = {value!r}: must be a number > 0")
        low, high = self.dt_min or 0.0, self.dt_max or math.inf
        if self.tolerance is not None and not low <= high:
            raise ConfigError(
                f"solver.dt_min = {self.dt_min!r}: must be <= solver.dt_max = {high!r}"
            )
        if self.tolerance is not None and self.integrator == "newmark":
            raise ConfigError(
                "solver.tolerance: steps chosen by accuracy take integrator = 'bdf2' or "
                "'implicit_euler', not 'newmark' (give solver.dt for fixed steps)"
            )
        if self.initial_state not in INITIAL_STATES:
            raise ConfigError(
                f"solver.initial_state = {self.initial_state!r}: must be one of "
                f"{', '.join(INITIAL_STATES)}"
            )
        if self.steps < 1:
            raise ConfigError(f"solver.steps = {self.steps!r}: must be an integer >= 1")
