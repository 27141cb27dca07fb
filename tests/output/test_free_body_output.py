"""A free body in the result file (contract §7): /mesh/obstacles/<k> attrs mass and
dataset inertia; /trajectory/obstacles/<k>/ center, rotation, velocity,
angular_velocity per frame, read from the body's four nodes in /trajectory/x and v; the
same under /result/obstacles/<k>/ at the end."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from meshes import net_under_gravity

from catenet.case import build, dumps_toml, parse_case


def test_a_free_body_is_stored_with_its_pose_and_motion(tmp_path):
    from click.testing import CliRunner

    from catenet.cli import main

    case = {
        **net_under_gravity(6, 0.1),
        "obstacle": [
            {
                "kind": "capsule", "start": [-0.2, 0.0, 0.3], "end": [0.2, 0.0, 0.3],
                "radius": 0.08, "density": 800.0, "velocity": [0.0, 0.0, -1.5],
                "angular_velocity": [0.0, 2.0, 1.0],
            }
        ],
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.15},
    }  # fmt: skip
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    out = tmp_path / "out.h5"
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(out)])
    assert res.exit_code == 0, res.output
    scene = build(parse_case(case))
    (body,) = scene.rigid
    frame = body.frame
    with h5py.File(out) as f:
        g = f["mesh/obstacles/0"]
        assert g.attrs["mass"] == pytest.approx(body.mass) and bool(g.attrs["moving"])
        assert np.asarray(g["inertia"]) == pytest.approx(body.inertia)
        assert np.asarray(g.attrs["origin"]) == pytest.approx([0.0, 0.0, 0.3])
        x, v = np.asarray(f["trajectory/x"]), np.asarray(f["trajectory/v"])
        t = f["trajectory/obstacles/0"]
        n = len(f["trajectory/time"])
        assert n > 10 and all(len(t[k]) == n for k in ("center", "rotation", "velocity"))
        for k in (0, n // 2, n - 1):
            c, R = frame.pose(x[k])
            vel, spin = frame.motion(x[k], v[k])
            assert np.asarray(t["center"][k]) == pytest.approx(c)
            assert np.asarray(t["rotation"][k]) == pytest.approx(R)
            assert np.asarray(t["velocity"][k]) == pytest.approx(vel)
            assert np.asarray(t["angular_velocity"][k]) == pytest.approx(spin)
        assert np.asarray(t["angular_velocity"][0]) == pytest.approx([0.0, 2.0, 1.0])
        R = np.asarray(t["rotation"])
        assert np.abs(np.einsum("kji,kjl->kil", R, R) - np.eye(3)).max() < 1e-9
        r = f["result/obstacles/0"]
        for name in ("center", "rotation", "velocity", "angular_velocity"):
            assert np.asarray(r[name]) == pytest.approx(np.asarray(t[name][-1]))
        frames = np.asarray(t["vertices"])
        times = np.asarray(f["trajectory/time"])
    # catenet plot draws it where the file has it.
    from catenet.output.reader import read_result
    from catenet.plot.obstacles import shapes

    res = read_result(out)
    (shape,) = shapes(res, float(times[n // 2]))
    drawn = np.unique(np.concatenate(shape.polys).round(9), axis=0)
    assert drawn == pytest.approx(np.unique(frames[n // 2].round(9), axis=0))
