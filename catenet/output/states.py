"""Reading every solved state of a result file for a report (``catenet report``): the
base state (/result), each load case and combination (/cases/<name>), the envelope
(/envelope), the net's cables and node sets by name, and a dynamic run's peaks.

The layout is the writer's (``catenet.output.result_group``, ``catenet.run.cases``,
``catenet.output.netsets``); the file is opened through ``catenet.output.reader``, and a
damaged file or one that is not catenet's gives one ConfigError.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.output.files import read_text
from catenet.output.netsets import read_sets
from catenet.output.reader import DAMAGED, NetMesh, damaged, is_dataset, open_result, read_result

#: The arrays of a state group besides x, by their shape: "M" per edge, "N" per node,
#: "N3" a vector per node.
ARRAYS = {
    "tension": "M",
    "reaction": "N3",
    "contact_force": "N3",
    "utilisation": "M",
    "peak_tension": "M",
    "peak_tension_time": "M",
    "least_tension": "M",
    "peak_displacement": "N",
    "peak_displacement_time": "N",
    "peak_utilisation": "M",
    "support_utilisation": "N",
}
#: The envelope's arrays by their shape.
ENVELOPE = {
    "tension_max": "M",
    "tension_min": "M",
    "displacement_max": "N",
    "utilisation_max": "M",
    "support_utilisation_max": "N",
}


@dataclass
class State:
    """One solved state: ``name`` ("base" for /result), ``kind`` ("base", "load_case",
    "combination"), positions ``x`` (N, 3) [m], the arrays of ``ARRAYS`` it holds (by
    name; tension (M,) [N], reaction and contact_force (N, 3) [N], utilisation (M,),
    a run's peaks) and its attributes (converged, stability, message, error, ...)."""

    name: str
    kind: str
    x: np.ndarray
    arrays: dict[str, np.ndarray]
    attrs: dict

    def get(self, name: str) -> np.ndarray | None:
        return self.arrays.get(name)


@dataclass
class States:
    """A result file's states for a report: ``mesh`` (the net, ``NetMesh``), the ``case``
    (its resolved TOML as a dict), ``title``, ``method`` ("static" | "dynamic"), the
    states (the base first, then the cases in the file's order), the ``envelope``'s
    arrays ({} without cases) and its ``envelope_cases`` (the names its ``*_case``
    indices refer to), the cables (``cable`` (M,) each edge's index into
    ``cable_names``, -1: none; None: the file names none) and the node ``sets``."""

    path: Path
    mesh: NetMesh
    case: dict
    title: str
    method: str
    states: list[State]
    envelope: dict[str, np.ndarray] = field(default_factory=dict)
    envelope_cases: tuple[str, ...] = ()
    cable: np.ndarray | None = None
    cable_names: tuple[str, ...] = ()
    sets: dict[str, np.ndarray] = field(default_factory=dict)


def read_states(path: str | Path) -> States:
    """Every state of the result file ``path`` (ConfigError: missing, not HDF5, not a
    catenet result file, damaged)."""
    head = read_result(path)  # the layout checked, a killed run's last frame as /result
    m, n = len(head.mesh.edges), len(head.mesh.nodes)
    shapes: dict[str, tuple[int, ...]] = {"M": (m,), "N": (n,), "N3": (n, 3)}
    try:
        with open_result(head.path) as h5:
            base = _state(h5.get("result"), "base", "base", head.x, head.tension, shapes)
            states = [base]
            envelope, env_cases = _envelope(h5.get("envelope"), shapes)
            cases = h5.get("cases")
            if cases is not None:  # in the order solved (the envelope's), else by name
                order = [n for n in env_cases if n in cases]
                order += sorted(n for n in cases if n not in order)
                for name in order:
                    g = cases[name]
                    kind = str(_plain(g.attrs.get("kind", "load_case")))
                    states.append(_state(g, str(name), kind, None, None, shapes))
            mesh = h5["mesh"]
            cable, names = _cables(mesh, len(head.mesh.edges))
            sets = read_sets(mesh)
    except ConfigError:
        raise
    except DAMAGED as exc:
        raise damaged(head.path, exc) from None
    method = head.method or "static"
    return States(
        path=head.path,
        mesh=head.mesh,
        case=head.case,
        title=head.title,
        method=method,
        states=states,
        envelope=envelope,
        envelope_cases=env_cases,
        cable=cable,
        cable_names=names,
        sets=sets,
    )


def _array(g, key: str, shape: tuple, dtype=np.float64) -> np.ndarray:
    """The dataset ``key`` of the group ``g`` in ``shape`` (ValueError naming it when
    it is not: the file is damaged)."""
    obj = g.get(key)
    if not is_dataset(obj) or obj.shape != shape:
        got = obj.shape if is_dataset(obj) else "a group"
        raise ValueError(f"{g.name}/{key} is {got}: must be of shape {shape}")
    return np.asarray(obj[()], dtype=dtype)


def _state(g, name: str, kind: str, x, tension, shapes: dict) -> State:
    """The State of the group ``g`` (None: /result missing; ``x``, ``tension``: the
    reader's, a killed run's last frame); ``shapes``: "M", "N", "N3" as tuples."""
    arrays: dict[str, np.ndarray] = {}
    attrs: dict = {}
    if g is not None:
        attrs = {k: _plain(v) for k, v in g.attrs.items()}
        for key, shape in ARRAYS.items():
            if key in g:
                arrays[key] = _array(g, key, shapes[shape])
        if x is None:
            x = _array(g, "x", shapes["N3"])
    if tension is not None:
        arrays["tension"] = np.asarray(tension, dtype=np.float64)
    return State(name, kind, np.asarray(x, dtype=np.float64), arrays, attrs)


def _envelope(g, shapes: dict) -> tuple[dict[str, np.ndarray], tuple[str, ...]]:
    """The envelope's arrays (and their ``*_case`` indices into the names of the cases,
    checked) and those names."""
    if g is None:
        return {}, ()
    names = tuple(str(_plain(c)) for c in np.atleast_1d(g.attrs.get("cases", ())))
    arrays = {}
    for key, shape in ENVELOPE.items():
        if key in g:
            arrays[key] = _array(g, key, shapes[shape])
            if f"{key}_case" in g:
                index = _array(g, f"{key}_case", shapes[shape], np.int64)
                if index.size and not (0 <= index.min() and index.max() < len(names)):
                    raise ValueError(f"{g.name}/{key}_case: indices beyond its {len(names)} cases")
                arrays[f"{key}_case"] = index
    return arrays, names


def _cables(mesh, n_edges: int) -> tuple[np.ndarray | None, tuple[str, ...]]:
    """/mesh/cable and its names, where the file has them in the right shape."""
    cable = mesh.get("cable")
    names = mesh.attrs.get("cable_names")
    if not is_dataset(cable) or names is None or cable.shape != (n_edges,):
        return None, ()
    return np.asarray(cable, dtype=np.int64), tuple(_plain(n) for n in names)


def _plain(v):
    """An attribute as a plain Python value (bytes decoded, NumPy scalars unwrapped)."""
    if isinstance(v, bytes | str):
        return read_text(v)
    if isinstance(v, np.generic):
        return v.item()
    return v
