"""A scene built in Python (``catenet.Scene.of(...).with_obstacle(...)``) and the same scene
read from a case file are the same computation: the same terms by the same contact
policy, the same trajectory to the bit.

The capture scene: an 11 x 11 net of 1 m cells (E = 100 GPa, radius 1 mm, density 970,
tension-only) thrown at 3 m/s onto a box (half sizes 1.5, 1, 1) with Coulomb friction
0.3 and a cylinder lying beside it, in zero gravity, undamped; and a net pressed by its
weight onto a plane (a static solve through the contact policy's stages)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import catenet
from catenet.case import build, parse_case
from catenet.errors import ConfigError

N = 11


def grid() -> tuple[list, list]:
    nodes = [[i - 5.0, j - 5.0, 2.0] for j in range(N) for i in range(N)]
    edges = [[j * N + i, j * N + i + 1] for j in range(N) for i in range(N - 1)]
    edges += [[j * N + i, (j + 1) * N + i] for j in range(N - 1) for i in range(N)]
    return nodes, edges


def capture_case() -> dict:
    nodes, edges = grid()
    return {
        "geometry": {
            "kind": "graph", "nodes": nodes, "edges": edges, "fixed": [],
            "sets": {"net": list(range(N * N))},
        },
        "material": {"E": 100e9, "radius": 0.001, "density": 970.0},
        "mass": [{"node": "net", "mass": 0.0, "velocity": [0.0, 0.0, -3.0]}],
        "obstacle": [
            {"kind": "box", "center": [0.0, 0.0, 0.0], "half_size": [1.5, 1.0, 1.0],
             "friction": 0.3},
            {"kind": "cylinder", "start": [3.0, -2.0, 0.5], "end": [3.0, 2.0, 0.5],
             "radius": 0.5},
        ],
        "solver": {"method": "dynamic", "dt": 0.002, "t_end": 0.4, "damping": 0.0},
    }  # fmt: skip


def capture_scene() -> catenet.Scene:
    """The same scene, written from the Python API alone."""
    nodes, edges = grid()
    material = catenet.Material.from_E(100e9, radius=0.001, density=970.0)
    net = catenet.graph(nodes, edges, [], material, flies=True)  # no support: it flies
    velocity = np.tile([0.0, 0.0, -3.0], (net.n_nodes, 1))
    return (
        catenet.Scene.of(net, catenet.Loads(), velocity=velocity)
        .with_obstacle(catenet.Box([0.0, 0.0, 0.0], [1.5, 1.0, 1.0]), friction=0.3)
        .with_obstacle(catenet.Cylinder([3.0, -2.0, 0.5], [3.0, 2.0, 0.5], 0.5))
    )


def trajectory(scene, settings) -> list[np.ndarray]:
    states: list[np.ndarray] = []
    result = catenet.solve(scene, settings, on_step=lambda s: states.append(s.x.copy()))
    assert result.converged or result.message
    return [*states, result.x]


def test_the_capture_from_python_and_from_toml_is_the_same_to_the_bit():
    case = parse_case(capture_case())
    read = build(case)
    made = capture_scene()
    assert [type(t).__name__ for t in read.terms] == [type(t).__name__ for t in made.terms]
    for a, b in zip(read.terms, made.terms, strict=True):
        assert vars(a).keys() == vars(b).keys()
        for key, value in vars(a).items():  # every number the same (the barriers' kappa, dhat)
            if isinstance(value, (float, np.ndarray)):
                assert np.array_equal(value, vars(b)[key]), key
    assert np.array_equal(read.net.nodes, made.net.nodes)
    assert np.array_equal(read.velocity, made.velocity)
    settings = catenet.Settings.of(case.solver)
    assert settings == catenet.Settings("dynamic", dt=0.002, t_end=0.4, damping=0.0)
    a = trajectory(read, settings)
    b = trajectory(made, settings)
    assert len(a) == len(b) > 100
    touched = [float(read.terms[0].gap(x).min()) for x in a]
    assert min(touched) < read.terms[0].dhat  # the net did meet the box
    for xa, xb in zip(a, b, strict=True):
        assert np.array_equal(xa, xb)


def test_a_static_net_on_the_ground_from_python_and_from_toml():
    """Static: the contact policy's continuation stages, from a case and from Python."""
    nodes, edges = grid()
    case = parse_case(
        {
            "geometry": {
                "kind": "graph", "nodes": nodes, "edges": edges, "fixed": [0, 10, 110, 120]
            },
            "material": {"EA": 1e4, "density": 1000.0, "area": 1e-4},
            "load": {"gravity": [0.0, 0.0, -9.81]},
            "obstacle": [{"kind": "plane", "point": [0.0, 0.0, 1.9]}],
            "solver": {"method": "static"},
        }
    )  # fmt: skip
    read = build(case)
    material = catenet.Material(EA=1e4, line_density=0.1)
    net = catenet.graph(nodes, edges, [0, 10, 110, 120], material)
    loads = catenet.Loads(gravity=np.array([0.0, 0.0, -9.81]))
    made = catenet.Scene.of(net, loads).with_obstacle(catenet.Plane([0.0, 0.0, 1.9], [0, 0, 1.0]))
    assert len(read.terms[0].stages) == len(made.terms[0].stages) > 0
    ra = catenet.solve(read, catenet.Settings.of(case.solver))
    rb = catenet.solve(made, catenet.Settings.of(case.solver))
    assert ra.converged and rb.converged
    assert np.array_equal(ra.x, rb.x)
    assert ra.x[:, 2].min() > 1.9


