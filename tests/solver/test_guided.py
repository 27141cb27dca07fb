"""Rollers and sliders (``Net.guides``) and elastic supports (``Net.springs``) in the
solvers: closed forms in orientations nobody tuned, reactions of every held component,
the equilibrium of reactions, contact forces and loads, natural modes that keep a
roller's free directions, and dynamic runs that keep the constraint exactly and the
energy balanced."""

from __future__ import annotations

import numpy as np
import pytest

import catenet
from catenet.model.guides import Elastic, Guides
from catenet.model.net import Loads, Net
from catenet.scene import Scene
from catenet.validate.analytic import discrete_catenary

G = 9.81


def _rotation(seed: int) -> np.ndarray:
    """A proper rotation of no special orientation."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _half_chain(kind: str, rot: np.ndarray, n: int = 12) -> tuple[Net, Loads, dict]:
    """The left half of a symmetric hanging chain of 2n edges: node 0 pinned, node n
    at mid-span on a roller whose normal is along the span (or a slider along the
    vertical), the whole turned by ``rot`` (gravity too). By symmetry the full chain's
    mid node has a horizontal tangent and carries half its lumped weight on each edge,
    so the half chain held across the span at the middle is the full chain's left half
    exactly (``discrete_catenary``), and the guide's reaction is H along the span."""
    L0, EA, rho_a, span = 14.0, 3.0e4, 1.7, 10.0
    nodes = np.column_stack([np.linspace(0.0, span / 2, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(
        nodes @ rot.T, edges, EA=EA, fixed=[0], rest_length=L0 / (2 * n), line_density=rho_a
    )
    if kind == "roller":
        net = net.with_guides(Guides.roller([n], rot @ [-2.5, 0.0, 0.0]))
    else:
        net = net.with_guides(Guides.slider([n], rot @ [0.0, 0.0, 0.7]))
    full = discrete_catenary(L0, EA, rho_a * G, span, 2 * n)
    return net, Loads(gravity=rot @ [0.0, 0.0, -G]), {"full": full, "n": n}


@pytest.mark.parametrize("kind", ["roller", "slider"])
def test_half_chain_on_a_guide_is_the_symmetric_chain(kind):
    rot = _rotation(3)
    net, loads, known = _half_chain(kind, rot)
    n, full = known["n"], known["full"]
    res = catenet.solve(Scene.of(net, loads))
    assert res.converged
    x = res.x @ rot  # back in the chain's own frame
    scale = full.x[-1]
    assert np.max(np.abs(x[:, 0] - full.x[: n + 1])) < 1e-9 * scale
    assert np.max(np.abs(-x[:, 2] - full.z[: n + 1])) < 1e-9 * scale
    assert np.max(np.abs(x[:, 1])) < 1e-12 * scale
    r = res.reaction @ rot
    # the guide holds the span's horizontal tension H and nothing else: no vertical part
    assert r[n] == pytest.approx([full.H, 0.0, 0.0], abs=1e-7 * full.H)  # rtol 1e-8 of the loads
    weight = net.mass.sum() * G
    assert r[0] == pytest.approx([-full.H, 0.0, weight], rel=1e-7, abs=1e-7 * weight)
    f = loads.external_force(net)
    assert np.abs((res.reaction + res.contact_force + f).sum(axis=0)).max() < 1e-8 * weight


def test_bead_on_an_inclined_slider():
    """A point mass m on a slider along d (inclined by theta), tied uphill along the same
    line by a bilateral edge of stiffness EA / l0 to a pinned node: the edge stretches by
    m g sin(theta) l0 / EA, it carries m g sin(theta), and the slider's reaction is the
    weight's part across the line, m g cos(theta), perpendicular to d."""
    theta, m, EA, l0 = 0.6, 3.0, 2.0e3, 1.5
    rot = _rotation(11)
    d = rot @ [np.cos(theta), 0.0, -np.sin(theta)]  # downhill
    up = rot @ [0.0, 0.0, 1.0]
    gravity = -G * up
    nodes = np.array([[0.0, 0.0, 0.0], l0 * d])
    net = Net.from_arrays(
        nodes, [[0, 1]], EA=EA, fixed=[0], line_density=0.0, tension_only=False, point_mass=[0, m]
    ).with_guides(Guides.slider([1], -3.0 * d))
    res = catenet.solve(Scene.of(net, Loads(gravity=gravity)))
    assert res.converged
    stretch = m * G * np.sin(theta) * l0 / EA
    assert res.x[1] == pytest.approx(nodes[1] + stretch * d, abs=1e-12)
    assert res.tension[0] == pytest.approx(m * G * np.sin(theta), rel=1e-10)
    across = m * G * np.cos(theta)
    assert abs(res.reaction[1] @ d) < 1e-10 * m * G
    assert np.linalg.norm(res.reaction[1]) == pytest.approx(across, rel=1e-10)
    assert res.reaction[1] @ up > 0  # pushes up off the line


def test_node_on_springs_deflects_by_load_over_k():
    """A node held only by springs (a 3x3 stiffness and a diagonal one at the same node)
    under a point force F: K u = F, the reaction -K u = -F."""
    nodes = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [4.0, 0.5, 0.0]])
    net = Net.from_arrays(nodes, [[0, 1], [1, 2]], EA=5e4, fixed=[0], tension_only=False)
    k3 = np.array([[4e3, 1e3, 0.0], [1e3, 3e3, -5e2], [0.0, -5e2, 2e3]])
    kd = np.array([1e3, 0.0, 2.5e3])
    net = net.with_springs(Elastic.of([2], k3), Elastic.of([2], kd))
    force = np.zeros((3, 3))
    force[1] = [0.0, 0.0, 0.0]
    force[2] = [40.0, -25.0, 60.0]
    res = catenet.solve(Scene.of(net, Loads(force=force)))
    assert res.converged
    # the node's own balance: springs and the edge, the edge's force from its tension
    u = res.x[2] - nodes[2]
    k = k3 + np.diag(kd)
    e = res.x[2] - res.x[1]
    edge = res.tension[1] * e / np.linalg.norm(e)
    assert k @ u == pytest.approx(force[2] - edge, rel=1e-9, abs=1e-9)
    assert res.reaction[2] == pytest.approx(-(k @ u), rel=1e-9)
    assert res.contact_force[2] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)
    assert np.abs((res.reaction + force + res.contact_force).sum(axis=0)).max() < 1e-8 * 80.0


