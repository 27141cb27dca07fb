"""Reading a graph from ``geometry.file``: a JSON object of the graph's keys, a CSV file
of two tables (nodes ``x,y,z`` and edges ``i,j``, as a spreadsheet saves them: see
``_read_csv``), a Wavefront OBJ file of polylines (``v`` and ``l`` lines, read here), a
VTK file (``.vtu``, ``.vtp``, legacy ``.vtk``: read here, catenet/case/kinds/vtkfile.py)
or any other line mesh that meshio reads (``.msh``, ``.ply``, ``.xdmf``, ...: its ``line``
cells are the edges, its point data flags and named groups of cells, such as gmsh's
physical groups, node sets; meshio is imported only then, and is optional).

A mesh file gives the nodes, the edges and the cables: a polyline of more than two points,
or one with a name (an OBJ ``o`` or ``g`` name, a VTK cell data array ``name``), is a
cable, named so or ``line<k>`` (k its place among the file's lines, from 0); a segment of
two points is an edge. Point data arrays of 0/1 flags (e.g. ``fixed``: of a VTK file or
any mesh meshio reads, or flag columns of a CSV nodes table) are node sets; an OBJ file
carries none (a set named that is not there says so). The other graph keys (supports,
more node sets, per-edge arrays) stay in the case file. Problems are recorded in a
Checker with the key ``geometry.file`` and the file's path.
"""

from __future__ import annotations

import json
import logging
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from catenet.case.keys import Checker, carried, too_large
from catenet.scene.meshfiles import read_mesh_file

log = logging.getLogger(__name__)

#: What a mesh file gives (the graph's other keys stay in the case file).
MESH_KEYS = ("nodes", "edges")
#: The keys whose problems are the file's.
FILE_KEYS = ("nodes", "edges", "cable")
VTK = (".vtu", ".vtp", ".vtk")


def is_mesh(file: str) -> bool:
    """Whether ``file`` is read as a mesh (OBJ or a meshio format), not as JSON."""
    return Path(file).suffix.lower() not in ("", ".json")


def read_net_file(ck: Checker, file: str, base_dir: Path, keys: tuple[str, ...]) -> dict | None:
    """The graph's keys from ``file`` (relative to ``base_dir``); ``keys`` are those a
    JSON file may hold. None when it cannot be read (the problem is in ``ck``)."""
    path = Path(file) if Path(file).is_absolute() else base_dir / file
    label = f"geometry.file = {file!r}"
    if not path.is_file():
        what = "is a directory" if path.is_dir() else "no such file"
        ck.add(f"{label}: {what} ({path})")
        return None
    if not is_mesh(file):
        return _read_json(ck, path, label, keys)
    if path.suffix.lower() == ".obj":
        return _read_obj(ck, path, label)
    if path.suffix.lower() in (".csv", ".txt"):
        return _read_csv(ck, path, label)
    if path.suffix.lower() in VTK:
        return _read_vtk(ck, path, label)
    return _read_meshio(ck, path, label)


def merge_file(ck: Checker, given: dict, read: dict, file: str) -> dict | None:
    """The graph's keys: the case file's ``given`` ones and what the mesh file gave
    (nodes, edges, cables, node sets; the case's node sets win over the file's flags)."""
    own = dict(given)
    if "cable" in read and "cable" in own:
        ck.add(
            f"geometry.cable: geometry.file = {file!r} gives the cables (its polylines): "
            "give them in one place"
        )
        return None
    flags = read.pop("sets", {})
    if flags:
        sets = own.get("sets")
        own["sets"] = {**flags, **(sets if isinstance(sets, dict) else {})}
    return {**own, **read}


def _net(nodes, lines, names, label: str, ck: Checker) -> dict | None:
    """Nodes, edges and cables from polylines (see the module's note)."""
    edges: list[list[int]] = []
    cables: list[dict[str, Any]] = []
    for k, line in enumerate(lines):
        idx = [int(i) for i in line]
        name = names[k] if names is not None and names[k] else None
        if len(idx) == 2 and name is None:
            edges.append(idx)
        else:
            cables.append({"name": name or f"line{k}", "nodes": idx})
    seen: dict[str, int] = {}
    for c in cables:
        n = seen[c["name"]] = seen.get(c["name"], 0) + 1
        if n > 1:
            c["name"] = f"{c['name']}#{n}"  # a repeated name: the second "a#2", ...
    out: dict = {"nodes": nodes}
    if edges:
        out["edges"] = edges
    if cables:
        out["cable"] = cables
    if not edges and not cables:
        ck.add(f"{label}: holds no lines: nothing to make edges or cables of")
        return None
    return out


