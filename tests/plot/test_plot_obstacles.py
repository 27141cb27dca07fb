"""``catenet plot`` draws a case's obstacles (catenet/plot/obstacles.py): each kind in the
3D view and the side view (with its legend entry), a moving one at its pose at the
plotted time, a plane clipped to the views, a large mesh by its edges, and a file
without obstacles as before."""

from __future__ import annotations

import logging
import shutil
import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from meshes import icosphere, write_stl

from catenet.case import dumps_toml
from catenet.cli import main
from catenet.output.reader import read_result
from catenet.plot.figure import figure
from catenet.plot.obstacles import MAX_EDGES, MAX_FACES, clipped, plane_patch, shapes


def base_case() -> dict:
    return {
        "title": "a small net over obstacles",
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.3, "size": 1.0, "edge_length": 0.1},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"pressure": 100.0},
        "solver": {"method": "static", "steps": 1},
    }


def all_kinds(mesh_file) -> list[dict]:
    return [
        {"kind": "plane", "point": [0.0, 0.0, -0.5], "normal": [0.0, 0.0, 1.0]},
        {"kind": "sphere", "center": [0.3, 0.3, -0.4], "radius": 0.1},
        {"kind": "box", "center": [-0.3, 0.2, -0.4], "half_size": [0.1, 0.05, 0.08]},
        {"kind": "capsule", "start": [-0.3, -0.3, -0.5], "end": [0.2, -0.3, -0.5], "radius": 0.05},
        {"kind": "mesh", "file": str(mesh_file), "scale": 0.1, "offset": [0.0, 0.0, -0.45]},
    ]


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    """A result file of the small net without obstacles (run once)."""
    d = tmp_path_factory.mktemp("plain")
    (d / "case.toml").write_text(dumps_toml(base_case()))
    out = d / "plain.h5"
    res = CliRunner().invoke(main, ["run", str(d / "case.toml"), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    return out


def with_case(src, dst, obstacles) -> object:
    """A copy of the result ``src`` whose stored case has these obstacles."""
    shutil.copy(src, dst)
    with h5py.File(dst, "r+") as h5:
        case = tomllib.loads(h5.attrs["case"])
        case["obstacle"] = obstacles
        h5.attrs["case"] = dumps_toml(case)
    return read_result(dst)


def obstacle_artists(ax) -> dict:
    """{gid: artist} of the obstacles drawn in ``ax``."""
    arts = [*ax.collections, *ax.patches]
    return {a.get_gid(): a for a in arts if (a.get_gid() or "").startswith("obstacle")}


def test_every_obstacle_kind_is_drawn_in_both_views_with_a_legend_entry(plain, tmp_path):
    V, T = icosphere(2)
    stl = write_stl(tmp_path / "ball.stl", V, T)
    res = with_case(plain, tmp_path / "all.h5", all_kinds(stl))
    fig = figure(res)
    fig.savefig(tmp_path / "all.png")  # renders (and projects the 3D artists)
    assert (tmp_path / "all.png").stat().st_size > 10_000
    ax3, ax2 = fig.axes[:2]
    labels = [
        "obstacle[0]: plane",
        "obstacle[1]: sphere",
        "obstacle[2]: box",
        "obstacle[3]: capsule",
        "obstacle[4]: mesh",
    ]
    drawn3 = obstacle_artists(ax3)
    assert sorted(drawn3) == labels
    assert {type(a).__name__ for a in drawn3.values()} == {"Poly3DCollection"}
    assert len(drawn3["obstacle[4]: mesh"].get_paths()) == len(T)  # every triangle
    assert len(drawn3["obstacle[2]: box"].get_paths()) == 6  # the faces
    # under the net in 3D: drawn before its lines, whatever mplot3d's depth order says
    assert ax3.computed_zorder is False
    net = [c for c in ax3.collections if type(c).__name__ == "Line3DCollection"]
    assert max(a.get_zorder() for a in drawn3.values()) < min(c.get_zorder() for c in net)
    legend = [t.get_text() for t in ax2.get_legend().get_texts()]
    assert all(label in legend for label in labels)
    drawn2 = {a.get_label() for a in [*ax2.collections, *ax2.patches]}
    assert set(labels) <= drawn2
    # the views include the obstacles below the net (the capsule reaches z = -0.55)
    assert ax3.get_zlim()[0] < -0.55 and ax2.get_ylim()[0] < -0.55
    # the plane is a patch across the 3D view's box
    (patch,) = drawn3["obstacle[0]: plane"].get_paths()
    assert len(patch.vertices) >= 4
    # through the command line too
    res = CliRunner().invoke(
        main, ["plot", str(tmp_path / "all.h5"), "-o", str(tmp_path / "c.png")]
    )
    assert res.exit_code == 0, res.output


def test_a_file_without_obstacles_plots_as_before(plain):
    res = read_result(plain)
    assert "obstacle" not in res.case
    fig = figure(res)
    ax3, ax2 = fig.axes[:2]
    assert not obstacle_artists(ax3) and not obstacle_artists(ax2)
    assert ax3.computed_zorder is True  # mplot3d's depth order, as before
    assert not [c for c in ax3.collections if type(c).__name__ == "Poly3DCollection"]
    legend = [t.get_text() for t in ax2.get_legend().get_texts()]
    assert not [t for t in legend if t.startswith("obstacle")]
    assert ax3.get_zlim()[0] > -0.6  # the views hold the net only


def test_a_moving_box_is_drawn_at_its_pose_at_the_plotted_time(plain, tmp_path):
    from catenet.case import build, parse_case

    box = {
        "kind": "box",
        "center": [0.0, 0.0, -0.5],
        "half_size": [0.3, 0.1, 0.05],
        "axis": [1.0, 1.0, 0.0],
        "angle": 0.35,
        "velocity": [0.2, 0.0, 0.1],
        "angular_velocity": [0.0, 0.0, 2.0],
        "history": [[0.0, 1.0], [1.0, 0.5]],
    }
    res = with_case(plain, tmp_path / "moving.h5", [box])
    case = base_case() | {"obstacle": [box]}
    case["solver"] = {"method": "dynamic", "dt": 0.01, "t_end": 0.1}
    (term,) = build(parse_case(case)).terms
    signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    for t in (0.0, 0.7):
        (shape,) = shapes(res, t)
        term.set_pose(t)
        body = term.shape.center + (signs * term.shape.half) @ term.shape.axes.T
        want = term.world(body)
        got = np.unique(np.concatenate(shape.polys).round(12), axis=0)
        assert len(got) == 8
        for p in want:
            assert np.min(np.linalg.norm(got - p, axis=1)) < 1e-12
        assert shape.label == "obstacle[0]: moving box"
    # a static result's plotted time is its /result time (no trajectory): the pose at t
    # = 0 here, the box as given
    (shape,) = shapes(res)
    assert np.allclose(np.concatenate(shape.polys).mean(axis=0), box["center"])


def test_a_large_mesh_is_drawn_by_at_most_max_edges_edges(plain, tmp_path):
    V, T = icosphere(5)  # 20480 triangles
    assert len(T) > MAX_FACES
    stl = write_stl(tmp_path / "big.stl", V, T)
    obstacle = {"kind": "mesh", "file": str(stl), "scale": 0.2, "offset": [0.0, 0.0, -0.5]}
    res = with_case(plain, tmp_path / "big.h5", [obstacle])
    fig = figure(res)
    fig.canvas.draw()
    ax3, ax2 = fig.axes[:2]
    (lines,) = obstacle_artists(ax3).values()
    assert type(lines).__name__ == "Line3DCollection"
    assert 0 < len(lines.get_segments()) <= MAX_EDGES
    assert "obstacle[0]: mesh" in [t.get_text() for t in ax2.get_legend().get_texts()]


def test_a_mesh_file_gone_since_the_run_is_skipped_with_a_warning(plain, tmp_path, caplog):
    V, T = icosphere(1)
    stl = write_stl(tmp_path / "gone.stl", V, T)
    obstacles = [
        {"kind": "mesh", "file": str(stl), "offset": [0.0, 0.0, -2.0]},
        {"kind": "box", "center": [0.0, 0.0, -0.5], "half_size": [0.1, 0.1, 0.1]},
    ]
    res = with_case(plain, tmp_path / "gone.h5", obstacles)
    stl.unlink()
    with caplog.at_level(logging.WARNING, logger="catenet.plot.obstacles"):
        ax3 = figure(res).axes[0]
    assert list(obstacle_artists(ax3)) == ["obstacle[1]: box"]
    assert "obstacle[0]: mesh not drawn: no such file" in caplog.text


def test_a_plane_patch_is_where_the_plane_cuts_the_box():
    lo, hi = np.zeros(3), np.array([2.0, 1.0, 1.0])
    P = plane_patch(np.array([0.0, 0.0, 0.25]), np.array([0.0, 0.0, 1.0]), lo, hi)
    assert len(P) == 4 and np.allclose(P[:, 2], 0.25)
    assert {tuple(p[:2]) for p in P} == {(0, 0), (2, 0), (0, 1), (2, 1)}
    n = np.array([1.0, 1.0, 1.0]) / np.sqrt(3)
    P = plane_patch(np.full(3, 0.5), n, lo, np.ones(3))  # a cube cut through its centre
    assert len(P) == 6 and np.allclose((P - 0.5) @ n, 0.0)  # a hexagon, in order:
    assert np.allclose(np.linalg.norm(np.diff(P, axis=0, append=P[:1]), axis=1), 0.5**0.5)
    assert not len(plane_patch(np.array([0.0, 0.0, 3.0]), np.array([0.0, 0.0, 1.0]), lo, hi))


def test_a_huge_obstacle_is_cut_to_the_views_which_it_widens_by_at_most_reach(plain, tmp_path):
    from catenet.plot.obstacles import REACH

    # a 200 m block whose top face is 0.3 m under the net
    seabed = {"kind": "box", "center": [0.0, 0.0, -50.3], "half_size": [100.0, 100.0, 50.0]}
    res = with_case(plain, tmp_path / "huge.h5", [seabed])
    fig = figure(res)
    fig.savefig(tmp_path / "huge.png")
    ax3, ax2 = fig.axes[:2]
    lo, hi = (np.array([ax3.get_xlim(), ax3.get_ylim(), ax3.get_zlim()]).T).astype(float)
    x0 = lo[0]
    assert -0.6 - REACH * 1.2 < x0 < -0.6 and lo[2] > -0.3 - 1.0 - REACH * 1.2
    (block,) = obstacle_artists(ax3).values()
    assert len(block.get_paths()) == 1  # its top face: the others are out of view
    (face,) = clipped(np.array(shapes(res)[0].polys), lo, hi)
    assert np.allclose(face[:, 2], -0.3) and len(face) == 4  # cut to the view's box
    assert np.allclose(np.sort(face[:, 0])[[0, -1]], [lo[0], hi[0]])
    (outline,) = obstacle_artists(ax2).values()
    xy = outline.get_xy()
    assert xy[:, 0].min() >= x0 - 1e-9 and xy[:, 1].max() == pytest.approx(-0.3)
    assert xy[:, 1].min() < -0.6  # the block fills the side view below its top
    assert ax2.get_xlim()[0] > -0.6 - 1.5 * REACH * 1.2


def test_a_moving_capsule_and_mesh_are_drawn_at_their_pose(plain, tmp_path):
    from catenet.case import build, parse_case

    V, T = icosphere(1)
    stl = write_stl(tmp_path / "rock.stl", V, T)
    motion = {"velocity": [0.3, -0.1, 0.2], "angular_velocity": [1.0, 0.5, -2.0]}
    obstacles = [
        {"kind": "capsule", "start": [-0.3, 0.0, -0.5], "end": [0.3, 0.1, -0.6], "radius": 0.05}
        | motion,
        {"kind": "mesh", "file": str(stl), "scale": 0.1, "offset": [0.0, 0.2, -0.5]} | motion,
    ]
    res = with_case(plain, tmp_path / "moving2.h5", obstacles)
    case = base_case() | {"obstacle": obstacles}
    case["solver"] = {"method": "dynamic", "dt": 0.01, "t_end": 0.1}
    capsule, rock = build(parse_case(case)).terms
    t = 0.8
    drawn_capsule, drawn_rock = shapes(res, t)
    capsule.set_pose(t)
    rock.set_pose(t)
    a, b = capsule.world(np.array([obstacles[0]["start"], obstacles[0]["end"]]))
    p = np.concatenate(drawn_capsule.polys)
    s = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    assert np.allclose(np.linalg.norm(p - (a + s[:, None] * (b - a)), axis=1), 0.05)
    assert not np.allclose(a, obstacles[0]["start"])  # it did move
    assert np.allclose(drawn_rock.vertices, rock.world(rock.shape.vertices))
    assert len(drawn_rock.triangles) == len(T)
