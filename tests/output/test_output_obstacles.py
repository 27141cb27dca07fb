"""Obstacles in result files (catenet/output/obstacles.py, catenet/output/surfaces.py):
every kind's surface in /mesh/obstacles, a moving one's pose and surface at every frame
(the solver's pose, and the closed form), the XDMF sidecar's grids (every path it names
exists with its shape; VTK's reader, ParaView's, shows them at each time; meshio still
reads the net), a killed run's file, a restart, a large moving mesh kept bounded, a run
that keeps only its final state, and ``read_obstacles``."""

from __future__ import annotations

import logging
import signal
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest
import pyvista as pv
from conftest import check_xdmf, read_with_vtk, spawn, wait_for_frames
from meshes import icosphere, write_stl
from scipy.spatial.transform import Rotation

from catenet.case import build, dumps_toml, load_case, parse_case
from catenet.output import read_obstacles, read_result, recover, repair, trajectory_length
from catenet.output.obstacles import FRAME_VERTICES, simplify
from catenet.run.runner import run_case
from catenet.terms.moving import Moving
from catenet.terms.shapes import closed_surface

BOX = {
    "kind": "box",
    "center": [0.0, -0.15, -0.3],
    "half_size": [0.08, 0.05, 0.04],
    "axis": [1.0, 1.0, 0.0],
    "angle": 0.35,
    "velocity": [0.3, 0.0, -0.1],
    "angular_velocity": [0.8, -0.6, 1.2],
}


def case_dict(mesh_file, *, moving=(BOX,), t_end=0.05, every=1, method="dynamic") -> dict:
    """A small net (sagging under pressure) above one fixed obstacle of each kind and
    the given moving ones, none touched in the run."""
    solver = {"method": "static", "steps": 2}
    if method == "dynamic":
        solver = {"method": "dynamic", "dt": 0.01, "t_end": t_end, "damping": 1.0}
    return {
        "title": "a net above obstacles",
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.3, "size": 1.0, "edge_length": 0.1},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"pressure": 100.0},
        "solver": solver,
        "output": {"every": every},
        "obstacle": [
            {"kind": "plane", "point": [0.0, 0.0, -0.6], "normal": [0.0, 0.0, 1.0]},
            {"kind": "sphere", "center": [0.3, 0.3, -0.4], "radius": 0.1},
            {"kind": "box", "center": [-0.3, 0.2, -0.4], "half_size": [0.1, 0.05, 0.08]},
            {"kind": "capsule", "start": [-0.3, -0.3, -0.5], "end": [0.2, -0.3, -0.5],
             "radius": 0.05},
            {"kind": "mesh", "file": str(mesh_file), "scale": 0.1, "offset": [0.3, -0.1, -0.45]},
            *moving,
        ],
    }  # fmt: skip


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    V, T = icosphere(2)
    return write_stl(tmp_path_factory.mktemp("mesh") / "ball.stl", V, T)


@pytest.fixture(scope="module")
def run(tmp_path_factory, ball):
    """The case run once: (result file, case)."""
    out = tmp_path_factory.mktemp("run") / "obstacles.h5"
    case = parse_case(case_dict(ball))
    res = run_case(case, out)
    assert res.converged, res.message
    return out, case


def closed_form(t: float, points) -> np.ndarray:
    """BOX's points (K, 3) at t = 0 where they are at t: turned about its centre by
    omega t (scipy's rotation vector), the centre moved by v t."""
    c0, v, w = (np.array(BOX[k]) for k in ("center", "velocity", "angular_velocity"))
    return c0 + v * t + Rotation.from_rotvec(w * t).apply(np.asarray(points) - c0)


def volume(V, T) -> float:
    return float(np.einsum("ij,ij->", V[T[:, 0]], np.cross(V[T[:, 1]], V[T[:, 2]]))) / 6.0


