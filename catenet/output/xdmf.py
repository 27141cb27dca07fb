"""The XDMF 3 sidecar of a result file: ``OUT.xdmf`` next to ``OUT.h5``, for ParaView and
VTK (pyvista), meshio's time-series reader, and ``meshio.read`` for a file that holds only
its final state.

The sidecar holds no data: every DataItem names a whole HDF5 dataset. A trajectory is a
Temporal collection with one Polyline grid per frame; frame k's geometry, tensions and
velocities are the datasets ``/xdmf/x/k``, ``/xdmf/tension/k`` and ``/xdmf/v/k``: virtual
datasets (HDF5 1.10) that map frame k of ``/trajectory/x`` and the others, so they cost
metadata only and the trajectory stays where SPEC section 5 puts it. (meshio reads whole
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
from collections.abc import Iterable
from pathlib import Path

import numpy as np

VIEWS = "xdmf"  # the group of the per-frame views

__all__ = ["VIEWS", "sidecar_path", "write_views", "write_xdmf"]


def sidecar_path(path: str | Path) -> Path:
    """The XDMF sidecar of a result file: ``OUT.xdmf`` next to ``OUT.h5``."""
    return Path(path).with_suffix(".xdmf")


# --------------------------------------------------------------------------------------------
# Per-frame views in the HDF5 file
# --------------------------------------------------------------------------------------------


def write_views(h5, start: int, stop: int) -> None:
    """Adds the views ``/xdmf/<name>/<k>`` of frames ``start <= k < stop`` (which have
    none yet) of every per-frame dataset of /trajectory (besides time) to an open,
    writable file. A view maps one frame of its source (same file, named "."), so a
    trajectory that grows later keeps its views valid."""
    from h5py import h5d, h5p, h5s, h5t

    traj = h5.get("trajectory")
    if traj is None or stop <= start:
        return
    base = h5p.create(h5p.DATASET_CREATE)
    base.set_fill_value(np.array(np.nan))
    for name in ("x", "tension", "v"):
        if name not in traj:
            continue
        tail = tuple(traj[name].shape[1:])
        group = h5.require_group(f"{VIEWS}/{name}").id
        view = h5s.create_simple(tail)
        whole = h5s.create_simple((stop, *tail), (h5s.UNLIMITED, *tail))
        target = f"/trajectory/{name}".encode()
        zeros = (0,) * len(tail)
        for k in range(start, stop):
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


def _grid(parent, name: str, h5name: str, n_edges: int):
    grid = ET.SubElement(parent, "Grid", Name=name, GridType="Uniform")
    topo = ET.SubElement(
        grid,
        "Topology",
        TopologyType="Polyline",
        NodesPerElement="2",
        NumberOfElements=str(n_edges),
    )
    _hdf_item(topo, h5name, "/mesh/edges", (n_edges, 2), number="Int")
    return grid


def _attribute(grid, name: str, center: str, kind: str):
    return ET.SubElement(grid, "Attribute", Name=name, AttributeType=kind, Center=center)


def write_xdmf(
    path: str | Path,
    h5name: str,
    *,
    n_nodes: int,
    n_edges: int,
    times: list[float],
    velocities: bool = False,
    bodies: int = 0,
) -> None:
    """Writes the XDMF 3 sidecar of a result file (atomically: a temporary file renamed).

    With ``times`` (the trajectory's frames, whose views ``write_views`` wrote): a
    Temporal collection with one Polyline grid per frame. Without: one grid of /result/x,
    /result/tension and /result/reaction. ``h5name`` is the HDF5 file as the sidecar names
    it (relative to the sidecar). ``bodies`` > 0 (the centres of moving spheres, the last
    nodes): a Temporal collection "bodies" before the net's, one Polyvertex grid of the
    centres (/mesh/bodies/node) per frame with their ``radius`` (a Sphere glyph scaled by
    it draws the balls); meshio's time-series reader takes the last collection, the net's.
    """
    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    if len(times) and bodies:
        series = ET.SubElement(
            domain, "Grid", Name="bodies", GridType="Collection", CollectionType="Temporal"
        )
        for k, t in enumerate(times):
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
            ET.SubElement(grid, "Time", Value=repr(float(t)))
            att = _attribute(grid, "radius", "Cell", "Scalar")
            _hdf_item(att, h5name, "/mesh/bodies/radius", (bodies,))
    if len(times):
        series = ET.SubElement(
            domain, "Grid", Name="trajectory", GridType="Collection", CollectionType="Temporal"
        )
        for k, t in enumerate(times):
            grid = _grid(series, f"frame {k}", h5name, n_edges)
            geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            _hdf_item(geom, h5name, f"/{VIEWS}/x/{k}", (n_nodes, 3))
            ET.SubElement(grid, "Time", Value=repr(float(t)))
            att = _attribute(grid, "tension", "Cell", "Scalar")
            _hdf_item(att, h5name, f"/{VIEWS}/tension/{k}", (n_edges,))
            att = _attribute(grid, "position", "Node", "Vector")
            _hdf_item(att, h5name, f"/{VIEWS}/x/{k}", (n_nodes, 3))
            if velocities:
                att = _attribute(grid, "velocity", "Node", "Vector")
                _hdf_item(att, h5name, f"/{VIEWS}/v/{k}", (n_nodes, 3))
    else:
        grid = _grid(domain, "result", h5name, n_edges)
        geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
        _hdf_item(geom, h5name, "/result/x", (n_nodes, 3))
        att = _attribute(grid, "tension", "Cell", "Scalar")
        _hdf_item(att, h5name, "/result/tension", (n_edges,))
        att = _attribute(grid, "reaction", "Node", "Vector")
        _hdf_item(att, h5name, "/result/reaction", (n_nodes, 3))
    ET.indent(root, space=" ")
    text = '<?xml version="1.0" ?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise
