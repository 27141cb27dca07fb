"""The result file (contract §5), its XDMF sidecar, and what survives crashes and full
disks."""

from __future__ import annotations

import datetime
import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import check_xdmf, small_net, subprocess_env, wait_for_frames

import catenet
from catenet.errors import ConfigError, OutputError
from catenet.output import (
    ResultWriter,
    check_output_path,
    open_result,
    read_frame,
    recover,
    trajectory_length,
)
from catenet.solver.result import Result, SolverStats, Timing


def make_scene(**kw):
    from catenet.case import build, parse_case

    return build(parse_case(tomllib.loads(small_net(**kw))))


def fake_result(scene, x, *, v=None, converged=True, message="equilibrium"):
    net = scene.net
    tension = np.linspace(0.0, 5.0, net.n_edges)
    reaction = np.zeros_like(x)
    reaction[net.fixed] = 1.0
    return Result(
        x=x,
        tension=tension,
        reaction=reaction,
        converged=converged,
        iterations=7,
        residual=1e-9,
        steps=3,
        time=0.2,
        v=v,
        equilibrium=converged,
        wall_time=0.5,
        message=message,
        max_strain=0.01,
    )


def moved(scene, k):
    x = scene.net.nodes.copy()
    x[~scene.net.fixed, 2] -= 0.001 * k
    return x


def test_layout_of_a_dynamic_run(tmp_path):
    scene = make_scene()
    net = scene.net
    path = tmp_path / "new" / "dir" / "run.h5"  # missing directories are created
    with ResultWriter(path, scene, every=1, attrs={"linear_backend": "scipy"}) as w:
        for k in range(3):
            w.frame(0.1 * k, moved(scene, k), np.full((net.n_nodes, 3), 0.5 * k))
        w.result(fake_result(scene, moved(scene, 2), v=np.zeros((net.n_nodes, 3))))
    n, m = net.n_nodes, net.n_edges
    with h5py.File(path, "r") as h5:  # a closed file opens with any HDF5 reader
        assert h5.attrs["catenet_version"] == catenet.__version__
        assert h5.attrs["case"] == scene.case.to_toml()
        assert tomllib.loads(h5.attrs["case"])["solver"]["method"] == "dynamic"
        assert datetime.datetime.fromisoformat(h5.attrs["created"]).tzinfo is not None
        for name in ("numpy", "scipy", "numba", "h5py", "hdf5"):
            assert h5.attrs[f"{name}_version"]
        assert h5.attrs["linear_backend"] == "scipy"
        mesh = h5["mesh"]
        assert mesh["nodes"].shape == (n, 3) and mesh["nodes"].dtype == np.float64
        assert mesh["edges"].shape == (m, 2) and mesh["edges"].dtype == np.int64
        assert mesh["rest_length"].shape == (m,) and mesh["EA"].shape == (m,)
        assert mesh["fixed"].dtype == bool and mesh["fixed"][()].sum() == net.fixed.sum()
        np.testing.assert_array_equal(mesh["edges"][()], net.edges)
        traj = h5["trajectory"]
        np.testing.assert_allclose(traj["time"][()], [0.0, 0.1, 0.2])
        assert traj["x"].shape == (3, n, 3) and traj["v"].shape == (3, n, 3)
        assert traj["tension"].shape == (3, m)
        for name in ("x", "v", "tension"):
            ds = traj[name]
            assert ds.maxshape[0] is None and ds.chunks[0] == 1 and ds.compression == "gzip"
        np.testing.assert_array_equal(traj["x"][1], moved(scene, 1))
        np.testing.assert_array_equal(traj["v"][2], 1.0)
        assert np.all(traj["tension"][0] == 0.0)  # the reference state is unstressed
        res = h5["result"]
        assert res["x"].shape == (n, 3) and res["tension"].shape == (m,)
        assert res["reaction"].shape == (n, 3)
        a = dict(res.attrs)
        assert a["converged"] and a["equilibrium"] and a["iterations"] == 7 and a["steps"] == 3
        assert a["message"] == "equilibrium" and a["wall_time"] == 0.5 and a["time"] == 0.2
        assert a["residual"] == 1e-9 and a["max_strain"] == 0.01
        assert a["delta"] == pytest.approx(0.002) and a["probe"] == scene.probe
        assert a["delta_over_L"] == pytest.approx(0.002 / scene.size)
    found = check_xdmf(path.with_suffix(".xdmf"))
    assert found["grids"] == 3 and found["times"] == pytest.approx([0.0, 0.1, 0.2])
    assert found["slabs"] == 9  # x, tension, v of every frame