def test_every_kind_is_a_closed_outward_surface_and_the_moving_box_follows_its_motion(run, ball):
    out, case = run
    stored = read_obstacles(out)
    assert [(o.index, o.kind, o.moving) for o in stored] == [
        (0, "plane", False), (1, "sphere", False), (2, "box", False),
        (3, "capsule", False), (4, "mesh", False), (5, "box", True),
    ]  # fmt: skip
    plane, sphere, box, capsule, mesh, moving = stored
    with h5py.File(out, "r") as h5:
        g = h5["mesh/obstacles"]
        assert g.attrs["count"] == 6 and sorted(g, key=int) == ["0", "1", "2", "3", "4", "5"]
        assert g["5"].attrs["kind"] == "box" and g["5"].attrs["obstacle"] == 5
        assert bool(g["5"].attrs["moving"]) and not bool(g["2"].attrs["moving"])
        nodes = h5["mesh/nodes"][()]
    # closed, consistently oriented with outward normals (closed_surface would flip
    # them otherwise), and round enough: volumes within 2 % of the solids'
    for o, want in (
        (sphere, 4 / 3 * np.pi * 0.1**3),
        (box, 8 * 0.1 * 0.05 * 0.08),
        (capsule, np.pi * 0.05**2 * 0.5 + 4 / 3 * np.pi * 0.05**3),
        (moving, 8 * 0.08 * 0.05 * 0.04),
    ):
        V, T = closed_surface(o.vertices, o.triangles)
        assert volume(o.vertices, o.triangles) == pytest.approx(want, rel=0.02), o.kind
        assert volume(V, T) == pytest.approx(volume(o.vertices, o.triangles), rel=1e-12)
    assert len(box.triangles) == 12 and len(box.vertices) == 8
    assert len(sphere.vertices) >= 600  # 36 meridians, 18 parallels
    assert np.allclose(np.linalg.norm(sphere.vertices - [0.3, 0.3, -0.4], axis=1), 0.1)
    # the mesh as read (scaled and moved), every triangle of it
    Vm, Tm = icosphere(2)
    assert len(mesh.triangles) == len(Tm) and volume(mesh.vertices, mesh.triangles) > 0
    assert np.allclose(np.linalg.norm(mesh.vertices - [0.3, -0.1, -0.45], axis=1), 0.1)
    V4, T4 = case.obstacles[4].shape().surface_mesh()  # as the solver's term takes it
    assert np.array_equal(mesh.vertices, V4) and np.array_equal(mesh.triangles, T4)
    # the plane: a quad at z = -0.6 facing up, covering the net 1.5 times
    assert len(plane.vertices) == 4 and np.allclose(plane.vertices[:, 2], -0.6)
    n = np.cross(*(plane.vertices[plane.triangles[0, 1:]] - plane.vertices[plane.triangles[0, 0]]))
    assert n[2] > 0
    lo, hi = nodes[:, :2].min(axis=0), nodes[:, :2].max(axis=0)
    span = plane.vertices[:, :2].max(axis=0) - plane.vertices[:, :2].min(axis=0)
    assert span == pytest.approx(1.5 * (hi - lo))
    assert plane.vertices[:, :2].mean(axis=0) == pytest.approx(0.5 * (lo + hi))
    assert plane.times is None and box.frames is None  # fixed: no frames
    # the moving box: a pose and 8 corners per frame, as many frames as the net's
    r = read_result(out)
    assert len(r.times) == 6 and np.array_equal(moving.times, r.times)
    assert moving.frames.shape == (6, 8, 3) and moving.center.shape == (6, 3)
    assert np.array_equal(moving.frame_triangles, moving.triangles)
    (term,) = [t for t in build(case).terms if isinstance(t, Moving)]
    for k, t in enumerate(moving.times):
        # the closed form: rotation about the axis by |omega| t, the centre moved by v t
        np.testing.assert_allclose(moving.frames[k], closed_form(t, moving.vertices), atol=1e-14)
        # the solver's pose, exactly
        c, R = term.pose(t)
        assert np.array_equal(moving.center[k], c) and np.array_equal(moving.rotation[k], R)
        assert np.array_equal(moving.frames[k], c + (moving.vertices - moving.origin) @ R.T)
    assert moving.times[-1] == pytest.approx(0.05) and moving.times[1] > 0
    assert not np.allclose(moving.frames[-1], moving.frames[0])
    # at /result's time too
    np.testing.assert_array_equal(moving.final, moving.frames[-1])
    # at t = 0 the box is where the case puts it: corners at +-half along its turned axes
    axis = np.array(BOX["axis"]) / np.linalg.norm(BOX["axis"])
    R0 = Rotation.from_rotvec(BOX["angle"] * axis).as_matrix()
    body = (moving.vertices - BOX["center"]) @ R0
    np.testing.assert_allclose(np.abs(body), np.tile(BOX["half_size"], (8, 1)), atol=1e-15)
    assert len(np.unique(np.sign(body), axis=0)) == 8


