"""Contact between two rigid solids (catenet.terms.touch, catenet.scene.touching): a free
body against a fixed or free box, sphere, capsule or mesh. Finite-difference checks of
the gradient and Hessian of every pair of kinds, at strained, turned poses with
features within reach (corner on face, crossing edges, a sphere's or a capsule's
rounded surface); the edge-edge barrier's share (the pairs that only it holds: two
boxes edge on edge); the step cap: exact for a corner falling onto a face, conservative
and close for crossing edges; the features' gap against an independent distance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.terms import check_derivatives
from catenet.terms.touch import STEP_CHECKED, BodyTouch
from tests.meshes import icosphere, write_stl


def scene_of(obstacles, gravity=(0.0, 0.0, -9.81)):
    """A short pinned cable far below the solids, and the ``obstacles``."""
    case = {
        "geometry": {"kind": "cable", "start": [2, 0, -2], "end": [3, 0, -2], "nodes": 5},
        "material": {"E": 1e9, "radius": 0.001, "density": 1000.0, "prestress": 10.0},
        "obstacle": obstacles,
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.1},
    }
    if gravity is not None:
        case["load"] = {"gravity": list(gravity)}
    return build(parse_case(case))


def touch(scene) -> BodyTouch:
    (term,) = [t for t in scene.terms if isinstance(t, BodyTouch)]
    return term


#: A free body just above z = 0.2 (the top of each lower solid), within reach (0.01 m).
TOPS = {
    "box": {"kind": "box", "center": [0.05, 0.03, 0.3025], "half_size": [0.35, 0.1, 0.1],
            "angle": 0.3, "mass": 3.0},
    "sphere": {"kind": "sphere", "center": [0.05, 0.03, 0.3025], "radius": 0.1,
               "density": 500.0},
    "capsule": {"kind": "capsule", "start": [-0.1, 0.03, 0.305], "end": [0.2, 0.05, 0.305],
                "radius": 0.1, "mass": 2.0},
}  # fmt: skip
#: The lower solids, their tops at z = 0.2 (the capsule's: near its middle).
BOTTOMS = {
    "box": {"kind": "box", "center": [0.0, 0.0, 0.0], "half_size": [0.3, 0.3, 0.2]},
    "sphere": {"kind": "sphere", "center": [0.0, 0.0, 0.0], "radius": 0.2},
    "capsule": {"kind": "capsule", "start": [-0.3, 0.0, 0.0], "end": [0.3, 0.1, 0.0],
                "radius": 0.2},
}  # fmt: skip


@pytest.mark.parametrize("free", [False, True], ids=["fixed", "free"])
@pytest.mark.parametrize("bottom", list(BOTTOMS))
@pytest.mark.parametrize("top", list(TOPS))
def test_derivatives_of_every_pair_of_kinds(top, bottom, free):
    """Gradient and Hessian against central differences (relative 1e-6) at a pose with
    the body's nodes moved by 3e-4 m at random (turned and strained a little), where the
    pair is within reach (its energy is not zero)."""
    lower = dict(BOTTOMS[bottom], distance=0.01, **({"mass": 5.0} if free else {}))
    scene = scene_of([lower, dict(TOPS[top], distance=0.01)])
    term = touch(scene)
    x = scene.net.nodes.copy()
    x[term.nodes] += 3e-4 * np.random.default_rng(7).standard_normal((len(term.nodes), 3))
    assert 0.0 < term.gap(x) < 0.01 and term.energy(x) > 0.0
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-6


def crossed_boxes(free: bool, lift: float = 0.004):
    """Two boxes edge on edge: the upper turned 45 degrees about x (an edge down along
    x), the lower 45 degrees about y (an edge up along y), ``lift`` apart at the
    crossing; no corner of either is near the other's faces."""
    h = 0.1 * math.sqrt(2.0)
    lower = {"kind": "box", "center": [0.0, 0.0, -h], "half_size": [0.1, 0.3, 0.1],
             "axis": [0.0, 1.0, 0.0], "angle": math.pi / 4, "distance": 0.01}  # fmt: skip
    if free:
        lower["mass"] = 4.0
    upper = {"kind": "box", "center": [0.0, 0.0, h + lift], "half_size": [0.3, 0.1, 0.1],
             "axis": [1.0, 0.0, 0.0], "angle": math.pi / 4, "mass": 2.0,
             "distance": 0.01}  # fmt: skip
    return scene_of([lower, upper])