def test_every_zero_writes_no_trajectory(tmp_path):
    scene = make_scene(method="static", every=0)
    path = tmp_path / "final.h5"
    with ResultWriter(path, scene, every=0) as w:
        w.frame(1.0, moved(scene, 1))  # ignored: the run keeps the final state only
        w.result(fake_result(scene, moved(scene, 1)))
    with h5py.File(path, "r") as h5:
        assert "trajectory" not in h5
        assert "v" not in h5["result"]  # a static case keeps no velocities
        np.testing.assert_array_equal(h5["result/x"][()], moved(scene, 1))
    found = check_xdmf(path.with_suffix(".xdmf"))
    # topology, x, tension, reaction and contact_force
    assert found["grids"] == 1 and found["slabs"] == 0 and found["refs"] == 5
    text = path.with_suffix(".xdmf").read_text()
    assert "/result/x" in text and "/result/tension" in text


def test_non_finite_frames_are_refused_and_earlier_frames_kept(tmp_path):
    scene = make_scene()
    path = tmp_path / "nan.h5"
    with ResultWriter(path, scene, every=1) as w:
        w.frame(0.0, moved(scene, 0))
        w.frame(0.1, moved(scene, 1))
        bad = moved(scene, 2)
        bad[3, 1] = np.nan
        with pytest.raises(OutputError, match="non-finite"):
            w.frame(0.2, bad)
        with pytest.raises(OutputError, match="non-finite"):
            w.frame(0.2, moved(scene, 2), np.full((scene.net.n_nodes, 3), np.inf))
        with pytest.raises(OutputError, match="non-finite"):
            w.result(fake_result(scene, bad))
    with h5py.File(path, "r") as h5:
        assert trajectory_length(h5) == 2
        assert np.all(np.isfinite(h5["trajectory/x"][()]))
    assert check_xdmf(path.with_suffix(".xdmf"))["grids"] == 2


def test_output_path_checks_create_nothing(tmp_path):
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(ConfigError, match="is a directory"):
        check_output_path(tmp_path)
    with pytest.raises(ConfigError, match="not a directory"):
        check_output_path(tmp_path / "a_file" / "sub" / "out.h5")
    assert check_output_path(tmp_path / "x" / "y" / "out.h5") == tmp_path / "x" / "y" / "out.h5"
    assert not (tmp_path / "x").exists()  # checking creates nothing


def test_output_path_permission(tmp_path):
    """A directory the user may not write to is refused before any computation. Root
    may write anywhere: as root the check runs in a child without the capability that
    overrides file permissions (CAP_DAC_OVERRIDE, dropped with util-linux's setpriv)."""
    import subprocess
    import sys

    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    script = (
        "from catenet.errors import ConfigError\n"
        "from catenet.output import check_output_path\n"
        "try:\n"
        f"    check_output_path({str(locked / 'out.h5')!r})\n"
        "except ConfigError as exc:\n"
        "    print(exc)\n"
    )
    command = [sys.executable, "-c", script]
    if os.geteuid() == 0:
        caps = "-dac_override,-dac_read_search"
        command = ["setpriv", f"--bounding-set={caps}", f"--inh-caps={caps}", *command]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    finally:
        locked.chmod(0o700)
    assert done.returncode == 0, done.stderr
    assert "permission denied" in done.stdout
    assert not (locked / "out.h5").exists()


def test_result_can_be_read_back_as_a_frame(tmp_path):
    scene = make_scene(every=0)
    path = tmp_path / "r.h5"
    v = np.full((scene.net.n_nodes, 3), 0.25)
    with ResultWriter(path, scene, every=0) as w:
        w.result(fake_result(scene, moved(scene, 4), v=v))
    frame = read_frame(path)
    assert frame.source == "result" and frame.t == 0.2
    np.testing.assert_array_equal(frame.v, v)
    with pytest.raises(ConfigError, match="no such result file"):
        read_frame(tmp_path / "missing.h5")


