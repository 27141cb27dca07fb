"""/modes in a result file (catenet.output.modes): what is stored, the animation frames
and the sidecar that ParaView (VTK's XDMF reader) and meshio read."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.output.modes import animated_count, read_modes
from tests.conftest import check_xdmf, read_with_vtk

CASE = """\
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [20, 0, 0]
nodes = 41

[material]
EA = 1e6
area = 1e-4
density = 7850.0
prestress = 2000.0

[load]
gravity = [0, 0, -9.81]

[output]
file = "out/cable.h5"
every = {every}
"""


def modes_file(tmp_path, every=0, count=4):
    from catenet.case import load_case
    from catenet.run.modes import modes_case

    path = tmp_path / "cable.toml"
    path.write_text(CASE.format(every=every))
    done = modes_case(load_case(path, ()), tmp_path / "cable.h5", count=count)
    return done


def test_stored_modes_and_frames(tmp_path):
    done = modes_file(tmp_path)
    stored = read_modes(done.path)
    modes = done.modes
    np.testing.assert_array_equal(stored.frequency, modes.frequency)
    np.testing.assert_array_equal(stored.shape, modes.shape)
    np.testing.assert_array_equal(stored.x, modes.x)
    frames = int(stored.attrs["frames"])
    assert stored.attrs["animated"] == 4 and stored.attrs["amplitude"] == pytest.approx(1.0)
    import h5py

    with h5py.File(done.path, "r") as h5:
        for k in range(stored.count):
            quarter = h5[f"modes/frames/{k}/{frames // 4}"][()]  # phase 1/4: the largest
            top = np.abs(quarter - modes.x).max()
            assert top == pytest.approx(stored.attrs["amplitude"], rel=1e-5)  # float32
            np.testing.assert_allclose(h5[f"modes/shape_views/{k}"][()], modes.shape[k])
            np.testing.assert_allclose(h5[f"modes/frames/{k}/0"][()], modes.x, atol=1e-5)
    assert stored.frame(1, frames // 4) == pytest.approx(
        modes.x + modes.shape[1] * (1.0 / np.abs(modes.shape[1]).max()) * math.sin(math.pi / 2)
    )


@pytest.mark.parametrize("every", [0, 1])
def test_sidecar_animates_every_mode(tmp_path, every):
    """Each mode is a Temporal collection of its frames (phases 0 .. 15/16) that VTK's
    reader (ParaView's) reads without a complaint; the trajectory, where there is one,
    stays the last collection: meshio's time-series reader reads it."""
    import meshio

    done = modes_file(tmp_path, every=every)
    side = done.path.with_suffix(".xdmf")
    checked = check_xdmf(side)
    assert checked["modes"] == 4
    data, events = read_with_vtk(side)
    assert not [e for e in events if "rror" in str(e)]
    assert data.n_blocks == 4 + 1
    with meshio.xdmf.TimeSeriesReader(side) as reader:
        reader.read_points_cells()
        if every:
            assert reader.num_steps == len(checked["times"])


def test_animation_is_capped(monkeypatch):
    assert animated_count(10, 100) == 10
    assert animated_count(10, 10**7) == 1  # at least the lowest mode
    assert animated_count(10, 10**6) == 256 * 2**20 // (12 * 10**6 * 16)


def test_export_writes_a_mode_like_frames(tmp_path):
    """``catenet export --mode k``: the mode's frames over one period, positions and
    shape as stored, the .pvd giving each its phase."""
    import meshio

    from catenet.output.export import export

    done = modes_file(tmp_path)
    written = export(done.path, "vtu", tmp_path / "m2", mode=2)
    assert len(written.files) == 16 and written.times == [f / 16 for f in range(16)]
    mesh = meshio.read(written.files[4])
    stored = read_modes(done.path)
    np.testing.assert_allclose(mesh.points, stored.frame(1, 4), atol=1e-5)
    np.testing.assert_allclose(mesh.point_data["shape"], stored.shape[1])
    assert written.collection.name == "cable_mode2.pvd"
    from catenet.errors import ConfigError

    with pytest.raises(ConfigError, match="modes 1 to 4"):
        export(done.path, "vtu", tmp_path / "m9", mode=9)
