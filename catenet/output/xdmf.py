"""The XDMF 3 sidecar of a result file, for ParaView: ``OUT.xdmf`` next to ``OUT.h5``.

The sidecar holds no data: it points at the HDF5 datasets (the mesh's edges, and per frame
the trajectory's positions, tensions and velocities by HyperSlab, or the final state in
/result) and is rewritten as a run goes on. Writing it is all this module does: the writer
(``catenet.output.writer``) and ``recover`` (``catenet.output.reader``) say what to write.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from pathlib import Path

__all__ = ["sidecar_path", "write_xdmf"]


def sidecar_path(path: str | Path) -> Path:
    """The XDMF sidecar of a result file: ``OUT.xdmf`` next to ``OUT.h5``."""
    return Path(path).with_suffix(".xdmf")


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


def _slab(parent, h5name: str, dataset: str, k: int, full: tuple[int, ...]):
    """Frame k of a (T, ...) dataset as an XDMF HyperSlab."""
    rest = full[1:]
    count = (1, *rest)
    slab = ET.SubElement(
        parent,
        "DataItem",
        ItemType="HyperSlab",
        Dimensions=" ".join(map(str, count)),
        Type="HyperSlab",
    )
    sel = ET.SubElement(
        slab, "DataItem", Dimensions=f"3 {len(full)}", Format="XML", NumberType="Int"
    )
    start = (k, *(0 for _ in rest))
    stride = tuple(1 for _ in full)
    sel.text = " ".join(" ".join(map(str, row)) for row in (start, stride, count))
    _hdf_item(slab, h5name, dataset, full)
    return slab


def _grid(parent, name: str, h5name: str, n_nodes: int, n_edges: int):
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
) -> None:
    """Writes the XDMF 3 sidecar of a result file (atomically: a temporary file renamed).

    With ``times`` (the trajectory's frames): a Temporal collection with one Polyline grid
    per frame, geometry and tension read from frame k of /trajectory/x and
    /trajectory/tension by HyperSlab. Without: one grid of /result/x and /result/tension.
    ``h5name`` is the HDF5 file as the sidecar names it (relative to the sidecar).
    """
    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    n_t = len(times)
    if n_t:
        series = ET.SubElement(
            domain, "Grid", Name="trajectory", GridType="Collection", CollectionType="Temporal"
        )
        for k, t in enumerate(times):
            grid = _grid(series, f"frame {k}", h5name, n_nodes, n_edges)
            ET.SubElement(grid, "Time", Value=repr(float(t)))
            geom = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            _slab(geom, h5name, "/trajectory/x", k, (n_t, n_nodes, 3))
            att = _attribute(grid, "tension", "Cell", "Scalar")
            _slab(att, h5name, "/trajectory/tension", k, (n_t, n_edges))
            if velocities:
                att = _attribute(grid, "velocity", "Node", "Vector")
                _slab(att, h5name, "/trajectory/v", k, (n_t, n_nodes, 3))
    else:
        grid = _grid(domain, "result", h5name, n_nodes, n_edges)
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
