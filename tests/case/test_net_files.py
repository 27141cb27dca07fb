"""Nets read from VTK files (catenet's own reader: .vtu, .vtp and legacy .vtk, ASCII,
base64, appended raw data, zlib or not) and OBJ: polylines become cables (named by a cell
data array ``name`` or an OBJ ``o`` line, else by their place), segments edges, point
data flags node sets; the same net from every file gives the same run; every file that
cannot be read is refused with exit status 2 and catenet's message."""

from __future__ import annotations

import base64
import zlib

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.run.runner import run_case

POINTS = np.array(
    [[0, 0, 0], [1, 0, 0], [2, 0, 0.2], [3, 0, 0], [1.5, -1, 0.1], [1.5, 1, 0.1]], dtype=float
)
LINES = ([0, 1, 2, 3], [4, 2, 5])
NAMES = ("main", "cross")
FIXED = [1, 0, 0, 1, 1, 1]

OBJ = """# two cables through a shared node
v 0 0 0
v 1 0 0
v 2 0 0.2
v 3 0 0
v 1.5 -1 0.1
v 1.5 1 0.1
o main
l 1 2 3 4
o cross
l 5 3 6
"""


def _array(values, dtype, fmt, name="", comps=1, compress=False, appended=None) -> str:
    """A VTK XML DataArray of ``values`` in the format ``fmt`` (ascii, binary, appended:
    then its bytes go to ``appended``, a bytearray)."""
    attrs = f'type="{dtype}" Name="{name}" NumberOfComponents="{comps}"'
    kind = {"Float64": "<f8", "Int64": "<i8", "UInt8": "u1", "Int32": "<i4"}[dtype]
    raw = np.asarray(values).astype(kind).tobytes()
    if fmt == "ascii":
        text = " ".join(str(v) for v in np.asarray(values).ravel().tolist())
        return f'<DataArray {attrs} format="ascii">{text}</DataArray>'
    if compress:
        block = zlib.compress(raw)
        head = np.array([1, len(raw), len(raw), len(block)], dtype="<u8").tobytes()
    else:
        block, head = raw, np.array([len(raw)], dtype="<u8").tobytes()
    if fmt == "binary":
        body = (
            base64.b64encode(head).decode() + base64.b64encode(block).decode()
            if compress
            else base64.b64encode(head + block).decode()
        )
        return f'<DataArray {attrs} format="binary">{body}</DataArray>'
    offset = len(appended)
    appended += head + block
    return f'<DataArray {attrs} format="appended" offset="{offset}"/>'


def vtk_xml(kind: str, fmt: str, compress: bool) -> bytes:
    """The net as a .vtu (VTK_POLY_LINE cells) or .vtp (Lines) in the given format."""
    extra = bytearray()
    conn = np.concatenate(LINES)
    offsets = np.cumsum([len(line) for line in LINES])
    names = "".join(f"{' '.join(str(b) for b in n.encode())} 0 " for n in NAMES)
    arr = lambda *a, **k: _array(*a, compress=compress, appended=extra, **k)  # noqa: E731
    cells = arr(conn, "Int64", fmt, "connectivity") + arr(offsets, "Int64", fmt, "offsets")
    if kind == "UnstructuredGrid":
        cells = f"<Cells>{cells}{arr([4, 4], 'UInt8', fmt, 'types')}</Cells>"
        count = 'NumberOfCells="2"'
    else:
        cells = f"<Lines>{cells}</Lines>"
        count = 'NumberOfLines="2"'
    comp = ' compressor="vtkZLibDataCompressor"' if compress else ""
    text = (
        f'<?xml version="1.0"?>\n<VTKFile type="{kind}" version="1.0" '
        f'byte_order="LittleEndian" header_type="UInt64"{comp}><{kind}>'
        f'<Piece NumberOfPoints="6" {count}>'
        f"<PointData>{arr(FIXED, 'Int32', fmt, 'fixed')}</PointData>"
        f'<CellData><Array type="String" Name="name" format="ascii">{names}</Array></CellData>'
        f"<Points>{arr(POINTS, 'Float64', fmt, 'Points', 3)}</Points>{cells}"
        f"</Piece></{kind}>"
    )
    if fmt == "appended":
        return (
            text.encode()
            + b'<AppendedData encoding="raw">_'
            + bytes(extra)
            + b"</AppendedData></VTKFile>"
        )
    return (text + "</VTKFile>").encode()