def test_the_sidecar_shows_every_obstacle_at_every_frame(run, tmp_path):
    out, _ = run
    side = out.with_suffix(".xdmf")
    found = check_xdmf(side)  # every DataItem's dataset exists with its stated shape
    assert found["grids"] == 6 and found["others"] == 5 + 6  # 5 fixed, 6 frames of the box
    root = ET.parse(side).getroot()
    domain = root.find("Domain")
    tops = [(g.get("Name"), g.get("CollectionType")) for g in domain.findall("Grid")]
    assert tops == [
        ("obstacles", "Spatial"),
        ("obstacle[5] box", "Temporal"),
        ("trajectory", "Temporal"),  # the net's last: meshio's time-series reader takes it
    ]
    names = [g.get("Name") for g in domain.find("Grid").findall("Grid")]
    assert names == [
        "obstacle[0] plane", "obstacle[1] sphere", "obstacle[2] box",
        "obstacle[3] capsule", "obstacle[4] mesh",
    ]  # fmt: skip
    # every HDF5 path named, opened with h5py, has the shape the sidecar states
    with h5py.File(out, "r") as h5:
        for item in root.iter("DataItem"):
            name, dataset = item.text.strip().split(":")
            assert name == out.name
            dims = tuple(map(int, item.get("Dimensions").split()))
            assert h5[dataset].shape == dims, dataset
        frames = h5["trajectory/obstacles/5/vertices"][()]
        triangles = h5["mesh/obstacles/5/triangles"][()]
    # VTK's XDMF reader (ParaView's): each obstacle a block, the moving box at its pose
    with pv.VtkErrorCatcher() as caught:
        reader = pv.get_reader(str(side))
        times = reader.time_values
        assert len(times) == 6
        for k, t in enumerate(times):
            reader.set_active_time_value(t)
            blocks = reader.read()
            assert blocks.keys() == ["obstacles", "obstacle[5] box", "trajectory"]
            box = blocks["obstacle[5] box"]
            np.testing.assert_array_equal(box.points, frames[k])
            assert box.n_cells == 12 and set(box.celltypes) == {pv.CellType.TRIANGLE}
            faces = box.cells.reshape(-1, 4)
            np.testing.assert_array_equal(faces[:, 1:], triangles)
            fixed = blocks["obstacles"]
            assert fixed.keys()[4] == "obstacle[4] mesh" and fixed[4].n_cells == 320
    assert not caught.events, [str(e.alert) for e in caught.events]
    with meshio.xdmf.TimeSeriesReader(side) as reader:
        points, cells = reader.read_points_cells()
        assert cells[0].type == "line" and reader.num_steps == 6
    # catenet repair writes the same sidecar from the file
    text = side.read_text()
    side.unlink()
    assert repair(out).sidecar == side and side.read_text() == text


def test_a_static_run_and_a_final_state_only_run(tmp_path, ball):
    # static: the fixed obstacles beside the load steps' frames
    out = tmp_path / "static.h5"
    run_case(parse_case(case_dict(ball, moving=(), method="static")), out)
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["grids"] == 2 and found["others"] == 5
    with h5py.File(out, "r") as h5:
        assert "obstacles" not in h5["trajectory"] and "obstacles" not in h5["result"]
    # a dynamic run keeping only its final state: the moving box at /result's time
    out = tmp_path / "final.h5"
    res = run_case(parse_case(case_dict(ball, every=0)), out)
    (moving,) = [o for o in read_obstacles(out) if o.moving]
    assert moving.frames is None and len(moving.times) == 0
    np.testing.assert_allclose(moving.final, closed_form(res.time, moving.vertices), atol=1e-14)
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["grids"] == 1 and found["others"] == 6
    text = out.with_suffix(".xdmf").read_text()
    assert "/result/obstacles/5/vertices" in text and "Temporal" not in text
    # VTK's XDMF reader (ParaView's; pyvista's wrapper needs times): obstacles, then the net
    blocks, events = read_with_vtk(out.with_suffix(".xdmf"))
    assert not events
    assert blocks.keys() == ["obstacles", "result"] and len(blocks["obstacles"]) == 6
    np.testing.assert_array_equal(blocks["obstacles"][5].points, moving.final)
    np.testing.assert_array_equal(blocks["result"].points, res.x)