def test_solve_and_startup_time_come_from_a_runs_timing_only(tmp_path):
    """/result solve_time and startup_time are a whole run's (``Result.timing``, set by
    ``catenet run``); a result without one (a sweep's saved run, a Python solve) stores
    -1, not its linear solver's seconds (``Result.stats``)."""
    scene = make_scene(every=0)
    res = fake_result(scene, moved(scene, 1))
    res.stats = SolverStats(backend="scipy", solve_seconds=0.25, factorize_seconds=0.5)
    with ResultWriter(tmp_path / "a.h5", scene, every=0) as w:
        w.result(res)
    res.timing = Timing(solve=1.5, startup=0.75)
    with ResultWriter(tmp_path / "b.h5", scene, every=0) as w:
        w.result(res)
    with h5py.File(tmp_path / "a.h5") as a, h5py.File(tmp_path / "b.h5") as b:
        assert a["result"].attrs["solve_time"] == -1.0 == a["result"].attrs["startup_time"]
        assert b["result"].attrs["solve_time"] == 1.5
        assert b["result"].attrs["startup_time"] == 0.75


WRITER_SCRIPT = """
import sys, tomllib, numpy as np
sys.path.insert(0, {tests!r})
from conftest import small_net
from catenet.case import build, parse_case
from catenet.output import ResultWriter
scene = build(parse_case(tomllib.loads(small_net())))
x0 = scene.net.nodes
with ResultWriter({path!r}, scene, every=1, flush_frames=50) as w:
    k = 0
    while True:
        w.frame(0.5 * k, x0 + k, np.full_like(x0, k))
        k += 1
"""


