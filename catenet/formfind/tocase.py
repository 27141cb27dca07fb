"""The graph case that holds a form-found net (``to_case``): its positions, edges, EA per
edge and the rest lengths l0 = L / (1 + eps) at which each edge carries its force N = q L
under the case's law, its fixed nodes and loads, and the case's material, solver and
output settings, so that ``catenet run`` on it starts in equilibrium.

A graph case keeps its structure: every node of the built net becomes a given node (in
the same order, so node indices, node sets and the loads' node references hold), the
graph's own edges stay ``edges``, and each cable stays a named cable through all its nodes
(none split again) with its material and the rest length of each of its edges; node sets
are written as the nodes they held (a region as the nodes it selected); point loads keep
their node references (one along a cable: the node there), and the loads that depend on
the geometry (line, area) are written as the nodal forces they gave where the shape was
found."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.errors import ConfigError
from catenet.model.measures import line_mass

if TYPE_CHECKING:
    from catenet.formfind.fdm import FormFound

PREFIX = "formfind."
ROUNDOFF = 64  # a nodal force within this many round-offs of the largest load is none


def to_case(found: FormFound, case=None, *, output_file: str | None = None, scene=None) -> dict:
    """The graph case (a dict of TOML tables) that holds the form-found net. ``case``: the
    case it was found from (its title, material, loads, solver and output settings); None
    for a net made in Python (its law must then be the linear one). ``scene``: the case
    built (a graph's cables, node sets and load nodes are kept then)."""
    net = found.net
    rest = found.rest_length(PREFIX + "force_density")
    structured = scene is not None and case.geometry.kind == "graph"
    if structured:
        geometry = _graph(found, case, scene, rest)
    else:
        geometry = {
            "kind": "graph",
            "nodes": found.x[: net.n_net].tolist(),
            "edges": net.edges.tolist(),
            "rest_length": rest.tolist(),
            "EA": net.EA.tolist(),
            "fixed": np.flatnonzero(net.fixed[: net.n_net]).tolist(),
        }
    load: dict = {}
    const = found.load.copy()
    if case is not None and case.load.gravity is not None:
        load["gravity"] = list(case.load.gravity)
        const -= _weight(net, rest, case.load.gravity)
        scale = float(np.abs(found.load).max(initial=0.0))  # the weight's round-off left
        const[np.abs(const) <= ROUNDOFF * np.finfo(float).eps * scale] = 0.0  # is no load
    points: list[dict[str, Any]] = []
    if structured:
        points, const = _kept_points(case, scene, const)
    if case is not None and scene is not None:
        points += _timed(case, scene, structured, load)
    nodes = np.flatnonzero(np.any(const[: net.n_net] != 0.0, axis=1))  # (not the bodies')
    points += [{"node": int(i), "force": const[i].tolist()} for i in nodes]
    if points:
        load["point"] = points
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
            "units": case.units,  # the numbers below are the case's own
            "material": material,
            "solver": case.solver.to_dict(),
            "output": case.output.to_dict(),
        }
    out["geometry"] = geometry
    out["load"] = load
    if case is not None:
        out.update(_kept_tables(case, scene))
    probe = out.get("output", {}).get("probe")
    if scene is not None and isinstance(probe, str):
        out["output"]["probe"] = _ref(probe, scene)  # ("center" moves with the shape)
    if output_file is not None:
        out.setdefault("output", {})["file"] = output_file
    order = ("title", "units", "geometry", "material", "load", "solver", "output", *TABLES)
    return {k: out[k] for k in order if k in out}


#: The case's arrays of tables the written case keeps (loads of the found net's analysis).
TABLES = ("mass", "obstacle", "load_case", "combination")


def _ref(ref, scene):
    """A node reference of the case as the written case holds it: a named node (e.g.
    "center", found from the geometry, which moves) as its index; a node set or an index
    as given."""
    if isinstance(ref, str) and ref not in (scene.sets or {}) and ref in (scene.names or {}):
        return int(scene.names[ref])
    return ref


def _refs(value, scene):
    if isinstance(value, (list, tuple)):
        return [_ref(r, scene) for r in value]
    return _ref(value, scene)


