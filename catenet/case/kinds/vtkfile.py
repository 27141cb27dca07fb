"""Reading nets from VTK files without VTK: the XML formats (``.vtu`` unstructured grids,
``.vtp`` poly data; ASCII, base64 or appended raw data, zlib-compressed or not) and the
legacy format (``.vtk``: ``POLYDATA`` or ``UNSTRUCTURED_GRID``, ASCII or binary).

What a net needs is read: the points, the line and polyline cells (``VTK_LINE``,
``VTK_POLY_LINE``, a poly data's ``Lines``; other cells are left out with a warning), the
cell data array ``name`` (strings or numbers: a cable's name) and the point data arrays of
one component (flags such as ``fixed``). A problem is a ``VtkError`` with a message for
the user.
"""

from __future__ import annotations

import base64
import re
import xml.etree.ElementTree as ET
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

LINE, POLY_LINE = 3, 4
#: VTK cell types by id (those a net file may hold besides lines), as messages name them.
CELL_NAMES = {
    1: "vertex", 2: "poly_vertex", 5: "triangle", 6: "triangle_strip", 7: "polygon",
    8: "pixel", 9: "quad", 10: "tetra", 11: "voxel", 12: "hexahedron", 13: "wedge",
    14: "pyramid",
}  # fmt: skip
_SECTIONS = {
    "Verts": "vertex",
    "Strips": "triangle_strip",
    "Polys": "polygon",
    "VERTICES": "vertex",
    "TRIANGLE_STRIPS": "triangle_strip",
    "POLYGONS": "polygon",
}


def _cell_names(types) -> list[str]:
    return sorted({CELL_NAMES.get(int(t), f"VTK cell type {int(t)}") for t in types})


_XML_TYPES = {
    "Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "Int32": "i4",
    "UInt32": "u4", "Int64": "i8", "UInt64": "u8", "Float32": "f4", "Float64": "f8",
}  # fmt: skip
_LEGACY_TYPES = {
    "bit": "u1", "unsigned_char": "u1", "char": "i1", "unsigned_short": "u2", "short": "i2",
    "unsigned_int": "u4", "int": "i4", "unsigned_long": "u8", "long": "i8",
    "float": "f4", "double": "f8", "vtktypeint64": "i8", "vtktypeint32": "i4",
    "vtkidtype": "i8",
}  # fmt: skip


class VtkError(Exception):
    """A VTK file catenet cannot read (the message says why)."""


@dataclass
class Lines:
    """Points (N, 3), polylines (arrays of point indices), each cell's name (None: none
    given), point data of one component by name, the kinds of cells left out."""

    points: np.ndarray
    lines: list[np.ndarray]
    names: list[str] | None = None
    point_data: dict[str, np.ndarray] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)


def read_vtk(path: Path) -> Lines:
    """The lines of a ``.vtu``, ``.vtp`` or legacy ``.vtk`` file."""
    data = path.read_bytes()
    if data.lstrip()[:1] == b"<":
        return _read_xml(data)
    if data.startswith(b"# vtk DataFile"):
        return _read_legacy(data)
    raise VtkError("not a VTK file (neither XML nor a legacy '# vtk DataFile' header)")


# --------------------------------------------------------------------------- XML


