"""catenet: static and dynamic analysis of elastic cable structures.

Cables are discretised into nodes and edges with the stretching energy of the discrete
catenary; equilibria come from Newton's method on the total potential (``solve_static``)
or from the paper's implicit Euler with damping (``solve_dynamic``).

Names are loaded on first use, so that ``catenet --help`` does not import NumPy or Numba.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_NAMES = {
    "CatenetError": "catenet.errors",
    "ConfigError": "catenet.errors",
    "ConvergenceError": "catenet.errors",
    "OutputError": "catenet.errors",
    "SingularSystemError": "catenet.errors",
    "Material": "catenet.geometry",
    "SquareNet": "catenet.geometry",
    "cable": "catenet.geometry",
    "graph": "catenet.geometry",
    "pressure_force": "catenet.geometry",
    "square_net": "catenet.geometry",
    "Loads": "catenet.net",
    "Net": "catenet.net",
    "Result": "catenet.result",
    "Workspace": "catenet.static",
    "continuation": "catenet.static",
    "solve_static": "catenet.static",
    "solve_dynamic": "catenet.dynamic",
}

__all__ = sorted(_NAMES) + ["__version__"]


def __getattr__(name: str):
    module = _NAMES.get(name)
    if module is None:
        raise AttributeError(f"module 'catenet' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
