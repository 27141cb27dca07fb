"""The XDMF 3 sidecar of a result file: ``OUT.xdmf`` next to ``OUT.h5``, for ParaView and
VTK (pyvista), meshio's time-series reader, and ``meshio.read`` for a file that holds only
its final state.

The sidecar holds no data: every DataItem names a whole HDF5 dataset. A trajectory is a
Temporal collection with one Polyline grid per frame; frame k's geometry, tensions and
velocities are the datasets ``/xdmf/x/k``, ``/xdmf/tension/k`` and ``/xdmf/v/k``: virtual
datasets (HDF5 1.10) that map frame k of ``/trajectory/x`` and the others, so they cost
metadata only and the trajectory stays where contract §5 puts it. (meshio reads whole
datasets only, not XDMF HyperSlabs, hence these views.) Each frame also carries its
positions as the point attribute ``position``: meshio's time-series reader takes the
geometry of the first grid only. A file without a trajectory gets one grid of /result.

``write_views`` adds the views of new frames to an open file; ``write_xdmf`` writes the
sidecar (atomically). The writer (``catenet.output.writer``) and ``recover``
(``catenet.output.reader``) say what to write.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

VIEWS = "xdmf"  # the group of the per-frame views

__all__ = ["VIEWS", "sidecar_path", "view_sources", "write_views", "write_xdmf"]


def sidecar_path(path: str | Path) -> Path:
    """The XDMF sidecar of a result file: ``OUT.xdmf`` next to ``OUT.h5``."""
    return Path(path).with_suffix(".xdmf")


# --------------------------------------------------------------------------------------------
# Per-frame views in the HDF5 file
# --------------------------------------------------------------------------------------------


def view_sources(traj) -> list[str]:
    """The per-frame datasets of a /trajectory group that have views, relative to it: x,
    tension, v and each moving obstacle's vertices (``catenet.output.obstacles``)."""
    names = [name for name in ("x", "tension", "v") if name in traj]
    obstacles = traj.get("obstacles")
    if obstacles is not None:
        keys = sorted(obstacles, key=int)
        names += [f"obstacles/{k}/vertices" for k in keys if "vertices" in obstacles[k]]
    return names


def write_views(h5, start: int, stop: int) -> None:
    """Adds the views ``/xdmf/<name>/<k>`` of frames ``start <= k < stop`` (those it lacks)
    of every per-frame dataset ``view_sources`` names to an open, writable
    file. A view maps one frame of its source (same file, named "."), so a trajectory
    that grows later keeps its views valid."""
    from h5py import h5d, h5p, h5s, h5t

    traj = h5.get("trajectory")
    if traj is None or stop <= start:
        return
    base = h5p.create(h5p.DATASET_CREATE)
    base.set_fill_value(np.array(np.nan))
    for name in view_sources(traj):
        tail = tuple(traj[name].shape[1:])
        group = h5.require_group(f"{VIEWS}/{name}").id
        view = h5s.create_simple(tail)
        whole = h5s.create_simple((stop, *tail), (h5s.UNLIMITED, *tail))
        target = f"/trajectory/{name}".encode()
        zeros = (0,) * len(tail)
        for k in range(start, stop):
            if str(k).encode() in group:  # made by a write broken off, then done again
                continue
            dcpl = base.copy()
            whole.select_hyperslab((k, *zeros), (1, *tail))
            dcpl.set_virtual(view, b".", target, whole)
            h5d.create(group, str(k).encode(), h5t.IEEE_F64LE, view, dcpl=dcpl).close()


# --------------------------------------------------------------------------------------------
# The sidecar
# --------------------------------------------------------------------------------------------


def _hdf_item(parent, h5name: str, dataset: str, dims: Iterable[int], number: str = "Float"):
    item = ET.SubElement(
        parent,
        "DataItem",
        Format="HDF",
        NumberType=number,
        Precision="8",
        Dimensions=" ".join(map(str, dims)),
    )
    item.text = f"{h5name}:{dataset}"
    return item


def _uniform(parent, name: str, h5name: str, topology: str, per: int, count: int, cells: str):
    """A Uniform grid of ``count`` cells of ``per`` nodes each (the dataset ``cells``)."""
    grid = ET.SubElement(parent, "Grid", Name=name, GridType="Uniform")
    topo = ET.SubElement(
        grid,
        "Topology",
        TopologyType=topology,
        NodesPerElement=str(per),
        NumberOfElements=str(count),
    )
    _hdf_item(topo, h5name, cells, (count, per), number="Int")
    return grid