class _Xml:
    """The decoding of a VTK XML file's data arrays."""

    def __init__(self, root: ET.Element, raw: bytes):
        self.big = root.get("byte_order", "LittleEndian") == "BigEndian"
        self.header = _dtype(root.get("header_type", "UInt32"), self.big)
        self.zlib = root.get("compressor", "") == "vtkZLibDataCompressor"
        if root.get("compressor", "") not in ("", "vtkZLibDataCompressor"):
            raise VtkError(f"compressor {root.get('compressor')!r}: catenet reads zlib only")
        self.appended = b""
        self.base64 = False
        start = raw.find(b"<AppendedData")
        if start >= 0:
            tag_end = raw.find(b">", start)
            self.base64 = b'encoding="base64"' in raw[start:tag_end]
            body = raw[tag_end + 1 :]
            body = body[body.find(b"_") + 1 :]
            end = body.rfind(b"</AppendedData>")
            self.appended = body[:end] if end >= 0 else body
            if self.base64:
                self.appended = self.appended.strip()

    def array(self, el: ET.Element) -> np.ndarray:
        kind = el.get("type", "")
        fmt = el.get("format", "ascii")
        if kind == "String":
            return self._strings(el, fmt)
        if kind not in _XML_TYPES:
            raise VtkError(f"data array {el.get('Name')!r}: type {kind!r} not read")
        dtype = _dtype(kind, self.big)
        if fmt == "ascii":  # (the decimal text at full precision, whatever its type)
            values = np.array((el.text or "").split(), dtype=np.float64)
            return values if dtype.kind == "f" else values.astype(dtype)
        return np.frombuffer(self._bytes(el, fmt), dtype=dtype)

    def _strings(self, el, fmt) -> np.ndarray:
        if fmt == "ascii":
            raw = bytes(int(v) for v in (el.text or "").split())
        else:
            raw = self._bytes(el, fmt)
        parts = raw.split(b"\0")
        if parts and parts[-1] == b"":
            parts = parts[:-1]
        return np.array([p.decode("utf-8", "replace") for p in parts], dtype=object)

    def _bytes(self, el, fmt) -> bytes:
        if fmt == "binary":
            text = "".join((el.text or "").split()).encode()
            return self._unpack_base64(text)
        if fmt == "appended":
            offset = int(el.get("offset", "0"))
            if self.base64:
                return self._unpack_base64(self.appended[offset:])
            return self._unpack_raw(self.appended[offset:])
        raise VtkError(f"data array {el.get('Name')!r}: format {fmt!r} not read")

    def _unpack_raw(self, buf: bytes) -> bytes:
        h = self.header.itemsize
        if not self.zlib:
            n = int(np.frombuffer(buf[:h], self.header)[0])
            return buf[h : h + n]
        nblocks = int(np.frombuffer(buf[:h], self.header)[0])
        head = np.frombuffer(buf[: h * (3 + nblocks)], self.header).astype(np.int64)
        sizes = head[3:]
        out, at = [], h * (3 + nblocks)
        for s in sizes:
            out.append(zlib.decompress(buf[at : at + s]))
            at += s
        return b"".join(out)

    def _unpack_base64(self, text: bytes) -> bytes:
        h = self.header.itemsize
        if not self.zlib:
            first = base64.b64decode(text[: _b64len(h)] + b"==", validate=False)
            n = int(np.frombuffer(first[:h], self.header)[0])
            whole = base64.b64decode(text[: _b64len(h + n)] + b"==")
            return whole[h : h + n]
        # The header (its own base64 block), then the compressed blocks.
        first = base64.b64decode(text[: _b64len(h)] + b"==")
        nblocks = int(np.frombuffer(first[:h], self.header)[0])
        hlen = _b64len(h * (3 + nblocks))
        head = np.frombuffer(base64.b64decode(text[:hlen] + b"=="), self.header)[: 3 + nblocks]
        sizes = head[3:].astype(np.int64)
        body = base64.b64decode(text[hlen : hlen + _b64len(int(sizes.sum()))] + b"==")
        out, at = [], 0
        for s in sizes:
            out.append(zlib.decompress(body[at : at + s]))
            at += s
        return b"".join(out)