def test_a_restart_goes_on_with_the_obstacles_where_the_solver_has_them(run, tmp_path, ball):
    out, _ = run
    case = parse_case(case_dict(ball, t_end=0.08))
    again = tmp_path / "again.h5"
    run_case(case, again, restart=out)
    (moving,) = [o for o in read_obstacles(again) if o.moving]
    assert moving.times[0] == pytest.approx(0.05) and moving.times[-1] == pytest.approx(0.08)
    assert len(moving.frames) == len(read_result(again).times) == 4
    for k, t in enumerate(moving.times):
        np.testing.assert_allclose(moving.frames[k], closed_form(t, moving.vertices), atol=1e-14)
    (first,) = [o for o in read_obstacles(out) if o.moving]
    np.testing.assert_array_equal(moving.frames[0], first.frames[-1])  # they join up
    check_xdmf(again.with_suffix(".xdmf"))


@pytest.mark.slow
def test_a_killed_run_keeps_as_many_obstacle_frames_as_net_frames(tmp_path, ball):
    d = case_dict(ball, t_end=1.0)
    d["solver"]["dt"] = 5e-4  # 2000 steps: seconds of frames, then killed
    d["obstacle"][-1] = BOX | {"velocity": [0.03, 0.0, -0.01], "angular_velocity": [0, 0, 0.5]}
    src = tmp_path / "case.toml"
    src.write_text(dumps_toml(d))
    out = tmp_path / "killed.h5"
    proc = spawn("run", src, "-o", out)
    try:
        wait_for_frames(out, 2, proc)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.communicate()
    with h5py.File(out, "r") as h5:  # a plain reader opens it
        n = trajectory_length(h5)
        assert n >= 2 and "result" not in h5
        for name in ("center", "rotation", "vertices"):
            assert h5[f"trajectory/obstacles/5/{name}"].shape[0] == h5["trajectory/time"].shape[0]
        times = h5["trajectory/time"][:n]
    (moving,) = [o for o in read_obstacles(out) if o.moving]
    assert len(moving.frames) == n and np.array_equal(moving.times, times)
    assert moving.final is None
    found = check_xdmf(out.with_suffix(".xdmf"))  # the sidecar names frames in the file only
    assert found["grids"] == found["others"] - 5 <= n
    # recover copies them with the net's frames
    clean = recover(out, tmp_path / "clean.h5")
    (kept,) = [o for o in read_obstacles(clean) if o.moving]
    np.testing.assert_array_equal(kept.frames, moving.frames)
    assert check_xdmf(clean.with_suffix(".xdmf"))["grids"] == n


def test_a_large_moving_mesh_is_stored_per_frame_simplified_and_bounded(tmp_path, caplog):
    V, T = icosphere(5)  # 10242 vertices
    stl = write_stl(tmp_path / "rock.stl", V, T)
    rock = {
        "kind": "mesh", "file": str(stl), "scale": 0.1, "offset": [0.0, 0.0, -0.4],
        "angular_velocity": [0.0, 0.0, 1.0],
    }  # fmt: skip
    out = tmp_path / "rock.h5"
    with caplog.at_level(logging.WARNING, logger="catenet.output.obstacles"):
        run_case(parse_case(case_dict(stl, moving=[rock], t_end=0.02)), out)
    (message,) = [r.getMessage() for r in caplog.records if "simplified" in r.getMessage()]
    assert "obstacle[5]: moving mesh" in message and "10242 vertices" in message
    (moving,) = [o for o in read_obstacles(out) if o.moving]
    assert len(moving.vertices) == len(V) and len(moving.triangles) == len(T)  # all of it
    assert moving.frames.shape[1] <= FRAME_VERTICES and moving.frames.shape[0] == 3
    assert moving.frame_triangles.max() < moving.frames.shape[1]
    r = np.linalg.norm(moving.frames[-1] - [0.0, 0.0, -0.4], axis=1)
    assert r.min() > 0.09 and r.max() < 0.1 + 1e-12  # still the ball (cluster means: inside)
    # the exact pose is kept: it takes the whole surface where the solver has it
    R = Rotation.from_rotvec([0.0, 0.0, moving.times[-1]]).as_matrix()
    np.testing.assert_allclose(moving.rotation[-1], R, atol=1e-15)
    check_xdmf(out.with_suffix(".xdmf"))
    with h5py.File(out, "r") as h5:
        assert "frame_triangles" in h5["mesh/obstacles/5"]
    # the small mesh of the other test is stored whole, without a warning
    caplog.clear()
    small = rock | {"file": str(write_stl(tmp_path / "small.stl", *icosphere(2)))}
    with caplog.at_level(logging.WARNING, logger="catenet.output.obstacles"):
        run_case(parse_case(case_dict(stl, moving=[small], t_end=0.01)), tmp_path / "s.h5")
    assert not [r for r in caplog.records if "simplified" in r.getMessage()]
    (moving,) = [o for o in read_obstacles(tmp_path / "s.h5") if o.moving]
    assert moving.frames.shape == (2, 162, 3)


