"""catenet: static and dynamic analysis of elastic cable structures.

Cables are discretised into nodes and edges with the stretching energy of the discrete
catenary; equilibria come from Newton's method on the total potential (``solve_static``)
or from the paper's implicit Euler with damping (``solve_dynamic``).
"""

from catenet.errors import (
    CatenetError,
    ConfigError,
    ConvergenceError,
    OutputError,
    SingularSystemError,
)
from catenet.geometry import Material, SquareNet, cable, graph, pressure_force, square_net
from catenet.net import Loads, Net
from catenet.result import Result

__version__ = "0.1.0"

__all__ = [
    "CatenetError",
    "ConfigError",
    "ConvergenceError",
    "Loads",
    "Material",
    "Net",
    "OutputError",
    "Result",
    "SingularSystemError",
    "SquareNet",
    "Workspace",
    "__version__",
    "cable",
    "continuation",
    "graph",
    "pressure_force",
    "solve_dynamic",
    "solve_static",
    "square_net",
]


def __getattr__(name):  # solvers import Numba: load them on first use
    if name in ("solve_static", "continuation", "Workspace"):
        from catenet import static

        return getattr(static, name)
    if name == "solve_dynamic":
        from catenet.dynamic import solve_dynamic

        return solve_dynamic
    raise AttributeError(f"module 'catenet' has no attribute {name!r}")
