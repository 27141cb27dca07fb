"""The graph case that holds a form-found net (``to_case``): its positions, edges, EA per
edge and the rest lengths l0 = L / (1 + eps) at which each edge carries its force N = q L
under the case's law, its fixed nodes and loads, and the case's material, solver and
output settings, so that ``catenet run`` on it starts in equilibrium."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError

if TYPE_CHECKING:
    from catenet.formfind.fdm import FormFound

PREFIX = "formfind."


def to_case(found: FormFound, case=None, *, output_file: str | None = None) -> dict:
    """The graph case (a dict of TOML tables) that holds the form-found net. ``case``: the
    case it was found from (its title, material, loads, solver and output settings); None
    for a net made in Python (its law must then be the linear one)."""
    net = found.net
    rest = found.rest_length(PREFIX + "force_density")
    geometry = {
        "kind": "graph",
        "nodes": found.x.tolist(),
        "edges": net.edges.tolist(),
        "rest_length": rest.tolist(),
        "EA": net.EA.tolist(),
        "fixed": np.flatnonzero(net.fixed).tolist(),
    }
    load: dict = {}
    const = found.load.copy()
    if case is not None and case.load.gravity is not None:
        load["gravity"] = list(case.load.gravity)
        const -= _weight(net, rest, case.load.gravity)
    nodes = np.flatnonzero(np.any(const != 0.0, axis=1))
    if nodes.size:
        load["point"] = [{"node": int(i), "force": const[i].tolist()} for i in nodes]
    if case is None:
        if np.any(net.law.kind != 0):
            raise ConfigError("to_case: a net under a nonlinear law needs the case it came from")
        material = {"tension_only": bool(net.law.tension_only.all())}
        out: dict[str, Any] = {"title": "form found", "material": material}
    else:
        material = case.material.to_dict()
        material.pop("prestress", None)
        out = {
            "title": case.title,
            "material": material,
            "solver": case.solver.to_dict(),
            "output": case.output.to_dict(),
        }
    out["geometry"] = geometry
    out["load"] = load
    if output_file is not None:
        out.setdefault("output", {})["file"] = output_file
    order = ("title", "geometry", "material", "load", "solver", "output")
    return {k: out[k] for k in order if k in out}


def _weight(net, rest: np.ndarray, gravity) -> np.ndarray:
    half = 0.5 * net.line_density * rest
    mass = np.bincount(net.edges[:, 0], half, net.n_nodes)
    mass += np.bincount(net.edges[:, 1], half, net.n_nodes)
    return mass[:, None] * np.asarray(gravity, dtype=np.float64)[None, :]
