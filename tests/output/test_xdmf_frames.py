"""The XDMF sidecar of many frames (``catenet.output.xdmf.write_xdmf``): its frames'
grids are written from two ElementTree frames as text (``_expand``), and the file is
exactly what ElementTree writes for the whole tree: parsed and indented again, it is the
same text, and every frame's grid names its own views and time."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from catenet.output.xdmf import write_xdmf


class _Moving:
    """An obstacle grid on a prescribed motion, as ``catenet.output.obstacles`` gives it."""

    index, moving, name, triangles, vertices, simplified = 0, True, "obstacle 0", 12, 8, False
    topology = "/mesh/obstacles/0/triangles"
    final = "/result/obstacles/0/vertices"

    def path(self, name: str) -> str:
        return f"/mesh/obstacles/0/{name}"

    def frame(self, k) -> str:
        return f"/xdmf/obstacles/0/vertices/{k}"


@pytest.mark.parametrize("frames", [1, 2, 3, 40])
def test_a_sidecar_of_many_frames_is_elementtree_s_own_text(tmp_path, frames):
    times = [0.001 * k**1.5 for k in range(frames)]
    side = tmp_path / "o.xdmf"
    write_xdmf(side, "a&b <o>.h5", n_nodes=7, n_edges=6, times=times, velocities=True,
               bodies=1, obstacles=[_Moving()])  # fmt: skip
    text = side.read_text()
    root = ET.fromstring(text.split("\n", 1)[1])
    ET.indent(root, space=" ")
    assert text == '<?xml version="1.0" ?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    series = {g.get("Name"): g for g in root.iter("Grid") if g.get("GridType") == "Collection"}
    assert set(series) == {"obstacle 0", "bodies", "trajectory"}
    for name, prefix in (
        ("obstacle 0", "obstacle 0 "),
        ("bodies", "bodies "),
        ("trajectory", "frame "),
    ):
        grids = series[name].findall("Grid")
        assert [g.get("Name") for g in grids] == [f"{prefix}{k}" for k in range(frames)]
        assert [g.find("Time").get("Value") for g in grids] == [repr(t) for t in times]
        for k, g in enumerate(grids):  # every view the grid names is its own frame's
            views = [d.text for d in g.iter("DataItem") if "/xdmf/" in d.text]
            assert views and all(v.endswith(f"/{k}") for v in views)
            assert all(d.text.startswith("a&b <o>.h5:") for d in g.iter("DataItem"))