LEGACY_OLD = """# vtk DataFile Version 4.2
two cables
ASCII
DATASET POLYDATA
POINTS 6 double
0 0 0 1 0 0 2 0 0.2 3 0 0 1.5 -1 0.1 1.5 1 0.1
LINES 2 9
4 0 1 2 3
3 4 2 5
CELL_DATA 2
FIELD FieldData 1
name 1 2 string
main
cross
POINT_DATA 6
SCALARS fixed int 1
LOOKUP_TABLE default
1 0 0 1 1 1
"""

LEGACY_NEW = """# vtk DataFile Version 5.1
two cables
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 6 float
0 0 0 1 0 0 2 0 0.2 3 0 0 1.5 -1 0.1 1.5 1 0.1
CELLS 3 7
OFFSETS vtktypeint64
0 4 7
CONNECTIVITY vtktypeint64
0 1 2 3 4 2 5
CELL_TYPES 2
4
4
CELL_DATA 2
FIELD FieldData 1
name 1 2 string
main
cross
POINT_DATA 6
FIELD FieldData 1
fixed 1 6 int
1 0 0 1 1 1
"""


def files(tmp_path) -> dict[str, str]:
    """The net in every form: name -> file name in tmp_path."""
    out = {}
    for kind, ext in (("UnstructuredGrid", "vtu"), ("PolyData", "vtp")):
        for fmt in ("ascii", "binary", "appended"):
            for compress in (False, True):
                name = f"{fmt}{'_z' if compress else ''}.{ext}"
                (tmp_path / name).write_bytes(vtk_xml(kind, fmt, compress))
                out[name] = name
    (tmp_path / "old.vtk").write_text(LEGACY_OLD)
    (tmp_path / "new.vtk").write_text(LEGACY_NEW)
    (tmp_path / "net.obj").write_text(OBJ)
    return {**out, "old.vtk": "old.vtk", "new.vtk": "new.vtk", "net.obj": "net.obj"}


def case(file: str, fixed) -> dict:
    return {
        "geometry": {"kind": "graph", "file": file, "edge_length": 0.25},
        "supports": {"fixed": fixed},
        "material": {"EA": 1e4, "prestress": 10.0},
        "load": {"point": [{"node": "cable:cross", "force": [0, 0, -1.0]}]},
    }


def test_every_vtk_file_and_the_obj_give_the_same_net_and_run(tmp_path):
    names = files(tmp_path)
    obj = parse_case(case("net.obj", [0, 3, 4, 5]), base_dir=tmp_path)
    assert [(c.name, c.nodes) for c in obj.geometry.cables] == [
        ("main", (0, 1, 2, 3)),
        ("cross", (4, 2, 5)),
    ]
    want = run_case(obj, tmp_path / "obj.h5")
    assert want.converged and set(want.report.cables) == set(NAMES)
    for name in names:
        if name == "net.obj":
            continue
        got = parse_case(case(name, ["fixed"]), base_dir=tmp_path)
        assert got.geometry.cables == obj.geometry.cables, name
        assert got.geometry.sets.as_dict()["fixed"] == (0, 3, 4, 5), name
        assert np.array_equal(np.asarray(got.geometry.nodes), POINTS), name
        res = run_case(got, tmp_path / f"{name}.h5")
        assert np.array_equal(res.x, want.x) and res.report.cables == want.report.cables


def test_files_written_by_vtk_itself(tmp_path):
    vtk = pytest.importorskip("vtk")
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    for p in POINTS:
        pts.InsertNextPoint(*p)
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(pts)
    poly = vtk.vtkPolyData()
    poly.SetPoints(pts)
    cells = vtk.vtkCellArray()
    for line in LINES:
        ids = vtk.vtkIdList()
        for i in line:
            ids.InsertNextId(i)
        grid.InsertNextCell(vtk.VTK_POLY_LINE, ids)
        cells.InsertNextCell(ids)
    poly.SetLines(cells)
    for data in (grid, poly):
        names = vtk.vtkStringArray()
        names.SetName("name")
        for n in NAMES:
            names.InsertNextValue(n)
        data.GetCellData().AddArray(names)
        flag = vtk.vtkIntArray()
        flag.SetName("fixed")
        for v in FIXED:
            flag.InsertNextValue(v)
        data.GetPointData().AddArray(flag)
    written = []
    for ext, writer, data in (
        ("vtu", vtk.vtkXMLUnstructuredGridWriter, grid),
        ("vtp", vtk.vtkXMLPolyDataWriter, poly),
    ):
        for mode in ("Ascii", "Binary", "Appended"):
            for encode in (True, False):
                w = writer()
                name = f"{mode}{int(encode)}.{ext}"
                w.SetFileName(str(tmp_path / name))
                w.SetInputData(data)
                getattr(w, f"SetDataModeTo{mode}")()
                w.SetEncodeAppendedData(encode)
                w.Write()
                written.append(name)
    for ext, writer, data in (
        ("ug", vtk.vtkUnstructuredGridWriter, grid),
        ("pd", vtk.vtkPolyDataWriter, poly),
    ):
        for version in (42, 51):
            for binary in (False, True):
                w = writer()
                name = f"{ext}{version}{'b' if binary else 'a'}.vtk"
                w.SetFileName(str(tmp_path / name))
                w.SetInputData(data)
                if version == 42:
                    w.SetFileVersion(42)
                if binary:
                    w.SetFileTypeToBinary()
                w.Write()
                written.append(name)
    (tmp_path / "net.obj").write_text(OBJ)
    want = build(parse_case(case("net.obj", [0, 3, 4, 5]), base_dir=tmp_path))
    for name in written:
        got = build(parse_case(case(name, ["fixed"]), base_dir=tmp_path))
        assert np.array_equal(got.net.nodes, want.net.nodes), name
        assert np.array_equal(got.net.edges, want.net.edges), name
        assert got.cables.names == want.cables.names, name


