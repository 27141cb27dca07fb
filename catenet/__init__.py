"""catenet: static and dynamic analysis of elastic cable structures.

Cables are discretised into nodes and edges with the stretching energy of the discrete
catenary; equilibria come from Newton's method on the total potential (``solve_static``)
or from the paper's implicit Euler with damping (``solve_dynamic``).

In Python: ``catenet.Scene.of(net, loads)`` with obstacles of any shape
(``.with_obstacle(catenet.Box(...), friction=0.3)``) and ``catenet.solve(scene,
method="dynamic", dt=1e-3)``, the same computation as a case file's.

From a case file: ``catenet.load_case(path)`` (a validated case; ``--set`` overrides as
``overrides=[...]``), ``catenet.run_case(case, out)`` (the run ``catenet run`` makes:
its Result, ``result.report.summary`` the summary's numbers, ``result.cases`` the load cases),
``catenet.read_result(path)`` (a result file). docs/guide/results.md shows them.

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
    "Material": "catenet.model.builders",
    "SquareNet": "catenet.model.builders",
    "cable": "catenet.model.builders",
    "graph": "catenet.model.builders",
    "pressure_force": "catenet.model.builders",
    "square_net": "catenet.model.builders",
    "Loads": "catenet.model.net",
    "Guides": "catenet.model.guides",
    "Elastic": "catenet.model.guides",
    "Net": "catenet.model.net",
    "Modes": "catenet.solver.modes",
    "modes": "catenet.solver.modes",
    "Result": "catenet.solver.result",
    "Workspace": "catenet.solver.workspace",
    "continuation": "catenet.solver.loadsteps",
    "Scene": "catenet.scene",
    "Contact": "catenet.scene.contact",
    "Box": "catenet.scene.shapes.box",
    "Capsule": "catenet.scene.shapes.capsule",
    "Cylinder": "catenet.scene.shapes.cylinder",
    "Mesh": "catenet.scene.shapes.mesh",
    "Plane": "catenet.scene.shapes.plane",
    "Sphere": "catenet.scene.shapes.sphere",
    "Settings": "catenet.solver.path",
    "Start": "catenet.solver.path",
    "solve": "catenet.solver.path",
    "solve_static": "catenet.solver.static",
    "solve_dynamic": "catenet.solver.dynamic",
    "load_case": "catenet.case",
    "parse_case": "catenet.case",
    "build": "catenet.case",
    "run_case": "catenet.run.runner",
    "read_result": "catenet.output",
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