def _read_vtk(ck: Checker, path: Path, label: str) -> dict | None:
    from catenet.case.kinds.vtkfile import VtkError, read_vtk

    try:
        got = read_vtk(path)
    except VtkError as exc:
        ck.add(f"{label}: cannot read it as VTK: {exc}")
        return None
    except (OSError, ValueError, IndexError, KeyError, zlib.error) as exc:
        kind = type(exc).__name__
        ck.add(f"{label}: cannot read it as VTK (a damaged or unsupported file: {kind})")
        return None
    n = len(got.points)
    if not got.lines:
        found = ", ".join(got.skipped) or "no cells"
        ck.add(
            f"{label}: holds no line cells (it has {found}): catenet reads a mesh's lines "
            "and polylines"
        )
        return None
    for k, line in enumerate(got.lines):
        if len(line) < 2 or line.min() < 0 or line.max() >= n:
            ck.add(
                f"{label}: line {k} ({line.tolist()}): needs at least 2 of the file's {n} points"
            )
            return None
    if got.skipped:
        log.warning("%s: ignoring its %s", path, ", ".join(got.skipped))
    if not np.all(np.isfinite(got.points)):
        ck.add(f"{label}: its points have non-finite coordinates")
        return None
    out = _net(got.points.tolist(), got.lines, got.names, label, ck)
    sets = flag_sets(got.point_data)
    if out is not None and sets:
        out["sets"] = sets
    return out


def flag_sets(point_data) -> dict[str, list[int]]:
    """The node sets of point data arrays of 0/1 flags, one value per point (each set:
    the points where it is 1); other arrays are not node sets."""
    sets = {}
    for name, values in point_data.items():
        v = np.asarray(values)
        if v.ndim == 2 and v.shape[1] == 1:
            v = v[:, 0]
        if v.ndim != 1 or v.dtype.kind not in "biuf":
            continue
        if name and np.all((v == 0) | (v == 1)) and v.any():
            sets[str(name)] = np.flatnonzero(v).tolist()
    return sets


#: The net files that carry no point data (so no flags), by suffix, as messages name them.
NO_FLAGS = {".obj": "an OBJ file", ".json": "a JSON file", "": "a JSON file"}


def flag_note(file: str | None) -> str:
    """Why a net file gives no node set of a name, for a message: its format carries no
    point data (OBJ; JSON holds its node sets as ``sets``); "" for the others."""
    if not file:
        return ""
    what = NO_FLAGS.get(Path(file).suffix.lower())
    if what is None:
        return ""
    if what.startswith("a JSON"):
        return f"; geometry.file = {file!r} is {what}: its node sets are its 'sets'"
    return (
        f"; geometry.file = {file!r} is {what}, which carries no point data flags: name "
        "the nodes in [geometry.sets] (by region: { box = ... }), or give the net as "
        ".vtu, .vtp, .vtk, .msh or CSV with flag columns"
    )


def _read_text(ck: Checker, path: Path, label: str) -> str | None:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        ck.add(f"{label}: cannot read {path}: {reason}")
        return None


def _read_json(ck: Checker, path: Path, label: str, keys: tuple[str, ...]) -> dict | None:
    text = _read_text(ck, path, label)
    if text is None:
        return None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        ck.add(f"{label}: not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}")
        return None
    except (ValueError, RecursionError) as exc:
        ck.add(f"{label}: not valid JSON: {exc}")
        return None
    if not isinstance(obj, dict):
        ck.add(
            f"{label}: must hold a JSON object with keys {', '.join(keys)}, "
            f"not {type(obj).__name__}"
        )
        return None
    return obj


def _read_obj(ck: Checker, path: Path, label: str) -> dict | None:
    """Vertices (``v x y z``) and polylines (``l i j k ...``, 1-based, negative indices
    count back from the last vertex so far), named by the ``o`` or ``g`` line before them;
    faces and the rest are ignored."""
    text = _read_text(ck, path, label)
    if text is None:
        return None
    nodes: list[list[float]] = []
    lines: list[list[int]] = []
    names: list[str | None] = []
    group = None
    for lineno, raw in enumerate(text.splitlines(), 1):
        parts = raw.split("#", 1)[0].split()
        if parts and parts[0] in ("o", "g"):
            group = " ".join(parts[1:]) or None
            continue
        if not parts or parts[0] not in ("v", "l"):
            continue
        try:
            if parts[0] == "v":
                xyz = [float(c) for c in parts[1:4]]
                if len(xyz) < 2:
                    raise ValueError("a vertex needs x and y")
                nodes.append(xyz + [0.0] * (3 - len(xyz)))
                continue
            idx = [int(p.split("/")[0]) for p in parts[1:]]
        except ValueError as exc:
            ck.add(f"{label}: line {lineno}: {raw.strip()!r}: {exc}")
            return None
        idx = [i - 1 if i > 0 else len(nodes) + i for i in idx]
        if len(idx) < 2 or any(not 0 <= i < len(nodes) for i in idx):
            ck.add(
                f"{label}: line {lineno}: {raw.strip()!r}: a polyline needs at least 2 "
                f"vertices defined before it (1..{len(nodes)})"
            )
            return None
        lines.append(idx)
        names.append(group)
    if not lines:
        ck.add(f"{label}: holds no polylines (OBJ 'l' lines): nothing to make edges of")
        return None
    return _net(nodes, lines, names, label, ck)