def test_unnamed_polylines_are_named_by_their_place_and_segments_are_edges(tmp_path):
    (tmp_path / "n.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 1 1 0\nv 1 2 0\nl 1 2 3\nl 4 2\nl 5 4\n"
    )
    data = case("n.obj", [0, 2, 4])
    data["load"]["point"][0]["node"] = "cable:line0"
    g = parse_case(data, base_dir=tmp_path).geometry
    assert g.edges == ((3, 1), (4, 3)) and [c.name for c in g.cables] == ["line0"]


def run_bad(tmp_path, file: str, content: bytes) -> str:
    (tmp_path / file).write_bytes(content)
    data = case(file, [0])
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "c.h5")])
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output and "Couldn't read" not in r.output  # (meshio's text)
    return r.output


@pytest.mark.parametrize(
    "file, content, message",
    [
        ("empty.vtu", b"", "cannot read it as VTK: not a VTK file"),
        ("junk.vtp", b"<VTKFile type='PolyData'><PolyData>", "cannot read it as VTK: not valid"),
        ("cut.vtu", vtk_xml("UnstructuredGrid", "appended", True)[:-60], "cannot read it as VTK"),
        (
            "grid.vtk",
            b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\n",
            "DATASET STRUCTURED_POINTS: catenet reads POLYDATA and UNSTRUCTURED_GRID",
        ),
        (
            "tri.vtk",
            b"# vtk DataFile Version 4.2\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
            b"0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n",
            "holds no line cells (it has polygon)",
        ),
        (
            "far.vtk",
            b"# vtk DataFile Version 4.2\nt\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n"
            b"0 0 0 1 0 0\nLINES 1 3\n2 0 7\n",
            "line 0 ([0, 7]): needs at least 2 of the file's 2",
        ),
        ("bad.msh", b"not a mesh", "cannot read it as a .msh mesh (through meshio)"),
        ("none.obj", b"v 0 0 0\n", "holds no polylines"),
    ],
)
def test_files_that_cannot_be_read_exit_2_with_the_key(tmp_path, file, content, message):
    out = run_bad(tmp_path, file, content)
    assert f"geometry.file = {file!r}: " in out and message in out


def test_a_json_net_file_leaves_the_other_graph_keys_to_the_case(tmp_path):
    """A JSON file of the net (nodes, edges, cables, supports) with the discretisation and
    node sets in the case file: one place for each key; a key in both is refused."""
    import json

    net = {
        "nodes": POINTS.tolist(),
        "cable": [{"name": n, "nodes": list(c)} for n, c in zip(NAMES, LINES, strict=True)],
    }
    net["fixed"] = [i for i, f in enumerate(FIXED) if f]
    (tmp_path / "net.json").write_text(json.dumps(net))
    data = {
        "geometry": {
            "kind": "graph",
            "file": "net.json",
            "edge_length": 0.25,
            "sets": {"mid": {"near": [1.5, 0, 0]}},
        },
        "material": {"EA": 1e4, "prestress": 10.0},
        "load": {"point": [{"node": "mid", "force": [0, 0, -1.0]}]},
    }
    scene = build(parse_case(data, base_dir=tmp_path))
    assert scene.net.n_nodes > len(POINTS) and tuple(scene.cables.names) == NAMES
    data["geometry"]["file"] = "net.json"
    net["edge_length"] = 0.5
    (tmp_path / "net.json").write_text(json.dumps(net))
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path)])
    assert r.exit_code == 2
    assert (
        "geometry.edge_length: given in geometry.file = 'net.json' too: give it in one place "
        "(the file holds nodes, fixed, edge_length, cable)" in r.output
    )
