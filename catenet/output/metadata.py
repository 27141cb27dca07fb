"""What a result file records about its run besides the states: the versions of the
software that wrote it (root attributes ``<name>_version``) and the /result attributes
(contract §5)."""

from __future__ import annotations

import math
import platform
from typing import TYPE_CHECKING

import numpy as np

from catenet.model import measures, summary

if TYPE_CHECKING:
    from catenet.scene.scene import Scene
    from catenet.solver.result import Result

__all__ = ["environment", "result_attrs"]


def _with_tension(res: Result, tension: np.ndarray) -> Result:
    """The Result with the tension the file stores (a copy only when they differ)."""
    if res.tension is tension:
        return res
    import copy

    other = copy.copy(res)
    other.tension = tension
    return other


def environment() -> dict[str, str]:
    """Versions of catenet, Python and the libraries it runs on ('' where missing)."""
    from importlib.metadata import PackageNotFoundError

    import catenet

    out = {"catenet": catenet.__version__, "python": platform.python_version()}
    for name in ("numpy", "scipy", "numba", "h5py", "click", "pypardiso", "mkl"):
        try:
            out[name] = _version(name)
        except PackageNotFoundError:
            out[name] = ""
    try:
        import h5py

        out["hdf5"] = h5py.version.hdf5_version
    except ImportError:  # pragma: no cover - h5py is a dependency
        out["hdf5"] = ""
    return out


def _version(name: str) -> str:
    """The installed version of the distribution ``name`` (``importlib.metadata.version``):
    read from the Version line of its metadata's headers, without parsing the whole file
    (a long licence text) as e-mail, which took most of a result file's header time."""
    from importlib.metadata import distribution

    dist = distribution(name)
    for line in (dist.read_text("METADATA") or dist.read_text("PKG-INFO") or "").splitlines():
        if not line:  # the end of the headers
            break
        if line.startswith("Version:"):
            return line[len("Version:") :].strip()
    return dist.version


def result_attrs(res: Result, scene: Scene, tension: np.ndarray | None = None) -> dict:
    """The /result attributes of a Result: contract §5 plus what a user reads first:
    the summary's numbers (``catenet.model.summary.summarize``; a vector v as v_x, v_y, v_z; -1
    for no node or edge, the per-cable table in datasets); ``tension``: the stored one
    (default: the Result's)."""
    if tension is None:
        tension = res.tension if res.tension is not None else measures.tension(scene.net, res.x)
    tension = np.asarray(tension, dtype=np.float64)
    numbers = summary.flat(summary.summarize_result(scene, _with_tension(res, tension)))
    delta = numbers["delta"]
    residual = float(res.residual)
    strain = float(res.max_strain)
    timing = res.timing
    nested = res.nested
    return {
        # an unstable equilibrium is refused (exit 1): never converged in the file either
        "converged": bool(res.converged) and res.stable is not False,
        "iterations": int(res.iterations),
        # a nested start's Newton iterations on the coarse net (0: none; not in iterations)
        "nested_iterations": 0 if nested is None else int(nested.iterations),
        "nested_dofs": 0 if nested is None else int(nested.dofs),
        "residual": residual if not math.isnan(residual) else math.inf,
        "steps": int(res.steps),
        "wall_time": float(res.wall_time),
        "equilibrium": bool(res.equilibrium),
        "message": str(res.message or ""),
        # how the solve ended: equilibrium, ... (catenet.solver.result.Outcome); "" unknown
        "outcome": str(res.outcome) if res.outcome is not None else "",
        "time": float(res.time),
        **numbers,
        "delta_over_L": delta / float(scene.size),
        "size": float(scene.size),
        "max_strain": strain if math.isfinite(strain) else 0.0,
        # bilateral nets: 1 stable, 0 unstable equilibrium; -1 not checked (tension-only)
        "stable": -1 if res.stable is None else int(bool(res.stable)),
        # stable | unstable | collapsed | post-collapse (catenet.solver.stability); a
        # transient (a dynamic run that ran its time) or a static run that failed to
        # converge is "not judged"
        "stability": _stability(res),
        # a dynamic run's energy balance at its end [J] (catenet.solver.energy.COLUMNS)
        **_energy(res),
        # catenet run: seconds of the solve (the engine) and of the start-up before it
        # (imports, the case, the JIT cache); -1 where not measured
        "solve_time": -1.0 if timing is None else float(timing.solve),
        "startup_time": -1.0 if timing is None else float(timing.startup),
    }


def _stability(res: Result) -> str:
    """The /result ``stability`` attr: the solve's verdict, else one from ``stable``."""
    verdict = str(res.stability or "")
    if verdict:
        return verdict
    if res.stable is False:
        return "unstable"
    return "stable" if res.equilibrium else "not judged"


def _energy(res: Result) -> dict:
    """``energy_<column>`` attrs of a dynamic run's final balance [J] (none for static)."""
    row = res.energy
    if row is None:
        return {}
    from catenet.solver.energy import COLUMNS

    return {f"energy_{name}": float(value) for name, value in zip(COLUMNS, row, strict=True)}