def _kept_tables(case, scene) -> dict:
    """The point masses, obstacles, load cases and combinations of ``case``, their node
    references kept (named nodes as indices; a point load along a cable: the node there,
    split so when the shape was found)."""
    out: dict = {}
    if scene is None:
        tables = (
            ("mass", case.masses),
            ("obstacle", case.obstacles),
            ("load_case", case.load_cases),
            ("combination", case.combinations),
        )
        return {k: [t.to_dict() for t in items] for k, items in tables if items}
    if case.masses:
        out["mass"] = [{**m.to_dict(), "node": _refs(m.node, scene)} for m in case.masses]
    if case.obstacles:
        out["obstacle"] = [o.to_dict() for o in case.obstacles]
    offset = len(case.load.points)  # the load cases' points along cables follow the base's
    cases = []
    for lc in case.load_cases:
        item = lc.to_dict()
        points = []
        for j, pt in enumerate(lc.points):
            one = pt.to_dict()
            if pt.cable is not None:
                one.pop("cable")
                one.pop("at")
                one = {"node": int(scene.at_nodes[offset + j]), **one}
            else:
                one["node"] = _refs(pt.node, scene)
            points.append(one)
        offset += len(lc.points)
        if points:
            item["point"] = points
        for a, area in zip(item.get("area", ()), lc.areas, strict=True):
            if area.nodes is not None:
                a["nodes"] = _refs(area.nodes, scene)
        cases.append(item)
    if cases:
        out["load_case"] = cases
    if case.combinations:
        out["combination"] = [c.to_dict() for c in case.combinations]
    return out


def _graph(found: FormFound, case, scene, rest: np.ndarray) -> dict:
    """A graph case's geometry with its structure: own edges, cables, node sets."""
    net, g = found.net, case.geometry
    own = np.ones(net.n_edges, dtype=bool) if scene.cables is None else scene.cables.edge < 0
    geometry: dict = {"kind": "graph", "nodes": found.x[: net.n_net].tolist()}
    if own.any():
        geometry["edges"] = net.edges[own].tolist()
        geometry["rest_length"] = rest[own].tolist()
        geometry["EA"] = net.EA[own].tolist()
        if g.tension_only is not None:
            geometry["tension_only"] = list(g.tension_only)
    geometry["fixed"] = np.flatnonzero(net.fixed[: net.n_net]).tolist()  # (bodies' own: not)
    sets = {k: list(v) for k, v in (scene.sets or {}).items() if not k.startswith("cable:")}
    if sets:
        geometry["sets"] = sets
    cables = []
    for c, cable in enumerate(g.cables):
        sel = np.flatnonzero(scene.cables.edge == c)
        chain = [int(net.edges[sel[0], 0]), *net.edges[sel, 1].tolist()]
        item: dict = {"name": cable.name, "nodes": chain, "rest_length": rest[sel].tolist()}
        if cable.material is not None:
            over = cable.material.to_dict()
            over.pop("prestress", None)
            if over:
                item["material"] = over
        cables.append(item)
    if cables:
        geometry["cable"] = cables  # (no edge_length: every cable is written as split)
    return geometry


def _kept_points(case, scene, const: np.ndarray) -> tuple[list, np.ndarray]:
    """The point loads with their node references (one along a cable: the node there),
    and the constant nodal forces left once the constant ones are taken out."""
    points, rest = [], const.copy()
    scale = float(np.abs(const).max(initial=0.0))
    for k, pt in enumerate(case.load.points):
        item = pt.to_dict()
        if pt.cable is not None:
            item.pop("cable")
            item.pop("at")
            item = {"node": int(scene.at_nodes[k]), **item}
        points.append(item)
        if pt.history is None and case.load.history is None:
            ref = item["node"]
            if isinstance(ref, str) and ref not in scene.sets:  # a named node: its index
                ref = item["node"] = int(scene.names[ref])
            for i in scene.sets[ref] if isinstance(ref, str) else (ref,):
                rest[i] -= pt.force
    rest[np.abs(rest) <= ROUNDOFF * np.finfo(float).eps * scale] = 0.0  # the round-off left
    return points, rest


def _timed(case, scene, structured: bool, load: dict) -> list[dict]:
    """The loads that follow a time history (dynamic runs; form finding leaves them out):
    ``load.history`` and, of a graph, its line and area loads with a history as given
    (into ``load``; its point loads are kept with the others); of another kind, each
    timed nodal force as a point load with its history (returned)."""
    timed = case.load.history is not None
    if timed:
        load["history"] = [list(p) for p in case.load.history]
    if structured:
        for key, items in (("line", case.load.lines), ("area", case.load.areas)):
            kept = [t.to_dict() for t in items if timed or t.history is not None]
            for t in kept if key == "area" else ():
                if "nodes" in t:
                    t["nodes"] = _refs(t["nodes"], scene)
            if kept:
                load[key] = kept
        return []
    points = []
    for force, history in scene.loads.parts:
        table = np.column_stack([history.times, history.factors]).tolist()
        for i in np.flatnonzero(np.any(force != 0.0, axis=1)):
            points.append({"node": int(i), "force": force[i].tolist(), "history": table})
    return points


def _weight(net, rest: np.ndarray, gravity) -> np.ndarray:
    return line_mass(net, rest)[:, None] * np.asarray(gravity, dtype=np.float64)[None, :]