def test_simplify_keeps_at_most_cap_vertices_of_a_like_surface():
    V, T = icosphere(4)  # 2562 vertices
    for cap in (2000, 500, 60):
        W, S = simplify(V, T, cap)
        assert len(W) <= cap and S.max() == len(W) - 1 and len(S) > 0
        assert np.all(np.linalg.norm(W, axis=1) <= 1 + 1e-12)
        assert volume(W, S) == pytest.approx(volume(V, T), rel=0.3 if cap == 60 else 0.05)
    W, S = simplify(V, T, len(V))
    assert len(W) <= len(V)


def test_the_capture_scene_file_shows_the_net_wrapping_the_tumbling_box(tmp_path):
    """The example's short version: in the file, the box is at every frame where the
    solver had it, so the net's nodes of that frame touch it (within the barrier's 1 cm)
    and none is inside."""
    from conftest import CONFIGS

    from catenet.terms.shapes import BoxBarrier, rotation

    case = load_case(CONFIGS / "contact" / "tether_capture.toml", ["solver.t_end=0.6"])
    out = tmp_path / "capture.h5"
    run_case(case, out)
    (box,) = read_obstacles(out)
    assert box.kind == "box" and box.moving and len(box.frames) == len(read_result(out).times)
    w, c0 = np.array([0.8, -0.6, 1.2]), np.array([0.0, 0.0, -1.2])
    R0 = rotation([1.0, 1.0, 0.0], 0.35)
    with h5py.File(out, "r") as h5:
        x = h5["trajectory/x"][()]
    gaps = []
    for k, t in enumerate(box.times):
        want = c0 + Rotation.from_rotvec(w * t).apply(box.vertices - c0)
        np.testing.assert_allclose(box.frames[k], want, atol=1e-14)
        R = Rotation.from_rotvec(w * t).as_matrix() @ R0  # the box's axes at t
        solid = BoxBarrier(np.arange(x.shape[1]), c0, [0.5, 0.4, 0.3], R, kappa=1.0, dhat=0.01)
        gaps.append(solid.gap(x[k]).min())
    assert min(gaps) > 0.0 and gaps[0] > 0.5  # thrown from afar, never inside
    assert min(gaps) < 0.01 and sum(g < 0.01 for g in gaps) > 10  # then wrapped round it
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["others"] == found["grids"] == len(box.times)


def test_the_trajectory_estimate_counts_the_moving_obstacles_frames(run, ball):
    from catenet.run import advice

    out, case = run
    fixed = parse_case(case_dict(ball, moving=()))
    net = build(fixed).net
    with_box, without = advice.trajectory(case, net), advice.trajectory(fixed, net)
    assert with_box.frames == without.frames == len(read_result(out).times)
    with h5py.File(out, "r") as h5:  # what the file holds per frame for the box
        stored = sum(h5[f"trajectory/obstacles/5/{k}"][0].size for k in ("center", "rotation"))
        stored += h5["trajectory/obstacles/5/vertices"][0].size
    assert with_box.frame - without.frame == 8 * stored == 8 * (3 * 8 + 12)


def test_balls_and_obstacles_side_by_side(tmp_path, ball):
    """A moving sphere is a node of the net (/mesh/bodies), not an obstacle surface; the
    sidecar shows the obstacles, then the balls, then the net."""
    rigid = {"kind": "sphere", "center": [-0.3, -0.1, -0.3], "radius": 0.05, "mass": 1.0}
    out = tmp_path / "balls.h5"
    run_case(parse_case(case_dict(ball, moving=(BOX, rigid), t_end=0.02)), out)
    assert [o.index for o in read_obstacles(out)] == [0, 1, 2, 3, 4, 5]
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["grids"] == 3 and found["others"] == 5 + 3 + 3  # fixed, box, balls
    domain = ET.parse(out.with_suffix(".xdmf")).getroot().find("Domain")
    names = [g.get("Name") for g in domain.findall("Grid")]
    assert names == ["obstacles", "obstacle[5] box", "bodies", "trajectory"]