def _grid(parent, name: str, h5name: str, n_edges: int):
    return _uniform(parent, name, h5name, "Polyline", 2, n_edges, "/mesh/edges")


def _attribute(grid, name: str, center: str, kind: str):
    return ET.SubElement(grid, "Attribute", Name=name, AttributeType=kind, Center=center)


def _surface(parent, name: str, h5name: str, grid, geometry: str):
    """A Uniform grid of an obstacle's triangles with the vertices ``geometry``."""
    out = _uniform(parent, name, h5name, "Triangle", 3, grid.triangles, grid.topology)
    geom = ET.SubElement(out, "Geometry", GeometryType="XYZ")
    _hdf_item(geom, h5name, geometry, (grid.vertices, 3))
    return out


def _obstacles(domain, h5name: str, obstacles: Sequence, times: Stamps) -> None:
    """The obstacles' grids (see ``write_xdmf``)."""
    still = [g for g in obstacles if not g.moving or not len(times)]
    if still:
        spatial = ET.SubElement(
            domain, "Grid", Name="obstacles", GridType="Collection", CollectionType="Spatial"
        )
        for g in still:
            _surface(spatial, g.name, h5name, g, g.final if g.moving else g.path("vertices"))
    for g in obstacles:
        if g.moving and len(times):
            series = ET.SubElement(
                domain, "Grid", Name=g.name, GridType="Collection", CollectionType="Temporal"
            )
            for k, t in times:
                grid = _surface(series, f"{g.name} {k}", h5name, g, g.frame(k))
                ET.SubElement(grid, "Time", Value=t)


def write_xdmf(
    path: str | Path,
    h5name: str,
    *,
    n_nodes: int,
    n_edges: int,
    times: list[float],
    velocities: bool = False,
    bodies: int = 0,
    obstacles: Sequence = (),
    contact: bool = True,
) -> None:
    """Writes the XDMF 3 sidecar of a result file (atomically: a temporary file renamed).

    With ``times`` (the trajectory's frames, whose views ``write_views`` wrote): a
    Temporal collection with one Polyline grid per frame. Without: one grid of /result/x,
    /result/tension, /result/reaction and (``contact``: the file has it)
    /result/contact_force. ``h5name`` is the HDF5 file as the sidecar names
    it (relative to the sidecar). ``bodies`` > 0 (the centres of moving spheres, the last
    nodes): a Temporal collection "bodies" before the net's, one Polyvertex grid of the
    centres (/mesh/bodies/node) per frame with their ``radius`` (a Sphere glyph scaled by
    it draws the balls); meshio's time-series reader takes the last collection, the net's.
    ``obstacles`` (``catenet.output.obstacles.ObstacleGrid``), first: a Spatial collection
    "obstacles" of a Triangle grid per fixed obstacle (and per moving one at /result's
    time when there are no frames), then a Temporal collection per moving obstacle with
    a Triangle grid per frame.
    """
    stamps = [(str(k), repr(float(t))) for k, t in enumerate(times)]
    many = len(stamps) > len(_TOKENS)  # the frames' grids from two, as text (``_expand``)
    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    shown = _TOKENS if many else stamps
    _obstacles(domain, h5name, obstacles, shown)
    if len(shown) and bodies:
        _bodies(domain, h5name, shown, bodies, n_nodes)
    if len(shown):
        _trajectory(domain, h5name, shown, n_nodes, n_edges, velocities)
    else:
        _result(domain, h5name, n_nodes, n_edges, contact)
    ET.indent(root, space=" ")
    text = ET.tostring(root, encoding="unicode")
    _write_atomically(
        Path(path), '<?xml version="1.0" ?>\n' + (_expand(text, stamps) if many else text) + "\n"
    )


Stamps = Sequence[tuple[str, str]]  # per frame: its index and its time, as written
#: Two frames whose grids stand for all of them: their index and time, as tokens no
#: name or path holds (a grid's text differs from frame to frame in those alone, but
#: for the last one's trailing indentation).
_TOKENS = (("@@k0@@", "@@t0@@"), ("@@k1@@", "@@t1@@"))


