"""Coulomb friction on boxes, capsules and meshes, fixed and on a prescribed motion
(catenet/terms/friction.py): normals from the barrier's gradient, finite differences, the
spring-held block of test_friction on a box top (same closed form as on a plane), a node
carried by a conveyor box and by a turning box when it sticks, and the kinetic force
mu N on a node held back from a conveyor it slides on."""

from __future__ import annotations

import math

import numpy as np
import pytest
from contact_cases import DHAT, KAPPA, block, moving_shapes, near
from meshes import CUBE_T, CUBE_V

from catenet.case import build, parse_case
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.friction import Friction, contact_normals
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier, CapsuleBarrier, MeshBarrier, rotation

# --------------------------------------------------------------------------- the term


def test_normals_from_the_barrier_are_the_gap_gradient_of_each_feature():
    """Box face, edge and corner; capsule side and end; mesh face: the unit normal is
    (x - nearest point) / distance, and +z where the barrier does not act."""
    nodes = np.arange(6)
    box = BoxBarrier(nodes, [0, 0, 0], [1.0, 1.0, 1.0], np.eye(3), kappa=10.0, dhat=0.1)
    x = np.array(
        [[0.2, 0.3, 1.05], [1.03, 1.04, 0.0], [1.02, 1.03, 1.01], [0, 0, 3.0], [-1.06, 0, 0.5],
         [0.5, -1.01, -0.2]]
    )  # fmt: skip
    nearest = np.clip(x, -1.0, 1.0)
    want = (x - nearest) / np.linalg.norm(x - nearest, axis=1)[:, None]
    want[3] = [0, 0, 1]  # out of reach
    assert np.allclose(contact_normals(box, x), want, atol=1e-12)
    cap = CapsuleBarrier(np.arange(2), [0, 0, 0], [2.0, 0, 0], 0.5, kappa=10.0, dhat=0.1)
    x = np.array([[1.0, 0.3, 0.42], [2.3, 0.0, 0.45]])
    want = np.array([[0, 0.3, 0.42], [0.3, 0, 0.45]])
    want /= np.linalg.norm(want, axis=1)[:, None]
    assert np.allclose(contact_normals(cap, x), want, atol=1e-12)
    cube = MeshBarrier(np.arange(1), CUBE_V - 0.5, CUBE_T, kappa=10.0, dhat=0.1)
    assert np.allclose(contact_normals(cube, np.array([[0.1, 0.2, 0.53]])), [[0, 0, 1]])


@pytest.mark.parametrize("kind", ["box", "capsule", "mesh"])
def test_friction_on_moving_shapes_passes_finite_differences(kind):
    """Within a step (lambda, normals and anchors lagged) the potential is smooth: the
    friction term on each moving shape, begun at t = 0.3 from 0.25, sticking and sliding
    nodes alike."""
    rng = np.random.default_rng(11)
    dhat = 0.05
    obstacle = moving_shapes(dhat=dhat, n=12)[kind]
    obstacle.set_pose(0.25)
    x = near(obstacle, rng, 12, dhat)
    term = Friction(obstacle, mu=0.4, slip=0.01)
    term.begin_step(x, 0.3, 0.25)
    active = term.weight > 0
    assert 0 < active.sum() < len(active)
    x1 = x + rng.normal(scale=0.004, size=x.shape)  # some within the slip distance
    x1[::2] += rng.normal(scale=0.05, size=x1[::2].shape)  # some beyond it
    g, h = check_derivatives(term, x1)
    assert g < 1e-6 and h < 1e-5


def test_anchors_and_normals_ride_with_the_obstacle_over_the_step():
    """A node touching a box that turns and translates: lagged at the step's start (its
    anchor is where it is), carried to the step's end by the obstacle's rigid motion."""
    box = BoxBarrier(np.arange(1), [0, 0, 0], [1.0, 1.0, 1.0], np.eye(3), kappa=10.0, dhat=0.1)
    moving = Moving(box, [0, 0, 0], [0.5, 0, 0], [0, 0, 2.0], reach=2.0)
    x = np.array([[0.3, 0.2, 1.02]])
    term = Friction(moving, mu=0.5, slip=1e-3)
    term.begin_step(x, 0.1, 0.0)
    turn = rotation([0, 0, 1], 0.2)
    assert np.allclose(term.anchor, [0.05, 0, 0] + x @ turn.T)
    assert np.allclose(term.normal, [[0, 0, 1]])
    assert np.allclose(moving.center, [0.05, 0, 0])  # left at the step's end
    assert term.weight[0] > 0


# --------------------------------------------------------------------------- closed forms


def tops(kinds=("box", "capsule", "mesh")):
    """Obstacles on node 1 whose top is z = 0 near the origin, straight along x (the
    capsule's axis lies along x)."""
    one = np.array([1])
    out = {
        "box": BoxBarrier(one, [0, 0, -1.0], [3.0, 3.0, 1.0], np.eye(3), kappa=KAPPA, dhat=DHAT),
        "capsule": CapsuleBarrier(one, [-3, 0, -1.0], [3, 0, -1.0], 1.0, kappa=KAPPA, dhat=DHAT),
        "mesh": MeshBarrier(one, 6.0 * (CUBE_V - [0.5, 0.5, 1.0]), CUBE_T, kappa=KAPPA, dhat=DHAT),
    }
    return [out[k] for k in kinds]