CSV_HEADERS = {("x", "y", "z"): "nodes", ("x", "y"): "nodes", ("i", "j"): "edges"}


def _read_csv(ck: Checker, path: Path, label: str) -> dict | None:
    """Two tables in one sheet, each under its header row: ``x,y,z`` (or ``x,y``, z = 0)
    then one row per node, and ``i,j`` then one row per edge (node k is the k-th row of
    the nodes table, counting from 0). Columns after x, y, z of the nodes table are flags
    (0 or 1) that name node sets: ``x,y,z,fixed``. Separators: comma, semicolon or tab
    (the first header's); blank lines, empty trailing cells and lines starting with #
    are skipped."""
    import csv

    text = _read_text(ck, path, label)
    if text is None:
        return None
    lines = text.lstrip("\ufeff").splitlines()  # (Excel writes a byte-order mark)
    first = next((ln for ln in lines if ln.strip() and not ln.lstrip().startswith("#")), "")
    sep = next((c for c in (";", "\t", ",") if c in first), ",")
    sheet = _Sheet()
    for lineno, row in enumerate(csv.reader(lines, delimiter=sep), 1):
        cells = [c.strip() for c in row]
        while cells and not cells[-1]:
            cells.pop()
        if not cells or cells[0].startswith("#"):
            continue
        header = tuple(c.lower() for c in cells)
        lead = _coordinates(header)
        if header in CSV_HEADERS or lead:
            problem = sheet.start(cells, header, lead)
        else:
            problem = sheet.add(cells)
        if problem is not None:
            ck.add(f"{label}: line {lineno}: {sep.join(row).strip()!r}: {problem}")
            return None
    tables = sheet.tables
    missing = [t for t in ("nodes", "edges") if not tables[t]]
    if missing:
        head = "'x,y,z'" if missing[0] == "nodes" else "'i,j'"
        ck.add(f"{label}: has no {missing[0]}: give a header row {head} and a row per one")
        return None
    sets = flag_sets({k: np.array(v, dtype=bool) for k, v in sheet.flags.items()})
    return {**tables, "sets": sets} if sets else tables


@dataclass
class _Sheet:
    """The tables of a CSV net file as its rows are read: ``table`` the one under way
    (None before the first header row), ``width`` its columns; the nodes table's ``xyz``
    coordinate columns, then its ``flags`` columns (name -> a value per node)."""

    tables: dict[str, list] = field(default_factory=lambda: {"nodes": [], "edges": []})
    seen: set[str] = field(default_factory=set)
    table: str | None = None
    width: int = 0
    xyz: int = 3
    flags: dict[str, list[bool]] = field(default_factory=dict)

    def start(self, cells: list[str], header: tuple[str, ...], lead: int) -> str | None:
        """Starts the table a header row opens (``lead``: its coordinate columns before
        flag columns, 0 for none); what is wrong with the row, or None."""
        self.table = CSV_HEADERS.get(header, "nodes")
        if self.table in self.seen:
            return f"a second {self.table} table"
        self.seen.add(self.table)
        self.width = len(header)
        if self.table == "nodes":
            self.xyz = lead or self.width
            self.flags = {name: [] for name in cells[self.xyz :]}
            if len(self.flags) < self.width - self.xyz:
                return "a flag column named twice"
        return None

    def add(self, cells: list[str]) -> str | None:
        """Adds a row to the table under way; what is wrong with the row, or None."""
        if self.table is None:
            accepted = " or ".join(repr(",".join(h)) for h in CSV_HEADERS)
            return f"must start with a header row {accepted}"
        if len(cells) != self.width:
            return f"has {len(cells)} cells: the {self.table} table has {self.width} columns"
        try:
            if self.table == "nodes":
                problem = self._add_node(cells)
                if problem is not None:
                    return problem
            else:
                self.tables["edges"].append([int(c) for c in cells])
        except ValueError:
            need = (
                f"finite numbers within {too_large()}"
                if self.table == "nodes"
                else "node indices (0, 1, ...)"
            )
            return f"the {self.table} table holds {need}"
        if self.table == "edges":
            return self._edge_problem()
        return None

    def _add_node(self, cells: list[str]) -> str | None:
        """Adds a row of the nodes table (ValueError for a coordinate that is not a
        finite number); what is wrong with its flags, or None."""
        coords = [float(c) for c in cells[: self.xyz]]
        if not all(map(carried, coords)):
            raise ValueError
        self.tables["nodes"].append(coords + [0.0] * (3 - self.xyz))
        for name, c in zip(self.flags, cells[self.xyz :], strict=True):
            if c not in ("0", "1"):
                return (
                    f"the flag column {name!r} holds 0 or 1 (a node set: its nodes are the "
                    f"rows with 1), not {c!r}"
                )
            self.flags[name].append(c == "1")
        return None

    def _edge_problem(self) -> str | None:
        """What is wrong with the last edge: a node that is no row of the nodes table."""
        n = len(self.tables["nodes"]) if "nodes" in self.seen else None
        bad = [k for k in self.tables["edges"][-1] if k < 0 or (n is not None and k >= n)]
        if not bad:
            return None
        rows = f"0..{n - 1}" if n is not None else "counting from 0"
        return f"node {bad[0]} is not a row of the nodes table ({rows})"


