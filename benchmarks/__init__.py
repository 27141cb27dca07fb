"""catenet's timing and accuracy studies (repository tooling: not part of the installed
package). Run them with ``python -m benchmarks STUDY...`` or ``python benchmarks/<study>.py``
from the repository root (see ``benchmarks/__main__.py``); ``python -m benchmarks render``
fills the tables of docs/performance.md from benchmarks/results/*.csv.

One module per study; each has ``NAME``, ``TITLE`` and ``run(out_dir, *, quick=False,
progress=..., threads=1) -> Study``, which writes ``<name>.csv`` and ``bench-<name>.png``
into ``out_dir`` and returns the rows with a summary and any findings. The modules import
NumPy and the solvers only inside ``run``.
"""

from __future__ import annotations

import importlib

STUDIES = {
    "step-size": "benchmarks.step_size",
    "pareto": "benchmarks.pareto",
    "scale": "benchmarks.scale",
    "baseline": "benchmarks.baseline",
    "skips": "benchmarks.skips",
    "cold-start": "benchmarks.cold_start",
    "stress": "benchmarks.stress",
    "flush": "benchmarks.flush",
    "formfind": "benchmarks.formfind",
    "reuse": "benchmarks.reuse",
    "integrators": "benchmarks.integrators",
    "drop": "benchmarks.drop",
    "accuracy": "benchmarks.accuracy",
}


def study(name: str):
    """The module of a study by its name (``step-size``, ``pareto``, ...)."""
    if name not in STUDIES:
        raise KeyError(f"no study {name!r}: one of {', '.join(STUDIES)}")
    return importlib.import_module(STUDIES[name])