@pytest.mark.parametrize("pull", [0.045, 0.1])
@pytest.mark.parametrize("index", [0, 1, 2])
def test_a_block_on_a_box_capsule_or_mesh_top_sticks_below_mu_n_and_slides_to_it(pull, index):
    """The spring-held block of test_friction on a rough plane, now on the top of a box, a
    capsule and a mesh box: the same closed form."""
    mu, N, k, slip = 0.5, 10.0, 100.0, 1e-3
    obstacle = tops()[index]
    r = solve(
        block(mu=mu, slip=slip, force=[0, 0, -N], spring=k, pull=pull, obstacle=obstacle),
        Settings("static", rtol=1e-10, steps=2),
    )
    assert r.converged
    u = -r.x[1, 0]
    if k * pull < mu * N:
        assert 0 < u < slip
    else:
        assert u == pytest.approx(pull - mu * N / k, abs=1e-9)


def conveyor(velocity, *, mu, spring=None, angular=None, mass=1.0, N=20.0, axis=(0.0, 0.0)):
    """Node 1 on the top (z = 0) of a wide box moving at ``velocity`` (turning at
    ``angular`` about the vertical through ``axis`` (x, y), its centre), pressed by N,
    optionally tied to support 0 one metre behind it (along -x) by a bilateral spring."""
    one = np.array([1])
    center = [axis[0], axis[1], -1.0]
    box = BoxBarrier(one, center, [5.0, 5.0, 1.0], np.eye(3), kappa=KAPPA, dhat=DHAT)
    belt = Moving(box, center, velocity, angular, reach=8.0)
    return block(mu=mu, slip=1e-4, force=[0, 0, -N], mass=mass, spring=spring, obstacle=belt)


def test_a_node_on_a_conveyor_box_slides_until_it_sticks_then_travels_with_it():
    """Dropped at rest on a belt moving at v, the node slides with a = mu N / m until it
    has the belt's speed, a slip of |v|^2 / (2 a) behind the belt; then it sticks and
    travels with it. Without friction the belt slides under it."""
    mu, N, m, h = 0.8, 20.0, 1.0, 0.002
    v = np.array([0.4, 0.1, 0.0])
    seen = []
    settings = Settings("dynamic", dt=h, damping=0.0, t_end=0.3)
    problem = conveyor(v, mu=mu, N=N, mass=m)
    r = solve(problem, settings, on_step=lambda s: seen.append((s.time, s.x[1, :2].copy())))
    assert r.converged and len(seen) == 150
    behind = [v[:2] * t - x for t, x in seen if t >= 0.1]  # sticking: the lag stays
    assert np.ptp(behind, axis=0).max() < 1e-6
    a = mu * N / m
    lag = v[:2] * (v @ v) / (2 * a) / np.linalg.norm(v)
    assert np.allclose(behind[0], lag, atol=np.linalg.norm(v) * h)  # first order in h
    r = solve(conveyor(v, mu=0.0), settings)
    assert np.allclose(r.x[1, :2], 0.0, atol=1e-9)


def test_a_node_held_back_from_a_conveyor_feels_mu_n_against_its_slip():
    """Held by a spring k behind it, the node slides on the belt once k u = mu N: it
    settles at u = mu N / k along the belt's motion (kinetic friction, closed form)."""
    mu, N, k = 0.3, 20.0, 500.0
    settings = Settings("dynamic", dt=0.01, damping=20.0, t_end=3.0)
    r = solve(conveyor([0.5, 0, 0], mu=mu, spring=k, N=N), settings)
    assert r.converged
    assert r.x[1, 0] == pytest.approx(mu * N / k, rel=1e-6)
    assert abs(r.x[1, 1]) < 1e-9


def test_a_node_sticking_to_a_turning_box_turns_with_it():
    """A turntable spinning at w about a vertical 1 m from the node: the node slides
    until it has the table's speed, then sticks (m w^2 r well below mu N) and turns with
    it at a fixed lag angle and radius."""
    w, h = 0.5, 0.002
    seen = []
    settings = Settings("dynamic", dt=h, damping=0.0, t_end=0.6)
    problem = conveyor([0, 0, 0], mu=0.8, angular=[0, 0, w], mass=0.5, axis=(-1.0, 0.0))
    r = solve(problem, settings, on_step=lambda s: seen.append((s.time, s.x[1].copy())))
    assert r.converged
    late = [(t, x) for t, x in seen if t >= 0.1]
    lag = [w * t - math.atan2(x[1], x[0] + 1.0) for t, x in late]
    radius = [math.hypot(x[0] + 1.0, x[1]) for _, x in late]
    assert 0 < lag[0] < 0.01 and np.ptp(lag) < 1e-5
    assert np.ptp(radius) < 1e-5 and radius[0] == pytest.approx(1.0, abs=1e-3)


# --------------------------------------------------------------------------- cases


@pytest.mark.parametrize("kind", ["box", "capsule", "mesh"])
def test_box_capsule_and_mesh_take_friction_keys(kind, tmp_path):
    shape = {
        "box": {"kind": "box", "center": [0, 0, -1.2], "half_size": [1, 1, 1]},
        "capsule": {"kind": "capsule", "start": [-1, 0, -1.3], "end": [1, 0, -1.3], "radius": 1},
        "mesh": {"kind": "mesh", "file": str(tmp_path / "cube.obj"), "scale": 2.0,
                 "offset": [-1.0, -1.0, -2.3]},
    }[kind]  # fmt: skip
    if kind == "mesh":
        lines = [f"v {a} {b} {c}" for a, b, c in CUBE_V]
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in CUBE_T]
        (tmp_path / "cube.obj").write_text("\n".join(lines) + "\n")
    case = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 5},
        "material": {"E": 1e9, "area": 1e-5, "density": 1000.0},
        "load": {"gravity": [0, 0, -9.81]},
        "obstacle": [{**shape, "friction": 0.4, "slip": 0.002}],
    }
    terms = build(parse_case(case)).terms
    assert [type(t).__name__ for t in terms][1:] == ["Friction"]
    assert terms[1].mu == 0.4 and terms[1].slip == 0.002
