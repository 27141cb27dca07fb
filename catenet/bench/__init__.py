"""Timing and accuracy studies behind ``catenet bench`` and ``benchmarks/*.py``.

One module per study; each has ``NAME``, ``TITLE`` and ``run(out_dir, *, quick=False,
progress=..., threads=1) -> Study``, which writes ``<name>.csv`` and ``bench-<name>.png``
into ``out_dir`` and returns the rows with a summary and any findings. The modules import
NumPy and the solvers only inside ``run``.
"""

from __future__ import annotations

import importlib

STUDIES = {
    "step-size": "catenet.bench.step_size",
    "pareto": "catenet.bench.pareto",
    "scale": "catenet.bench.scale",
    "baseline": "catenet.bench.baseline",
    "skips": "catenet.bench.skips",
    "cold-start": "catenet.bench.cold_start",
    "stress": "catenet.bench.stress",
}


def study(name: str):
    """The module of a study by its name (``step-size``, ``pareto``, ...)."""
    if name not in STUDIES:
        raise KeyError(f"no study {name!r}: one of {', '.join(STUDIES)}")
    return importlib.import_module(STUDIES[name])