def _expand(text: str, stamps: Stamps) -> str:
    """The sidecar ``text``, built with the two token frames of ``_TOKENS`` in each
    Temporal collection, with every frame of ``stamps`` in their place: the first token
    frame's text (its grid and the indentation after it) for every frame but the last,
    the second's for the last. A frame's grid holds no grid. ElementTree takes about
    0.1 ms a frame: a run of 9300 frames spent 15 s of its 27 s rewriting the sidecar at
    its flushes."""
    (k0, t0), (k1, t1) = _TOKENS
    out, at = [], 0
    while (first := text.find(k0, at)) >= 0:
        begin = text.rfind("<Grid ", at, first)  # the first token frame's grid
        second = text.rfind("<Grid ", first, text.find(k1, first))  # the second's
        end = text.index("</Grid>", second) + len("</Grid>")
        head, last = text[begin:second], text[second:end]
        out.append(text[at:begin])
        out.extend(head.replace(k0, k).replace(t0, t) for k, t in stamps[:-1])
        k, t = stamps[-1]
        out.append(last.replace(k1, k).replace(t1, t))
        at = end
    out.append(text[at:])
    return "".join(out)


def _bodies(domain, h5name: str, times: Stamps, bodies: int, n_nodes: int) -> None:
    """The Temporal collection "bodies": per frame, a Polyvertex grid of the moving
    spheres' centres with their radii (see ``write_xdmf``)."""
    series = ET.SubElement(
        domain, "Grid", Name="bodies", GridType="Collection", CollectionType="Temporal"
    )
    for k, t in times:
        grid = ET.SubElement(series, "Grid", Name=f"bodies {k}", GridType="Uniform")
        topo = ET.SubElement(
            grid,
            "Topology",
            TopologyType="Polyvertex",
            NodesPerElement="1",
            NumberOfElements=str(bodies),
        )
        _hdf_item(topo, h5name, "/mesh/bodies/node", (bodies,), number="Int")
        geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
        _hdf_item(geom, h5name, f"/{VIEWS}/x/{k}", (n_nodes, 3))
        ET.SubElement(grid, "Time", Value=t)
        att = _attribute(grid, "radius", "Cell", "Scalar")
        _hdf_item(att, h5name, "/mesh/bodies/radius", (bodies,))


def _trajectory(
    domain, h5name: str, times: Stamps, n_nodes: int, n_edges: int, velocities: bool
) -> None:
    """The net's Temporal collection "trajectory": a Polyline grid per frame on its views
    (see ``write_xdmf``)."""
    series = ET.SubElement(
        domain, "Grid", Name="trajectory", GridType="Collection", CollectionType="Temporal"
    )
    for k, t in times:
        grid = _grid(series, f"frame {k}", h5name, n_edges)
        geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
        _hdf_item(geom, h5name, f"/{VIEWS}/x/{k}", (n_nodes, 3))
        ET.SubElement(grid, "Time", Value=t)
        att = _attribute(grid, "tension", "Cell", "Scalar")
        _hdf_item(att, h5name, f"/{VIEWS}/tension/{k}", (n_edges,))
        att = _attribute(grid, "position", "Node", "Vector")
        _hdf_item(att, h5name, f"/{VIEWS}/x/{k}", (n_nodes, 3))
        if velocities:
            att = _attribute(grid, "velocity", "Node", "Vector")
            _hdf_item(att, h5name, f"/{VIEWS}/v/{k}", (n_nodes, 3))


def _result(domain, h5name: str, n_nodes: int, n_edges: int, contact: bool) -> None:
    """The net's one grid of /result, for a file without a trajectory (see
    ``write_xdmf``)."""
    grid = _grid(domain, "result", h5name, n_edges)
    geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
    _hdf_item(geom, h5name, "/result/x", (n_nodes, 3))
    att = _attribute(grid, "tension", "Cell", "Scalar")
    _hdf_item(att, h5name, "/result/tension", (n_edges,))
    att = _attribute(grid, "reaction", "Node", "Vector")
    _hdf_item(att, h5name, "/result/reaction", (n_nodes, 3))
    if contact:
        att = _attribute(grid, "contact_force", "Node", "Vector")
        _hdf_item(att, h5name, "/result/contact_force", (n_nodes, 3))


def _write_atomically(path: Path, text: str) -> None:
    """Writes ``text`` to ``path`` through a temporary file renamed over it."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise
