"""Rigid obstacles: finite differences of the barrier terms, no node ever inside an
obstacle (static and dynamic, at every step size), and a chain lying on the seabed
against the classic closed form.

Seabed closed form (a catenary mooring line with a grounded part, inextensible, on a
frictionless bed): the suspended part of length s is a catenary tangent to the bed at the
touchdown point, z = a (cosh(x/a) - 1) with a = H/w (H the horizontal tension, w the
weight per length); reaching the fairlead at height h gives s^2 = h^2 + 2 a h and a
horizontal run a acosh(1 + h/a). The grounded part lies straight and carries H to the
anchor. With the anchor at x = 0, the fairlead at (X, h) and the length L,

    X = L - sqrt(h^2 + 2 a h) + a acosh(1 + h/a),    touchdown at x_t = L - s,

which fixes a (brentq). The discrete chain lumps the weight at the nodes and rests on its
barrier gap (below dhat), so H and x_t agree to a few tenths of a per cent and to about an
edge length.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

import catenet as cn
from catenet.kernels.contact import barrier
from catenet.scene import Scene
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.contact import PlaneBarrier, SphereBarrier, default_stiffness


def test_barrier_is_c2_at_the_activation_distance_and_infinite_at_contact():
    dhat = 0.01
    assert barrier(dhat, dhat) == (0.0, 0.0, 0.0)
    # b, b' and b'' all tend to 0 at dhat (b'' linearly in the distance to it).
    near, nearer = barrier(dhat * (1 - 1e-5), dhat), barrier(dhat * (1 - 1e-6), dhat)
    assert all(abs(v) < 1e-4 for v in near)
    assert abs(nearer[2]) == pytest.approx(abs(near[2]) / 10, rel=1e-3)
    assert barrier(0.0, dhat)[0] == math.inf
    assert barrier(1e-12, dhat)[0] > barrier(1e-6, dhat)[0] > 0
    h = 1e-9
    for d in (1e-4, 3e-3, 9e-3):
        b, db, ddb = barrier(d, dhat)
        assert db == pytest.approx(
            (barrier(d + h, dhat)[0] - barrier(d - h, dhat)[0]) / (2 * h), rel=1e-5
        )
        assert ddb == pytest.approx(
            (barrier(d + h, dhat)[1] - barrier(d - h, dhat)[1]) / (2 * h), rel=1e-5
        )


def near(rng, n, surface):
    """n points at gaps between 0.1 and 0.9 dhat (dhat = 0.05) from ``surface``."""
    return surface(rng.uniform(0.005, 0.045, n), rng)


@pytest.mark.parametrize("kind", ["plane", "sphere"])
def test_obstacle_terms_pass_finite_differences(kind):
    rng = np.random.default_rng(4)
    dhat = 0.05
    if kind == "plane":
        normal = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
        x = rng.uniform(-1, 1, (6, 3))
        x -= np.outer(x @ normal, normal)  # onto the plane through 0
        x += np.outer(rng.uniform(0.005, 0.07, 6), normal)  # some inside dhat, some not
        term = PlaneBarrier(np.arange(6), [0, 0, 0], normal, kappa=30.0, dhat=dhat)
    else:
        c, R = np.array([0.1, 0.2, -0.3]), 0.5
        u = rng.standard_normal((6, 3))
        u /= np.linalg.norm(u, axis=1)[:, None]
        x = c + u * (R + rng.uniform(0.005, 0.07, 6))[:, None]
        term = SphereBarrier(np.arange(6), c, R, kappa=30.0, dhat=dhat)
    assert np.all(term.gap(x) > 0)
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


@pytest.mark.parametrize("kind", ["plane", "sphere"])
def test_max_step_is_the_first_contact_along_a_step(kind):
    if kind == "plane":
        term = PlaneBarrier(np.arange(2), [0, 0, 1.0], [0, 0, 1], kappa=1.0, dhat=0.1)
        x = np.array([[0.0, 0.0, 3.0], [1.0, 0.0, 2.0]])
        dx = np.array([[0.0, 0.0, -4.0], [0.0, 0.0, -4.0]])
        assert term.max_step(x, dx) == pytest.approx(0.25)  # node 1 reaches z = 1 first
    else:
        term = SphereBarrier(np.arange(1), [0, 0, 0], 1.0, kappa=1.0, dhat=0.1)
        x = np.array([[-3.0, 0.0, 0.0]])
        dx = np.array([[6.0, 0.0, 0.0]])  # would pass right through the sphere
        assert term.max_step(x, dx) == pytest.approx(2.0 / 6.0)
        assert term.max_step(x, -dx) == math.inf


def seabed_chain(n: int, EA: float, dhat: float = 1e-2):
    L, X, h, w = 30.0, 24.0, 8.0, 10.0
    net = cn.cable([0, 0, 0], [X, 0, h], n, cn.Material(EA=EA, line_density=w / 9.81), length=L)
    loads = cn.Loads(gravity=np.array([0.0, 0.0, -9.81]))
    free = np.flatnonzero(~net.fixed)
    kappa = default_stiffness(w * L / n, dhat)
    bed = PlaneBarrier(free, [0, 0, 0], [0, 0, 1], kappa=kappa, dhat=dhat)
    a = brentq(
        lambda a: L - math.sqrt(h * h + 2 * a * h) + a * math.acosh(1 + h / a) - X, 1e-3, 1e4
    )
    return Scene(net, loads, (bed,)), bed, a * w, L - math.sqrt(h * h + 2 * a * h), L / (n - 1)


@pytest.mark.parametrize("method", ["static", "dynamic"])
def test_a_chain_on_the_seabed_touches_down_where_the_closed_form_says(method):
    problem, bed, H, touchdown, edge = seabed_chain(151, EA=1e6)
    gaps = []
    settings = Settings(method, dt=0.05, damping=2.0, t_end=200.0, rtol=1e-9)
    r = solve(problem, settings, on_step=lambda s: gaps.append(float(bed.gap(s.x).min())))
    assert r.converged and (method == "static" or r.equilibrium)
    assert min(gaps) > 0.0 and bed.gap(r.x).min() > 0.0
    assert -r.reaction[0, 0] == pytest.approx(H, rel=1e-2)  # the anchor holds H
    grounded = np.flatnonzero(bed.gap(r.x) < bed.dhat)
    assert abs(r.x[grounded.max(), 0] - touchdown) < 1.5 * edge
    # Balance: support reactions + weight + contact forces = 0.
    contact = np.zeros_like(r.x)
    bed.gradient(r.x, contact)
    weight = problem.loads.external_force(problem.net)
    total = r.reaction.sum(axis=0) + weight.sum(axis=0) - contact.sum(axis=0)
    assert np.abs(total).max() < 1e-6 * np.abs(weight).sum()


@pytest.mark.parametrize("dt", [1e-1, 1e-2, 1e-3])
def test_no_node_ever_enters_a_sphere_that_catches_a_falling_net(dt):
    """The paper's net (n = 10) falls under its weight and a pressure onto a sphere below
    its centre; at every accepted step of every step size each node stays outside."""
    mat = cn.Material.from_E(10e6, radius=0.01, density=1000.0)
    sq = cn.square_net(10, 0.3, 1.0, 0.05, mat)
    net = sq.net
    loads = cn.Loads(force=cn.pressure_force(net, 300.0, 1.0), gravity=np.array([0, 0, -9.81]))
    free = np.flatnonzero(~net.fixed)
    ball = SphereBarrier(free, [0.0, 0.0, -0.23], 0.2, kappa=2e3, dhat=0.01)
    gaps = []
    settings = Settings("dynamic", dt=dt, damping=5.0, t_end=0.3)
    r = solve(
        Scene(net, loads, (ball,)),
        settings,
        on_step=lambda s: gaps.append(float(ball.gap(s.x).min())),
    )
    assert r.converged
    assert min(gaps) > 0.0
    assert ball.gap(r.x).min() < ball.dhat  # it did touch


# --------------------------------------------------------------------------- cases


def ball_case(**changes) -> dict:
    case = {
        "title": "a net catching a ball",
        "geometry": {"kind": "square_net", "n": 10, "alpha": 0.3, "size": 1.0, "edge_length": 0.05},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"pressure": 300.0, "gravity": [0, 0, -9.81]},
        "obstacle": [
            {"kind": "sphere", "center": [0, 0, -0.23], "radius": 0.2, "distance": 0.01},
            {"kind": "plane", "point": [0, 0, -0.6]},
        ],
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 5.0, "t_end": 0.3},
    }
    case.update(changes)
    return case


def test_a_case_names_its_obstacles_and_the_scene_carries_their_terms():
    from catenet.case import build, parse_case

    case = parse_case(ball_case())
    scene = build(case)
    kinds = [type(t).__name__ for t in scene.terms]
    assert kinds == ["SphereBarrier", "PlaneBarrier"]
    ball, ground = scene.terms
    # The ground's default barrier: 1e-4 of the median edge, reached in static solves
    # through wider ones from 1e-3 of L = 1 m, ten times narrower each.
    edge = float(np.median(scene.net.rest_length))
    assert ball.dhat == 0.01 and ground.dhat == pytest.approx(1e-4 * edge)
    assert [s.dhat for s in ground.stages][0] == pytest.approx(1e-3)
    assert all(
        a.dhat == pytest.approx(10 * b.dhat)
        for a, b in zip(ground.stages[:-1], ground.stages[1:], strict=True)
    )
    assert parse_case(tomllib.loads(case.to_toml())) == case  # the resolved case reads back
    r = solve(scene, Settings.of(case.solver))
    assert ball.gap(r.x).min() > 0.0 and ground.gap(r.x).min() > 0.0
    assert parse_case(ball_case(obstacle=[])).obstacles == ()


@pytest.mark.parametrize(
    "obstacle, message",
    [
        (
            {"kind": "sphere", "center": [0, 0, -0.1], "radius": 0.2},
            "obstacle[0] (kind 'sphere'): node",
        ),
        (
            {"kind": "sphere", "center": [0, 0, -1], "radius": -0.2},
            "obstacle[0].radius = -0.2: must be finite and > 0",
        ),
        ({"kind": "sphere", "radius": 0.2}, "obstacle[0].center: missing"),
        ({"kind": "cube"}, "obstacle[0].kind = 'cube': must be one of 'plane', 'sphere'"),
        ({"kind": "plane", "nromal": [0, 0, 1]}, "did you mean 'normal'?"),
        ({"kind": "plane", "normal": [0, 0, 0]}, "obstacle[0].normal = [0, 0, 0]"),
        ({"kind": "plane", "point": [0, 0, 0.1]}, "starts inside or on it"),
    ],
)
def test_bad_obstacles_exit_2_with_their_key_path(tmp_path, obstacle, message):
    from click.testing import CliRunner

    from catenet.case import dumps_toml
    from catenet.cli import main

    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(ball_case(obstacle=[obstacle])))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert not (tmp_path / "out.h5").exists()


CONTACT_CONFIGS = sorted(
    p
    for p in (Path(__file__).parents[2] / "configs" / "contact").glob("*.toml")
    # free flights, not equilibria: tests/terms/test_shapes.py, tests/terms/test_capture.py,
    # tests/solver/test_self_contact_runs.py
    if p.stem not in ("tether_capture", "envisat_capture", "folded_net")
)


#: The examples shortened as their first lines say (a static one runs as it is): the
#: dynamic ones past their first contact.
SHORT = {"ball_off_box": 0.8, "sphere_catch": 0.5}


@pytest.mark.parametrize("path", CONTACT_CONFIGS, ids=lambda p: p.stem)
def test_contact_examples_run_short_and_keep_every_node_outside(path, tmp_path):
    """Each contact example, the dynamic ones shortened past their first contact: in every
    frame written no node is inside an obstacle, and at the end one touches (within the
    activation distance). The balance at rest: the full-length runs below (slow)."""
    import h5py

    from catenet.case import build, load_case
    from catenet.run.runner import run_case

    assert path.read_text().startswith("# "), "an example says in its first lines what it shows"
    short = [f"solver.t_end={SHORT[path.stem]}"] if path.stem in SHORT else []
    case = load_case(path, short)
    assert short or case.solver.method == "static", "a dynamic example needs a short version"
    out = tmp_path / "out.h5"
    r = run_case(case, out)
    assert r.converged
    scene = build(case)
    assert scene.terms
    with h5py.File(out, "r") as h5:
        frames = h5["trajectory/x"][()] if "trajectory" in h5 else r.x[None]
    for term in scene.terms:
        assert min(term.gap(x).min() for x in frames) > 0.0
        assert term.gap(r.x).min() > 0.0
    assert min(term.gap(r.x).min() for term in scene.terms) < max(t.dhat for t in scene.terms)


@pytest.mark.slow
@pytest.mark.parametrize("path", CONTACT_CONFIGS, ids=lambda p: p.stem)
def test_contact_examples_run_and_keep_every_node_outside(path, tmp_path):
    """Each contact example at full length, to rest: every node outside, one touching,
    and the reactions, the loads and the contact forces in balance."""
    from catenet.case import build, load_case
    from catenet.run.runner import run_case

    case = load_case(path)
    assert path.read_text().startswith("# "), "an example says in its first lines what it shows"
    r = run_case(case, tmp_path / "out.h5")
    assert r.converged
    scene = build(case)
    assert scene.terms
    for term in scene.terms:
        assert term.gap(r.x).min() > 0.0
    assert min(term.gap(r.x).min() for term in scene.terms) < max(t.dhat for t in scene.terms)
    contact = np.zeros_like(r.x)
    for term in scene.terms:
        term.gradient(r.x, contact)
    load = scene.loads.external_force(scene.net)
    total = r.reaction.sum(axis=0) + load.sum(axis=0) - contact.sum(axis=0)
    assert np.abs(total).max() < 1e-6 * np.abs(load).sum()