def test_repair_restores_missing_obstacle_views(run, tmp_path):
    import shutil

    out, _ = run
    copy = shutil.copy(out, tmp_path / "copy.h5")
    with h5py.File(copy, "r+") as h5:
        del h5["xdmf/obstacles"]
    done = repair(copy)
    assert done.rewrote and done.problems == [
        "no per-frame views of obstacles/5/vertices for the XDMF sidecar"
    ]
    assert check_xdmf(done.sidecar)["others"] == 5 + 6
    (moving,) = [o for o in read_obstacles(copy) if o.moving]
    (first,) = [o for o in read_obstacles(out) if o.moving]
    np.testing.assert_array_equal(moving.frames, first.frames)
    np.testing.assert_array_equal(moving.final, first.final)


@pytest.mark.parametrize("fmt", ["vtu", "xdmf"])
def test_export_writes_each_obstacle_beside_the_net(run, tmp_path, fmt):
    """catenet export: a fixed obstacle once, a moving one at every exported frame (its
    stored surface there), and in the ParaView collection a part per obstacle at every
    time."""
    from catenet.output.export import export

    path, _ = run
    stored = {o.index: o for o in read_obstacles(path)}
    done = export(path, fmt, tmp_path / fmt, frames="1:4")
    assert sorted(done.obstacles) == sorted(stored)
    for k, files in done.obstacles.items():
        o = stored[k]
        if not o.moving:
            assert len(files) == 1
            got = meshio.read(files[0])
            assert np.array_equal(got.points, o.vertices)
            assert np.array_equal(got.cells_dict["triangle"], o.triangles)
            continue
        assert len(files) == 3
        for f, frame in zip(files, (1, 2, 3), strict=True):
            got = meshio.read(f)
            assert np.array_equal(got.points, o.frames[frame])
            assert np.array_equal(got.cells_dict["triangle"], o.frame_triangles)
    if fmt == "xdmf":
        assert done.collection is None
        return
    root = ET.parse(done.collection).getroot()
    sets = root.find("Collection").findall("DataSet")
    assert len(sets) == 3 * (1 + len(stored))
    parts = {(d.get("timestep"), d.get("part")) for d in sets}
    assert len(parts) == len(sets)  # one file per part and time
    for d in sets:
        assert (done.collection.parent / d.get("file")).is_file()


def test_the_sidecar_of_a_free_body_names_only_datasets_the_file_has(tmp_path):
    """A free box (four nodes of the net, no ball) at rest on a fixed table, a wire
    beside it: the sidecar named a balls' grid (/mesh/bodies/node) the file did not have,
    so VTK's reader failed on it. It now shows the table, the box and the wire."""
    case = tmp_path / "crate.toml"
    case.write_text(
        'title = "a crate on a table"\n'
        '[geometry]\nkind = "cable"\nstart = [-3.0, 0.0, 2.0]\nend = [-1.0, 0.0, 2.0]\n'
        "length = 2.1\nnodes = 21\n"
        "[material]\nE = 200e9\nradius = 0.003\ndensity = 7850.0\n"
        "[load]\ngravity = [0.0, 0.0, -9.81]\n"
        '[[obstacle]]\nkind = "box"\ncenter = [1.0, 0.0, 0.9]\nhalf_size = [0.8, 0.6, 0.1]\n'
        '[[obstacle]]\nkind = "box"\ncenter = [1.0, 0.0, 1.26]\nhalf_size = [0.5, 0.4, 0.25]\n'
        'mass = 200.0\n[solver]\nmethod = "static"\n'
    )
    out = tmp_path / "crate.h5"
    run_case(load_case(case), out)
    side = out.with_suffix(".xdmf")
    found = check_xdmf(side)  # every DataItem's dataset exists with its stated shape
    assert found["grids"] == 1 and found["others"] == 2  # the table; the box at 1 frame
    with pv.VtkErrorCatcher() as caught:
        reader = pv.get_reader(str(side))
        reader.set_active_time_value(reader.time_values[-1])
        blocks = reader.read()
    assert not caught.events, caught.events
    assert blocks.keys() == ["obstacles", "obstacle[1] box", "trajectory"]
    assert blocks["obstacle[1] box"].n_cells == 12
    assert blocks["trajectory"].n_cells == 20