def test_chain_on_springs_alone():
    """A straight bar held by springs only (no fixed node; the far end's spring holds it
    across the bar only): a force F along it at the far end moves the near end by
    F / k0 and the far end by F l0 / EA more; the bar carries F, the reactions sum to -F."""
    k0, k1, EA, l0, F = 2e3, 5e3, 1e4, 2.0, 30.0
    nodes = np.array([[0.0, 0.0, 0.0], [l0, 0.0, 0.0]])
    springs = Elastic.join([Elastic.of([0], [k0, k0, k0]), Elastic.of([1], [0.0, k1, k1])])
    net = Net.from_arrays(
        nodes, [[0, 1]], EA=EA, fixed=np.zeros(2, bool), tension_only=False, springs=springs
    )
    force = np.array([[0.0, 0.0, 0.0], [F, 0.0, 0.0]])
    res = catenet.solve(Scene.of(net, Loads(force=force)))
    assert res.converged
    assert res.x[0, 0] == pytest.approx(F / k0, rel=1e-9)
    assert res.x[1, 0] - l0 == pytest.approx(F / k0 + F * l0 / EA, rel=1e-9)
    assert res.tension[0] == pytest.approx(F, rel=1e-9)
    assert res.reaction.sum(axis=0) == pytest.approx([-F, 0.0, 0.0], rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("n", [16, 120])  # the dense eigensolver, then Lanczos
def test_modes_keep_a_rollers_free_directions(n):
    """A taut string pinned at node 0, its end on a roller held along the string: the
    transverse modes of a fixed-free chain of n masses m (the last m/2) and springs T/h,
    omega_k = 2 sqrt(T / (m h)) sin((2k - 1) pi / (4n)), twice each (two directions);
    the end moves across the string and never along it."""
    span, T, rho_a, EA = 8.0, 800.0, 0.4, 1e7
    rot = _rotation(5)
    nodes = np.column_stack([np.linspace(0.0, span, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    l0 = span / n / (1 + T / EA)
    net = Net.from_arrays(
        nodes @ rot.T, edges, EA=EA, fixed=[0], rest_length=l0, line_density=rho_a,
        tension_only=False,
    ).with_guides(Guides.roller([n], rot @ [1.0, 0.0, 0.0]))  # fmt: skip
    found = catenet.modes(net, Loads(), 6)
    h, m = span / n, rho_a * l0
    k = np.arange(1, 4)
    omega = 2.0 * np.sqrt(T / (m * h)) * np.sin((2 * k - 1) * np.pi / (4 * n))
    assert 2 * np.pi * found.frequency[:6] == pytest.approx(np.repeat(omega, 2), rel=1e-6)
    along = found.shape[:, n, :] @ (rot @ [1.0, 0.0, 0.0])
    assert np.abs(along).max() < 1e-12
    assert np.abs(found.shape[:, n, :]).max() > 0.1 * np.abs(found.shape).max()


def _guided_chain() -> Net:
    """Eight edges pinned at node 0, node 8 on a tilted roller plane, node 4 on a
    slider, node 2 on springs."""
    n = 8
    nodes = np.column_stack([np.linspace(0.0, 4.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(nodes, edges, EA=2e3, fixed=[0], rest_length=0.55, line_density=1.0)
    return net.with_guides(
        Guides.roller([n], [1.0, 0.2, 0.6]), Guides.slider([n // 2], [0.3, 1.0, -0.2])
    ).with_springs(Elastic.of([2], [50.0, 80.0, 20.0]))


def _swinging(dt: float, integrator: str) -> tuple[Net, object]:
    """A chain pinned at one end, its other end on a tilted roller plane and a middle
    node on a slider, one node on springs, falling from the straight line under gravity
    without damping."""
    net = _guided_chain()
    res = catenet.solve(
        Scene.of(net, Loads(gravity=np.array([0.0, 0.0, -G]))),
        method="dynamic",
        dt=dt,
        t_end=0.4,
        damping=0.0,
        integrator=integrator,
        rho_inf=1.0,
    )
    return net, res


def test_dynamic_run_keeps_the_guides_and_the_energy():
    """Newmark's trapezoidal rule (rho_inf = 1) on the chain: the roller node stays on its
    plane and the slider node on its line to round-off at every step, the energy balance
    closes (the work of gravity is the kinetic and elastic energy, springs' included, to
    a remainder that falls with the step: 1.3 %, 0.2 %, 0.07 % of the work at 4, 2 and
    1 ms), and halving the step changes the end state by about a quarter (second order)."""
    ends, remainders = [], []
    for dt in (4e-3, 2e-3, 1e-3):
        net, res = _swinging(dt, "newmark")
        assert res.converged
        guides = net.guides
        assert guides is not None
        moved = res.x[guides.nodes] - net.nodes[guides.nodes]
        assert np.abs(guides.held_part(moved)).max() < 1e-14
        kinetic, elastic, contact, work, dissipated, numerical = res.energy
        assert work > 1.0 and kinetic > 0.5 * work and elastic > 0.1 * work
        assert contact == 0.0 and dissipated == 0.0  # the springs' energy is elastic
        remainders.append(abs(numerical) / work)
        ends.append(res.x)
    assert remainders[0] < 0.03 and remainders[2] < 1e-3
    assert remainders[1] < 0.5 * remainders[0] and remainders[2] < 0.5 * remainders[1]
    coarse, fine = np.abs(ends[0] - ends[1]).max(), np.abs(ends[1] - ends[2]).max()
    assert fine < 0.4 * coarse


def test_implicit_euler_dissipates_and_keeps_the_guides():
    net, res = _swinging(2e-3, "implicit_euler")
    assert res.converged
    assert res.energy[-1] < 0.0  # its numerical dissipation, never energy created
    guides = net.guides
    moved = res.x[guides.nodes] - net.nodes[guides.nodes]
    assert np.abs(guides.held_part(moved)).max() < 1e-14


def test_ring_on_radial_sliders_is_free_to_expand():
    """A ring of N cable edges in a turned plane, every node on a slider along its
    radius (held around the ring and along its axis), pulled out by F per node and
    weighed down along its axis by W per node: each edge carries T = F / (2 sin(pi/N)),
    the ring grows to the radius l0 (1 + T/EA) / (2 sin(pi/N)), and the sliders hold
    the weight along the axis and nothing around the ring. No node is fixed."""
    n, radius, EA, F, W = 24, 3.0, 4e4, 50.0, 7.0
    rot = _rotation(9)
    angle = 2.0 * np.pi * np.arange(n) / n
    radial = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n)])
    nodes = radius * radial @ rot.T
    edges = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    guides = Guides.join([Guides.slider([k], rot @ radial[k]) for k in range(n)])
    l0 = 2.0 * radius * np.sin(np.pi / n)  # unstressed as given
    net = Net.from_arrays(nodes, edges, EA=EA, fixed=np.zeros(n, bool), guides=guides)
    axis = rot @ [0.0, 0.0, 1.0]
    force = F * radial @ rot.T - W * axis
    res = catenet.solve(Scene.of(net, Loads(force=force)))
    assert res.converged
    t = F / (2.0 * np.sin(np.pi / n))
    assert res.tension == pytest.approx(np.full(n, t), rel=1e-9)
    grown = l0 * (1.0 + t / EA) / (2.0 * np.sin(np.pi / n))
    assert np.linalg.norm(res.x, axis=1) == pytest.approx(np.full(n, grown), rel=1e-12)
    assert res.reaction @ axis == pytest.approx(np.full(n, W), rel=1e-9)
    around = np.cross(axis, res.x / np.linalg.norm(res.x, axis=1)[:, None])
    assert np.abs(np.einsum("ij,ij->i", res.reaction, around)).max() < 1e-9 * F
    out = radial @ rot.T  # free along the sliders: no radial reaction
    assert np.abs(np.einsum("ij,ij->i", res.reaction, out)).max() < 1e-9 * F


def test_initial_velocity_across_a_guide_is_left_out_with_a_warning(caplog):
    n = 4
    nodes = np.column_stack([np.linspace(0.0, 2.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(nodes, edges, EA=1e3, fixed=[0], line_density=1.0)
    net = net.with_guides(Guides.roller([n], [1.0, 0.0, 0.0]))
    v0 = np.zeros_like(nodes)
    v0[n] = [2.0, 0.0, -1.0]  # 2 m/s into the wall
    with caplog.at_level("WARNING"):
        res = catenet.solve(
            Scene.of(net, Loads(), velocity=v0), method="dynamic", dt=1e-3, t_end=0.01
        )
    assert res.converged and abs(res.x[n, 0] - 2.0) < 1e-15
    assert "initial velocity of node 4" in caplog.text and "(2 m/s)" in caplog.text


def test_modes_of_a_mass_on_springs():
    """A point mass m at the end of an unstressed bar (EA, l0) held by springs: along the
    bar omega^2 = (EA / l0 + kx) / m, across it ky / m and kz / m (no tension)."""
    m, EA, l0, k = 2.0, 3e3, 1.5, np.array([400.0, 50.0, 120.0])
    net = Net.from_arrays(
        [[0.0, 0.0, 0.0], [l0, 0.0, 0.0]], [[0, 1]], EA=EA, fixed=[0], tension_only=False,
        point_mass=[0.0, m], springs=Elastic.of([1], k),
    )  # fmt: skip
    found = catenet.modes(net, Loads(), 3)
    want = np.sort([(EA / l0 + k[0]) / m, k[1] / m, k[2] / m])
    assert (2 * np.pi * found.frequency) ** 2 == pytest.approx(want, rel=1e-9)


def test_run_to_rest_and_bdf2_end_where_the_static_solve_does():
    """The chain on its guides and springs: a damped run to rest (dynamic relaxation)
    ends at the static equilibrium, and bdf2 with steps chosen by accuracy keeps the
    guides exactly."""
    net = _guided_chain()
    scene = Scene.of(net, Loads(gravity=np.array([0.0, 0.0, -G])))
    static = catenet.solve(scene)
    rest = catenet.solve(scene, method="dynamic", t_end="rest", damping=2.0)
    assert static.converged and rest.converged
    assert np.abs(rest.x - static.x).max() < 1e-6
    assert rest.reaction == pytest.approx(static.reaction, abs=1e-4)
    bdf2 = catenet.solve(
        scene, method="dynamic", integrator="bdf2", tolerance=1e-3, t_end=0.3, damping=0.0
    )
    moved = bdf2.x[net.guides.nodes] - net.nodes[net.guides.nodes]
    assert bdf2.converged and np.abs(net.guides.held_part(moved)).max() < 1e-14
    assert bdf2.energy[-1] <= 0.0