@pytest.mark.parametrize("delay", [0.0, 0.137, 0.31])
def test_sigkill_leaves_a_readable_file(tmp_path, delay):
    """A writer killed at an arbitrary moment leaves every flushed frame readable (it
    flushes every 50 frames, so that the kill meets a flush as often as a frame)."""
    path = tmp_path / "killed.h5"
    script = WRITER_SCRIPT.format(tests=str(Path(__file__).parents[1]), path=str(path))
    proc = subprocess.Popen(
        [sys.executable, "-c", script],
        env=subprocess_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_for_frames(path, 5, proc)
        time.sleep(delay)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    with h5py.File(path, "r") as h5:  # an ordinary file: it is only ever replaced whole
        assert trajectory_length(h5) >= 5
    with open_result(path) as h5:
        n = trajectory_length(h5)
        assert n >= 5
        g = h5["trajectory"]
        t = g["time"][:n]
        np.testing.assert_array_equal(t, 0.5 * np.arange(n))
        x = g["x"][:n]
        nodes = h5["mesh/nodes"][()]
        for k in range(n):
            np.testing.assert_array_equal(x[k], nodes + k)
            assert np.all(g["v"][k] == k)
        assert "result" not in h5
    frame = read_frame(path)
    assert frame.index == n - 1 and frame.t == 0.5 * (n - 1)
    # catenet plot reads it as it is (its last flushed frame stands in for /result).
    from catenet.output import read_result

    shown = read_result(path)
    np.testing.assert_array_equal(shown.x, frame.x)
    # recover() turns it into an ordinary file with a matching sidecar.
    recover(path)
    with h5py.File(path, "r") as h5:
        assert h5["trajectory/x"].shape[0] == n
    assert check_xdmf(path.with_suffix(".xdmf"))["grids"] == n


FULL_DISK_SCRIPT = """
import json, resource, signal, sys, tomllib, numpy as np
sys.path.insert(0, {tests!r})
from conftest import small_net
from catenet.case import build, parse_case
from catenet.errors import OutputError
from catenet.output import ResultWriter
from catenet.solver.result import Result
scene = build(parse_case(tomllib.loads(small_net())))
net = scene.net
rng = np.random.default_rng(1)
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes beyond the limit fail with EFBIG
resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))
out = {{}}
with ResultWriter({path!r}, scene, every=1) as w:
    for k in range(200):  # incompressible frames: the limit is reached after a few
        w.frame(0.1 * k, net.nodes + rng.random(net.nodes.shape), rng.random(net.nodes.shape))
    x = net.nodes + 0.125
    res = Result(x=x, tension=np.ones(net.n_edges), reaction=np.zeros_like(x), converged=True,
                 iterations=3, residual=0.0, steps=200, time=20.0, v=np.zeros_like(x))
    try:
        w.result(res)
    except OutputError as exc:
        out = dict(message=str(exc), saved_to=str(exc.saved_to), frames=w.frames)
print(json.dumps(out))
"""


def test_full_disk_keeps_the_result_in_a_temporary_file(tmp_path):
    path = tmp_path / "full.h5"
    script = FULL_DISK_SCRIPT.format(
        tests=str(Path(__file__).parents[1]), path=str(path), limit=120_000
    )
    proc = subprocess.run(
        [sys.executable, "-c", script],
        env=subprocess_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out, "writing never failed: the file size limit did not apply"
    saved = Path(out["saved_to"])
    try:
        assert str(saved) in out["message"] and str(path) in out["message"]
        assert 0 < out["frames"] < 200
        with h5py.File(saved, "r") as h5:
            np.testing.assert_array_equal(h5["result/x"][()], h5["mesh/nodes"][()] + 0.125)
            assert bool(h5["result"].attrs["converged"])
            assert "failed" in h5.attrs["note"]
        with open_result(path) as h5:  # the frames written before the failure
            assert trajectory_length(h5) >= out["frames"] - 1
        recover(path)  # an ordinary file again, its sidecar matching
        with h5py.File(path, "r") as h5:
            assert trajectory_length(h5) >= out["frames"] - 1
            assert np.all(np.isfinite(h5["trajectory/x"][()]))
        check_xdmf(path.with_suffix(".xdmf"))
    finally:
        saved.unlink(missing_ok=True)


def test_xdmf_of_a_static_run_with_steps(tmp_path):
    from catenet.case import load_case
    from catenet.run.runner import run_case

    case_file = tmp_path / "c.toml"
    case_file.write_text(small_net(method="static", every=1))
    case = load_case(case_file, ["solver.steps=3"])
    res = run_case(case, tmp_path / "s.h5")
    assert res.converged and res.steps == 3
    found = check_xdmf(tmp_path / "s.xdmf")
    assert found["times"] == pytest.approx([1 / 3, 2 / 3, 1.0])  # time = load factor
    with h5py.File(tmp_path / "s.h5", "r") as h5:
        assert "v" not in h5["trajectory"]
        np.testing.assert_array_equal(h5["trajectory/x"][-1], h5["result/x"][()])


def test_recover_rewrites_a_clean_file(tmp_path):
    scene = make_scene()
    path = tmp_path / "ok.h5"
    with ResultWriter(path, scene, every=1) as w:
        w.frame(0.0, moved(scene, 0))
        w.result(fake_result(scene, moved(scene, 0), v=np.zeros((scene.net.n_nodes, 3))))
    recover(path, tmp_path / "copy.h5")
    with h5py.File(tmp_path / "copy.h5", "r") as a, h5py.File(path, "r") as b:
        assert dict(a["result"].attrs) == dict(b["result"].attrs)
        assert a.attrs["case"] == b.attrs["case"]
    check_xdmf(tmp_path / "copy.xdmf")


def test_writer_refuses_bad_every(tmp_path):
    with pytest.raises(ConfigError, match="output.every"):
        ResultWriter(tmp_path / "x.h5", make_scene(), every=-1)
    assert not (tmp_path / "x.h5").exists()


# --------------------------------------------------------------------------------------------
# Flushing in batches into a file that is only ever replaced whole
# --------------------------------------------------------------------------------------------


def ticking(step: float = 10.0):
    """A clock for the writer's flush interval that advances ``step`` s per reading."""
    now = [0.0]

    def clock() -> float:
        now[0] += step
        return now[0]

    return clock


def frames_on_disk(path) -> int:
    with h5py.File(path, "r") as h5:  # a plain reader opens the file at any moment
        return trajectory_length(h5)


def test_frames_reach_the_file_in_batches_by_count_and_by_time(tmp_path):
    scene = make_scene()
    path = tmp_path / "batches.h5"
    spare = tmp_path / ".batches.h5.spare"
    with ResultWriter(path, scene, every=1, flush_seconds=1e9, flush_frames=3) as w:
        assert frames_on_disk(path) == 0 and spare.exists()
        w.frame(0.0, moved(scene, 0))  # the first frame at once
        assert frames_on_disk(path) == 1 and w.flushes == 1
        for k in range(1, 7):
            w.frame(0.1 * k, moved(scene, k))
        assert frames_on_disk(path) == 7 and w.flushes == 3  # 1 + 3 + 3
        w.frame(0.7, moved(scene, 7))
        assert frames_on_disk(path) == 7 and w.pending == 1  # in memory until the next flush
        assert check_xdmf(path.with_suffix(".xdmf"))["grids"] == 7  # in step with the file
    assert frames_on_disk(path) == 8 and not spare.exists()
    assert check_xdmf(path.with_suffix(".xdmf"))["grids"] == 8
    # By wall time: frames 10 s apart, flushed every second: each frame at once.
    with ResultWriter(tmp_path / "each.h5", scene, every=1, flush_seconds=1.0) as w:
        w.clock = ticking()
        for k in range(4):
            w.frame(0.1 * k, moved(scene, k))
            assert frames_on_disk(tmp_path / "each.h5") == k + 1
        assert w.flushes == 4
    with h5py.File(tmp_path / "each.h5", "r") as h5:
        for k in range(4):  # what was given, bit for bit
            np.testing.assert_array_equal(h5["trajectory/x"][k], moved(scene, k))


def test_a_reader_holding_the_file_open_keeps_its_version(tmp_path):
    """The version a reader has open is never written to: the writer copies instead."""
    scene = make_scene()
    path = tmp_path / "held.h5"
    with ResultWriter(path, scene, every=1) as w:
        w.clock = ticking()  # every frame flushed
        w.frame(0.0, moved(scene, 0))
        w.frame(0.1, moved(scene, 1))
        with h5py.File(path, "r") as held:  # a reader (ParaView, say) keeps it open
            w.frame(0.2, moved(scene, 2))
            w.frame(0.3, moved(scene, 3))
            assert trajectory_length(held) == 2
            np.testing.assert_array_equal(held["trajectory/x"][1], moved(scene, 1))
        w.frame(0.4, moved(scene, 4))
    with h5py.File(path, "r") as h5:
        assert trajectory_length(h5) == 5
        for k in range(5):
            np.testing.assert_array_equal(h5["trajectory/x"][k], moved(scene, k))
    check_xdmf(path.with_suffix(".xdmf"))


def test_spares_of_a_killed_run_are_removed_by_the_next(tmp_path):
    scene = make_scene()
    path = tmp_path / "again.h5"
    for name in (".again.h5.spare", ".again.h5.prev"):
        (tmp_path / name).write_bytes(b"left by a killed run")
    with ResultWriter(path, scene, every=1) as w:
        assert not (tmp_path / ".again.h5.prev").exists()
        w.frame(0.0, moved(scene, 0))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["again.h5", "again.xdmf"]


def test_the_recorded_versions_are_the_installed_distributions():
    """``environment`` reads each version from its metadata's headers: the same as
    importlib.metadata.version, '' for a distribution that is not installed."""
    from importlib.metadata import PackageNotFoundError, version

    from catenet.output.metadata import environment

    env = environment()
    for name in ("numpy", "scipy", "numba", "h5py", "click", "pypardiso", "mkl"):
        try:
            expected = version(name)
        except PackageNotFoundError:
            expected = ""
        assert env[name] == expected, name
    assert env["numpy"] and env["h5py"]


def test_a_last_frame_is_written_with_the_result_in_one_flush(tmp_path):
    """``frame(..., last=True)``: the final frame waits for /result (one write, not two),
    and reaches the file on close when no result comes."""
    scene = make_scene()
    path = tmp_path / "last.h5"
    with ResultWriter(path, scene, every=1) as w:
        w.frame(0.5, moved(scene, 0))
        assert w.flushes == 1 and frames_on_disk(path) == 1  # the first frame at once
        w.frame(1.0, moved(scene, 1), last=True)
        assert w.flushes == 1 and frames_on_disk(path) == 1
        w.result(fake_result(scene, moved(scene, 1)))
        assert w.flushes == 2 and frames_on_disk(path) == 2
    with h5py.File(path, "r") as h5:
        assert list(h5["trajectory/time"][:]) == [0.5, 1.0] and "x" in h5["result"]
    alone = tmp_path / "alone.h5"
    with ResultWriter(alone, scene, every=1) as w:
        w.frame(1.0, moved(scene, 1), last=True)
        assert frames_on_disk(alone) == 0
    assert frames_on_disk(alone) == 1
