"""Timing and accuracy studies behind ``catenet bench`` and ``benchmarks/*.py``.

One module per study; each has ``NAME``, ``TITLE`` and ``run(out_dir, *, quick=False,
progress=..., threads=1) -> Study``, which writes ``<name>.csv`` and ``bench-<name>.png``
into ``out_dir`` and returns the rows with a summary and any findings. The modules import
NumPy and the solvers only inside ``run``.
"""

from __future__ import annotations

import importlib

STUDIES = {
    "step-size": "catenet.studies.bench.step_size",
    "pareto": "catenet.studies.bench.pareto",
    "scale": "catenet.studies.bench.scale",
    "baseline": "catenet.studies.bench.baseline",
    "skips": "catenet.studies.bench.skips",
    "cold-start": "catenet.studies.bench.cold_start",
    "stress": "catenet.studies.bench.stress",
    "flush": "catenet.studies.bench.flush",
    "formfind": "catenet.studies.bench.formfind",
    "reuse": "catenet.studies.bench.reuse",
    "integrators": "catenet.studies.bench.integrators",
}


def study(name: str):
    """The module of a study by its name (``step-size``, ``pareto``, ...)."""
    if name not in STUDIES:
        raise KeyError(f"no study {name!r}: one of {', '.join(STUDIES)}")
    return importlib.import_module(STUDIES[name])