@pytest.mark.parametrize("free", [False, True], ids=["fixed", "free"])
def test_crossing_edges_are_held_by_the_edge_barrier_alone(free):
    """Edge on edge, the points' sides are out of reach: the whole energy is the
    edge-edge barrier's, on the gap of the two edges (``lift``), and its derivatives
    pass; the force on the upper box is along z, the lower box's opposite."""
    scene = crossed_boxes(free)
    term = touch(scene)
    x = scene.net.nodes
    assert term.gap(x) == pytest.approx(0.004, abs=1e-12)
    for side in term.sides:
        assert float(side.term.gap(side.local(x)).min()) > 0.01
    assert term.energy(x) > 0.0
    grad = np.zeros_like(x)
    term.gradient(x, grad)
    up = grad[scene.rigid[-1].frame.nodes].sum(axis=0)
    assert abs(up[0]) + abs(up[1]) < 1e-9 * abs(up[2]) and up[2] < 0.0  # pushed up
    if free:
        assert np.allclose(grad[scene.rigid[0].frame.nodes].sum(axis=0), -up, rtol=1e-12)
    x = x.copy()
    x[term.nodes] += 2e-4 * np.random.default_rng(3).standard_normal((len(term.nodes), 3))
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-6


def test_step_cap_corner_on_face_is_exact_and_edges_conservative():
    """A box sinking straight onto a fixed box (not turning): the step cap is the first
    time a corner reaches the face, exactly (its edges within the face: no edge pair
    near); moving apart: not within the steps checked. Crossing edges closing at 1 m
    per unit step from a gap of 4 mm: the cap is before the touch at 0.004 and within
    the additive CCD's share of it."""
    small = dict(TOPS["box"], half_size=[0.2, 0.1, 0.1], distance=0.01)  # within the face
    scene = scene_of([dict(BOTTOMS["box"], distance=0.01), small])
    term = touch(scene)
    x = scene.net.nodes
    dx = np.zeros_like(x)
    dx[term.a.nodes] = [0.0, 0.0, -1.0]
    assert term.max_step(x, dx) == pytest.approx(term.gap(x), rel=1e-9)
    assert term.max_step(x, -dx) == STEP_CHECKED  # apart: as far as the edges are checked
    scene = crossed_boxes(False)
    term = touch(scene)
    x = scene.net.nodes
    dx = np.zeros_like(x)
    dx[term.a.nodes] = [0.0, 0.0, -1.0]
    t = term.max_step(x, dx)
    assert 0.9 * 0.004 * 0.9 < t < 0.004


def test_far_apart_the_pair_costs_nothing_and_never_caps():
    """Out of reach: zero energy, no Hessian values, and a step that does not bring the
    bounding spheres together is not capped at all (inf), one that does is, before the
    boxes would touch (their faces 1.7 m apart)."""
    lower = dict(BOTTOMS["box"], mass=5.0)
    upper = dict(TOPS["box"], center=[0.0, 0.0, 2.0])
    scene = scene_of([lower, upper])
    term = touch(scene)
    x = scene.net.nodes
    values = np.zeros(len(term.pattern()[0]))
    assert term.energy(x) == 0.0 and term.hessian(x, values) is False and not values.any()
    dx = np.zeros_like(x)
    dx[term.a.nodes] = [1.0, 0.0, 0.0]
    assert term.max_step(x, dx) == math.inf
    dx[term.a.nodes] = [0.0, 0.0, 1.0]  # the lower box (the first free body) rises
    assert 1.0 < term.max_step(x, dx) <= 1.7