def _coordinates(header: tuple[str, ...]) -> int:
    """How many coordinate columns (x, y[, z]) a nodes table's header starts with when
    flag columns follow them; 0 otherwise."""
    if len(header) > 3 and header[:3] == ("x", "y", "z"):
        return 3
    if len(header) > 2 and header[:2] == ("x", "y") and header[2] != "z":
        return 2
    return 0


def _read_meshio(ck: Checker, path: Path, label: str) -> dict | None:
    try:  # (meshio prints its own message and exits for a file none of its readers takes)
        mesh = read_mesh_file(path)
    except ImportError:
        ck.add(
            f"{label}: reading {path.suffix} files needs the Python package meshio, which "
            "is not installed (pip install meshio), or give the graph as JSON or OBJ"
        )
        return None
    except ValueError:  # (meshio's own words name its internals, not the user's file)
        ck.add(
            f"{label}: cannot read it as a {path.suffix or 'suffix-less'} mesh (through meshio): "
            "give a mesh of line cells in a format meshio reads, or the net as .vtu, .vtp, "
            ".vtk, OBJ, CSV or JSON"
        )
        return None
    lines = [c.data for c in mesh.cells if c.type == "line"]
    if not lines:
        found = ", ".join(sorted({c.type for c in mesh.cells})) or "no cells"
        ck.add(f"{label}: holds no line cells (it has {found}): catenet reads a mesh's lines")
        return None
    other = sorted({c.type for c in mesh.cells if c.type not in ("line", "vertex")})
    if other:
        log.warning("%s: ignoring its cells of type %s", path, ", ".join(other))
    points = np.asarray(mesh.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        ck.add(f"{label}: its points have shape {points.shape}: must be 2D or 3D")
        return None
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    edges = np.concatenate([np.asarray(d, dtype=np.int64) for d in lines])
    out: dict = {"nodes": points.tolist(), "edges": edges.tolist()}
    sets = {**_group_sets(mesh), **flag_sets(mesh.point_data)}
    if sets:
        out["sets"] = sets
    return out


def _group_sets(mesh) -> dict[str, list[int]]:
    """The node sets of a mesh's named groups of cells, each the points of its cells:
    gmsh's physical groups (a Physical Point, Curve, ...: ``field_data`` name -> [tag,
    dimension], the cells' ``gmsh:physical`` tags) and meshio's ``cell_sets``."""
    groups: dict[str, list] = {}
    physical = (getattr(mesh, "cell_data", None) or {}).get("gmsh:physical")
    for name, value in (getattr(mesh, "field_data", None) or {}).items():
        tag_dim = np.asarray(value).ravel()
        if physical is None or len(tag_dim) != 2:
            continue
        tag, dim = int(tag_dim[0]), int(tag_dim[1])
        for cells, tags in zip(mesh.cells, physical, strict=False):
            if CELL_DIMENSION.get(cells.type) == dim:
                groups.setdefault(str(name), []).append(np.asarray(cells.data)[tags == tag])
    for name, blocks in (getattr(mesh, "cell_sets", None) or {}).items():
        if str(name).startswith("gmsh:"):
            continue
        for cells, idx in zip(mesh.cells, blocks, strict=False):
            if idx is not None and len(idx):
                chosen = np.asarray(cells.data)[np.asarray(idx, dtype=np.int64)]
                groups.setdefault(str(name), []).append(chosen)
    sets = {}
    for name, parts in groups.items():
        nodes = np.unique(np.concatenate([part.ravel() for part in parts]))
        if name and nodes.size:
            sets[name] = nodes.astype(int).tolist()
    return sets


#: The dimension of meshio's cell types that gmsh's physical groups hold.
CELL_DIMENSION = {
    **{"vertex": 0, "line": 1, "line3": 1},
    **{"triangle": 2, "triangle6": 2, "quad": 2, "quad8": 2, "quad9": 2},
    **{"tetra": 3, "hexahedron": 3},
}
