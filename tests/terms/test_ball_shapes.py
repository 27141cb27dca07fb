"""Rigid balls against boxes, capsules and meshes (catenet.terms.collide): the centre's
barrier against the shape grown by the radius. Finite differences in every region (box
faces, edges and corners; capsule ends; mesh faces, edges and vertices), the first
contact never lets the ball overlap (random and grazing rays against a dense sampling of
the path), the grown cube mesh acts as the rounded box, a ball at rest at the closed-form
height, a drop on a tumbling box that never overlaps, carrying a ball's contacts with a
moving obstacle, and bad input.

Closed form: a ball of weight W resting on a horizontal face (or a capsule's top end)
sits at the top + r + g*, where the barrier's force balances its weight,
-kappa b'(g*) = W (g* < dhat).
"""

from __future__ import annotations

import copy
import math
from types import SimpleNamespace

import numpy as np
import pytest
from contact_cases import catch_case
from meshes import CUBE_T, CUBE_V, icosphere, write_stl

from catenet.case import build, dumps_toml, parse_case
from catenet.kernels.contact import barrier
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.body import Ball
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier, CapsuleBarrier, MeshBarrier, rotation

R_BALL = 0.2
DHAT = 0.05
TURN = rotation([1.0, 2.0, 3.0], 0.7)


def probe(term, n):
    """A copy of ``term`` on nodes 0..n-1 (to evaluate gaps at many points)."""
    p = type(term).__new__(type(term))
    p.__dict__.update(term.__dict__)
    if isinstance(term, Moving):
        p.shape = probe(term.shape, n)
    p.nodes = np.arange(n)
    return p


def near_feature(rng, center, axes, half, outside: int, n: int, r: float, dhat: float):
    """n points (world) whose nearest feature of the box (center, axes, half) has
    ``outside`` coordinates beyond the box (1: a face, 2: an edge, 3: a corner), at gaps
    between 0.05 and 1.4 dhat from the box grown by r."""
    out = []
    for _ in range(n):
        axes_out = rng.choice(3, outside, replace=False)
        q, w = np.empty(3), np.zeros(3)
        for a in range(3):
            if a in axes_out:
                s = rng.choice([-1.0, 1.0])
                q[a], w[a] = s * half[a], s * rng.uniform(0.2, 1.0)
            else:
                q[a] = rng.uniform(-0.9, 0.9) * half[a]
        w /= np.linalg.norm(w)
        out.append(center + axes @ (q + (r + rng.uniform(0.05, 1.4) * dhat) * w))
    return np.array(out)


def grown_box(n=10, offset=R_BALL):
    return BoxBarrier(
        np.arange(n), [0.1, 0, 0], [0.5, 0.3, 0.2], TURN, kappa=30.0, dhat=DHAT, offset=offset
    )


def grown_cube(n=10, offset=R_BALL):
    """The unit cube as a mesh, turned, grown by ``offset``."""
    return MeshBarrier(np.arange(n), CUBE_V @ TURN.T, CUBE_T, kappa=30.0, dhat=DHAT, offset=offset)