def _b64len(n: int) -> int:
    return 4 * ((n + 2) // 3)


def _dtype(name: str, big: bool) -> np.dtype:
    if name not in _XML_TYPES:
        raise VtkError(f"type {name!r} not read")
    return np.dtype(("<" if not big else ">") + _XML_TYPES[name])


def _read_xml(raw: bytes) -> Lines:
    cut = raw.find(b"<AppendedData")
    text = raw[:cut] + b"</VTKFile>" if cut >= 0 else raw
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise VtkError(f"not valid VTK XML: {exc}") from None
    kind = root.get("type", "")
    if kind not in ("UnstructuredGrid", "PolyData"):
        raise VtkError(
            f"a VTK XML file of type {kind!r}: catenet reads UnstructuredGrid "
            "(.vtu) and PolyData (.vtp)"
        )
    xml = _Xml(root, raw)
    pieces = root.findall(f"./{kind}/Piece")
    if len(pieces) != 1:
        raise VtkError(f"{len(pieces)} pieces: catenet reads a file of one piece")
    piece = pieces[0]
    pts = piece.find("./Points/DataArray")
    if pts is None:
        raise VtkError("no points")
    points = xml.array(pts).astype(np.float64).reshape(-1, int(pts.get("NumberOfComponents", "3")))
    skipped: list[str] = []
    if kind == "UnstructuredGrid":
        arrays = {a.get("Name"): a for a in piece.findall("./Cells/DataArray")}
        if not {"connectivity", "offsets", "types"} <= set(arrays):
            raise VtkError("its Cells lack connectivity, offsets or types")
        conn = xml.array(arrays["connectivity"]).astype(np.int64)
        offsets = xml.array(arrays["offsets"]).astype(np.int64)
        types = xml.array(arrays["types"]).astype(np.int64)
        cells = np.split(conn, offsets[:-1])
        keep = np.flatnonzero((types == LINE) | (types == POLY_LINE))
        skipped = _cell_names(types[(types != LINE) & (types != POLY_LINE)])
    else:
        cells, line_cells = [], []
        for section in ("Verts", "Lines", "Strips", "Polys"):
            arrays = {a.get("Name"): a for a in piece.findall(f"./{section}/DataArray")}
            if not arrays:
                continue
            conn = xml.array(arrays["connectivity"]).astype(np.int64)
            offsets = xml.array(arrays["offsets"]).astype(np.int64)
            these = np.split(conn, offsets[:-1]) if len(offsets) else []
            if section == "Lines":
                line_cells = list(range(len(cells), len(cells) + len(these)))
            elif these:
                skipped.append(_SECTIONS[section])
            cells += these
        keep = np.asarray(line_cells, dtype=np.int64)
    lines = [cells[k] for k in keep]
    names = None
    for a in [*piece.findall("./CellData/DataArray"), *piece.findall("./CellData/Array")]:
        if a.get("Name") == "name":
            values = xml.array(a)
            names = [_label(values[k]) for k in keep] if len(values) == len(cells) else None
    point_data = {}
    for a in piece.findall("./PointData/DataArray"):
        if int(a.get("NumberOfComponents", "1")) == 1 and a.get("type") != "String":
            point_data[a.get("Name", "")] = xml.array(a)
    return Lines(_xyz(points), lines, names, point_data, skipped)


def _label(v) -> str:
    if isinstance(v, str):
        return v
    f = float(v)
    return str(int(f)) if f == int(f) else repr(f)


def _xyz(points: np.ndarray) -> np.ndarray:
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise VtkError(f"its points have shape {points.shape}: must be 2D or 3D")
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    return np.ascontiguousarray(points, dtype=np.float64)


# --------------------------------------------------------------------------- legacy


class _Legacy:
    """A cursor over a legacy file: words in ASCII, raw big-endian blocks in binary."""

    def __init__(self, data: bytes):
        self.data = data
        self.at = 0
        lines = data.split(b"\n", 4)
        if len(lines) < 4:
            raise VtkError("a legacy VTK file needs a header, a title, ASCII/BINARY and data")
        self.binary = lines[2].strip().upper() == b"BINARY"
        self.at = sum(len(x) + 1 for x in lines[:3])

    def word(self) -> str:
        m = re.compile(rb"\s*(\S+)").match(self.data, self.at)
        if m is None:
            return ""
        self.at = m.end()
        return m.group(1).decode("latin-1")

    def line(self) -> str:
        end = self.data.find(b"\n", self.at)
        end = len(self.data) if end < 0 else end
        out = self.data[self.at : end].decode("latin-1")
        self.at = end + 1
        return out

    def values(self, n: int, kind: str) -> np.ndarray:
        dtype = np.dtype(">" + _LEGACY_TYPES.get(kind.lower(), "f8"))
        if not self.binary:  # (the decimal text at full precision, whatever its type)
            values = np.array([float(self.word()) for _ in range(n)])
            return values if dtype.kind == "f" else values.astype(dtype.newbyteorder("="))
        self.at = self.data.find(b"\n", self.at) + 1
        size = n * dtype.itemsize
        out = np.frombuffer(self.data[self.at : self.at + size], dtype=dtype)
        self.at += size
        return out.astype(dtype.newbyteorder("="))


def _read_legacy(data: bytes) -> Lines:
    cur = _Legacy(data)
    points = None
    cells: list[np.ndarray] = []
    types = None
    keep: list[int] = []
    skipped: list[str] = []
    names = None
    point_data: dict[str, np.ndarray] = {}
    where, count = "", 0
    while True:
        w = cur.word().upper()
        if not w:
            break
        if w == "DATASET":
            kind = cur.word().upper()
            if kind not in ("POLYDATA", "UNSTRUCTURED_GRID"):
                raise VtkError(f"DATASET {kind}: catenet reads POLYDATA and UNSTRUCTURED_GRID")
        elif w == "POINTS":
            n, kind = int(cur.word()), cur.word()
            points = cur.values(3 * n, kind).astype(np.float64).reshape(n, 3)
        elif w in ("LINES", "VERTICES", "POLYGONS", "TRIANGLE_STRIPS", "CELLS"):
            these = _legacy_cells(cur)
            if w == "LINES":
                keep += list(range(len(cells), len(cells) + len(these)))
            elif w != "CELLS" and these:
                skipped.append(_SECTIONS[w])
            cells += these
        elif w == "CELL_TYPES":
            n = int(cur.word())
            types = cur.values(n, "int").astype(np.int64)
        elif w in ("POINT_DATA", "CELL_DATA"):
            where, count = w, int(cur.word())
        elif w in ("SCALARS", "FIELD"):
            for name, values in _legacy_arrays(cur, w, count):
                if where == "POINT_DATA" and values.ndim == 1:
                    point_data[name] = values
                elif where == "CELL_DATA" and name == "name":
                    names = values
        elif w in ("METADATA",):
            _skip_metadata(cur)
        else:
            cur.line()
    if points is None:
        raise VtkError("no POINTS")
    if types is not None:
        keep = [k for k, t in enumerate(types) if t in (LINE, POLY_LINE)]
        skipped = _cell_names([t for t in types if t not in (LINE, POLY_LINE)])
    lines = [cells[k] for k in keep]
    if names is not None:
        names = [_label(names[k]) for k in keep] if len(names) == len(cells) else None
    return Lines(_xyz(points), lines, names, point_data, skipped)


def _legacy_cells(cur: _Legacy) -> list[np.ndarray]:
    n, size = int(cur.word()), int(cur.word())
    save = cur.at
    if cur.word().upper() == "OFFSETS":  # the 5.1 format: offsets, then connectivity
        offsets = cur.values(n, cur.word()).astype(np.int64)
        if cur.word().upper() != "CONNECTIVITY":
            raise VtkError("OFFSETS without CONNECTIVITY")
        conn = cur.values(size, cur.word()).astype(np.int64)
        return [conn[offsets[k] : offsets[k + 1]] for k in range(n - 1)]
    cur.at = save
    flat = cur.values(size, "int").astype(np.int64)
    out, at = [], 0
    for _ in range(n):
        m = int(flat[at])
        out.append(flat[at + 1 : at + 1 + m])
        at += 1 + m
    return out


def _legacy_arrays(cur: _Legacy, what: str, count: int):
    if what == "SCALARS":
        parts = cur.line().split()
        name, kind = parts[0], parts[1]
        comps = int(parts[2]) if len(parts) > 2 else 1
        save = cur.at
        if cur.word().upper() == "LOOKUP_TABLE":
            cur.word()
        else:
            cur.at = save
        values = cur.values(count * comps, kind)
        yield name, values if comps == 1 else values.reshape(count, comps)
        return
    cur.word()  # the field's name
    for _ in range(int(cur.word())):
        name, comps, tuples, kind = cur.word(), int(cur.word()), int(cur.word()), cur.word()
        if kind.lower() == "string":
            cur.line()
            yield name, _legacy_strings(cur, comps * tuples)
            continue
        values = cur.values(comps * tuples, kind)
        yield name, values if comps == 1 else values.reshape(tuples, comps)
        save = cur.at
        if cur.word().upper() == "METADATA":
            _skip_metadata(cur)
        else:
            cur.at = save


def _legacy_strings(cur: _Legacy, n: int) -> np.ndarray:
    """Strings one a line (ASCII), or each after its length (binary: the first byte's
    two high bits say how many bytes hold the length: 11 one, 10 two, 01 four, 00 eight)."""
    if not cur.binary:
        return np.array([cur.line().strip() for _ in range(n)], dtype=object)
    out = []
    for _ in range(n):
        b = cur.data[cur.at]
        width = {3: 1, 2: 2, 1: 4, 0: 8}[b >> 6]
        head = bytearray(cur.data[cur.at : cur.at + width])
        head[0] &= 0x3F
        size = int.from_bytes(head, "big")
        cur.at += width
        out.append(cur.data[cur.at : cur.at + size].decode("utf-8", "replace"))
        cur.at += size
    return np.array(out, dtype=object)


def _skip_metadata(cur: _Legacy) -> None:
    """A METADATA block ends at an empty line."""
    cur.line()  # the rest of the METADATA line
    while cur.at < len(cur.data):
        if not cur.line().strip():
            break
