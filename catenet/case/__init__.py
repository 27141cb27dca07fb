"""Case files: TOML -> validated frozen dataclasses -> a scene (net and loads) to solve.

``load_case`` reads a TOML file (or the bundled default), applies ``--set`` overrides to the
raw table and hands it to ``parse_case``, which checks every key before anything is
computed and reports all problems at once in one ``ConfigError``, each as
``key.path = value: what is accepted``. ``build`` turns a ``Case`` into a ``Scene``: the
``Net``, its ``Loads``, the probe node whose deflection is reported and the length scale.

The package, by job: keys.py (how a key is declared and checked), kinds/ (the geometry
kinds, registered by name), sections.py (material, supports, load, solver, output),
guard.py (the memory guard), nodes.py (node references), parse.py (the whole case),
scene.py (building), toml.py (reading, overrides, writing), readme.py (the README table
of keys, generated from the declarations).
"""

from catenet.case.guard import (
    MEMORY_SHARE,
    estimate_memory,
    estimate_size,
    physical_memory,
)
from catenet.case.kinds import (
    KINDS,
    GeometryConfig,
    GraphConfig,
    SingleCableConfig,
    SquareNetConfig,
)
from catenet.case.parse import Case, load_case, parse_case
from catenet.case.scene import Scene, build
from catenet.case.sections import (
    LINEAR,
    METHODS,
    LoadConfig,
    MaterialConfig,
    MoveConfig,
    OutputConfig,
    PointLoadConfig,
    SolverConfig,
    SupportsConfig,
)
from catenet.case.toml import apply_overrides, dumps_toml, parse_toml, read_case_bytes
from catenet.model.builders import MAX_NODES

__all__ = [
    "KINDS",
    "LINEAR",
    "MAX_NODES",
    "MEMORY_SHARE",
    "METHODS",
    "SingleCableConfig",
    "Case",
    "GeometryConfig",
    "GraphConfig",
    "LoadConfig",
    "MaterialConfig",
    "MoveConfig",
    "OutputConfig",
    "PointLoadConfig",
    "Scene",
    "SolverConfig",
    "SquareNetConfig",
    "SupportsConfig",
    "apply_overrides",
    "build",
    "dumps_toml",
    "estimate_memory",
    "estimate_size",
    "load_case",
    "parse_case",
    "parse_toml",
    "physical_memory",
    "read_case_bytes",
]
