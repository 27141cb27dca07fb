"""Where a dynamic run goes on from (``catenet run --restart OLD.h5``): the last stored
state of an earlier run of the same case, checked against the scene before anything is
computed (``read_restart``)."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError

log = logging.getLogger(__name__)

__all__ = ["RestartState", "read_restart"]


@dataclass
class RestartState:
    """Where a dynamic run goes on from: time, positions, velocities and the newmark
    scheme's acceleration state (None: not in the file, or not a newmark case)."""

    path: Path
    t: float
    x: np.ndarray
    v: np.ndarray
    source: str
    a: np.ndarray | None = None
    peaks: dict | None = None  # the earlier run's peaks up to t (None: not in the file)


def read_restart(path: str | Path, scene) -> RestartState:
    """The last stored state of an earlier dynamic run of the same net, checked against
    the scene. Raises ConfigError for a file that does not fit."""
    from catenet.output import read_frame, read_mesh

    path = Path(path)
    label = f"--restart {path}"
    if scene.case.solver.method != "dynamic":
        raise ConfigError(
            f"{label}: only dynamic runs can be restarted (solver.method = "
            f"{scene.case.solver.method!r}); set solver.method = 'dynamic'"
        )
    try:
        frame = read_frame(path)
    except ConfigError as exc:
        raise ConfigError([f"--restart: {p}" for p in exc.problems]) from None
    except OSError as exc:
        raise ConfigError(f"{label}: cannot be read: {exc}") from None
    try:
        problems = _mesh_mismatch(read_mesh(path, what=label), scene.net)
    except (TypeError, ValueError) as exc:  # /mesh datasets that are not numbers
        if isinstance(exc, ConfigError):
            raise
        problems = [f"its /mesh is damaged or not a catenet result file's ({exc})"]
    shape = scene.net.nodes.shape
    for name, arr in (("positions", frame.x), ("velocities", frame.v)):
        if arr is not None and arr.shape != shape:
            problems.append(
                f"its stored {name} ({frame.source}) have shape {arr.shape}: the case's net "
                f"needs {shape}: restart with the case that wrote it"
            )
    if problems:
        raise ConfigError([f"{label}: {p}" for p in problems])
    if frame.v is None:
        raise ConfigError(
            f"{label}: holds no velocities (/trajectory/v or /result/v): it is not the file "
            "of a dynamic run with output.every > 0"
        )
    if not (np.all(np.isfinite(frame.x)) and np.all(np.isfinite(frame.v))):
        raise ConfigError(f"{label}: its last stored state is not finite")
    t_end = scene.case.solver.t_end  # "rest": goes on to rest from any time
    if not isinstance(t_end, str) and not frame.t < t_end * (1 - 1e-12):
        raise ConfigError(
            f"{label}: its last state is at t = {frame.t:.6g} s, not before solver.t_end = "
            f"{t_end!r}: raise solver.t_end to go on"
        )
    a = frame.a if scene.case.solver.integrator == "newmark" else None
    if a is not None and not (a.shape == frame.x.shape and np.all(np.isfinite(a))):
        raise ConfigError(f"{label}: its stored accelerations (/trajectory/a) are not usable")
    if a is None and scene.case.solver.integrator == "newmark":
        log.info(
            "%s: holds no newmark acceleration state: the run goes on from the physical "
            "acceleration (not exactly as the uninterrupted run would)",
            label,
        )
    from catenet.output.reader import read_peaks

    peaks = read_peaks(path, frame.t)
    if peaks is not None and _relaxed(path):
        log.info(
            "%s: relaxed to rest (solver.t_end = 'rest': pseudo-time): its peaks are not "
            "carried; the peaks count from this run's start at t = %.6g s",
            label,
            frame.t,
        )
        peaks = None
    return RestartState(path, frame.t, frame.x, frame.v, frame.source, a, peaks)


def _relaxed(path: Path) -> bool:
    """Whether the run that wrote ``path`` ran to rest (its case's solver.t_end = "rest"):
    its time is pseudo-time, its peaks those of a relaxation, not of a physical motion."""
    import tomllib

    from catenet.output.files import read_text
    from catenet.output.reader import open_result

    try:
        with open_result(path) as h5:
            text = h5.attrs.get("case", "")
        solver = tomllib.loads(read_text(text)).get("solver", {})
    except (OSError, ValueError, tomllib.TOMLDecodeError):
        return False
    return isinstance(solver, dict) and solver.get("t_end") == "rest"


def _mesh_mismatch(mesh, net) -> list[str]:
    """How the net of a result file (an ``output.Mesh``) differs from the case's."""
    nodes, edges, rest, fixed = mesh.nodes, mesh.edges, mesh.rest_length, mesh.fixed
    if nodes.shape != net.nodes.shape or edges.shape != net.edges.shape:
        return [
            f"its net has {len(nodes)} nodes and {len(edges)} edges, the case's "
            f"{net.n_nodes} and {net.n_edges}: restart with the case that wrote it"
        ]
    problems = []
    if not np.array_equal(edges, net.edges):
        problems.append("its edges differ from the case's: restart with the case that wrote it")
    if not np.allclose(rest, net.rest_length, rtol=1e-12, atol=0.0):
        problems.append("its rest lengths differ from the case's")
    if not np.array_equal(fixed.astype(bool), net.fixed):
        problems.append("its supports differ from the case's")
    EA = mesh.EA
    if EA is not None and (EA.shape != net.EA.shape or not np.allclose(EA, net.EA, rtol=1e-12)):
        problems.append("its axial stiffnesses EA differ from the case's")
    return problems
