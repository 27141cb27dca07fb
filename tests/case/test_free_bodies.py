"""Free rigid bodies in case files (catenet/case/rigid.py, catenet/scene/rigid.py): which
tables are free bodies, their mass properties from the shape (box, sphere, capsule, mesh)
or as given, and bad input (zero or negative mass, an inertia that is not symmetric
positive definite, a body overlapping the net, a mesh that is not closed, ...) exiting 2
with the key path."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from meshes import CUBE_T, CUBE_V, net_under_gravity, write_stl

from catenet.case import build, dumps_toml, parse_case
from catenet.case.rigid import movers
from catenet.scene.rigid import mass_properties


def drop(**body) -> dict:
    """A 12 kg box 0.1 m above the paper's square net (n = 10), dynamic."""
    obstacle = {
        "kind": "box", "center": [0.0, 0.0, 0.2], "half_size": [0.15, 0.1, 0.05],
        "mass": 12.0, **body,
    }  # fmt: skip
    return {
        **net_under_gravity(10, 0.05),
        "obstacle": [{k: v for k, v in obstacle.items() if v is not None}],
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.05},
    }  # fmt: skip


def test_a_box_with_mass_is_four_nodes_with_its_weight_and_initial_motion():
    scene = build(parse_case(drop(velocity=[0.0, 0.0, -1.0], angular_velocity=[0.0, 0.0, 3.0])))
    net = scene.net
    (body,) = scene.rigid
    assert net.bodies == 4
    assert body.frame.nodes.tolist() == list(range(net.n_nodes - 4, net.n_nodes))
    assert net.mass[-4:] == pytest.approx([3.0] * 4) and not net.fixed[-4:].any()
    f = scene.loads.external_force(net)[-4:].sum(axis=0)
    assert f == pytest.approx([0.0, 0.0, -12.0 * 9.81])
    v, w = body.frame.motion(net.nodes, scene.velocity)
    assert v == pytest.approx([0, 0, -1.0]) and w == pytest.approx([0, 0, 3.0])
    assert body.inertia == pytest.approx(12.0 / 3 * np.diag([0.0125, 0.025, 0.0325]))


def test_mass_properties_of_each_shape(tmp_path):
    case = drop(density=500.0, mass=None, angle=0.4, axis=[0, 1, 0])
    m, c, inertia, axes = mass_properties(movers(parse_case(case))[0])
    assert m == pytest.approx(500.0 * 0.3 * 0.2 * 0.1) and c == pytest.approx([0, 0, 0.2])
    assert axes[:, 1] == pytest.approx([0, 1, 0])  # turned about y
    # A mesh of the same box (the unit cube scaled and moved) has the same properties.
    write_stl(str(tmp_path / "cube.stl"), CUBE_V, CUBE_T)
    mesh = copy.deepcopy(case)
    mesh["obstacle"][0] = {
        "kind": "mesh", "file": str(tmp_path / "cube.stl"), "scale": 0.4,
        "offset": [-0.2, -0.2, 0.0], "density": 500.0,
    }  # fmt: skip
    m2, c2, inertia2, axes2 = mass_properties(movers(parse_case(mesh))[0])
    assert m2 == pytest.approx(500.0 * 0.4**3) and c2 == pytest.approx([0, 0, 0.2])
    assert inertia2 == pytest.approx(m2 * 0.4**2 / 6 * np.eye(3))
    assert axes2 == pytest.approx(np.eye(3))
    # A capsule against a fine voxel sum of the same solid.
    cap = copy.deepcopy(case)
    cap["obstacle"][0] = {
        "kind": "capsule", "start": [0, 0, 0], "end": [0.6, 0, 0], "radius": 0.2,
        "density": 1.0,
    }  # fmt: skip
    m3, c3, inertia3, axes3 = mass_properties(movers(parse_case(cap))[0])
    g = np.linspace(-0.5, 0.5, 201)
    X, Y, Z = np.meshgrid(g + 0.3, g * 0.5, g * 0.5, indexing="ij")
    p = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    t = np.clip(p[:, 0], 0.0, 0.6)
    inside = p[np.linalg.norm(p - np.column_stack([t, 0 * t, 0 * t]), axis=1) <= 0.2]
    dv = (g[1] - g[0]) ** 3 * 0.25
    r = inside - [0.3, 0, 0]
    J = dv * r.T @ r
    assert m3 == pytest.approx(len(inside) * dv, rel=5e-3) and c3 == pytest.approx([0.3, 0, 0])
    world = axes3 @ inertia3 @ axes3.T
    assert world == pytest.approx(np.trace(J) * np.eye(3) - J, rel=1e-2, abs=1e-6)
    sphere = copy.deepcopy(case)
    sphere["obstacle"][0] = {"kind": "sphere", "center": [0, 0, 1], "radius": 0.5, "density": 2.0}
    m4, _, inertia4, _ = mass_properties(movers(parse_case(sphere))[0])
    assert m4 == pytest.approx(2.0 * 4 / 3 * math.pi / 8)
    assert inertia4 == pytest.approx(0.4 * m4 * 0.25 * np.eye(3))