def test_the_builder_refuses_a_net_inside_an_obstacle_naming_it():
    made = capture_scene()
    with pytest.raises(ConfigError, match=r"obstacle\[2\] \(kind 'sphere'\): node 60"):
        made.with_obstacle(catenet.Sphere([0.0, 0.0, 2.0], 0.2))


def test_solve_takes_solver_keys():
    nodes, edges = grid()
    net = catenet.graph(nodes, edges, [0, 10, 110, 120], catenet.Material(EA=1e4, line_density=0.1))
    scene = catenet.Scene.of(net, catenet.Loads(gravity=np.array([0.0, 0.0, -9.81])))
    a = catenet.solve(scene, steps=2)
    b = catenet.solve(scene, catenet.Settings(steps=2))
    assert a.converged and np.array_equal(a.x, b.x)


@pytest.mark.parametrize(
    ("keys", "message"),
    [
        ({"friction": -0.1}, "friction = -0.1: must be a finite number >= 0"),
        ({"accuracy": 1.0}, "accuracy = 1.0: must be a number in (0, 1)"),
        ({"distance": 0.0}, "distance = 0.0: must be a finite number > 0"),
        ({"velocity": [1.0, 2.0]}, "velocity = [1.0, 2.0]: must be 3 finite numbers"),
    ],
)
def test_the_builder_refuses_what_a_case_file_would_naming_the_key(keys, message):
    made = capture_scene()
    with pytest.raises(ConfigError, match=re.escape(message)):
        made.with_obstacle(catenet.Sphere([0.0, 0.0, -3.0], 0.2), **keys)


def drop_case() -> dict:
    """A free box and a ball dropped onto a net held at its corners, a ground below and a
    fixed ball beside it, in gravity: the obstacles listed in another order than the
    Python scene below adds them."""
    nodes, edges = grid()
    return {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges, "fixed": [0, 10, 110, 120]},
        "material": {"EA": 2e5, "density": 1000.0, "area": 1e-4},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [
            {"kind": "box", "center": [1.0, 0.5, 2.6], "half_size": [0.4, 0.3, 0.2],
             "mass": 12.0, "velocity": [0.0, 0.0, -2.0], "angular_velocity": [0.0, 1.0, 0.0],
             "friction": 0.2},
            {"kind": "sphere", "center": [-2.0, -1.5, 2.5], "radius": 0.3, "mass": 5.0},
            {"kind": "plane", "point": [0.0, 0.0, -4.0]},
            {"kind": "sphere", "center": [3.0, 3.0, 3.0], "radius": 0.4},
        ],
        "solver": {"method": "dynamic", "dt": 0.002, "t_end": 0.3, "damping": 0.0},
    }  # fmt: skip