@pytest.mark.parametrize("outside", [1, 2, 3], ids=["face", "edge", "corner"])
def test_a_ball_against_a_box_passes_finite_differences_in_each_region(outside):
    rng = np.random.default_rng(outside)
    box = grown_box()
    x = near_feature(rng, box.center, box.axes, box.half, outside, 10, R_BALL, DHAT)
    gap = box.gap(x)
    assert np.all(gap > 0) and np.any(gap < DHAT) and np.any(gap > DHAT)
    grad_err, hess_err = check_derivatives(box, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


@pytest.mark.parametrize("outside", [1, 2, 3], ids=["face", "edge", "vertex"])
def test_a_ball_against_a_mesh_passes_finite_differences_near_faces_edges_and_vertices(outside):
    rng = np.random.default_rng(10 + outside)
    cube = grown_cube()
    x = near_feature(rng, TURN @ [0.5, 0.5, 0.5], TURN, np.full(3, 0.5), outside, 10, R_BALL, DHAT)
    assert np.all(cube.gap(x) > 0) and np.any(cube.gap(x) < DHAT)
    grad_err, hess_err = check_derivatives(cube, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5
    # A curved mesh (a sphere of 320 triangles): any feature.
    V, T = icosphere(2)
    ball = MeshBarrier(np.arange(10), 0.5 * V + 0.2, T, kappa=30.0, dhat=DHAT, offset=R_BALL)
    u = rng.standard_normal((10, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    x = 0.2 + u * (0.5 + R_BALL + rng.uniform(0.05, 1.4, (10, 1)) * DHAT)
    x = x[ball.gap(x) > 0.01 * DHAT]
    grad_err, hess_err = check_derivatives(probe(ball, len(x)), x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


def test_a_ball_against_a_moving_box_passes_finite_differences_at_a_turned_pose():
    rng = np.random.default_rng(5)
    term = Moving(grown_box(), [0.1, 0, 0], [0.3, -0.2, 0.1], [0.5, 1.0, -2.0], reach=1.0)
    term.set_pose(0.4)
    c, R = term.pose(0.4)
    x = near_feature(rng, c, R @ TURN, np.array([0.5, 0.3, 0.2]), 2, 10, R_BALL, DHAT)
    assert np.all(term.gap(x) > 0) and np.any(term.gap(x) < DHAT)
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


def test_a_grown_cube_mesh_acts_as_the_rounded_box():
    """Same gaps, forces, Hessians and first contacts: the mesh grown by r is the box
    grown by r (faces, edge cylinders, corner balls)."""
    rng = np.random.default_rng(3)
    n = 30
    box = BoxBarrier(
        np.arange(n), TURN @ [0.5, 0.5, 0.5], [0.5] * 3, TURN, kappa=5.0, dhat=DHAT, offset=R_BALL
    )
    mesh = grown_cube(n)
    x = np.vstack(
        [near_feature(rng, box.center, TURN, box.half, k, 10, R_BALL, DHAT) for k in (1, 2, 3)]
    )
    mesh.kappa = box.kappa

    def values(term):  # gap, energy, gradient, Hessian
        grad, hess = np.zeros_like(x), np.zeros(9 * n)
        energy = term.gradient(x, grad)
        term.hessian(x, hess)
        return term.gap(x), energy, grad, hess

    for m, b in zip(values(mesh), values(box), strict=True):
        assert np.allclose(m, b, rtol=1e-9, atol=1e-12 * max(np.abs(b).max(), 1.0))
    for _ in range(30):
        dx = rng.standard_normal(x.shape)
        assert mesh.max_step(x, dx) == pytest.approx(box.max_step(x, dx), rel=1e-9)


def capsule_with_ball(n=10):
    """The capsule a ball of radius R_BALL meets: its radius grown by R_BALL."""
    return CapsuleBarrier(
        np.arange(n), [0, 0, 0], [1.0, 0.5, 0.0], 0.3 + R_BALL, kappa=30.0, dhat=DHAT
    )


def test_a_ball_against_a_capsule_passes_finite_differences_near_its_ends():
    rng = np.random.default_rng(9)
    cap = capsule_with_ball()
    a, b = cap.a, cap.b
    x = []
    for end, away in ((a, a - b), (b, b - a)):  # beyond each end: the end balls
        for _ in range(5):
            u = rng.standard_normal(3)
            u += 3.0 * away / np.linalg.norm(away)
            u /= np.linalg.norm(u)
            x.append(end + u * (cap.radius + rng.uniform(0.05, 1.4) * DHAT))
    x = np.array(x)
    assert np.all(cap.gap(x) > 0) and np.any(cap.gap(x) < DHAT)
    grad_err, hess_err = check_derivatives(cap, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


def surface_point(term, rng, inside):
    """A random point of the grown surface: bisection from a far point to ``inside``."""
    one = probe(term, 1)
    far = rng.standard_normal(3)
    far = 3.0 * far / np.linalg.norm(far)
    lo, hi = 0.0, 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if one.gap((far + mid * (inside - far))[None])[0] > 0:
            lo = mid
        else:
            hi = mid
    return far + lo * (inside - far)


def unit_normal(term, p, h=1e-7):
    one = probe(term, 1)
    e = np.eye(3) * h
    g = np.array([one.gap((p + e[a])[None])[0] - one.gap((p - e[a])[None])[0] for a in range(3)])
    return g / np.linalg.norm(g)


def moving_box():
    term = Moving(grown_box(1), [0.1, 0, 0], [0.3, -0.2, 0.1], [0.5, 1.0, -2.0], reach=1.0)
    term.set_pose(0.3)
    return term


@pytest.mark.parametrize("kind", ["box", "cube mesh", "sphere mesh", "capsule", "moving box"])
def test_max_step_never_lets_a_ball_overlap(kind):
    """Rays aimed at the grown shape, random ones from just outside it, and grazing
    ones (passing 1e-6 outside, 1e-9 outside or 1e-6 inside a tangent): every point of
    the path before max_step is outside (dense sampling), and max_step is the first
    contact the sampling sees (to the sampling's resolution)."""
    rng = np.random.default_rng(17)
    V, T = icosphere(2)
    term, inside = {
        "box": lambda: (grown_box(1), np.array([0.1, 0, 0])),
        "cube mesh": lambda: (grown_cube(1), TURN @ [0.5, 0.5, 0.5]),
        "sphere mesh": lambda: (
            MeshBarrier(np.arange(1), 0.5 * V + 0.2, T, kappa=1.0, dhat=DHAT, offset=R_BALL),
            np.full(3, 0.2),
        ),
        "capsule": lambda: (capsule_with_ball(1), np.array([0.5, 0.25, 0.0])),
        "moving box": lambda: (moving_box(), moving_box().pose(0.3)[0]),
    }[kind]()
    ts = np.linspace(0.0, 2.0, 20001)
    path = probe(term, len(ts))
    hits = grazes = 0
    for k in range(60):
        p = surface_point(term, rng, inside)
        n = unit_normal(term, p)
        if k % 3 == 0:  # grazing: along a tangent, just outside or just inside
            tangent = rng.standard_normal(3)
            tangent -= (tangent @ n) * n
            tangent /= np.linalg.norm(tangent)
            x0 = p + rng.choice([1e-6, 1e-9, -1e-6]) * n - 0.7 * tangent
            dx = 1.4 * tangent
            grazes += 1
        elif k % 3 == 1:  # aimed at the surface from up to 1 m away
            x0 = p + rng.uniform(0.01, 1.0) * n + 0.3 * rng.standard_normal(3)
            dx = (p - x0) * rng.uniform(0.5, 2.0)
        else:  # from just outside, any direction
            x0 = p + rng.uniform(1e-4, DHAT) * n
            dx = 0.5 * rng.standard_normal(3)
        if not probe(term, 1).gap(x0[None])[0] > 0:
            continue
        t = term.max_step(x0[None], dx[None])
        gap = path.gap(x0 + ts[:, None] * dx)
        assert np.all(gap[ts < t] > 0)  # never a point inside before the cap
        first = np.flatnonzero(gap <= 0)
        if first.size:
            hits += 1
            assert t >= ts[first[0] - 1] - 1e-9  # the cap is the first contact
    assert hits >= 20 and grazes >= 15


# --------------------------------------------------------------------------- scenes


def beside(obstacles, **solver):
    """The coarse net of tests/terms/test_bodies.py far from ``obstacles`` (at x = 2 m)."""
    case = catch_case(coarse=True, **solver)
    case["obstacle"] = obstacles
    return case


BALL = {"kind": "sphere", "radius": 0.1, "mass": 1.0, "distance": 0.005}


def rest_gap(term, weight: float) -> float:
    """g* with -kappa b'(g*) = weight (bisection on the monotone barrier force)."""
    lo, hi = 1e-12, term.dhat
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if -term.kappa * barrier(mid, term.dhat)[1] > weight else (lo, mid)
    return 0.5 * (lo + hi)


def ball_term(scene):
    """The barrier between the ball's centre and the other obstacle."""
    (node,) = [b.node for b in scene.bodies]
    (term,) = [t for t in scene.terms if list(t.nodes) == [node] and not isinstance(t, Ball)]
    return node, term


@pytest.mark.parametrize("kind", ["box", "capsule", "cube mesh"])
def test_a_ball_rests_on_a_box_a_capsule_end_and_a_mesh_cube_at_the_closed_form_height(
    kind, tmp_path
):
    """Static: a 1 kg ball let go just above the top (inside the barrier's reach) comes
    to rest at top + r + g*; the mesh cube of the box's size gives the box's answer."""
    centre, half = np.array([2.0, 0.0, -0.2]), np.array([0.2, 0.3, 0.1])
    top, start = -0.1, [2.05, 0.02, 0.003]
    if kind == "box":
        other = {"kind": "box", "center": centre.tolist(), "half_size": half.tolist()}
    elif kind == "capsule":  # upright: the ball sits on its upper end ball
        other = {"kind": "capsule", "start": [2.0, 0, -0.5], "end": [2.0, 0, -0.2], "radius": 0.1}
        start = [2.0, 0.0, 0.003]
    else:
        stl = write_stl(tmp_path / "cube.stl", centre + (CUBE_V - 0.5) * 2 * half, CUBE_T)
        other = {"kind": "mesh", "file": str(stl)}
    case = beside([{**other, "distance": 0.005}, {**BALL, "center": start}])
    case["solver"] = {"method": "static"}
    scene = build(parse_case(case))
    node, term = ball_term(scene)
    r = solve(scene, Settings.of(scene.case.solver))
    assert r.converged
    g_star = rest_gap(term, 9.81)
    assert 0 < g_star < term.dhat
    assert r.x[node, 2] == pytest.approx(top + 0.1 + g_star, abs=1e-9)
    assert r.x[node, :2] == pytest.approx(start[:2], abs=1e-9)  # a flat top: no sliding


def test_a_ball_dropped_on_a_box_comes_to_rest_at_the_closed_form_height():
    """Dynamic: dropped from 0.1 m, the ball bounces (implicit Euler's numerical damping
    takes its energy: mu acts on the net only) and rests at top + r + g*, never below."""
    box = {"kind": "box", "center": [2.0, 0.0, -0.2], "half_size": [0.2, 0.3, 0.1]}
    case = beside([{**box, "distance": 0.005}, {**BALL, "center": [2.05, 0.02, 0.1]}])
    case["solver"].update(dt=0.01, t_end=5.0, damping=2.0)
    scene = build(parse_case(case))
    node, term = ball_term(scene)
    gaps = []
    r = solve(
        scene, Settings.of(scene.case.solver), on_step=lambda s: gaps.append(term.gap(s.x)[0])
    )
    assert r.converged and r.equilibrium
    assert min(gaps) > 0.0
    assert r.x[node] == pytest.approx([2.05, 0.02, -0.1 + 0.1 + rest_gap(term, 9.81)], abs=1e-7)


@pytest.mark.parametrize(
    "kind, dt",
    [("box", 0.05), ("box", 0.01), ("box", 0.002), ("capsule", 0.01), ("mesh", 0.01)],
)
def test_a_ball_dropped_on_a_tumbling_rising_shape_never_overlaps_it(kind, dt, tmp_path):
    """Every frame: the ball's centre outside the shape (at that frame's pose) grown by
    the radius; the ball touched it and was thrown off. The mesh is the box's cube."""
    centre, half = [2.0, 0.0, -0.2], np.array([0.3, 0.3, 0.1])
    shape = {
        "box": {"kind": "box", "center": centre, "half_size": half.tolist()},
        "capsule": {
            "kind": "capsule",
            "start": [1.7, 0, -0.2],
            "end": [2.3, 0, -0.2],
            "radius": 0.1,
        },
        "mesh": {
            "kind": "mesh",
            "file": str(write_stl(tmp_path / "cube.stl", (CUBE_V - 0.5) * 2 * half, CUBE_T)),
            "offset": centre,
        },
    }[kind]
    shape.update(distance=0.005, angular_velocity=[0.0, 2.0, 1.0], velocity=[0, 0, 0.2])
    case = beside([shape, {**BALL, "center": [2.05, 0.02, 0.3]}], dt=dt, t_end=1.0, damping=2.0)
    scene = build(parse_case(case))
    node, term = ball_term(scene)
    assert isinstance(term, Moving) and not term.guards_supports
    gaps = []

    def on_step(s):
        c, R = term.pose(s.time)
        gaps.append(float(term.shape.gap(term._body(s.x, c, R))[0]))

    r = solve(scene, Settings.of(scene.case.solver), on_step=on_step)
    assert r.converged and len(gaps) >= round(1.0 / dt)
    assert min(gaps) > 0.0
    assert min(gaps) < term.dhat  # it touched
    assert abs(r.x[node, 0] - 2.0) > 0.3  # knocked off the box


def test_carrying_brings_a_balls_contacts_along(monkeypatch):
    """A box rising by 0.1 m in a step: the ball it may reach rides with it and so does
    the net node resting on the ball (too far from the box to be carried by it); a net
    node the box carries brings the ball resting on it (too far for its own term) and
    that ball's other contact. Without it the carried node would be inside the ball.
    Every node within the box's reach rides here, as with a turning box (a translating
    one leaves in place what its straight path keeps clear: ``Moving.stays``)."""
    from catenet.terms import moving

    monkeypatch.setattr(moving.Moving, "stays", lambda self, items, *a: np.zeros(len(items), bool))

    def scene_terms(ball_dhat):
        net = np.arange(3)  # net nodes 0, 1, 2; ball centre 3
        kw = dict(velocity=[0, 0, 1.0], reach=1.0)
        box = BoxBarrier(net, [0, 0, 0], [0.5] * 3, kappa=1.0, dhat=0.01)
        grown = BoxBarrier([3], [0, 0, 0], [0.5] * 3, kappa=1.0, dhat=ball_dhat, offset=0.1)
        on_ball = Moving(grown, [0, 0, 0], **kw)
        on_ball.guards_supports = False
        terms = [
            Moving(box, [0, 0, 0], **kw),
            on_ball,
            Ball(net, 3, 0.1, kappa=1.0, dhat=0.01, n_nodes=4),
        ]
        return SimpleNamespace(system=SimpleNamespace(terms=terms))

    fixed = np.zeros(4, bool)
    # The ball 0.05 above the box (carried by its own term); node 0 on top of it, 0.253 m
    # from the box; node 1 far away.
    x = np.array([[0, 0, 0.753], [3.0, 0, 0], [3.0, 1, 0], [0, 0, 0.65]])
    base = moving.carry(scene_terms(0.01), x, x.copy(), 0.0, 0.1, fixed)
    assert base[3] == pytest.approx([0, 0, 0.75]) and base[0] == pytest.approx([0, 0, 0.853])
    assert base[1:3] == pytest.approx(x[1:3])
    # Node 0 0.205 m beside the box's top edge (carried: below 2 x 0.1 + 0.01); the
    # ball outward of it, 0.003 away (0.208 from the box, beyond 2 x 0.1 + 0.001 of its
    # own term); node 1 on the ball's far side.
    u = np.array([1.0, 0, 1.0]) / math.sqrt(2)
    corner = np.array([0.5, 0, 0.5])
    x = np.array([corner + 0.205 * u, corner + 0.411 * u, [3.0, 1, 0], corner + 0.308 * u])
    terms = scene_terms(0.001)
    assert terms.system.terms[1].gap(x)[0] > 0.201
    base = moving.carry(terms, x, x.copy(), 0.0, 0.1, fixed)
    assert np.allclose(base[[0, 1, 3]] - x[[0, 1, 3]], [0, 0, 0.1])
    ball = terms.system.terms[2]
    assert ball.gap(base).min() == pytest.approx(ball.gap(x).min())
    alone = x.copy()
    alone[0, 2] += 0.1  # node 0 carried, the ball left behind
    assert ball.gap(alone)[0] < 0


def test_a_net_lifted_by_a_rising_box_into_a_ball_on_it_never_overlaps():
    """A box rises under the net's centre, where a ball rests: every frame keeps every
    node outside the ball and the box, and the ball outside the box."""
    box = {"kind": "box", "center": [0, 0, -0.12], "half_size": [0.15, 0.15, 0.05]}
    box.update(distance=0.005, velocity=[0, 0, 0.3])
    ball = {**BALL, "center": [0.0, 0.0, 0.11]}
    case = beside([box, ball], dt=0.05, t_end=0.8, damping=2.0)
    scene = build(parse_case(case))
    movers = [t for t in scene.terms if isinstance(t, Moving)]
    (contact,) = [t for t in scene.terms if isinstance(t, Ball)]
    gaps = []

    def on_step(s):
        row = [contact.gap(s.x).min()]
        for m in movers:
            c, R = m.pose(s.time)
            row.append(m.shape.gap(m._body(s.x, c, R)).min())
        gaps.append(row)

    r = solve(scene, Settings.of(scene.case.solver), on_step=on_step)
    assert r.converged
    gaps = np.array(gaps)
    assert gaps.min() > 0.0
    assert (gaps.min(axis=0) < 0.005).all()  # each pair touched
    assert r.x[scene.bodies[0].node, 2] > 0.11 + 0.1  # the ball was lifted


def test_a_ball_collides_with_every_kind_without_a_warning(caplog, tmp_path):
    stl = write_stl(tmp_path / "cube.stl", CUBE_V + [3.0, 0, 0], CUBE_T)
    case = beside(
        [
            {**BALL, "center": [2.0, 0.0, 0.5]},
            {"kind": "box", "center": [2.0, 0.0, 0.0], "half_size": [0.1, 0.1, 0.1]},
            {"kind": "capsule", "start": [2.0, 1.0, 0.0], "end": [2.0, 2.0, 0.0], "radius": 0.1},
            {"kind": "mesh", "file": str(stl)},
        ]
    )
    with caplog.at_level("WARNING"):
        scene = build(parse_case(case))
    assert "collide" not in caplog.text
    node = scene.bodies[0].node
    kinds = {type(t).__name__: t for t in scene.terms if list(t.nodes) == [node]}
    assert set(kinds) == {"BoxBarrier", "CapsuleBarrier", "MeshBarrier"}
    assert kinds["BoxBarrier"].offset == 0.1 and kinds["MeshBarrier"].offset == 0.1
    assert kinds["CapsuleBarrier"].radius == pytest.approx(0.2)


@pytest.mark.parametrize(
    "other",
    [
        {"kind": "box", "center": [2.0, 0.0, 0.0], "half_size": [0.1, 0.1, 0.1]},
        {"kind": "capsule", "start": [1.7, 0.0, 0.0], "end": [1.7, 1.0, 0.0], "radius": 0.3},
        {"kind": "mesh", "file": "cube.stl"},
        {
            "kind": "box",
            "center": [2.0, 0.0, 0.0],
            "half_size": [0.1, 0.1, 0.1],
            "velocity": [1, 0, 0],
        },
    ],
    ids=["box", "capsule", "mesh", "moving box"],
)
def test_a_ball_that_starts_overlapping_a_shape_exits_2_with_its_key_path(tmp_path, other):
    """The ball (centre 2, 0, 0.15; radius 0.1) overlaps each shape, not the net."""
    from click.testing import CliRunner

    from catenet.cli import main

    write_stl(tmp_path / "cube.stl", CUBE_V * 0.2 + [1.9, -0.1, -0.1], CUBE_T)
    case = beside([{**BALL, "center": [2.0, 0.0, 0.15]}, copy.deepcopy(other)])
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    kind = other["kind"]
    message = f"obstacle[0] (kind 'sphere'): starts inside or touching obstacle[1] (kind '{kind}'"
    assert message in res.output
    assert not (tmp_path / "out.h5").exists()


def test_the_ball_off_box_example_runs_short_and_never_overlaps(tmp_path):
    """configs/contact/ball_off_box.toml as a user runs it, shortened by --set: in every
    written frame the ball is outside the rounded box and every node outside the ball;
    the ball slid off the box, reached the net, and ``catenet plot`` draws the scene."""
    from pathlib import Path

    from click.testing import CliRunner

    from catenet.case import load_case
    from catenet.cli import main
    from catenet.output import read_bodies
    from catenet.output.reader import read_frame

    config = Path(__file__).parents[2] / "configs" / "contact" / "ball_off_box.toml"
    out = tmp_path / "ball.h5"
    res = CliRunner().invoke(
        main, ["run", str(config), "-o", str(out), "--set", "solver.t_end=0.8"]
    )
    assert res.exit_code == 0, res.output
    scene = build(load_case(config))
    node, box = ball_term(scene)
    (contact,) = [t for t in scene.terms if isinstance(t, Ball)]
    b = read_bodies(out)
    centres = b.center[:, 0]
    assert len(centres) == 17 and b.times[-1] == pytest.approx(0.8)  # every 0.05 s
    box_gaps, net_gaps = [], []
    for k, c in enumerate(centres):
        x = read_frame(out, k).x
        assert np.array_equal(x[node], c)
        box_gaps.append(float(box.gap(x)[0]))
        net_gaps.append(float(contact.gap(x).min()))
    assert min(box_gaps) > 0.0 and min(net_gaps) > 0.0
    assert min(box_gaps) < box.dhat and min(net_gaps) < contact.dhat  # touched both
    first_box = int(np.argmax(np.array(box_gaps) < box.dhat))
    first_net = int(np.argmax(np.array(net_gaps) < contact.dhat))
    assert first_box < first_net and centres[first_net, 0] > -0.2  # off the box, then down
    png = tmp_path / "ball.png"
    res = CliRunner().invoke(main, ["plot", str(out), "-o", str(png)])
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 10_000
