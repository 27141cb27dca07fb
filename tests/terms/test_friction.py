"""Coulomb friction on obstacles (catenet.terms.friction): finite differences, the force
bound and sticking without creep, a block on a plane against its closed forms (static and
dynamic), and the key check of a mooring line on the seabed pulled sideways: with friction
its grounded part stays where it lies, without it the grounded part swings round.

Block closed forms: a node pressed on a plane by N and held by a horizontal spring of
stiffness k whose far end moves by D sticks (moves less than the slip distance) while
k D < mu N and otherwise slides until the spring force is mu N: u = D - mu N / k. Pushed
by a constant F > mu N from rest, a node of mass m slides with a = (F - mu N) / m; implicit
Euler with step h gives x_n = a t_n (t_n + h) / 2 exactly.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from contact_cases import block

import catenet as cn
from catenet.model.net import Loads, Net
from catenet.scene import Scene
from catenet.solver.path import Settings, Start, solve
from catenet.terms import check_derivatives
from catenet.terms.contact import PlaneBarrier, SphereBarrier, default_stiffness
from catenet.terms.friction import Friction

# --------------------------------------------------------------------------- the term


def rough(kind: str, rng, mu=0.4, slip=0.02):
    """A plane or sphere with friction on 8 nodes at gaps 0.1..1.4 dhat (dhat = 0.05),
    its step begun there."""
    dhat = 0.05
    if kind == "plane":
        normal = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
        x = rng.uniform(-1, 1, (8, 3))
        x -= np.outer(x @ normal, normal)
        x += np.outer(rng.uniform(0.005, 0.07, 8), normal)
        obstacle = PlaneBarrier(np.arange(8), [0, 0, 0], normal, kappa=30.0, dhat=dhat)
    else:
        c, R = np.array([0.1, 0.2, -0.3]), 0.5
        u = rng.standard_normal((8, 3))
        u /= np.linalg.norm(u, axis=1)[:, None]
        x = c + u * (R + rng.uniform(0.005, 0.07, 8))[:, None]
        obstacle = SphereBarrier(np.arange(8), c, R, kappa=30.0, dhat=dhat)
    term = Friction(obstacle, mu=mu, slip=slip)
    term.begin_step(x, None)
    return term, x


@pytest.mark.parametrize("kind", ["plane", "sphere"])
def test_friction_passes_finite_differences_sticking_and_sliding(kind):
    rng = np.random.default_rng(7)
    term, x = rough(kind, rng)
    active = term.weight > 0
    assert 0 < active.sum() < len(active)  # some nodes in contact, some not
    # Displacements within and beyond the slip distance (0.02), and none at all.
    for size in (0.004, 0.05):
        y = x + rng.uniform(-size, size, x.shape)
        y[0] = x[0]  # u = 0 exactly: the Hessian is 2 mu lambda / eps P there
        grad_err, hess_err = check_derivatives(term, y, step=1e-7)
        assert grad_err < 1e-6 and hess_err < 1e-5, (size, grad_err, hess_err)


@pytest.mark.parametrize("kind", ["plane", "sphere"])
def test_friction_force_is_bounded_tangential_and_the_hessian_positive(kind):
    rng = np.random.default_rng(3)
    term, x = rough(kind, rng)
    for size in (1e-3, 1e-2, 0.1, 1.0):
        y = x + rng.uniform(-size, size, x.shape)
        force = term.forces(y)
        bound = term.mu * term.normal_force
        mag = np.linalg.norm(force, axis=1)
        assert np.all(mag <= bound * (1 + 1e-12))
        assert np.allclose(np.sum(force * term.normal, axis=1), 0.0, atol=1e-12)  # tangential
        r = y - term.anchor
        u = r - np.sum(r * term.normal, axis=1)[:, None] * term.normal
        assert np.all(np.sum(force * u, axis=1) <= 1e-15)  # against the slip
        sliding = np.linalg.norm(u, axis=1) > term.slip
        assert np.allclose(mag[sliding], bound[sliding], rtol=1e-12)  # full kinetic force
        values = np.zeros(9 * len(term.nodes))
        term.hessian(y, values)
        eig = np.linalg.eigvalsh(values.reshape(-1, 3, 3))
        assert eig.min() >= -1e-12 * max(eig.max(), 1.0)


def test_a_sticking_node_does_not_creep_and_a_sliding_one_drags_its_anchor():
    plane = PlaneBarrier(np.arange(1), [0, 0, 0], [0, 0, 1], kappa=10.0, dhat=0.1)
    term = Friction(plane, mu=0.5, slip=0.01)
    x = np.array([[0.0, 0.0, 0.05]])
    term.begin_step(x, None)
    anchor = term.anchor.copy()
    assert np.allclose(anchor, x) and term.weight[0] > 0
    for _ in range(50):  # 50 steps, each ending 0.6 slip from the anchor: it stays
        term.begin_step(x + [[0.006, 0.0, 0.0]], None)
    assert np.allclose(term.anchor, anchor) and term.dragged == 0
    term.begin_step(x + [[0.5, 0.0, 0.0]], None)  # slid: the anchor trails by the slip
    assert term.dragged == 1
    assert np.allclose(term.anchor, [[0.49, 0.0, 0.05]])
    term.begin_step(x + [[0.0, 0.0, 1.0]], None)  # lifted off: no friction, re-anchored
    assert term.weight[0] == 0.0 and np.allclose(term.anchor, x + [[0.0, 0.0, 1.0]])
    assert term.energy(x + [[3.0, 0.0, 1.0]]) == 0.0


def test_bad_friction_arguments_raise():
    plane = PlaneBarrier(np.arange(1), [0, 0, 0], [0, 0, 1], kappa=10.0, dhat=0.1)
    with pytest.raises(ValueError, match="mu = -0.1"):
        Friction(plane, mu=-0.1, slip=0.01)
    with pytest.raises(ValueError, match="slip = nan"):
        Friction(plane, mu=0.1, slip=math.nan)


# --------------------------------------------------------------------------- a block


@pytest.mark.parametrize("steps", [1, 4])
@pytest.mark.parametrize("pull", [0.01, 0.045, 0.06, 0.1])
def test_a_block_held_by_a_spring_sticks_below_mu_n_and_slides_to_it_beyond(pull, steps):
    """In 4 load steps N and the pull grow together: each step's friction sees its own
    normal force (a static step is re-solved until the lagged normal forces agree)."""
    mu, N, k, slip = 0.5, 10.0, 100.0, 1e-3
    problem = block(mu=mu, slip=slip, force=[0, 0, -N], spring=k, pull=pull)
    r = solve(problem, Settings("static", rtol=1e-10, steps=steps))
    assert r.converged
    u = -r.x[1, 0]
    if k * pull < mu * N:
        assert 0 < u < slip  # sticks: the spring's force is below mu N
    else:
        assert u == pytest.approx(pull - mu * N / k, abs=1e-9)  # slides to k (D - u) = mu N
    assert abs(r.x[1, 1]) < 1e-12


@pytest.mark.parametrize("ratio", [0.8, 1.5])
def test_a_pushed_block_stays_below_mu_n_and_slides_as_coulomb_says_beyond(ratio):
    m, g, mu, slip, h = 2.0, 9.81, 0.5, 1e-4, 0.01
    F = ratio * mu * m * g
    problem = block(mu=mu, slip=slip, force=[F, 0, -m * g], mass=m)
    seen = []
    settings = Settings("dynamic", dt=h, damping=0.0, t_end=1.0)
    r = solve(problem, settings, on_step=lambda s: seen.append((s.time, s.x[1, 0])))
    assert r.converged
    if ratio < 1:
        assert max(abs(x) for _, x in seen) < slip  # at rest within the slip distance
        assert r.equilibrium  # and the run knows it came to rest
    else:
        a = (F - mu * m * g) / m
        for t, x in seen:
            assert x == pytest.approx(a * t * (t + h) / 2, rel=1e-6, abs=slip)


@pytest.mark.parametrize("mu", [0.7, 0.4])
def test_a_node_on_a_sphere_sticks_where_tan_theta_is_below_mu_and_slides_off_beyond(mu):
    """A node of mass m rests on a sphere at 30 degrees from its top: weight m g splits
    into m g cos 30 normal and m g sin 30 along the surface, so it sticks iff
    tan 30 = 0.577 <= mu. Static (mu = 0.7): it stays within the slip distance; dynamic
    (mu = 0.4): it slides off with the tangential acceleration g (sin - mu cos) of its
    angle."""
    m, g, R, dhat, slip = 1.0, 9.81, 1.0, 1e-3, 1e-6
    theta = math.radians(30.0)
    start = (R + dhat / 2) * np.array([math.sin(theta), 0.0, math.cos(theta)])
    net = Net.from_arrays(
        [[-3.0, 0.0, 0.0], start], [[0, 1]], EA=1.0, fixed=[0], rest_length=20.0, point_mass=[0, m]
    )
    ball = SphereBarrier(
        np.array([1]),
        [0, 0, 0],
        R,
        kappa=default_stiffness(m * g * math.cos(theta), dhat),
        dhat=dhat,
    )
    problem = Scene(
        net, Loads(gravity=np.array([0.0, 0.0, -g])), (ball, Friction(ball, mu=mu, slip=slip))
    )
    if mu > math.tan(theta):
        r = solve(problem, Settings("static", rtol=1e-10))
        assert r.converged and ball.gap(r.x).min() > 0
        moved = r.x[1] - start
        radial = start / np.linalg.norm(start)
        assert np.linalg.norm(moved - (moved @ radial) * radial) < slip
    else:
        seen = []
        settings = Settings("dynamic", dt=1e-3, damping=0.0, t_end=0.2)
        r = solve(problem, settings, on_step=lambda s: seen.append(s.x[1].copy()))
        assert r.converged and ball.gap(r.x).min() > 0
        arc = R * (math.atan2(r.x[1, 0], r.x[1, 2]) - theta)  # the slide along the surface
        # Along the arc s: s'' = g (sin - mu cos)(theta + s / R), linearised about theta:
        # s'' = a + k s, s = (a / k)(cosh(sqrt(k) t) - 1); implicit Euler adds O(h / t).
        a = g * (math.sin(theta) - mu * math.cos(theta))
        k = g * (math.cos(theta) + mu * math.sin(theta)) / R
        assert arc == pytest.approx(a / k * (math.cosh(math.sqrt(k) * 0.2) - 1), rel=1e-2)


# --------------------------------------------------------------------------- the seabed


def mooring(n=61):
    """A chain (30 m, 10 N/m) from an anchor at the origin on the seabed z = 0 to a
    fairlead at (24, 0, 8), lying on the bed (static, frictionless), and its bed."""
    L, X, h, w, dhat = 30.0, 24.0, 8.0, 10.0, 1e-2
    net = cn.cable([0, 0, 0], [X, 0, h], n, cn.Material(EA=1e6, line_density=w / 9.81), length=L)
    free = np.flatnonzero(~net.fixed)
    bed = PlaneBarrier(
        free, [0, 0, 0], [0, 0, 1], kappa=default_stiffness(w * L / n, dhat), dhat=dhat
    )
    gravity = np.array([0.0, 0.0, -9.81])
    laid = solve(Scene(net, Loads(gravity=gravity), (bed,)), Settings("static", rtol=1e-9))
    assert laid.converged
    return net, bed, gravity, laid.x


def test_a_mooring_line_on_the_seabed_keeps_its_grounded_part_under_a_sideways_pull():
    """The fairlead moves 3 m sideways (static). Frictionless, the grounded part swings
    round the anchor into the new vertical plane (its far end by metres); with mu = 1 it
    stays within the slip distance, except the four edges next to the touchdown point
    (where it lifts and its normal force fades), and the touchdown point moves sideways
    by a tenth of the frictionless 2.5 m."""
    net, bed, gravity, laid = mooring()
    free = np.flatnonzero(~net.fixed)
    grounded = free[bed.gap(laid) < bed.dhat]
    touchdown = laid[grounded.max(), 0]
    assert 15.0 < touchdown < 25.0
    move = np.zeros_like(laid)
    move[-1, 1] = 3.0
    loads = Loads(gravity=gravity, support_displacement=move)
    out = {}
    for mu in (0.0, 1.0):
        terms = (bed, Friction(bed, mu=mu, slip=bed.dhat)) if mu else (bed,)
        r = solve(Scene(net, loads, terms), Settings("static", rtol=1e-9), start=Start(x=laid))
        assert r.converged and bed.gap(r.x).min() > 0
        out[mu] = r.x
    slid = {mu: np.linalg.norm((x - laid)[:, :2], axis=1) for mu, x in out.items()}
    far = grounded[laid[grounded, 0] < touchdown - 2.0]  # four edges behind touchdown
    assert slid[0.0][far].max() > 100 * bed.dhat  # frictionless: dragged round by metres
    assert slid[1.0][far].max() < bed.dhat  # with friction: stuck where it lay
    shift = {mu: abs(x[free[bed.gap(x) < bed.dhat].max(), 1]) for mu, x in out.items()}
    assert shift[0.0] > 2.0 and shift[1.0] < 0.15 * shift[0.0]  # the touchdown point
    # In 4 load steps (weight and pull growing together) the line ends where one step
    # puts it, to well within the slip distance.
    rough = (bed, Friction(bed, mu=1.0, slip=bed.dhat))
    r = solve(Scene(net, loads, rough), Settings("static", rtol=1e-9, steps=4), start=Start(x=laid))
    assert r.converged and np.abs(r.x - out[1.0]).max() < 0.1 * bed.dhat


# --------------------------------------------------------------------------- cases

MOORING = Path(__file__).parents[2] / "configs" / "friction" / "mooring_pulled.toml"


def pulled_run(tmp_path, *overrides):
    """The mooring example as `catenet run` runs it (with --set overrides): its result,
    its scene and the trajectory (times, positions)."""
    import h5py

    from catenet.case import build, load_case
    from catenet.run.runner import run_case

    case = load_case(MOORING, list(overrides))
    out = tmp_path / "mooring.h5"
    r = run_case(case, out)
    with h5py.File(out, "r") as h5:
        times, xs = h5["trajectory/time"][()], h5["trajectory/x"][()]
    return r, build(case), times, xs


def grounded_far(bed, settled, final):
    """The nodes on the bed when settled and at the end, more than 3 m before the
    settled touchdown point."""
    on_bed = bed.nodes[(bed.gap(settled) < bed.dhat) & (bed.gap(final) < bed.dhat)]
    touchdown = settled[on_bed, 0].max()
    return on_bed[settled[on_bed, 0] < touchdown - 3.0]


def test_the_mooring_example_short_keeps_its_grounded_part_while_pulled(tmp_path):
    """configs/friction/mooring_pulled.toml to t = 9 s: the line settles on the rough bed
    (t < 5 s) and the fairlead is 1.2 m into its 3 m sideways move: no node is ever below
    the bed, every node lying on it more than 3 m before the touchdown point stays within
    the slip distance, and `catenet plot` draws it. Frictionless
    (--set obstacle.0.friction=0) the same part has swung by more than ten slip distances.
    The full run (to rest, 3 m of pull): the slow test below."""
    from click.testing import CliRunner

    from catenet.cli import main

    assert MOORING.read_text().startswith("# "), "an example says in its first lines what it shows"
    r, scene, times, xs = pulled_run(tmp_path, "solver.t_end=9")
    assert r.converged and times[-1] == pytest.approx(9.0)
    bed, friction = scene.terms
    assert friction.mu == 1.0 and friction.slip == 0.01
    assert min(bed.gap(x).min() for x in xs) > 0.0
    settled = xs[np.searchsorted(times, 5.0)]
    far = grounded_far(bed, settled, r.x)
    assert far.size >= 15  # 7.5 m of line and more
    slid = np.linalg.norm((r.x - settled)[far, :2], axis=1)
    assert slid.max() < friction.slip
    assert abs(r.x[9, 1] - 3.0 * (9.0 - 5.0) / 10.0) < 1e-12  # the fairlead is moving
    res = CliRunner().invoke(main, ["plot", str(tmp_path / "mooring.h5")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "mooring.png").stat().st_size > 10_000

    r0, _, times0, xs0 = pulled_run(tmp_path, "obstacle.0.friction=0", "solver.t_end=9")
    settled0 = xs0[np.searchsorted(times0, 5.0)]
    assert np.linalg.norm((r0.x - settled0)[far, :2], axis=1).max() > 10 * friction.slip


@pytest.mark.slow
def test_the_mooring_example_keeps_its_grounded_part_while_pulled_sideways(tmp_path):
    """configs/friction/mooring_pulled.toml: the line laid on the rough seabed
    settles (t < 5 s), the fairlead moves 3 m sideways (5 s to 15 s): every node lying
    on the bed more than 3 m before the touchdown point stays within the slip distance,
    no node is ever below the bed, and the run comes to rest; `catenet plot` draws it.
    Frictionless (--set obstacle.0.friction=0) the grounded line swings round by metres."""
    from click.testing import CliRunner

    from catenet.cli import main

    assert MOORING.read_text().startswith("# "), "an example says in its first lines what it shows"
    r, scene, times, xs = pulled_run(tmp_path)
    assert r.converged and r.equilibrium
    bed, friction = scene.terms
    assert friction.mu == 1.0 and friction.slip == 0.01
    assert min(bed.gap(x).min() for x in xs) > 0.0
    settled = xs[np.searchsorted(times, 5.0)]
    free = bed.nodes
    on_bed = free[(bed.gap(settled) < bed.dhat) & (bed.gap(r.x) < bed.dhat)]
    touchdown = settled[on_bed, 0].max()
    far = on_bed[settled[on_bed, 0] < touchdown - 3.0]
    assert far.size >= 15  # 7.5 m of line and more
    slid = np.linalg.norm((r.x - settled)[far, :2], axis=1)
    assert slid.max() < friction.slip
    assert abs(r.x[9, 1] - 3.0) < 1e-12  # the fairlead did move
    res = CliRunner().invoke(main, ["plot", str(tmp_path / "mooring.h5")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "mooring.png").stat().st_size > 10_000

    r0, _, times0, xs0 = pulled_run(tmp_path, "obstacle.0.friction=0", "solver.t_end=20")
    settled0 = xs0[np.searchsorted(times0, 5.0)]
    assert np.linalg.norm((r0.x - settled0)[far, :2], axis=1).max() > 1.0


def rough_case(**obstacle) -> dict:
    case = tomllib.loads(MOORING.read_text())
    case["obstacle"][0].update(obstacle)
    case["solver"]["t_end"] = 0.1
    return case


@pytest.mark.parametrize(
    "obstacle, message",
    [
        ({"friction": -0.5}, "obstacle[0].friction = -0.5: must be finite and >= 0"),
        ({"friction": math.nan}, "obstacle[0].friction = nan: must be finite and >= 0"),
        ({"slip": 0.0}, "obstacle[0].slip = 0.0: must be finite and > 0"),
        ({"frictoin": 0.5}, "did you mean 'friction'?"),
        (
            {"kind": "sphere", "center": [0, 0, -5], "radius": 1.0, "velocity": [0, 0, 1]},
            "obstacle[0].friction = 1.0: a moving sphere (mass or velocity) is frictionless",
        ),
    ],
)
def test_bad_friction_exits_2_with_its_key_path(tmp_path, obstacle, message):
    from click.testing import CliRunner

    from catenet.case import dumps_toml
    from catenet.cli import main

    case = rough_case(**obstacle)
    if obstacle.get("kind") == "sphere":
        for key in ("point", "normal", "slip", "distance"):
            case["obstacle"][0].pop(key)
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert not (tmp_path / "out.h5").exists()


def test_a_frictionless_obstacle_builds_no_friction_term_and_the_case_reads_back():
    from catenet.case import build, parse_case

    case = parse_case(rough_case())
    assert [type(t).__name__ for t in build(case).terms] == ["PlaneBarrier", "Friction"]
    assert parse_case(tomllib.loads(case.to_toml())) == case
    plain = parse_case(rough_case(friction=0.0))
    assert [type(t).__name__ for t in build(plain).terms] == ["PlaneBarrier"]
    unset = rough_case(distance=0.02)
    del unset["obstacle"][0]["slip"]
    assert build(parse_case(unset)).terms[1].slip == 0.02  # default: the activation distance
