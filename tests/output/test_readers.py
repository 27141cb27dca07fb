"""Result files in other people's readers: meshio's XDMF time-series reader and
``meshio.read``, pyvista (VTK's XDMF reader, the one ParaView uses), a plain
``h5py.File(path, "r")``, also for a run killed with SIGKILL; ``catenet export`` and
``catenet repair``."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest
import pyvista as pv
from click.testing import CliRunner
from conftest import catenet_command, check_xdmf, read_with_vtk, small_net, subprocess_env

from catenet.case import load_case
from catenet.cli import main
from catenet.output import trajectory_length
from catenet.run.runner import run_case


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def stored(path: Path) -> dict:
    """The complete frames of a result file as the HDF5 datasets hold them."""
    with h5py.File(path, "r") as h5:  # a plain reader: no SWMR, no recovery
        n = trajectory_length(h5)
        g = h5["trajectory"]
        out = {name: g[name][:n] for name in ("time", "x", "tension", "v") if name in g}
        out["edges"] = h5["mesh/edges"][()]
    return out


def check_meshio_series(xdmf: Path, data: dict) -> None:
    """meshio's TimeSeriesReader gives every frame's time, positions (point data
    ``position``; its points are the first frame's) and tensions, bitwise."""
    n = len(data["time"])
    with meshio.xdmf.TimeSeriesReader(xdmf) as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == n
        np.testing.assert_array_equal(points, data["x"][0])
        assert cells[0].type == "line"
        np.testing.assert_array_equal(cells[0].data, data["edges"])
        for k in range(n):
            t, point_data, cell_data = reader.read_data(k)
            assert t == data["time"][k]
            np.testing.assert_array_equal(point_data["position"], data["x"][k])
            np.testing.assert_array_equal(cell_data["tension"][0], data["tension"][k])
            if "v" in data:
                np.testing.assert_array_equal(point_data["velocity"], data["v"][k])


def check_pyvista_series(xdmf: Path, data: dict) -> None:
    """pyvista (VTK's XDMF reader) reads every frame's points and tensions, without a
    single VTK error or warning."""
    with pv.VtkErrorCatcher() as caught:
        reader = pv.get_reader(str(xdmf))
        np.testing.assert_array_equal(reader.time_values, data["time"])
        for k, t in enumerate(reader.time_values):
            reader.set_active_time_value(t)
            mesh = reader.read()
            np.testing.assert_array_equal(mesh.points, data["x"][k])
            np.testing.assert_array_equal(mesh.cell_data["tension"], data["tension"][k])
            assert mesh.n_cells == len(data["edges"])
    assert not caught.events, [str(e.alert) for e in caught.events]


@pytest.mark.parametrize("method", ["static", "dynamic"])
def test_meshio_and_pyvista_read_a_trajectory(tmp_path, write_case, method):
    over = ["solver.steps=4"] if method == "static" else ["solver.t_end=0.12"]
    case = load_case(write_case(small_net(method=method, every=1)), over)
    out = tmp_path / f"{method}.h5"
    res = run_case(case, out)
    assert res.converged or method == "dynamic"
    data = stored(out)
    assert len(data["time"]) == (4 if method == "static" else 13)
    assert ("v" in data) == (method == "dynamic")
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["grids"] == len(data["time"])
    check_meshio_series(out.with_suffix(".xdmf"), data)
    check_pyvista_series(out.with_suffix(".xdmf"), data)


def test_meshio_read_and_pyvista_read_a_final_state(tmp_path, write_case):
    """A file with the final state only: one grid, which meshio.read takes whole."""
    case = load_case(write_case(small_net(method="static", every=0)))
    out = tmp_path / "final.h5"
    run_case(case, out)
    with h5py.File(out, "r") as h5:
        x, tension, edges = h5["result/x"][()], h5["result/tension"][()], h5["mesh/edges"][()]
        reaction = h5["result/reaction"][()]
    mesh = meshio.read(out.with_suffix(".xdmf"))
    np.testing.assert_array_equal(mesh.points, x)
    np.testing.assert_array_equal(mesh.cells[0].data, edges)
    np.testing.assert_array_equal(mesh.cell_data["tension"][0], tension)
    np.testing.assert_array_equal(mesh.point_data["reaction"], reaction)
    # VTK's XDMF reader (ParaView's). pyvista's own XdmfReader (0.49) fails on a file
    # without times (it asks for the first time step), so it is wrapped here.
    grid, events = read_with_vtk(out.with_suffix(".xdmf"))
    assert not events
    np.testing.assert_array_equal(grid.points, x)
    np.testing.assert_array_equal(grid.cell_data["tension"], tension)


# --------------------------------------------------------------------------------------------
# A run killed with SIGKILL
# --------------------------------------------------------------------------------------------

# About 2000 steps of 5e-4 s: seconds of frames (flushed once a second), then killed.
KILLED = small_net(dt=5e-4, damping=0.1, t_end=1.0, every=1)


def wait_for_flushes(path: Path, frames: int, proc: subprocess.Popen, timeout=120.0) -> None:
    """Waits until the published file holds ``frames`` frames (a plain reader opens it
    at any moment)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            out, err = proc.communicate()
            raise AssertionError(f"catenet ended early ({proc.returncode}):\n{out}\n{err}")
        if path.exists():
            with h5py.File(path, "r") as h5:
                if "trajectory" in h5 and trajectory_length(h5) >= frames:
                    return
        time.sleep(0.02)
    proc.kill()
    raise AssertionError(f"{path}: fewer than {frames} frames after {timeout} s")


@pytest.mark.slow
def test_a_killed_run_opens_in_every_reader_with_the_uninterrupted_frames(tmp_path, write_case):
    case = write_case(KILLED)
    out = tmp_path / "killed.h5"
    proc = subprocess.Popen(
        catenet_command("run", case, "-o", out),
        env=subprocess_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_for_flushes(out, 2, proc)  # the first frame, then a batch
        time.sleep(0.3)  # somewhere between flushes, or in one
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    killed = stored(out)  # a plain h5py.File(path, "r") opens it
    n = len(killed["time"])
    assert n >= 2
    with h5py.File(out, "r") as h5:
        assert "result" not in h5
    # The sidecar names exactly the frames in the file, and every reader reads them.
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["grids"] == n
    check_meshio_series(out.with_suffix(".xdmf"), killed)
    check_pyvista_series(out.with_suffix(".xdmf"), killed)
    spare = tmp_path / ".killed.h5.spare"
    # The uninterrupted run's first n frames are the same, bit for bit.
    t_stop = float(killed["time"][-1]) + 0.002
    full = tmp_path / "full.h5"
    r = subprocess.run(
        catenet_command("run", case, "-o", full, "--set", f"solver.t_end={t_stop!r}"),
        env=subprocess_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode in (0, 1), r.stderr  # 1: not at rest by t_end
    whole = stored(full)
    assert len(whole["time"]) > n
    for name in ("time", "x", "tension", "v"):
        np.testing.assert_array_equal(killed[name], whole[name][:n], err_msg=name)
    # catenet repair: the file needed nothing; the spare copy the killed run left goes.
    r = invoke("repair", out)
    assert r.exit_code == 0, r.output
    assert "fine as it was" in r.stdout and f"{n} complete frames" in r.stdout
    assert not spare.exists()
    np.testing.assert_array_equal(stored(out)["x"], killed["x"])


# --------------------------------------------------------------------------------------------
# catenet repair of files that need it
# --------------------------------------------------------------------------------------------

# How earlier catenet versions wrote files: in place, in SWMR mode, flushed after every frame.
OLD_WRITER = """
import sys, h5py, numpy as np
with h5py.File({path!r}, "w", libver=("v110", "v110")) as h5:
    h5["mesh/nodes"] = np.zeros((3, 3)); h5["mesh/edges"] = np.array([[0, 1], [1, 2]])
    g = h5.create_group("trajectory")
    ds = {{name: g.create_dataset(name, shape=(0, *tail), maxshape=(None, *tail), chunks=(1, *tail),
        fillvalue=np.nan) for name, tail in (("time", ()), ("x", (3, 3)), ("tension", (2,)))}}
    h5.swmr_mode = True
    for k in range(10):
        for name, value in (("x", np.full((3, 3), k)), ("tension", [k, k]), ("time", 0.5 * k)):
            ds[name].resize(k + 1, axis=0); ds[name][k] = value
        h5.flush()
    print("ready", flush=True)
    sys.stdin.read()
"""


def test_repair_mends_a_file_killed_while_open_for_write(tmp_path):
    path = tmp_path / "old.h5"
    proc = subprocess.Popen(
        [sys.executable, "-c", OLD_WRITER.format(path=str(path))],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout.readline().strip() == "ready"
    proc.kill()
    proc.communicate()
    with pytest.raises(OSError):
        h5py.File(path, "r")  # HDF5's "open for write" mark
    r = invoke("repair", path)
    assert r.exit_code == 0, r.output
    assert "rewritten (ordinary HDF5 readers refuse it" in r.stdout
    assert "10 complete frames" in r.stdout
    data = stored(path)
    np.testing.assert_array_equal(data["x"][:, 0, 0], np.arange(10))
    check_xdmf(path.with_suffix(".xdmf"))
    check_meshio_series(path.with_suffix(".xdmf"), data)
    # Once mended, nothing more to do.
    r = invoke("repair", path)
    assert r.exit_code == 0 and "fine as it was" in r.stdout


def test_repair_refuses_what_is_not_a_result_file(tmp_path):
    text = tmp_path / "notes.h5"
    text.write_text("not hdf5")
    r = invoke("repair", tmp_path / "missing.h5")
    assert r.exit_code == 2 and "no such result file" in r.stderr
    r = invoke("repair", text)
    assert r.exit_code == 2 and "not an HDF5 file" in r.stderr
    with h5py.File(tmp_path / "other.h5", "w") as h5:
        h5["data"] = [1.0]
    r = invoke("repair", tmp_path / "other.h5")
    assert r.exit_code == 2 and "not a catenet result file" in r.stderr


# --------------------------------------------------------------------------------------------
# catenet export
# --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def dynamic_result(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("export")
    case = tmp / "case.toml"
    case.write_text(small_net(every=2))
    out = tmp / "dyn.h5"
    run_case(load_case(case, ["solver.t_end=0.1"]), out)
    return out


@pytest.mark.parametrize("fmt", ["vtu", "vtk", "xdmf"])
def test_export_writes_one_file_per_frame(dynamic_result, tmp_path, fmt):
    data = stored(dynamic_result)
    with h5py.File(dynamic_result, "r") as h5:
        nodes = h5["mesh/nodes"][()]
        rest = h5["mesh/rest_length"][()]
    r = invoke("export", dynamic_result, "--to", fmt, "-o", tmp_path / "x")
    assert r.exit_code == 0, r.output
    n = len(data["time"])
    files = sorted((tmp_path / "x").glob(f"dyn_*.{fmt}"))
    assert [f.name for f in files] == [f"dyn_{k:04d}.{fmt}" for k in range(n)]
    assert f"{n} {fmt} files" in r.stdout
    for k, f in enumerate(files):
        mesh = meshio.read(f)
        np.testing.assert_array_equal(mesh.points, data["x"][k])
        np.testing.assert_array_equal(mesh.cells[0].data, data["edges"])
        np.testing.assert_array_equal(mesh.cell_data["tension"][0], data["tension"][k])
        np.testing.assert_array_equal(mesh.cell_data["rest_length"][0], rest)
        np.testing.assert_array_equal(mesh.point_data["velocity"], data["v"][k])
        np.testing.assert_array_equal(mesh.point_data["displacement"], data["x"][k] - nodes)
    pvd = tmp_path / "x" / "dyn.pvd"
    assert pvd.exists() == (fmt in ("vtu", "vtk"))
    if pvd.exists():  # ParaView's collection: every file with its time
        with pv.VtkErrorCatcher() as caught:
            reader = pv.get_reader(str(pvd))
            np.testing.assert_array_equal(reader.time_values, data["time"])
            reader.set_active_time_value(reader.time_values[-1])
            last = reader.read()[0]
        assert not caught.events
        np.testing.assert_array_equal(last.points, data["x"][-1])


def test_export_frames_and_final_state(dynamic_result, tmp_path, write_case):
    r = invoke("export", dynamic_result, "--to", "vtu", "-o", tmp_path / "a", "--frames", "1:4:2")
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "a").glob("*.vtu")) == [
        "dyn_0001.vtu",
        "dyn_0003.vtu",
    ]
    r = invoke("export", dynamic_result, "--to", "xdmf", "-o", tmp_path / "b", "--frames", "last")
    assert r.exit_code == 0, r.output
    n = len(stored(dynamic_result)["time"])
    last = meshio.read(tmp_path / "b" / f"dyn_{n - 1:04d}.xdmf")
    np.testing.assert_array_equal(last.points, stored(dynamic_result)["x"][-1])
    # A file without a trajectory: its final state, with the reactions; default directory.
    case = load_case(write_case(small_net(method="static", every=0)))
    final = tmp_path / "final.h5"
    run_case(case, final)
    r = invoke("export", final, "--to", "vtk")
    assert r.exit_code == 0, r.output
    mesh = meshio.read(tmp_path / "final-vtk" / "final_result.vtk")
    with h5py.File(final, "r") as h5:
        np.testing.assert_array_equal(mesh.points, h5["result/x"][()])
        np.testing.assert_array_equal(mesh.point_data["reaction"], h5["result/reaction"][()])


def test_export_bad_input(dynamic_result, tmp_path, monkeypatch):
    for spec, words in (("99", "has 6 frames"), ("1:1", "selects none"), ("x", "must be all")):
        r = invoke("export", dynamic_result, "--to", "vtu", "-o", tmp_path, "--frames", spec)
        assert r.exit_code == 2 and words in r.stderr, (spec, r.stderr)
    r = invoke("export", tmp_path / "missing.h5", "--to", "vtu")
    assert r.exit_code == 2 and "no such result file" in r.stderr
    r = invoke("export", dynamic_result, "--to", "stl")
    assert r.exit_code == 2 and "'stl' is not one of" in r.stderr
    monkeypatch.setitem(sys.modules, "meshio", None)  # as if meshio were not installed
    r = invoke("export", dynamic_result, "--to", "vtu", "-o", tmp_path / "c")
    assert r.exit_code == 1 and "needs meshio" in r.stderr and "pip install meshio" in r.stderr
    assert "Traceback" not in r.output


def test_peaks_of_a_damaged_file_are_bad_input_not_silently_dropped(tmp_path, monkeypatch):
    """The long fuzz run (seed 3) found a restart from a dynamic file with flipped bytes
    ending in an internal RuntimeError ("incorrect metadata checksum") where the peaks
    were read. A damaged /result there is bad input naming the file; a file written
    before peaks existed still restarts without them (None)."""
    import contextlib

    import catenet.output.reader as reader
    from catenet.errors import ConfigError

    class Broken:
        def get(self, name):
            raise RuntimeError(
                "Unable to synchronously check link existence (incorrect metadata checksum)"
            )

    @contextlib.contextmanager
    def broken(path):
        yield Broken()

    monkeypatch.setattr(reader, "open_result", broken)
    with pytest.raises(ConfigError, match="damaged or not a catenet result file"):
        reader.read_peaks(tmp_path / "d.h5", 1.0)

    class Old:
        def get(self, name):
            return None  # no /result group: nothing to go on with

    @contextlib.contextmanager
    def old(path):
        yield Old()

    monkeypatch.setattr(reader, "open_result", old)
    assert reader.read_peaks(tmp_path / "d.h5", 1.0) is None


def test_a_file_whose_positions_no_run_writes_is_damaged_for_plot(tmp_path, write_case):
    """The long fuzz run (seed 6) found `catenet plot` of a static file with flipped bytes
    ending in matplotlib's "Singular matrix": a node at 7.5e307 m. Positions beyond what
    a run keeps (+-1e100) or not finite are a damaged file: exit 2 naming the dataset."""
    case = write_case(small_net(method="static"))
    out = tmp_path / "s.h5"
    runner = CliRunner()
    assert runner.invoke(main, ["run", str(case), "-o", str(out), "-q"]).exit_code == 0
    for value in (7.490388061926316e307, float("nan")):
        with h5py.File(out, "r+") as h5:
            h5["mesh/nodes"][0, 0] = value
        r = runner.invoke(main, ["plot", str(out), "-o", str(tmp_path / "f.png")])
        assert r.exit_code == 2, r.output
        assert "/mesh/nodes holds positions beyond +-1e+100 m or not finite" in r.output