def test_a_given_inertia_and_principal_moments():
    full = [[0.2, 0.01, 0.0], [0.01, 0.3, 0.0], [0.0, 0.0, 0.4]]
    box = movers(parse_case(drop(inertia=full)))[0]
    assert mass_properties(box)[2] == pytest.approx(np.array(full))
    box = movers(parse_case(drop(inertia=[0.2, 0.3, 0.4])))[0]
    assert mass_properties(box)[2] == pytest.approx(np.diag([0.2, 0.3, 0.4]))


@pytest.mark.parametrize(
    "change, message",
    [
        ({"mass": 0.0}, "obstacle[0].mass = 0.0: must be finite and > 0"),
        ({"mass": -3.0}, "obstacle[0].mass = -3.0: must be finite and > 0"),
        ({"density": 0.0, "mass": None}, "obstacle[0].density = 0.0: must be finite and > 0"),
        ({"density": 100.0}, "obstacle[0].density = 100.0: give mass or density, not both"),
        ({"inertia": [[1, 0, 0], [0, -1, 0], [0, 0, 1]]}, "obstacle[0].inertia = "),
        ({"inertia": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]}, "it is not symmetric"),
        ({"inertia": [1.0, 1.0, 3.0]}, "I1 + I2 > I3"),
        ({"inertia": [1.0, 2.0]}, "obstacle[0].inertia = [1.0, 2.0]: must be"),
        ({"center": [0.0, 0.0, 0.01]}, "obstacle[0] (kind 'box', a free body): node"),
        ({"history": [[0, 1]], "velocity": [0, 0, 1]}, "obstacle[0].history: a free body"),
        ({"solver": "static", "velocity": [0, 0, -1]}, "obstacle[0].velocity = [0, 0, -1]"),
        ({"second": True}, "obstacle[0] (a free box): it meets obstacle[1] (a free box) at"),
        ({"ground": True}, "obstacle[0] (a free box): its point [0.15, 0.1, 0.25] starts in"),
        ({"path": True}, "obstacle[1] (kind 'box'): an obstacle on a prescribed motion"),
        ({"mesh": "open"}, "obstacle[0].file = "),
        ({"rho": 1.0}, "solver.integrator = 'newmark': not for a run with contact"),
    ],
)
def test_bad_free_bodies_exit_2_with_their_key_path(tmp_path, change, message):
    from click.testing import CliRunner

    from catenet.cli import main

    case = drop()
    obs = case["obstacle"][0]
    if change.pop("solver", None):
        case["solver"] = {"method": "static"}
    if (rho := change.pop("rho", None)) is not None:
        case["solver"].update(integrator="newmark", rho_inf=rho)
    if change.pop("second", None):  # several bodies are allowed, not overlapping
        below = [c + d for c, d in zip(obs["center"], (0.05, 0.0, -0.02), strict=True)]
        case["obstacle"].append({**obs, "center": below})
    if change.pop("ground", None):  # a ceiling through the body
        case["obstacle"].append({"kind": "plane", "point": [0, 0, 0.22], "normal": [0, 0, -1]})
    if change.pop("path", None):  # a box on a prescribed motion: not beside a free body
        case["obstacle"].append(
            {"kind": "box", "center": [1.0, 0, 0.5], "half_size": [0.1] * 3, "velocity": [0, 0, 1]}
        )
    if change.pop("mesh", None):
        V, T = CUBE_V, CUBE_T[:-1]  # one triangle short: not closed
        write_stl(str(tmp_path / "open.stl"), V, T)
        case["obstacle"][0] = {
            "kind": "mesh", "file": "open.stl", "mass": 3.0, "offset": [0, 0, 0.3],
        }  # fmt: skip
    for k, v in change.items():
        if v is None:
            obs.pop(k, None)
        else:
            obs[k] = v
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "out.h5").exists()


def test_the_summary_says_where_a_free_body_is(tmp_path):
    from click.testing import CliRunner

    from catenet.cli import main

    # with friction: frictionless, the box balanced on the net's flat patch would be an
    # unstable equilibrium (tests/solver/test_modes_bodies.py), which a run refuses
    case = drop(
        center=[0.0, 0.0, 0.052], half_size=[0.15, 0.15, 0.05], distance=0.005, friction=0.5
    )
    case["solver"] = {"method": "static"}
    path = tmp_path / "rest.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "rest.h5")])
    assert res.exit_code == 0, res.output
    assert "body         obstacle[0] (box): resting on the net" in res.output
    case["obstacle"][0]["center"] = [0.0, 0.0, 0.5]  # out of reach, and nothing pulls it
    case["load"] = {}
    case["load"]["point"] = [{"node": "center", "force": [0.0, 0.0, -10.0]}]
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "away.h5")])
    assert res.exit_code == 0, res.output
    assert "body         obstacle[0] (box): not touching the net" in res.output
