"""Free bodies against each other and against fixed obstacles, in the same implicit step
as the net (catenet.scene.touching, catenet.terms.touch): closed forms and invariants.

- A box resting on a fixed box (statically, and dynamically after a drop): the contact
  force is its weight, the gap within the activation distance; a box on a free box on
  the ground: the ground carries both weights, the lower box the upper's.
- Two equal boxes flying head on, in zero gravity, undamped: the total linear momentum
  is kept at every step to the solver's tolerance and the velocities are exchanged
  (the barrier is elastic; the integrator's dissipation takes a few percent).
- A sphere falling onto a fixed capsule just off its top slides off it, never inside.
- Two boxes dropped edge on edge: never overlapping, checked by the separating axis
  theorem at every step and sampled between, at steps from 1 ms to 0.1 s.
- A closed mesh body dropped on a fixed box rests on its vertices, its weight carried.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.solver.path import Settings, solve
from catenet.terms.body_plane import BodyPlane
from catenet.terms.touch import BodyTouch
from tests.meshes import boxes_apart


def scene_of(obstacles, solver, gravity=(0.0, 0.0, -9.81)):
    """A short pinned cable far above and beside the solids, the ``obstacles`` and ``solver``."""
    case = {
        "geometry": {"kind": "cable", "start": [2, 0, 2], "end": [3, 0, 2], "nodes": 5},
        "material": {"E": 1e9, "radius": 0.001, "density": 1000.0, "prestress": 10.0},
        "obstacle": obstacles,
        "solver": solver,
    }
    if gravity is not None:
        case["load"] = {"gravity": list(gravity)}
    return build(parse_case(case))


def pushes(term, x, nodes) -> np.ndarray:
    """The force [N] of the term on the body with these four nodes at x."""
    grad = np.zeros_like(x)
    term.gradient(x, grad)
    return -grad[nodes].sum(axis=0)


BASE = {"kind": "box", "center": [0.0, 0.0, 0.0], "half_size": [0.5, 0.5, 0.2]}


def resting(z: float, **more) -> dict:
    """A 10 kg box (0.4 x 0.3 x 0.2 m, turned 0.3 rad about z) with its centre at z."""
    return {"kind": "box", "center": [0.0, 0.0, z], "half_size": [0.2, 0.15, 0.1],
            "angle": 0.3, "mass": 10.0, "distance": 0.005, **more}  # fmt: skip


def test_a_box_rests_on_a_fixed_box_its_weight_carried():
    """Static: the box placed 4 mm above the fixed box (its own distance 5 mm, the fixed
    box's default 1 mm: the pair takes the smaller) finds the equilibrium where the
    barrier carries its weight, 98.1 N, straight up, the gap within 1 mm. Dynamic: dropped
    from 5 cm (implicit Euler, undamped: the step's own dissipation settles it) it comes
    to rest at the same place, never below the face."""
    static = scene_of([BASE, resting(0.304)], {"method": "static"})
    r = solve(static, Settings.of(static.case.solver))
    assert r.converged
    (term,) = [t for t in static.terms if isinstance(t, BodyTouch)]
    assert term.dhat == 0.001
    nodes = static.rigid[0].frame.nodes
    assert np.allclose(pushes(term, r.x, nodes), [0.0, 0.0, 98.1], rtol=1e-6, atol=1e-6)
    assert 0.0 < term.gap(r.x) < term.dhat
    c_static = static.rigid[0].frame.pose(r.x)[0]
    solver = {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 1.5}
    dynamic = scene_of([BASE, resting(0.35)], solver)
    (term,) = [t for t in dynamic.terms if isinstance(t, BodyTouch)]
    gaps = []
    settings = Settings.of(dynamic.case.solver)
    rd = solve(dynamic, settings, on_step=lambda s: gaps.append(term.gap(s.x)))
    assert rd.converged and min(gaps) > 0.0
    c, R = dynamic.rigid[0].frame.pose(rd.x)
    assert np.abs(c - c_static).max() < 1e-6
    assert np.allclose(pushes(term, rd.x, nodes), [0.0, 0.0, 98.1], rtol=1e-4, atol=1e-3)


def test_a_box_on_a_free_box_on_the_ground():
    """A 10 kg box on a 20 kg box on the ground (a plane), static: the ground carries
    both weights (294.3 N), the lower box's top the upper's (98.1 N); each gap within
    its barrier's reach."""
    ground = {"kind": "plane", "point": [0.0, 0.0, -0.2], "distance": 0.002}
    lower = dict(BASE, half_size=[0.5, 0.5, 0.1], center=[0.0, 0.0, -0.0995], mass=20.0)
    scene = scene_of([ground, lower, resting(0.101)], {"method": "static"})
    r = solve(scene, Settings.of(scene.case.solver))
    assert r.converged
    (touch,) = [t for t in scene.terms if isinstance(t, BodyTouch)]
    planes = [t for t in scene.terms if isinstance(t, BodyPlane)]
    low, high = (b.frame.nodes for b in scene.rigid)
    assert np.allclose(pushes(touch, r.x, high), [0.0, 0.0, 98.1], rtol=1e-6, atol=1e-6)
    ground_force = sum(pushes(p, r.x, p.frame.nodes) for p in planes)
    assert np.allclose(ground_force, [0.0, 0.0, 294.3], rtol=1e-6, atol=1e-6)
    assert 0.0 < touch.gap(r.x) < touch.dhat


def test_two_equal_boxes_collide_head_on_and_exchange_their_velocities():
    """Zero gravity, no damping, 1 m/s each way, 0.1 m apart, at default settings (no
    dt: steps chosen by accuracy, bdf2; newmark is refused in contact): the total
    momentum kept to the solver's tolerance at every step, each box left with the other's
    velocity to 5 %; the boxes never meet."""
    a = {"kind": "box", "center": [-0.15, 0.0, 0.0], "half_size": [0.1, 0.1, 0.1], "mass": 2.0,
         "velocity": [1.0, 0.0, 0.0], "distance": 0.005}  # fmt: skip
    b = dict(a, center=[0.15, 0.0, 0.0], velocity=[-1.0, 0.0, 0.0])
    solver = {"method": "dynamic", "damping": 0.0, "t_end": 0.1}
    scene = scene_of([a, b], solver, gravity=None)
    (term,) = [t for t in scene.terms if isinstance(t, BodyTouch)]
    first, second = scene.rigid
    drift, gaps = [], []

    def seen(s):
        p = first.frame.momentum(s.x, s.v)[0] + second.frame.momentum(s.x, s.v)[0]
        drift.append(float(np.abs(p).max()))
        gaps.append(term.gap(s.x))

    r = solve(scene, Settings.of(scene.case.solver), on_step=seen)
    assert r.converged
    assert min(gaps) > 0.0 and min(gaps) < term.dhat  # they touched, never met
    assert max(drift) < 1e-8 * 2.0  # of |m v| = 2 kg m/s each
    va, wa = first.frame.motion(r.x, r.v)
    vb, _ = second.frame.motion(r.x, r.v)
    assert va[0] == pytest.approx(-1.0, rel=0.05) and vb[0] == pytest.approx(1.0, rel=0.05)
    assert np.abs(va[1:]).max() < 1e-6 and np.abs(wa).max() < 1e-6


def test_a_sphere_falls_onto_a_fixed_capsule_and_slides_off():
    """A 0.1 m sphere body dropped onto a horizontal capsule (radius 0.05) 2 cm off its
    top line: frictionless, it slides off the rounded side and falls past; its centre is
    never within the summed radii of the axis, at every step or sampled between, and
    at the end it is below the axis, beside it."""
    capsule = {"kind": "capsule", "start": [-0.5, 0.0, 0.0], "end": [0.5, 0.0, 0.0],
               "radius": 0.05, "distance": 0.003}  # fmt: skip
    sphere = {"kind": "sphere", "center": [0.1, 0.02, 0.3], "radius": 0.1, "density": 800.0,
              "distance": 0.003}  # fmt: skip
    solver = {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.8}
    scene = scene_of([capsule, sphere], solver)
    frame = scene.rigid[0].frame
    centres = [frame.state(scene.net.nodes)[0]]
    states = [scene.net.nodes.copy()]

    def seen(s):
        states.append(s.x.copy())

    r = solve(scene, Settings.of(scene.case.solver), on_step=seen)
    assert r.converged
    for x0, x1 in zip(states[:-1], states[1:], strict=True):
        for s in np.linspace(0.0, 1.0, 11):
            c = frame.state((1 - s) * x0 + s * x1)[0]
            centres.append(c)
    centres = np.array(centres)
    axis = np.hypot(centres[:, 1], centres[:, 2])  # distance to the axis (x within it)
    assert axis.min() > 0.15 and axis.min() < 0.15 + 0.003
    end = frame.state(r.x)[0]
    assert end[2] < 0.0 and end[1] > 0.15


def _pose(body, obs, x):
    """(centre, axes, half sizes) of a free box at x."""
    from catenet.terms.shapes import rotation

    c, R = body.frame.pose(x)
    return c, R @ rotation(obs["axis"], obs["angle"]), np.asarray(obs["half_size"])


@pytest.mark.parametrize("dt", [0.001, 0.02, 0.1])
def test_boxes_dropped_edge_on_edge_never_pass_through(dt):
    """A 2 kg box (an edge down along x) thrown down at 3 m/s onto a fixed box with an
    edge up along y: only the edge-edge barrier holds them where they cross. The
    separating axis theorem finds them apart at every step and at 10 states sampled
    between two steps, whatever the step."""
    h = 0.1 * math.sqrt(2.0)
    lower = {"kind": "box", "center": [0.0, 0.0, -h], "half_size": [0.1, 0.3, 0.1],
             "axis": [0.0, 1.0, 0.0], "angle": math.pi / 4, "distance": 0.005}  # fmt: skip
    upper = {"kind": "box", "center": [0.01, 0.02, h + 0.1], "half_size": [0.3, 0.1, 0.1],
             "axis": [1.0, 0.0, 0.0], "angle": math.pi / 4, "mass": 2.0,
             "velocity": [0.0, 0.0, -3.0], "distance": 0.005}  # fmt: skip
    solver = {"method": "dynamic", "dt": dt, "damping": 0.0, "t_end": 0.3}
    scene = scene_of([lower, upper], solver)
    body = scene.rigid[0]
    from catenet.terms.shapes import rotation

    fixed = (np.asarray(lower["center"]), rotation(lower["axis"], lower["angle"]),
             np.asarray(lower["half_size"]))  # fmt: skip
    states = [scene.net.nodes.copy()]
    r = solve(scene, Settings.of(scene.case.solver), on_step=lambda s: states.append(s.x.copy()))
    assert r.converged
    gaps = []
    for x0, x1 in zip(states[:-1], states[1:], strict=True):
        for s in np.linspace(0.0, 1.0, 11):
            gaps.append(boxes_apart(fixed, _pose(body, upper, (1 - s) * x0 + s * x1)))
    assert min(gaps) > 0.0
    lowest = min(body.frame.pose(x)[0][2] for x in states)
    assert lowest < h + 0.005  # it came down onto the edge (within the barrier's reach)


def test_a_mesh_body_dropped_on_a_fixed_box_rests_on_its_vertices(tmp_path):
    """A closed triangle mesh (an icosphere of radius 0.2, 162 vertices) as a 3 kg free
    body dropped from 5 cm onto a fixed box: its vertices meet the box's top face; it
    never reaches it, and at rest the box carries its weight, 29.43 N, straight up."""
    from tests.meshes import icosphere, write_stl

    V, T = icosphere(2)
    write_stl(tmp_path / "ball.stl", V, T)
    low = float((0.2 * V[:, 2]).min())
    box = dict(BASE, distance=0.003)
    mesh = {"kind": "mesh", "file": str(tmp_path / "ball.stl"), "scale": 0.2,
            "offset": [0.0, 0.0, 0.2 - low + 0.05], "mass": 3.0, "distance": 0.003}  # fmt: skip
    solver = {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 1.0}
    scene = scene_of([box, mesh], solver)
    (term,) = [t for t in scene.terms if isinstance(t, BodyTouch)]
    gaps = []
    r = solve(scene, Settings.of(scene.case.solver), on_step=lambda s: gaps.append(term.gap(s.x)))
    assert r.converged and min(gaps) > 0.0 and gaps[-1] < term.dhat
    force = pushes(term, r.x, scene.rigid[0].frame.nodes)
    assert np.allclose(force, [0.0, 0.0, 3.0 * 9.81], rtol=1e-4, atol=1e-3)


def slope_case(mu: float, method: str = "dynamic") -> dict:
    """A 5 kg box (0.4 x 0.4 x 0.2 m) on the top face of a fixed box tilted 20 degrees
    about y, 1 mm above it (the pair's reach 2 mm), the slope's ``friction`` mu."""
    th = math.radians(20.0)
    normal = np.array([math.sin(th), 0.0, math.cos(th)])
    turned = {"axis": [0.0, 1.0, 0.0], "angle": th, "distance": 0.002}
    lower = {"kind": "box", "center": [0.0, 0.0, 0.0], "half_size": [1.0, 0.5, 0.2],
             "friction": mu, **turned}  # fmt: skip
    upper = {"kind": "box", "center": (0.301 * normal).tolist(), "half_size": [0.2, 0.2, 0.1],
             "mass": 5.0, **turned}  # fmt: skip
    solver = {"method": method}
    if method == "dynamic":
        solver.update(dt=0.005, damping=0.0, t_end=0.5)
    return [lower, upper], solver


@pytest.mark.parametrize("mu", [0.5, 0.2])
def test_a_box_on_a_slope_sticks_or_slides_as_coulomb_says(mu):
    """tan 20 deg = 0.364. With mu = 0.5 the box stays where it was put (within the slip
    distance, 2 mm) over 0.5 s, and a static solve holds it there, the contact and
    friction forces its weight; with mu = 0.2 it slides down the slope, its speed
    growing at g (sin 20 deg - mu cos 20 deg) = 1.511 m/s^2 once it slips (to 1 %), the
    friction force mu times the normal force."""
    from catenet.terms.touch import BodyTouchFriction

    obstacles, solver = slope_case(mu)
    scene = scene_of(obstacles, solver)
    frame = scene.rigid[0].frame
    c0 = frame.state(scene.net.nodes)[0]
    seen = []
    r = solve(scene, Settings.of(scene.case.solver), on_step=lambda s: seen.append(s))
    assert r.converged
    moved = np.linalg.norm(frame.state(r.x)[0] - c0)
    pair = [t for t in scene.terms if isinstance(t, (BodyTouch, BodyTouchFriction))]
    if mu > math.tan(math.radians(20.0)):
        assert moved < 0.002
        obstacles, solver = slope_case(mu, "static")
        static = scene_of(obstacles, solver)
        rs = solve(static, Settings.of(static.case.solver))
        assert rs.converged
        held = sum(pushes(t, rs.x, frame.nodes) for t in static.terms
                   if isinstance(t, (BodyTouch, BodyTouchFriction)))  # fmt: skip
        assert np.allclose(held, [0.0, 0.0, 5.0 * 9.81], rtol=1e-6, atol=1e-6)
        assert np.linalg.norm(frame.state(rs.x)[0] - c0) < 0.002
        return
    speed = [np.linalg.norm(frame.motion(s.x, s.v)[0]) for s in seen]
    times = [s.time for s in seen]
    rate = np.polyfit(times[40:], speed[40:], 1)[0]  # from t = 0.2 s
    a = 9.81 * (math.sin(math.radians(20.0)) - mu * math.cos(math.radians(20.0)))
    assert rate == pytest.approx(a, rel=0.01) and moved > 0.15
    normal, friction = (pushes(t, r.x, frame.nodes) for t in pair)
    assert np.linalg.norm(friction) == pytest.approx(mu * np.linalg.norm(normal), rel=1e-6)
