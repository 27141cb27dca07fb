"""Newton's safeguarded mode (catenet/solver/newton.py, ``Potential.safeguard``): once a line
search cuts a time step's Newton step short, the rest of that solve holds near-slack
edges as if taut in Newton's model (``Stretch.hold``: released where the model's step
leaves them slack) and projects a free body's contact blocks to positive semidefinite
(``BodyContact.safeguard``). Phi, its gradient and the convergence test are the exact ones:
only the path to the same state changes.

The scene: a light 21 x 21 net of stiff cords (1 m mesh, Dyneema: EA = 1.26 MN on nodes
of 0.01 to 0.06 kg) thrown at 2 m/s, its corners diverging, 5 cm above a free 8 t box,
at fixed 10 ms bdf2 steps: the slack-taut switching of hundreds of edges per Newton
step. Without the safeguards it took 218 Newton iterations and 16 steps (10 planned,
some cut) to 0.1 s; a 41 x 41 net 670 iterations in 39 steps (benchmarks/peers/big_net.py)."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.kernels.rigid import _project_contact, frame_contact_hessian
from catenet.kernels.stretch import stretch_held, stretch_release
from catenet.solver import newton
from catenet.solver.path import solve
from catenet.solver.potential import Potential
from catenet.solver.settings import Settings


def thrown(side: int = 21, dt: float | None = 0.01, t_end: float = 0.1):
    """The scene of benchmarks/peers/big_net.py (a 20 m net, side x side nodes)."""
    step = 20.0 / (side - 1)
    nodes = [[-10.0 + i * step, -10.0 + j * step, 2.05] for j in range(side) for i in range(side)]
    edges = [[j * side + i, j * side + i + 1] for j in range(side) for i in range(side - 1)]
    edges += [[j * side + i, (j + 1) * side + i] for j in range(side - 1) for i in range(side)]
    corners = [0, side - 1, side * (side - 1), side * side - 1]
    every = (side - 1) // 10
    knots = [
        j * side + i
        for j in range(0, side, every)
        for i in range(0, side, every)
        if j * side + i not in corners
    ]
    cords = sorted(set(range(side * side)) - set(knots) - set(corners))
    sets = {"cords": cords, "knots": knots}
    masses = [
        {"node": "cords", "velocity": [0.0, 0.0, -2.0]},
        {"node": "knots", "mass": 0.05, "velocity": [0.0, 0.0, -2.0]},
    ]
    for node, (sx, sy) in zip(corners, ((-1, -1), (1, -1), (-1, 1), (1, 1)), strict=True):
        masses.append({"node": node, "mass": 10.0, "velocity": [0.3 * sx, 0.3 * sy, -2.0]})
    solver = {"method": "dynamic", "t_end": t_end, "damping": 0.0}
    if dt is not None:
        solver |= {"dt": dt, "integrator": "bdf2"}
    raw = {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges, "sets": sets},
        "material": {"E": 100e9, "radius": 0.002, "density": 970.0},
        "mass": masses,
        "obstacle": [
            {
                "kind": "box",
                "center": [0.0, 0.0, 0.0],
                "half_size": [5.0, 2.0, 2.0],
                "mass": 8000.0,
                "angular_velocity": [0.0, 0.035, 0.05],
                "distance": 0.02,
            }
        ],  # fmt: skip
        "solver": solver,
    }
    return build(parse_case(raw))


def run(scene):
    result = solve(scene, Settings.of(scene.case.solver))
    (body,) = scene.rigid
    return result, body.mass * result.v[body.frame.nodes].mean(axis=0)


def test_a_light_stiff_net_meeting_a_box_at_10_ms_steps_takes_no_cut_and_few_iterations():
    """Safeguarded: every one of the 10 steps of 10 ms converges (91 Newton iterations on the
    machine that measured it; without the safeguards 218 in 16 steps, its steps cut)."""
    result, momentum = run(thrown())
    assert result.converged and result.steps == 10
    assert result.iterations <= 130
    assert momentum[2] < -1.0  # the net has reached the box and pushes it


def test_unguarded_the_same_scene_needed_cuts(monkeypatch):
    """The measure of the test above: without the guards the same run cuts steps (each
    step's Newton held to 25 iterations, as it was when this was measured: a run to a
    time now lets a step still converging there go on, which takes the unguarded steps
    too, in more iterations)."""
    monkeypatch.setattr(newton, "SAFEGUARD_ALPHA", 0.0)  # never safeguarded
    scene = thrown()
    result = solve(scene, Settings.of(scene.case.solver, max_iter=25))
    assert result.converged and result.steps > 10 and result.iterations > 180


def test_the_guards_change_the_path_not_the_answer(monkeypatch):
    """At steps that converge either way (2.5 ms, through first contact; five of them
    went safeguarded), the safeguarded and unguarded runs reach the same state: the same box
    momentum to 1e-6 of it (2e-10 measured)."""
    turned_on = []
    guard = Potential.safeguard

    def counted(self, on):
        turned_on.append(on)
        guard(self, on)

    monkeypatch.setattr(Potential, "safeguard", counted)
    safeguarded, p_guarded = run(thrown(dt=2.5e-3, t_end=0.03))
    assert sum(turned_on) >= 3  # steps that went safeguarded
    monkeypatch.setattr(newton, "SAFEGUARD_ALPHA", 0.0)
    plain, p_plain = run(thrown(dt=2.5e-3, t_end=0.03))
    assert safeguarded.steps == plain.steps == 12
    assert np.linalg.norm(p_guarded) > 0.1
    assert np.linalg.norm(p_guarded - p_plain) <= 1e-6 * np.linalg.norm(p_plain)


def _edge(length: float, direction=(0.6, 0.8, 0.0)):
    x = np.zeros((2, 3))
    x[1] = length * np.asarray(direction)
    return x, np.array([[0, 1]]), np.array([1.0]), np.array([200.0])


def test_a_held_slack_edge_is_the_taut_branch_at_its_kink():
    """Held while slack, an edge enters the model as a spring pulling it to its rest
    length: gradient EA/l0 (l - l0) t (the finite difference of 1/2 EA/l0 (l - l0)^2),
    Hessian its axial block EA/l0 t t^T (the geometric part, negative below the rest
    length, left out: the model stays positive semidefinite); a taut edge is left to the
    exact law, an edge not held gets nothing."""
    x, edges, l0, ea = _edge(0.999)
    args = (edges, l0, ea, None, np.zeros((1, 2)), np.zeros((0, 3)))
    grad, values = np.zeros((2, 3)), np.zeros(36)
    assert stretch_held(x, *args, np.array([True]), values, grad) == 1

    def model(x):
        return 0.5 * ea[0] / l0[0] * (np.linalg.norm(x[1] - x[0]) - l0[0]) ** 2

    fd = np.zeros(6)
    for d in range(6):
        up, down = x.copy(), x.copy()
        up.reshape(-1)[d] += 1e-7
        down.reshape(-1)[d] -= 1e-7
        fd[d] = (model(up) - model(down)) / 2e-7
    assert np.allclose(grad.reshape(-1), fd, rtol=1e-6, atol=1e-9)
    t = np.array([0.6, 0.8, 0.0])
    block = values.reshape(6, 6)
    assert np.allclose(block[:3, :3], 200.0 * np.outer(t, t), rtol=1e-12)
    assert np.allclose(block[:3, 3:], -200.0 * np.outer(t, t), rtol=1e-12)
    assert np.linalg.eigvalsh(block).min() >= -1e-9
    for length, held in ((1.001, True), (0.999, False)):
        x, *_ = _edge(length)
        grad, values = np.zeros((2, 3)), np.full(36, 7.0)
        assert stretch_held(x, *args, np.array([held]), values, grad) == 0
        assert not grad.any() and (values == 7.0).all()


def test_a_held_edge_the_models_step_leaves_slack_is_released():
    """Released where the model's step leaves it below its rest length (its spring would
    push), kept where it ends taut; each release counted (``Stretch.hold`` holds it again
    at the next factorisation but one, and never after RELEASES of them)."""
    x, edges, l0, _ = _edge(0.999)
    t = np.array([0.6, 0.8, 0.0])
    for move, released in ((+2e-3, False), (+1e-4, True), (-1e-4, True)):
        held, times, recent = np.array([True]), np.array([1]), np.array([False])
        dx = np.zeros((2, 3))
        dx[1] = move * t
        assert stretch_release(x, dx, edges, l0, held, times, recent) == int(released)
        assert recent[0] == released and held[0] != released
        assert times[0] == 1 + int(released)


def _contact_block(A, u, H, g):
    """One contact's K_q = L^T H L + S (catenet/kernels/rigid.py's docstring)."""
    L = np.zeros((3, 15))
    L[:, :3], L[:, 3:6] = A.T, -A.T
    for m in range(3):
        L[m, 6 + 3 * m : 9 + 3 * m] = u
    k = L.T @ H @ L
    for m in range(3):
        for i in range(3):
            a = 6 + 3 * m + i
            k[a, i] += g[m]
            k[i, a] += g[m]
            k[a, 3 + i] -= g[m]
            k[3 + i, a] -= g[m]
    return k


def test_projected_contact_blocks_are_semidefinite_and_exact_where_they_were():
    """Contact blocks of random frames, points, barrier Hessians and gradients (and the
    degenerate ones: the point at the centre, no gradient, the gradient along the
    point): their positive part, exactly as the 15 x 15 eigendecomposition gives it;
    a semidefinite block unchanged."""
    rng = np.random.default_rng(7)
    Q, M, W = np.empty((9, 15)), np.empty((9, 9)), np.empty((15, 9))
    for trial in range(60):
        A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        u = rng.normal(size=3) * [1.0, 0.0, rng.uniform()][trial % 3]
        h = rng.normal(size=(3, 3))
        H = (h + h.T) * 10.0 ** rng.uniform(-3, 3)
        g = rng.normal(size=3) * 10.0 ** rng.uniform(-3, 3) * (trial % 5 != 0)
        if trial % 7 == 0:
            g = 2.0 * u
        k = _contact_block(A, u, H, g)
        kept = k.copy()
        _project_contact(k, u, g, Q, M, W)
        w = np.linalg.eigvalsh(kept)
        scale = abs(w).max() or 1.0
        assert np.linalg.eigvalsh(k).min() >= -1e-12 * scale
        assert np.allclose(k, k.T)
        v, q = np.linalg.eigh(kept)  # the positive part, exactly
        assert np.allclose(k, (q * np.maximum(v, 0.0)) @ q.T, atol=1e-12 * scale)
        s = _contact_block(A, u, H @ H.T, np.zeros(3))  # semidefinite already: unchanged
        p = s.copy()
        _project_contact(p, u, np.zeros(3), Q, M, W)
        assert np.array_equal(p, s) or np.allclose(p, s, rtol=1e-12)


@pytest.mark.parametrize("project", [False, True])
def test_the_frame_contact_hessian_projects_only_when_asked(project):
    rng = np.random.default_rng(1)
    A = np.eye(3) + 0.1 * rng.normal(size=(3, 3))
    U = rng.normal(size=(2, 3))
    H = np.stack([np.diag([5.0, 0.1, -0.2]), np.diag([1.0, 2.0, 3.0])])
    g = rng.normal(size=(2, 3))
    chain = np.eye(12)
    blocks, body = np.zeros((2, 81)), np.zeros(144)
    frame_contact_hessian(A, U, H, g, chain, np.array([0, 1]), blocks, body, project)
    full = np.zeros((15 + 3, 15 + 3))  # nodes 0, 1 and the body's 12 DOFs
    for k in range(2):
        r = slice(3 * k, 3 * k + 3)
        full[r, r] += blocks[k, :9].reshape(3, 3)
        full[r, 6:] += blocks[k, 9:45].reshape(3, 12)
        full[6:, r] += blocks[k, 45:].reshape(12, 3)
    full[6:, 6:] += body.reshape(12, 12)
    low = np.linalg.eigvalsh(full).min()
    if project:
        assert low >= -1e-9 * np.abs(full).max()
    else:
        assert low < 0.0  # the exact blocks are indefinite here


def test_the_stretchings_held_set_follows_its_releases():
    """``Stretch.hold``: the tension-only edges slack by less than HOLD_REACH, not the
    last step's releases nor edges released RELEASES times; off, nothing is held."""
    from catenet.model.builders import Material, cable
    from catenet.terms.stretch import HOLD_REACH, RELEASES, Stretch

    net = cable([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], 5, Material(EA=1e6))  # 4 edges of 1 m
    term = Stretch(net)
    x = net.nodes.copy()
    x[1:, 0] *= 1.0 - 0.5 * HOLD_REACH  # every edge slack by half the reach
    x[4, 0] = x[3, 0] + 1.0 - 2.0 * HOLD_REACH  # the last one by twice it
    term.hold(x)
    assert not term.held.any()  # not safeguarded
    term.safeguard(True)
    term.hold(x)
    assert term.held.tolist() == [True, True, True, False]
    shorten = np.zeros_like(x)
    shorten[1:, 0] = [-1e-3, 2e-3, 4e-3, 6e-3]  # edge 0 shortened, the others taut
    for _ in range(RELEASES):
        term.hold(x)
        assert term.held[0]
        assert term.release(x, shorten) == 1 and not term.held[0]
        term.hold(x)
        assert not term.held[0]  # the release's next factorisation
    term.hold(x)
    assert not term.held[0] and term.held[1]  # released for good
    term.safeguard(False)
    term.safeguard(True)
    term.hold(x)
    assert term.held[0]  # a new solve forgets
