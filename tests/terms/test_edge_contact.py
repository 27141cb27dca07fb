"""Contact along the whole edge (solver.edge_contact, ``catenet.terms.segments``): finite
differences of the edge barrier against every outline (a box's edges in each regime of
the segment distance, nearly parallel ones in the mollifier's, a sphere's centre, a
capsule's axis, a cylinder's core capsule and its end bands' prisms (a drum's prisms
whole), a mesh's edges; riding on a ball's node and on a free body's four nodes), the
step cap across a box's edge and a thin plate, and the
closed form of a taut two-edge cable drawn over a box's edge: the first edge rests on
the edge in its middle, straight and tangent to the capsule of the contact radius
about the box's edge, its node where the tensions balance by hand; friction along the
edge (finite differences; a rope piece across two rods sticks below mu times its weight
and slides at (pull - mu W) / m above)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from meshes import CUBE_T, CUBE_V
from scipy.optimize import brentq

import catenet
from catenet.model.measures import tension
from catenet.model.net import Loads, Net
from catenet.scene.segments import edge_outline
from catenet.scene.shapes.box import Box
from catenet.scene.shapes.capsule import Capsule
from catenet.scene.shapes.cylinder import Cylinder
from catenet.scene.shapes.mesh import Mesh
from catenet.scene.shapes.sphere import Sphere
from catenet.terms import check_derivatives
from catenet.terms.contact import default_stiffness
from catenet.terms.rigid import BodyFrame
from catenet.terms.segments import EdgeContact, EdgeFriction
from catenet.terms.strands import SelfContact

R = 0.01  # the edges' contact radius
DHAT = 0.05


def _term(shape, x, **kw) -> EdgeContact:
    points, lines, radius = edge_outline(shape)
    rest = [float(np.linalg.norm(x[1] - x[0]))]
    args = dict(r=R, kappa=10.0, dhat=DHAT, n_nodes=len(x))
    return EdgeContact([[0, 1]], rest, points, lines, radius, **(args | kw))


BOX = Box([0.0, 0.0, 0.0], [0.3, 0.2, 0.1])
CAPSULE = Capsule([-0.3, 0, 0], [0.3, 0, 0], 0.1)
CYLINDER = Cylinder([0, 0, -0.2], [0, 0, 0.2], 0.1)  # its core capsule from z = -0.1 to 0.1
CASES = {
    # box: across its top edge (both parameters free), past a corner (one clamped),
    # nearly parallel to its top edge (the mollifier), ends clamped against a corner
    "box across an edge": (BOX, [[-0.1, 0.35, 0.12], [0.2, 0.05, 0.13]]),
    "box past a corner": (BOX, [[0.33, 0.25, 0.0], [0.45, 0.2, 0.2]]),
    "box nearly parallel": (BOX, [[-0.2, 0.21, 0.125], [0.2, 0.212, 0.126]]),
    "box end on a corner": (BOX, [[0.32, 0.22, 0.125], [0.6, 0.5, 0.4]]),
    "sphere, middle": (Sphere([0, 0, 0], 0.3), [[-0.2, 0.1, 0.305], [0.2, 0.05, 0.31]]),
    "sphere, end": (Sphere([0, 0, 0], 0.3), [[0.05, 0.0, 0.33], [0.4, 0.1, 0.5]]),
    "capsule": (CAPSULE, [[-0.1, -0.1, 0.115], [0.1, 0.12, 0.12]]),
    "capsule parallel": (CAPSULE, [[-0.1, 0, 0.13], [0.1, 0.0005, 0.131]]),
    "cylinder, end band": (CYLINDER, [[0.12, -0.1, 0.2], [0.1, 0.1, 0.25]]),
    "cylinder, round side": (CYLINDER, [[0.115, -0.1, 0.0], [0.112, 0.1, 0.02]]),
    "drum": (Cylinder([0, 0, -0.05], [0, 0, 0.05], 0.1), [[0.115, -0.1, 0.0], [0.112, 0.1, 0.02]]),
    "cube mesh": (Mesh(CUBE_V, CUBE_T, np.zeros(3)), [[-0.3, 0.3, 1.03], [0.3, 0.6, 1.035]]),
}  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_the_edge_barrier_passes_finite_differences(case):
    shape, ends = CASES[case]
    x = np.array([*ends, [5.0, 5.0, 5.0]], dtype=np.float64)
    term = _term(shape, x)
    gap = float(term.gap(x)[0])
    assert 0.0 < gap < DHAT, gap  # in reach: the barrier acts
    assert term.energy(x) > 0.0
    g_err, h_err = check_derivatives(term, x, step=1e-7)
    assert g_err < 1e-6 and h_err < 1e-5, (g_err, h_err)


def test_the_barrier_rides_on_a_ball_and_on_a_free_body():
    ball = Sphere([0, 0, 0], 0.3)
    x = np.array([[-0.2, 0.1, 0.305], [0.2, 0.05, 0.31], [0.01, 0.0, -0.01]])
    points, lines, radius = ball.outline()
    term = EdgeContact([[0, 1]], [0.4], points, lines, radius, r=R, kappa=10.0, dhat=DHAT,
                       n_nodes=3, weights=np.ones((1, 1)), bnodes=[2])  # fmt: skip
    assert max(check_derivatives(term, x, step=1e-7)) < 1e-5
    frame = BodyFrame(2, 12.0, np.diag([1.0, 1.5, 2.0]), [0.0, 0.0, 0.0])
    places, _ = frame.place()
    points = BOX.outline().points
    weights = 0.25 + (points - frame.center) @ frame.B.T
    ends = np.array([[-0.1, 0.35, 0.12], [0.2, 0.05, 0.13]])
    x = np.vstack([ends, places + [0.003, -0.002, 0.001]])  # moved, a little turned below
    x[2:] += 0.002 * np.random.default_rng(3).standard_normal((4, 3))
    term = EdgeContact([[0, 1]], [0.4], points, BOX.outline().edges, 0.0, r=R, kappa=10.0,
                       dhat=DHAT, n_nodes=6, weights=weights, bnodes=frame.nodes)  # fmt: skip
    assert term.energy(x) > 0.0
    g_err, h_err = check_derivatives(term, x, step=1e-7)
    assert g_err < 1e-6 and h_err < 1e-5, (g_err, h_err)
    # the body's share: the net edge's forces and the body's are equal and opposite
    grad = np.zeros_like(x)
    term.gradient(x, grad)
    assert np.abs(grad.sum(axis=0)).max() < 1e-9 * np.abs(grad).max()


def test_the_step_cap_stops_an_edge_before_a_box_edge_and_a_thin_plate():
    # an edge swept down across the box's top edge: both nodes pass beside the box
    x = np.array([[0.4, -0.3, 0.3], [0.4, 0.3, 0.3], [5.0, 5.0, 5.0]])
    x[:2, 0] = 0.2  # over the box (|x| < 0.3), its ends beyond the box's y-extent
    x[:2, 1] = [-0.5, 0.5]
    dx = np.zeros_like(x)
    dx[:2, 2] = -1.0
    term = _term(BOX, x)
    t = term.max_step_within(x, dx, 4.0)
    # the segment touches the capsule of radius r about the top face's edges at z = 0.1 + r
    assert 0.0 < t < 0.3 - 0.1 - R
    assert t > 0.5 * (0.3 - 0.1 - R)  # conservative, not wasteful
    plate = Box([0.0, 0.0, 0.0], [0.3, 0.3, 1e-4])  # thinner than the step
    x[:2, 2] = 0.05
    term = _term(plate, x)
    assert 0.0 < term.max_step_within(x, dx, 4.0) < 0.05 - 1e-4 - R
    dx[:2] = [0.0, 0.0, 0.0]
    assert math.isinf(term.max_step_within(x, dx, 4.0))  # not moving: never touches


def _cable_over_edge(on: bool):
    """A taut two-edge cable from A to C over the top edge of a box turned 45 degrees
    about y (its ridge along y through K = (0, 0, 0)), node 1 free above the ridge's
    right side: the static equilibrium."""
    A, n1, C = [-1.0, 0.0, -0.5], [0.45, 0.0, 0.35], [2.0, 0.0, -0.5]
    nodes = np.array([A, n1, C])
    L0 = np.array([1.2, 1.2])
    net = Net.from_arrays(nodes, [[0, 1], [1, 2]], EA=1e4, fixed=[0, 2], rest_length=L0)
    h = 0.5
    c = math.sqrt(2.0) / 2
    axes = np.array([[c, 0.0, c], [0.0, 1.0, 0.0], [-c, 0.0, c]])  # x' and z' at 45 degrees
    box = Box([0.0, 0.0, -h * math.sqrt(2.0)], [h, 1.0, h], axes)  # ridge at z = 0
    radius = R if on else None
    scene = catenet.Scene.of(net, edge_radius=radius).with_obstacle(box)
    return scene, catenet.solve(scene, method="static")


def test_a_cable_drawn_over_a_box_edge_wraps_it_as_the_closed_form_says():
    scene, res = _cable_over_edge(on=True)
    assert res.converged
    x = res.x
    A, n1, C = x
    # the first edge is straight from A past the ridge K: its distance to the ridge line
    # (the y axis) is the contact radius plus a gap below the activation distance
    u = (n1 - A) / np.linalg.norm(n1 - A)
    s = -A @ u  # K's foot on the edge's line, from A
    foot = A + s * u
    assert 0.0 < s < np.linalg.norm(n1 - A)  # in the middle of the edge
    d = math.hypot(foot[0], foot[2])
    dhat = scene.terms[0].dhat  # 1e-4 of the edges (the default accuracy)
    assert dhat < 2e-4 and R < d < R + dhat
    # By hand: the line from A tangent to the circle of radius R about K, node 1 on it at
    # the distance lam from A where the tensions balance along it: T1 = T2 (c . u).
    a = np.array([A[0], A[2]])
    beta = math.atan2(-a[1], -a[0]) + math.asin(R / np.linalg.norm(a))  # tangent above K
    w = np.array([math.cos(beta), math.sin(beta)])
    c2 = np.array([C[0], C[2]])

    def balance(lam):
        p = a + lam * w
        t1 = 1e4 * (lam / 1.2 - 1.0)
        t2 = 1e4 * (np.linalg.norm(c2 - p) / 1.2 - 1.0)
        return t1 - t2 * (c2 - p) @ w / np.linalg.norm(c2 - p)

    lam = brentq(balance, 1.3, 3.0)
    p = a + lam * w
    assert np.hypot(n1[0] - p[0], n1[2] - p[1]) < 5 * dhat and abs(n1[1]) < 1e-12
    t1, t2 = tension(scene.net, x)
    assert t1 == pytest.approx(1e4 * (lam / 1.2 - 1.0), rel=1e-3)
    # the contact force: normal to the edge, node 1 takes s / lam of it
    cvec = (c2 - p) / np.linalg.norm(c2 - p)
    normal = np.array([-w[1], w[0]])
    force = abs(t2 * (cvec @ normal)) * lam / abs(a @ w)
    edge = next(t for t in scene.terms if isinstance(t, EdgeContact))
    push = np.zeros_like(x)
    edge.gradient(x, push)  # minus the force of the box's edge on the two nodes
    assert np.linalg.norm(push.sum(axis=0)) == pytest.approx(force, rel=1e-3)
    assert push[1] @ u == pytest.approx(0.0, abs=1e-9 * force)  # normal to the edge
    assert force > 100.0
    # node-only contact lets the edge cut through the box's edge
    _, plain = _cable_over_edge(on=False)
    A0, m1, _ = plain.x
    u0 = (m1 - A0) / np.linalg.norm(m1 - A0)
    foot0 = A0 - (A0 @ u0) * u0
    assert foot0[2] < -0.05  # below the ridge, inside the box


def test_edge_friction_passes_finite_differences():
    x = np.array([*CASES["box across an edge"][1], [5.0, 5.0, 5.0]])
    contact = _term(BOX, x)
    friction = EdgeFriction(contact, mu=0.5, slip=1e-3)
    friction.begin_step(x, 0.1, 0.0)
    assert len(friction.pairs) == 1 and 0.0 < friction.share[0] < 1.0  # across the edge
    for move in (2e-4, 5e-3):  # sticking (within slip) and sliding
        y = x + move * np.array([[1.0, 0.3, 0.0], [0.5, -0.2, 0.1], [0.0, 0.0, 0.0]])
        assert friction.energy(y) > 0.0
        assert max(check_derivatives(friction, y, step=1e-8)) < 1e-6


def _rope_on_two_rods(pull: float, mu: float):
    """A 1 m rope piece (two 0.5 kg end masses) lying across two rods (capsules of
    radius 0.05 m along y at x = -0.3 and 0.3) under gravity, its ends beyond them (only
    the edge touches), pulled along its length by ``pull`` [N] at one end: (times,
    positions, velocities) of every step."""
    z = 0.05 + R + 2e-4
    nodes = np.array([[-0.5, 0.0, z], [0.5, 0.0, z]])
    net = Net.from_arrays(nodes, [[0, 1]], EA=1e5, fixed=[], point_mass=[0.5, 0.5],
                          flies=True, tension_only=False)  # fmt: skip
    force = np.zeros((2, 3))
    force[1, 0] = pull
    loads = Loads(force=force, gravity=np.array([0.0, 0.0, -9.81]))
    scene = catenet.Scene.of(net, loads, edge_radius=R)
    for x0 in (-0.3, 0.3):
        rod = Capsule([x0, -0.5, 0.0], [x0, 0.5, 0.0], 0.05)
        scene = scene.with_obstacle(rod, friction=mu, distance=1e-3)
    assert any(isinstance(t, EdgeFriction) for t in scene.terms) == (mu > 0)
    times, xs, vs = [0.0], [nodes], [np.zeros_like(nodes)]

    def keep(step):
        times.append(step.time)
        xs.append(step.x.copy())
        vs.append(step.v.copy())

    catenet.solve(scene, method="dynamic", dt=0.005, t_end=0.5, damping=0.0, on_step=keep)
    return np.array(times), np.array(xs), np.array(vs)


@pytest.mark.parametrize("pull, mu", [(3.0, 0.5), (8.0, 0.5), (3.0, 0.0)])
def test_a_rope_on_two_rods_sticks_below_mu_times_its_weight_and_slides_above(pull, mu):
    """Coulomb: the rods' friction on the edge holds at most mu W = 4.905 N (W its
    weight, 9.81 N, the rods' normal forces); below it the rope moves less than the
    slip distance (frictionless: 0.38 m), above it slides at (pull - mu W) / m."""
    t, x, v = _rope_on_two_rods(pull, mu)
    later = t >= 0.2
    accel = (v[-1, :, 0].mean() - v[later][0, :, 0].mean()) / (t[-1] - t[later][0])
    if pull < mu * 9.81:
        assert np.abs(x[-1, :, 0] - x[0, :, 0]).max() < 1e-3  # within the slip distance
    else:
        assert accel == pytest.approx(pull - mu * 9.81, rel=0.05)


def _crossing(gap: float, radius: float):
    """Two straight cords of 4 edges crossing at right angles, ``gap`` apart (centre
    lines), the upper thrown down at 2 m/s: the net and its strands' barrier, capsules
    of ``radius``."""
    s = np.linspace(-0.2, 0.2, 5)
    lower = np.column_stack([s, np.zeros(5), np.zeros(5)])
    upper = np.column_stack([np.zeros(5) + 0.013, s + 0.031, np.full(5, gap)])  # no node on a node
    edges = [[k, k + 1] for k in range(4)] + [[5 + k, 6 + k] for k in range(4)]
    net = Net.from_arrays(np.vstack([lower, upper]), edges, EA=1e3, fixed=[0, 4],
                          line_density=0.01, flies=True, tension_only=False)  # fmt: skip
    term = SelfContact(net, kappa=default_stiffness(1.0, 1e-3), dhat=1e-3, radius=radius)
    return net, term


def test_the_strands_barrier_with_a_contact_radius_passes_finite_differences():
    net, term = _crossing(2 * R + 5e-4, R)
    x = net.nodes.copy()
    assert 0.0 < term.energy(x) < math.inf  # within reach of the capsules' gap
    assert max(check_derivatives(term, x, step=1e-8)) < 1e-5


def test_strands_with_a_contact_radius_stay_twice_it_apart():
    """The upper cord, thrown at the lower one, bounces off at a distance of the two
    radii (centre lines), never nearer, at every step."""
    from catenet.model.net import Loads
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.workspace import Workspace

    net, term = _crossing(0.05, R)
    v0 = np.zeros_like(net.nodes)
    v0[5:, 2] = -2.0
    closest = []

    def keep(k, t, x, v):
        closest.append(term.distances(x, 0.05)[:1].min(initial=np.inf))

    ws = Workspace(net, terms=[term])
    solve_dynamic(net, Loads(), dt=0.005, damping=0.0, t_end=0.06, workspace=ws, v0=v0,
                  stop_at_equilibrium=False, on_step=keep)  # fmt: skip
    assert 2 * R < min(closest) < 2 * R + term.dhat  # met, never nearer than the radii


def test_edge_friction_on_a_free_body_passes_finite_differences_and_is_internal():
    """Seen in the body's frame: its derivatives in the edge's and the body's nodes, and
    its forces on the edge and on the body equal and opposite."""
    from catenet.terms.body_segments import BodyEdgeFriction

    frame = BodyFrame(2, 12.0, np.diag([1.0, 1.5, 2.0]), [0.0, 0.0, 0.0])
    places, _ = frame.place()
    points, lines, _ = BOX.outline()
    weights = 0.25 + (points - frame.center) @ frame.B.T
    x = np.vstack([CASES["box across an edge"][1], places])
    contact = EdgeContact([[0, 1]], [0.4], points, lines, 0.0, r=R, kappa=10.0, dhat=DHAT,
                          n_nodes=6, weights=weights, bnodes=frame.nodes)  # fmt: skip
    friction = BodyEdgeFriction(contact, frame, mu=0.5, slip=1e-3)
    friction.begin_step(x, 0.1, 0.0)
    assert len(friction.pairs) == 1
    rng = np.random.default_rng(2)
    for move in (2e-4, 5e-3):  # sticking and sliding, the body moved and turned a little
        y = x + move * rng.standard_normal(x.shape)
        grad = np.zeros_like(y)
        friction.gradient(y, grad)
        assert np.abs(grad.sum(axis=0)).max() < 1e-12 * np.abs(grad).max()
        assert max(check_derivatives(friction, y, step=1e-8)) < 1e-6
