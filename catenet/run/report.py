"""What ``run_case`` reports beside the solved state: where it looked (the probe node and
the net's size), what it found there, what it wrote and what it warned about; the
summary ``catenet run`` prints is made from it."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

from catenet.solver.result import Result


@dataclass(frozen=True)
class CableSummary:
    """One cable of a graph case: its largest tension [N] and the share of its rest
    length that is slack."""

    max_tension: float
    slack_fraction: float


@dataclass(frozen=True)
class RunReport:
    """delta: the probe node's z-deflection [m] (positive down); size: the net's length scale L
    [m]; probe: the probe node; output: the file written (None: none); backend: the linear
    solver; strain_warning: the warning of a strain beyond the material law's range ("" when
    none); implausible: why the base state, converged, is no answer
    (``catenet.run.runner._implausible``; "" when it is one); trajectory_bytes: the
    trajectory's size as estimated before the run (0 without a file); cables: per cable of a
    graph case (None for other nets); bodies: per free rigid body (its obstacle index):
    kind, first contact time (None: none), final spin [deg/s] and axis, speed [m/s]
    (``catenet.run.bodies.BodyWatch.stats``), and ``unseen`` where the net met it where no
    barrier looks ("cut", "through": ``catenet.run.crossings.EdgeWatch.met``); summary: the
    summary's numbers (``catenet.model.summary.summarize_result``: largest displacement,
    reactions, slack edges, peaks, per cable, ...: the /result attributes and the sweep
    columns); cases: per load case and combination its numbers (with ``converged`` and
    ``error``); envelope: the extremes over the cases and the cases that give them
    (``catenet.run.cases.governing``)."""

    delta: float
    size: float
    probe: int
    output: str | None
    backend: str
    strain_warning: str = ""
    implausible: str = ""
    trajectory_bytes: int = 0
    cables: dict[str, CableSummary] | None = None
    bodies: dict[int, dict] = field(default_factory=dict)
    summary: dict = field(default_factory=dict)
    cases: dict = field(default_factory=dict)
    envelope: dict = field(default_factory=dict)

    @property
    def delta_over_L(self) -> float:
        return self.delta / self.size


@dataclass
class RunResult(Result):
    """The Result of ``run_case``, with its report (``RunReport``)."""

    report: RunReport = field(kw_only=True)

    @classmethod
    def of(cls, result: Result, report: RunReport) -> RunResult:
        return cls(**{f.name: getattr(result, f.name) for f in fields(Result)}, report=report)
