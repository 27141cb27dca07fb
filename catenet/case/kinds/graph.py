"""geometry.kind = "graph": an explicit net, inline or from a file (JSON, CSV, OBJ, VTK, or a
line mesh meshio reads), with optional cables (catenet/case/kinds/cables.py), node sets
(lists, regions: catenet/case/kinds/regions.py, and "cable:NAME") and per-edge arrays
(rest length, EA, tension-only switch, prestress)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    declared,
    key,
    names,
    parse_keys,
    real,
    tables,
    text,
    value,
)
from catenet.case.kinds import cables as cb
from catenet.case.kinds import graph_keys as gk
from catenet.case.kinds.base import Built, GeometryConfig, Topology, expand, with_prefix
from catenet.case.kinds.netfile import FILE_KEYS, MESH_KEYS, is_mesh, merge_file, read_net_file
from catenet.case.kinds.regions import empty_boxes
from catenet.case.material import model_material
from catenet.errors import ConfigError
from catenet.model import builders as geo
from catenet.model.laws import Law, prestressed_lengths
from catenet.model.net import Net

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class GraphConfig(GeometryConfig):
    """An explicit net. ``fixed`` are its default supports; ``rest_length``, ``EA``,
    ``tension_only`` and ``prestress`` (per edge of ``edges``) are optional; ``cable``
    adds cables through the given nodes, ``sets`` names groups of them. ``file`` records
    where the data came from (not compared, and the resolved case holds the data)."""

    kind: ClassVar[str] = "graph"
    summary: ClassVar[str] = (
        "an explicit net (inline, JSON, CSV, OBJ or a meshio line mesh), with optional cables"
    )
    node_names: ClassVar[tuple[str, ...]] = ("center",)
    default_supports: ClassVar[str] = "geometry.fixed"
    node_sets: ClassVar[bool] = True

    nodes: tuple[Vec3, ...] = key(
        gk.points,
        "an array of at least 2 [x, y, z]",
        missing="[[x, y, z], ...] (at least 2 nodes)",
        unit="m",
        doc="node positions; center is the free node nearest the bounding box's centre",
    )
    edges: tuple[tuple[int, int], ...] = key(
        gk.pairs,
        "an array of [i, j] (node indices)",
        (),
        write="given",
        shown="none (then cables)",
        doc="the edges, each joining two distinct nodes once; at least 1, or cables",
    )
    rest_length: tuple[float, ...] | None = key(
        gk.per_edge,
        "an array with one number > 0 per edge",
        None,
        write="given",
        null=True,
        shown="the initial lengths",
        unit="m",
        doc="unstressed length of each edge",
    )
    EA: tuple[float, ...] | None = key(
        gk.per_edge,
        "an array with one number > 0 per edge",
        None,
        write="given",
        null=True,
        shown="from [material]",
        unit="N",
        doc="axial stiffness of each edge (then [material] may be left out)",
    )
    tension_only: tuple[bool, ...] | None = key(
        gk.per_edge_of("true or false", gk.boolean, "must be true or false"),
        "an array with one true or false per edge",
        None,
        write="given",
        null=True,
        shown="material.tension_only",
        doc="whether each edge goes slack in compression (false: a strut)",
    )
    prestress: tuple[float, ...] | None = key(
        gk.per_edge_of("finite number", gk.finite, "must be a finite number"),
        "an array with one finite number per edge",
        None,
        write="given",
        null=True,
        shown="material.prestress",
        unit="N",
        doc="tension of each edge in the given geometry (rest length derived from it)",
    )
    fixed: tuple[int, ...] = key(
        gk.index_list,
        "an array of node indices",
        (),
        doc="the nodes held fixed (supports.fixed, where given, replaces them; none: a free net)",
    )
    prestrain: float = real(
        0.0, gt=-1, doc="rest lengths = initial / (1 + prestrain); not with rest_length"
    )
    edge_length: float | None = real(
        None,
        gt=0,
        write="given",
        shown="none: a segment is one edge",
        unit="m",
        doc="cables: longest edge after splitting each segment",
    )
    sets: cb.NodeSets | None = cb.sets_key()
    cables: tuple[cb.CableConfig, ...] = tables(
        cb.CableConfig, name="cable", doc="cables: named polylines through the given nodes"
    )
    file: str | None = text(
        None,
        nonempty=True,
        write="never",
        compare=False,
        doc="a JSON file of some of the keys above (relative to the case file; the others "
        "may stay here); or nodes and edges "
        "from a CSV sheet (a table under the header x,y,z, a row per node, and one under i,j, "
        "a row per edge, node k the k-th row from 0; comma, semicolon or tab; flag columns "
        "after x,y,z), an OBJ file of polylines, a VTK file (.vtu, .vtp, .vtk: lines and "
        "polylines) or a line mesh meshio reads (.msh, .ply, .xdmf, ...); point data flags "
        "and gmsh physical groups are node sets; a polyline of more than 2 points, or a "
        "named one, is a cable (docs/guide/loads.md)",
    )

    @classmethod
    def parse(cls, ck: Checker, g: dict, base_dir: Path) -> GraphConfig | None:
        ctx = Context(kind=cls)
        by_name = {k.name: k for k in declared(cls)}
        pre = value(ck, g, by_name["prestrain"], "geometry", ctx)
        file = None
        src: Any = g
        suffix = ""
        read: tuple[str, ...] = ()
        if "file" in g:
            file = value(ck, g, by_name["file"], "geometry", ctx)
            if file is BAD:
                return None
            mesh = is_mesh(file)
            inline = [k for k in MESH_KEYS if k in g]  # (a JSON file's others: below)
            if inline:
                held = ", ".join(MESH_KEYS) if mesh else "the graph's keys"
                ck.add(
                    f"geometry.{inline[0]}: give the graph in geometry.file or inline, not both "
                    f"(geometry.file = {file!r} holds {held})"
                )
                return None
            src = read_net_file(ck, file, base_dir, _DATA)
            if src is None:
                return None
            own = {k: g[k] for k in _DATA if k in g}
            read = FILE_KEYS if mesh else tuple(src)
            if mesh:
                src = merge_file(ck, own, src, file)
                if src is None:
                    return None
            else:
                src = _merge_json(ck, own, src, file)
                if src is None:
                    return None
            suffix = f" (in geometry.file = {file!r})"
        sub = Checker()
        if file is not None and not is_mesh(file):
            sub.keys(src, "geometry", _DATA, " in a graph file")
        data = _parse_data(sub, src, pre)
        for msg in sub.problems:
            from_file = msg.startswith(tuple(f"geometry.{k}" for k in read))
            ck.add(msg + (suffix if from_file else ""))
        if data is None or sub.problems or pre is BAD:
            return None
        config = cls(**data, prestrain=pre, file=file)
        if config.sets is not None and config.sets.regions and config._meshable():
            try:
                built = config._mesh()
            except ConfigError:
                return config  # reported where the net is built
            before = len(ck.problems)
            empty_boxes(ck, config.sets.items, built.nodes)
            if len(ck.problems) > before:
                return None
        return config

    @classmethod
    def gives_stiffness(cls, geometry: GeometryConfig | None) -> bool:
        # None: unknown, do not insist
        return geometry is None or (isinstance(geometry, GraphConfig) and geometry.EA is not None)

    def estimate_size(self) -> tuple[float, float, float, str]:
        n, m = len(self.nodes), len(self.edges)
        lines = self._polylines()
        pairs = [*self.edges, *(p for line in lines for p in zip(line[:-1], line[1:], strict=True))]
        degree = np.bincount(np.array(pairs, dtype=np.int64).reshape(-1).ravel(), minlength=n)
        extra_nodes, extra_edges = cb.estimate(self._xyz(), lines, self._hs())
        key = "geometry.file" if self.file else "geometry.nodes"
        own = [k for k, c in enumerate(self.cables) if c.edge_length is not None]
        if self.cables and (self.edge_length is not None or not own):
            key = "geometry.edge_length"
        elif own:
            key = f"geometry.cable[{own[0]}].edge_length"
        junctions = float(np.count_nonzero(degree > 2))
        return float(n + extra_nodes), float(m + extra_edges), junctions, key

    def topology(self) -> Topology:
        return Topology(
            len(self.nodes),
            frozenset(self.fixed),
            {"center": _center(self.nodes, self.fixed)},
            self._sets(self._mesh() if self._needs_mesh() else None),
            tuple(c.name for c in self.cables),
        )

    def check_supports(
        self, ck: Checker, fixed: set[int], fixed_key: str, flies: bool = False
    ) -> None:
        if flies and not fixed:
            return  # a net flying free (a dynamic run)
        if not fixed:
            ck.add(
                "geometry.fixed: missing or empty: a graph needs supports "
                "(geometry.fixed or supports.fixed) in a static run: without them the net "
                "moves as a rigid body and has no equilibrium; a dynamic run "
                "(solver.method = 'dynamic') lets it fly free"
            )
            return
        mesh = self._mesh()
        rest = self.rest_length if not self.cables else None
        try:
            Net.from_arrays(
                mesh.nodes, mesh.edges, EA=1.0, fixed=sorted(fixed), rest_length=rest, flies=flies
            )
        except ConfigError as exc:
            ck.problems.extend(with_prefix(p, fixed_key) for p in exc.problems)

    def check_material(self, ck: Checker, material: Any) -> None:
        cb.cable_materials(ck, material, self.cables)

    def build_case(self, case: Any, material: geo.Material) -> Built:
        """The case's net: each edge of the graph's own under [material] and its per-edge
        arrays, each cable's under its material (each a ``Material`` carrying its law:
        one law of every edge, ``Law.concat``); rest lengths from the prestress (per edge,
        per cable, or material.prestress) in the given geometry, else from rest_length or
        prestrain; the node of each point load along a cable. (A graph has no build
        without the case: its cables and loads along them need it.)"""
        at: dict[int, list[tuple[float, int]]] = {}
        order = {c.name: k for k, c in enumerate(self.cables)}
        for k, pt in enumerate(case.load.points):
            if pt.cable is not None:
                at.setdefault(order[pt.cable], []).append((pt.at, k))
        mesh = self._mesh(at)
        sets = self._sets(mesh)
        names = self._names(mesh, case.supports.fixed, sets)
        probe = names["center"]
        pinned = self._pinned(case.supports.fixed, names, sets)
        length = _lengths(mesh.nodes, mesh.edges)
        base = case.material
        m0 = len(self.edges)
        mats = cb.cable_materials(Checker(), base, self.cables)
        EA = np.empty(len(mesh.edges))
        rho = np.empty(len(mesh.edges))
        rest = length / (1.0 + self.prestrain)
        if self.rest_length is not None:
            rest[:m0] = self.rest_length
        laws = []
        for c, mat in enumerate([base, *mats]):
            sel = mesh.cable == c - 1
            n = int(np.count_nonzero(sel))
            ea = mat.axial_stiffness
            EA[sel] = self.EA if c == 0 and self.EA is not None else ea
            rho[sel] = mat.line_density
            only = None
            if c == 0 and self.tension_only is not None:
                only = np.asarray(self.tension_only, dtype=bool)
            law = model_material(mat).law_of(n, tension_only=only)
            laws.append(law)
            given = self.cables[c - 1].rest_length if c > 0 else None
            if given is not None:
                rest[sel] = _cable_rest(given, n, c - 1)
                continue
            t0 = mat.prestress
            if c == 0 and self.prestress is not None:
                t0 = np.asarray(self.prestress)
            if t0 is None:
                continue
            if c == 0:
                what = _prestress_key(self.prestress is not None)
            elif self.cables[c - 1].prestress is not None:
                what = lambda k, c=c: f"geometry.cable[{c - 1}].prestress"  # noqa: E731
            elif base.prestress != mat.prestress:
                what = lambda k, c=c: f"geometry.cable[{c - 1}].material.prestress"  # noqa: E731
            else:
                what = _prestress_key(False)
            rest[sel] = prestressed_lengths(
                law, t0, EA[sel], length[sel], what, np.flatnonzero(sel)
            )
        net = Net.from_arrays(
            mesh.nodes,
            mesh.edges,
            EA=EA,
            fixed=pinned,
            rest_length=rest,
            line_density=rho,
            law=Law.concat(laws),
            # a dynamic run needs no support; rollers and springs are checked when added
            flies=case.solver.method == "dynamic" or case.supports.partial,
        )
        cables = self._index(mesh)
        return Built(net, probe, _size(net), names, sets, cables, mesh.at_nodes)

    def given_nodes(self, net: Net) -> int:
        return len(self.nodes)

    # --- helpers --------------------------------------------------------------------------
    def _xyz(self) -> np.ndarray:
        return np.asarray(self.nodes, dtype=np.float64)

    def _needs_mesh(self) -> bool:
        return bool(self.cables) or (self.sets is not None and self.sets.regions)

    def _sets(self, mesh: cb.CableMesh | None = None) -> dict[str, tuple[int, ...]]:
        """The node sets: regions evaluated on the built nodes (the given ones without
        ``mesh``), and "cable:NAME" for every node of each cable."""
        xyz = self._xyz() if mesh is None else mesh.nodes
        out = self.sets.as_dict(xyz) if self.sets is not None else {}
        if mesh is not None:
            for c, cable in enumerate(self.cables):
                out[f"cable:{cable.name}"] = tuple(np.unique(mesh.edges[mesh.cable == c]).tolist())
        return out

    def _hs(self) -> list:
        return [c.edge_length or self.edge_length for c in self.cables]

    def _polylines(self) -> list[tuple[int, ...]]:
        if not self.cables:
            return []
        names = {"center": _center(self.nodes, self.fixed)}
        lines = cb.polylines(Checker(), self.cables, self._xyz(), (), self._sets(), names)
        # (regions of a cable's nodes: evaluated on the given nodes)
        if lines is None:  # checked when parsed
            raise ConfigError("geometry.cable: invalid cables")
        return lines

    def _meshable(self) -> bool:
        """Whether the split net is small enough to build (else the size guard, after
        parsing, names the key that makes it too large)."""
        nodes, edges, _, _ = self.estimate_size()
        return nodes + edges <= geo.MAX_NODES

    def _mesh(self, at=None) -> cb.CableMesh:
        return cb.cable_mesh(self._xyz(), np.asarray(self.edges), self._polylines(), self._hs(), at)

    def _names(self, mesh: cb.CableMesh, fixed: Any, sets: dict) -> dict[str, int]:
        """'center': the free node of the built net (cable subdivisions too) nearest the
        bounding box's centre (a cable-only net's given nodes are often all supports)."""
        given = {"center": _center(self.nodes, self.fixed)}
        if fixed is not None and "center" in fixed:
            return given
        held = self._pinned(fixed, given, sets)
        return {"center": _center(mesh.nodes, held)}

    def _pinned(self, fixed: Any, names: dict, sets: dict) -> list[int]:
        if fixed is None:
            return list(self.fixed)
        return sorted({i for r in fixed for i in expand(r, names, sets)})

    def _index(self, mesh: cb.CableMesh) -> cb.CableIndex | None:
        if not self.cables:
            return None
        return cb.CableIndex(tuple(c.name for c in self.cables), mesh.cable)


#: The keys that give the net (inline, or in the JSON file of geometry.file).
_DATA = tuple(n for n in names(GraphConfig) if n not in ("prestrain", "file"))


def _merge_json(ck: Checker, given: dict, read: dict, file: str) -> dict | None:
    """The graph's keys: the JSON file's and the case file's others (a key in both is
    refused: one place for each)."""
    both = [k for k in read if k in given]
    if both:
        ck.add(
            f"geometry.{both[0]}: given in geometry.file = {file!r} too: give it in one place "
            f"(the file holds {', '.join(k for k in _DATA if k in read)})"
        )
        return None
    return {**given, **read}


def _prestress_key(per_edge: bool):
    if per_edge:
        return lambda k: f"geometry.prestress[{k}]"
    return lambda k: "material.prestress"


def _cable_rest(given: tuple[float, ...], n: int, c: int) -> np.ndarray:
    """The rest lengths a cable gives, one per edge of it after splitting."""
    if len(given) != n:
        raise ConfigError(
            f"geometry.cable[{c}].rest_length: {len(given)} values: the cable has {n} edges "
            "after splitting (one value per edge, in order)"
        )
    return np.asarray(given, dtype=np.float64)


def _lengths(xyz: np.ndarray, edges: np.ndarray) -> np.ndarray:
    return np.linalg.norm(xyz[edges[:, 1]] - xyz[edges[:, 0]], axis=1)


def _size(net: Net) -> float:
    return float(np.linalg.norm(net.nodes.max(axis=0) - net.nodes.min(axis=0)))


def _center(nodes, fixed=()) -> int:
    """The node nearest the bounding box's centre, not in ``fixed`` (unless all are)."""
    xyz = np.asarray(nodes, dtype=np.float64)
    mid = 0.5 * (xyz.min(axis=0) + xyz.max(axis=0))
    dist = np.linalg.norm(xyz - mid, axis=1)
    held = [i for i in fixed if 0 <= i < len(xyz)]
    if len(held) < len(xyz):
        dist[held] = np.inf
    return int(np.argmin(dist))