def test_a_mesh_body_on_a_box_and_a_box_on_a_mesh(tmp_path):
    """A closed triangle mesh (an icosphere of radius 0.2) as the free body above a fixed
    box, and a free box above a fixed mesh: derivatives pass; the mesh's vertices meet the
    box's faces and the box's corners meet the mesh's triangles."""
    V, T = icosphere(1)
    write_stl(tmp_path / "ball.stl", V, T)
    mesh = {"kind": "mesh", "file": str(tmp_path / "ball.stl"), "scale": 0.2,
            "distance": 0.01}  # fmt: skip
    low = float((0.2 * V[:, 2]).min())
    body = dict(mesh, offset=[0.0, 0.0, 0.2 - low + 0.003], mass=1.0)
    scene = scene_of([dict(BOTTOMS["box"], distance=0.01), body])
    term = touch(scene)
    x = scene.net.nodes.copy()
    x[term.nodes] += 2e-4 * np.random.default_rng(5).standard_normal((len(term.nodes), 3))
    assert 0.0 < term.gap(x) < 0.01
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-6
    top = float((0.2 * V[:, 2]).max())
    box = {"kind": "box", "center": [0.0, 0.0, top + 0.05 + 0.003], "half_size": [0.1, 0.1, 0.05],
           "angle": 0.2, "axis": [1.0, 0.0, 0.0], "mass": 1.0, "distance": 0.01}  # fmt: skip
    scene = scene_of([mesh, box])
    term = touch(scene)
    x = scene.net.nodes.copy()
    assert 0.0 < term.gap(x) < 0.01
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-6


@pytest.mark.parametrize("kind", ["box", "capsule"])
def test_nearly_parallel_edges_are_mollified_and_smooth(kind):
    """Two equal boxes stacked edge over edge (their top and bottom edges parallel, 3 mm
    apart), two capsules crossing at 1 degree: the edges are within the mollifier's
    angle (about 1.8 degrees), where the end points' barriers take over; gradient and
    Hessian still pass the finite-difference check at poses moved at random."""
    if kind == "box":
        lower = {"kind": "box", "center": [0.0, 0.0, 0.0], "half_size": [0.2, 0.1, 0.1],
                 "distance": 0.01}  # fmt: skip
        upper = dict(lower, center=[0.0, 0.0, 0.203], mass=2.0)
    else:
        a = math.radians(1.0)
        lower = {"kind": "capsule", "start": [-0.3, 0.0, 0.0], "end": [0.3, 0.0, 0.0],
                 "radius": 0.05, "distance": 0.01}  # fmt: skip
        upper = dict(lower, start=[-0.3 * math.cos(a), -0.3 * math.sin(a), 0.103],
                     end=[0.3 * math.cos(a), 0.3 * math.sin(a), 0.103], mass=1.0)  # fmt: skip
    scene = scene_of([lower, upper])
    term = touch(scene)
    assert term.meet and term.energy(scene.net.nodes) > 0.0
    rng = np.random.default_rng(11)
    for _ in range(3):
        x = scene.net.nodes.copy()
        x[term.nodes] += 2e-4 * rng.standard_normal((len(term.nodes), 3))
        grad_err, hess_err = check_derivatives(term, x, step=1e-7)
        assert grad_err < 1e-6 and hess_err < 1e-6


@pytest.mark.parametrize("free", [False, True], ids=["fixed", "free"])
def test_friction_between_solids_derivatives(free):
    """The lagged Coulomb friction between a box resting on a box (``friction`` on the
    lower table): its normal forces and anchors taken at the start, the gradient and
    Hessian at a pose moved at random (sliding and turning a little) pass the
    finite-difference check; it acts on the points' sides only."""
    from catenet.terms.touch import BodyTouchFriction

    lower = dict(BOTTOMS["box"], distance=0.01, friction=0.4, **({"mass": 5.0} if free else {}))
    scene = scene_of([lower, dict(TOPS["box"], half_size=[0.2, 0.1, 0.1], distance=0.01)])
    (friction,) = [t for t in scene.terms if isinstance(t, BodyTouchFriction)]
    assert friction.rides_on is touch(scene) and len(friction.sides) == 2
    x0 = scene.net.nodes
    friction.begin_step(x0, 0.01, 0.0)
    x = x0.copy()
    x[friction.nodes] += 3e-4 * np.random.default_rng(4).standard_normal((len(friction.nodes), 3))
    assert friction.energy(x) > 0.0
    grad_err, hess_err = check_derivatives(friction, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-6