def test_bodies_from_python_in_any_order_and_from_toml_are_the_same_to_the_bit():
    """``with_body`` and ``with_ball`` take the contact policy of the case's free bodies and
    balls: the same nodes, terms and trajectory, whatever the order of the builder's calls
    (the ground added after the body still holds it)."""
    case = parse_case(drop_case())
    read = build(case)
    nodes, edges = grid()
    net = catenet.graph(nodes, edges, [0, 10, 110, 120], catenet.Material(EA=2e5, line_density=0.1))
    made = (
        catenet.Scene.of(net, catenet.Loads(gravity=np.array([0.0, 0.0, -9.81])))
        .with_body(
            catenet.Box([1.0, 0.5, 2.6], [0.4, 0.3, 0.2]),
            mass=12.0,
            velocity=(0.0, 0.0, -2.0),
            angular_velocity=(0.0, 1.0, 0.0),
            friction=0.2,
        )  # fmt: skip
        .with_ball(catenet.Sphere([-2.0, -1.5, 2.5], 0.3), mass=5.0)
        .with_obstacle(catenet.Plane([0.0, 0.0, -4.0], [0.0, 0.0, 1.0]))
        .with_obstacle(catenet.Sphere([3.0, 3.0, 3.0], 0.4))
    )
    names = [type(t).__name__ for t in made.terms]
    assert names == [type(t).__name__ for t in read.terms]
    assert {"Rigidity", "BodyContact", "BodyPlane", "BodyFriction", "Ball", "BodyTouch"} <= set(
        names
    )
    assert made.net.n_nodes == read.net.n_nodes == N * N + 1 + 4
    assert [b.obstacle for b in made.rigid] == [0] and [b.obstacle for b in made.bodies] == [1]
    assert np.array_equal(read.net.nodes, made.net.nodes)
    assert np.array_equal(read.net.mass, made.net.mass)
    assert np.array_equal(read.velocity, made.velocity)
    for a, b in zip(read.terms, made.terms, strict=True):
        for key, value in vars(a).items():
            if isinstance(value, float):
                assert value == vars(b)[key], (type(a).__name__, key)
    settings = catenet.Settings.of(case.solver)
    a = trajectory(read, settings)
    b = trajectory(made, settings)
    assert len(a) == len(b) > 100
    assert a[-1][-4:, 2].mean() < 2.6 - 0.3  # the box fell
    for xa, xb in zip(a, b, strict=True):
        assert np.array_equal(xa, xb)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2, 0.2, 0.2])), "give mass or density"),
        (
            lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2] * 3), mass=1.0, density=2.0),
            "give mass or density (one of them)",
        ),
        (
            lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2] * 3), mass=-1.0),
            "body: mass = -1.0: must be a finite number > 0",
        ),
        (
            lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2] * 3), mass=1.0, inertia=[1, 2]),
            "must be 3 x 3 or 3 principal moments",
        ),
        (
            lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2] * 3), mass=1.0, velocity=[1, 2]),
            "body: velocity = [1, 2]: must be 3 finite numbers",
        ),
        (lambda s: s.with_ball(catenet.Box([0, 0, 5.0], [0.2] * 3), mass=1.0), "must be a Sphere"),
        (
            lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2] * 3), mass="100"),
            "body: mass = '100': must be a number",
        ),
        (
            lambda s: s.with_body(catenet.Box([0, 0, 5.0], [0.2] * 3), mass=1.0, inertia="big"),
            "body: inertia = 'big': must be 3 x 3",
        ),
        (
            lambda s: s.with_body(catenet.Plane([0, 0, 5.0], [0, 0, 1.0]), mass=1.0),
            "a plane cannot be a free body",
        ),
        (lambda s: s.with_ball(catenet.Sphere([0, 0, 5.0], 0.2)), "give mass"),
        (
            lambda s: s.with_ball(catenet.Sphere([0.0, 0.0, 2.0], 0.2), mass=1.0),
            "obstacle[2] (kind 'sphere'): node 60",
        ),
        (
            lambda s: s.with_body(catenet.Box([0.0, 0.0, 2.0], [0.2] * 3), mass=1.0),
            "obstacle[2] (kind 'box', a free body): node 60",
        ),
    ],
)
def test_the_builder_refuses_a_bad_body_naming_it(call, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        call(capture_scene())


def test_a_solid_narrower_than_the_cells_is_warned_about():
    """The net touches solids at its nodes only: a free bar 0.1 m across over 1 m cells,
    or a fixed thin pipe, may pass between them, and the run says so
    (``catenet.run.advice.between_nodes``); a box wider than the cells does not, nor a
    bar farther from the net than its size (the run's watch says if it comes and cuts
    in)."""
    from catenet.run.advice import between_nodes

    nodes, edges = grid()
    net = catenet.graph(nodes, edges, [0, 10, 110, 120], catenet.Material(EA=1e4, line_density=0.1))
    scene = catenet.Scene.of(net, catenet.Loads())
    bar = scene.with_body(catenet.Capsule([-2.0, 0.3, 3.0], [2.0, 0.3, 3.0], 0.05), mass=5.0)
    pipe = scene.with_obstacle(catenet.Cylinder([-2.0, 0.5, 1.0], [2.0, 0.5, 1.0], 0.1))
    box = scene.with_body(catenet.Box([0.0, 0.0, 4.0], [1.5, 1.5, 0.75]), mass=5.0)
    (warning,) = between_nodes(bar)
    assert warning.startswith("obstacle[0] (a free capsule, 0.1 m across) is narrower than")
    assert "the net's edges (1 m, the median)" in warning
    (warning,) = between_nodes(pipe)
    assert warning.startswith("obstacle[0] (cylinder, 0.2 m across)")
    assert between_nodes(box) == []
    far = scene.with_body(catenet.Capsule([-2.0, 0.3, 30.0], [2.0, 0.3, 30.0], 0.05), mass=5.0)
    assert between_nodes(far) == []
    assert between_nodes(scene.with_obstacle(catenet.Plane([0, 0, 0.0], [0, 0, 1.0]))) == []
    # with every edge meeting solids (solver.edge_contact), nothing passes between nodes
    whole = catenet.Scene.of(net, catenet.Loads(), edge_radius=0.0)
    bar = whole.with_body(catenet.Capsule([-2.0, 0.3, 3.0], [2.0, 0.3, 3.0], 0.05), mass=5.0)
    assert between_nodes(bar) == []


def test_solve_refuses_newmark_that_cannot_damp_a_free_body():
    """As a case file does (``solver.rho_inf`` <= 0.95 with a free body)."""
    scene = catenet.Scene.of(*_net_and_gravity()).with_body(
        catenet.Box([0.0, 0.0, 3.0], [0.3, 0.3, 0.3]), mass=5.0
    )
    with pytest.raises(ConfigError, match=r"solver.rho_inf = 0.99: must be <= 0.95 with a free"):
        catenet.solve(scene, method="dynamic", integrator="newmark", rho_inf=0.99, t_end=0.1)


def _net_and_gravity():
    nodes, edges = grid()
    net = catenet.graph(nodes, edges, [0, 10, 110, 120], catenet.Material(EA=1e4, line_density=0.1))
    return net, catenet.Loads(gravity=np.array([0.0, 0.0, -9.81]))