def _parse_data(ck: Checker, g: dict, pre: Any) -> dict | None:
    """The net's keys checked, then its topology: indices, loops, duplicates, zero or
    overflowing lengths."""
    v = parse_keys(ck, g, GraphConfig, "geometry", Context(kind=GraphConfig), only=_DATA)
    if v["rest_length"] not in (None, BAD) and pre not in (BAD, 0.0):
        ck.add(
            f"geometry.prestrain = {pre!r}: give geometry.rest_length or geometry.prestrain, "
            "not both"
        )
    if v["prestress"] not in (None, BAD):
        for other in ("rest_length", "prestrain"):
            if v.get(other) not in (None, BAD) or (other == "prestrain" and pre not in (BAD, 0.0)):
                ck.add(
                    f"geometry.prestress: gives the rest lengths of the edges: give it or "
                    f"geometry.{other}, not both"
                )
    if v["cables"] not in ((), BAD) and pre not in (BAD, 0.0):
        if any(c.prestress is not None for c in v["cables"]):
            ck.add(
                f"geometry.prestrain = {pre!r}: a cable's prestress gives its rest lengths: "
                "give geometry.prestrain or prestress, not both"
            )
    if v["edges"] == () and v["cables"] == ():
        ck.add(
            "geometry.edges: missing: [[i, j], ...] (at least 1 edge), or cables "
            "([[geometry.cable]] with nodes = [i, j, ...])"
        )
    if BAD in v.values() or ck.problems:
        return None
    nodes, edges, fixed = v["nodes"], v["edges"], v["fixed"]
    n = len(nodes)
    bad_idx = [(f"geometry.edges[{k}]", list(e)) for k, e in enumerate(edges) if max(e) >= n]
    ck.first(bad_idx, f"node indices must be in 0..{n - 1}")
    bad_fixed = [(f"geometry.fixed[{k}]", i) for k, i in enumerate(fixed) if i >= n]
    ck.first(bad_fixed, f"must be a node index in 0..{n - 1}")
    if bad_idx or bad_fixed:
        return None
    e_arr = np.array(edges, dtype=np.int64).reshape(-1, 2)
    xyz = np.array(nodes, dtype=np.float64)
    loops = np.flatnonzero(e_arr[:, 0] == e_arr[:, 1])
    ck.first(
        [(f"geometry.edges[{k}]", list(edges[k])) for k in loops],
        "an edge must join two different nodes",
    )
    key = np.sort(e_arr, axis=1)
    _, counts = np.unique(key, axis=0, return_counts=True)
    seen: dict[tuple[int, int], int] = {}
    dups = []
    if (counts > 1).any():
        for k, pair in enumerate(map(tuple, key.tolist())):
            if pair in seen:
                dups.append((f"geometry.edges[{k}]", list(edges[k]), seen[pair]))
            else:
                seen[pair] = k
    for path, bad, k0 in dups[:5]:
        ck.bad(path, bad, f"repeats geometry.edges[{k0}]: edges must be unique")
    if len(dups) > 5:
        ck.add(f"geometry.edges: {len(dups) - 5} more repeated edges")
    with np.errstate(all="ignore"):
        length = np.linalg.norm(xyz[e_arr[:, 1]] - xyz[e_arr[:, 0]], axis=1)
    is_loop = set(loops.tolist())
    zero = [k for k in np.flatnonzero(~(length > 0)).tolist() if k not in is_loop]
    ck.first(
        [(f"geometry.edges[{k}]", list(edges[k])) for k in zero],
        "zero length: the nodes of an edge must be distinct points",
    )
    huge = np.flatnonzero(~np.isfinite(length))
    ck.first(
        [(f"geometry.edges[{k}]", list(edges[k])) for k in huge],
        "its length overflows: coordinates too large",
    )
    if v["cables"] and not ck.problems:
        sets = v["sets"].as_dict(xyz) if v["sets"] is not None else {}
        cb.polylines(ck, v["cables"], xyz, edges, sets, {"center": _center(nodes, fixed)})
    elif v["sets"] is not None and not ck.problems:
        cb.polylines(ck, (), xyz, edges, v["sets"].as_dict(xyz), {})
    return None if ck.problems else v
