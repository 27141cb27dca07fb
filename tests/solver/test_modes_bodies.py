"""Natural modes with free rigid bodies (catenet.solver.modes on the rigid motions,
catenet.solver.modal): the body's six rigid motions with its true mass and inertia, no
mode of the affine body's strains, closed forms for the bounce and the rocking of a box
held by taut strings (the rocking checks the inertia and the contact's geometric
stiffness), a plucked dynamic run ringing at the modes' frequencies, and a frictionless
box balanced on a net's flat patch refused as the unstable equilibrium it is."""

from __future__ import annotations

import math

import numpy as np
import pytest
from meshes import net_under_gravity

from catenet.case import build, parse_case
from catenet.errors import ConvergenceError
from catenet.solver.modal import Reduction, body_frames
from catenet.solver.modes import Operator, natural_modes
from catenet.solver.path import Settings, Start, solve, workspace
from catenet.terms.rigid_contact import BodyContact

HALF = (0.2, 0.15, 0.05)  # the box's half sizes [m]
MASS = 6.0  # [kg]
A = 0.1  # the strings at y = +-A
GAP = 0.002  # their middle nodes' initial gap to the box [m]
DHAT = 0.005
L = 1.0  # string length
T0 = 100.0  # prestress [N]
EA = 1e5  # [N]
PUSH = 20.0  # [N] on each middle node, towards the box


def squeezed_box(density: float = 0.0, friction: float = 0.0) -> dict:
    """A box between four taut strings along x in zero gravity: two below at y = +-A
    and two above, each pushed onto a face at its middle node by PUSH: the box is
    squeezed, the forces on it balance. The strings' own mass is ``density`` x area."""
    nodes, edges, fixed, middle = [], [], [], []
    for side in (-1.0, 1.0):
        for y in (-A, A):
            z = side * (HALF[2] + GAP)
            k = len(nodes)
            nodes += [[-L / 2, y, z], [0.0, y, z], [L / 2, y, z]]
            edges += [[k, k + 1], [k + 1, k + 2]]
            fixed += [k, k + 2]
            middle.append((k + 1, -side))
    return {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges, "fixed": fixed},
        "material": {"EA": EA, "area": 1e-5, "density": density, "prestress": T0},
        "load": {
            "point": [{"node": k, "force": [0.0, 0.0, PUSH * s]} for k, s in middle],
        },
        "obstacle": [
            {
                "kind": "box", "center": [0.0, 0.0, 0.0], "half_size": list(HALF),
                "mass": MASS, "distance": DHAT, "friction": friction,
            }
        ],
        "solver": {"method": "static"},
    }  # fmt: skip


def equilibrium(case: dict):
    scene = build(parse_case(case))
    settings = Settings.of(scene.case.solver)
    ws = workspace(scene, settings)
    result = solve(scene, settings, workspace=ws)
    assert result.converged
    return scene, ws, result.x


def barrier2(d: float, kappa: float) -> float:
    """kappa b''(d) of the barrier b = -(d - dhat)^2 ln(d / dhat)."""
    r = d - DHAT
    return kappa * (-2.0 * math.log(d / DHAT) - 4.0 * r / d + r * r / (d * d))


def supports(scene, x):
    """Per middle node: its contact force F, gap d, barrier stiffness kappa b''(d), and
    its V-shaped string's stiffness at the node vertically (k_z), across (k_y) and
    along (k_x), from the tension N and stretched length l of its two edges and their
    angle phi from the horizontal: each edge adds EA/l0 t t^T + N/l (1 - t t^T)."""
    net = scene.net
    contact = next(t for t in scene.terms if isinstance(t, BodyContact))
    gaps = contact.gap(x)
    rows = []
    for i in range(4):
        mid = 3 * i + 1
        d = float(gaps[np.flatnonzero(contact.nodes == mid)[0]])
        ky = kz = kx = 0.0
        for e in (2 * i, 2 * i + 1):
            a, b = net.edges[e]
            v = x[b] - x[a]
            length = float(np.linalg.norm(v))
            n = EA * (length / net.rest_length[e] - 1.0)
            s2 = (v[2] / length) ** 2
            kz += EA / net.rest_length[e] * s2 + n / length * (1 - s2)
            kx += EA / net.rest_length[e] * (1 - s2) + n / length * s2
            ky += n / length
        force = -contact.kappa * (-2 * (d - DHAT) * math.log(d / DHAT) - (d - DHAT) ** 2 / d)
        rows.append((force, d, barrier2(d, contact.kappa), kz, ky, kx))
    return rows


def test_body_mass_matrix_is_its_mass_and_inertia():
    """On the rigid motions the four lumped masses m/4 are the body's mass m 1 and its
    inertia tensor about the centre (a box turned about an oblique axis: a full 3 x 3)."""
    case = squeezed_box()
    case["obstacle"][0].update(axis=[1.0, 2.0, 0.5], angle=0.7, center=[0.0, 0.0, 0.3])
    scene = build(parse_case(case))
    ws = workspace(scene, Settings())
    x = scene.net.nodes
    op = Operator(ws.system, x, scene.net.mass)
    q = op.reduction.bodies[0][1]
    block = op.mm[q : q + 6, q : q + 6].toarray()
    body = scene.rigid[0]
    world = body.axes @ body.inertia @ body.axes.T
    assert np.allclose(block[:3, :3], MASS * np.eye(3), rtol=1e-12, atol=1e-12)
    assert np.allclose(block[3:, 3:], world, rtol=1e-10, atol=1e-12 * np.abs(world).max())
    assert np.allclose(block[:3, 3:], 0.0, atol=1e-12)


@pytest.mark.roundoff
def test_squeezed_box_bounce_and_rocking_closed_forms():
    """The box between the four strings, massless strings, zero gravity.

    Each middle node at gap d carries F = -kappa b'(d); its barrier kappa b''(d) and its
    V-string's stiffness are springs in series along the face's normal (k_s). A small
    motion of the box (z, rotation theta about x, psi about y) changes node i's gap by
    -+(z + y_i theta - x_i psi) - (h + d_i)(theta^2 + psi^2)/2 (h the half height: the
    face turns about the centre, at h + d from it), and tilts the normal so that node i
    gets F theta across (y) or F psi along (x) its string (k_y, k_x hold it).

    Bounce: omega^2 = sum k_s / m. Rocking about x, y_i = +-A:
        omega^2 = sum (k_s A^2 + F (h + d) - F^2 / k_y) / I_xx,
    about y (x_i = 0: no spring lever; the contact's geometric term alone):
        omega^2 = sum (F (h + d) - F^2 / k_x) / I_yy,
    I the box's (m (b^2 + c^2) / 3 ...). The forces on the box balance, so no motion
    couples to the sliding ones; x, y and the turn about z cost nothing (frictionless
    faces): three zero-frequency modes, named, not returned; no strain mode."""
    scene, ws, x = equilibrium(squeezed_box())
    rows = supports(scene, x)
    hx, hy, hz = HALF
    ixx = MASS * (hy**2 + hz**2) / 3
    iyy = MASS * (hx**2 + hz**2) / 3
    ks = [1.0 / (1.0 / kb + 1.0 / kz) for _, _, kb, kz, _, _ in rows]
    bounce = sum(ks) / MASS
    rock_x = sum(
        k * A**2 + f * (hz + d) - f * f / ky
        for k, (f, d, _, _, ky, _) in zip(ks, rows, strict=True)
    )
    rock_y = sum(f * (hz + d) - f * f / kx for f, d, _, _, _, kx in rows)
    forces = [f for f, *_ in rows]
    assert min(forces) > 0 and np.allclose(forces, forces[0], rtol=1e-9)  # symmetric
    modes = natural_modes(ws, x, 3)
    expected = np.sort([bounce, rock_x / ixx, rock_y / iyy])
    # The bounce within 1e-9; the rocking modes within 1e-5: their stiffness is what is
    # left of the strings' axial and the barrier's stiffness (4e5 and 2e4 N/m at levers of
    # 0.1 m) after the massless nodes are condensed out, about 1 N m, so the state's
    # round-off moves them by up to 2.2e-6 (measured on an Intel processor: the exact
    # start and starts moved by 1e-12 and 1e-9 of the size, -2.2e-6 to +6.4e-7; within
    # 1e-6 on the AMD one where the test was written).
    got = np.sort(modes.omega2)
    bounce_k = int(np.argmin(np.abs(expected - bounce)))
    assert got[bounce_k] == pytest.approx(bounce, rel=1e-9), (modes.omega2, expected)
    assert np.allclose(got, expected, rtol=1e-5), (modes.omega2, expected)
    assert modes.zero_modes == 3 and "obstacle[0]" in modes.zero_message
    assert modes.stats["bodies"] == 1 and modes.stats["dofs"] == 6 + 3 * 4
    frame = scene.rigid[0].frame
    for k in range(3):  # rigid on the body: its four nodes move as one body
        assert_rigid(frame, modes.shape[k], x)


def assert_rigid(frame, shape, x):
    """The body's four nodes move rigidly in ``shape``: dA = W A, W skew."""
    _, dA = frame.state(shape)
    _, A0 = frame.state(x)
    skew = dA @ np.linalg.inv(A0)
    size = float(np.abs(shape[frame.nodes]).max()) / frame.reach  # a turn of this size
    assert np.abs(skew + skew.T).max() <= 1e-9 * size


def test_plucked_squeezed_box_rings_at_its_modes():
    """Strings with mass, the box plucked from its equilibrium with a small spin about
    y (the rocking mode that the contact's geometric stiffness holds): an undamped
    newmark run (rho_inf 0.95, 80 steps a period: period error below 1e-3) rings at the
    frequency ``natural_modes`` gives, read from the zero crossings of the box's tilt."""
    case = squeezed_box(density=500.0)
    scene, ws, x = equilibrium(case)
    modes = natural_modes(ws, x, 6)
    frame = scene.rigid[0].frame
    rock = next(k for k in range(modes.count) if _turn(frame, modes, k, x)[1] > 0.9)
    f = modes.frequency[rock]
    v = np.zeros_like(x)
    c = x[frame.nodes].mean(axis=0)
    v[frame.nodes] = np.cross([0.0, 1e-3, 0.0], x[frame.nodes] - c)
    periods = 4  # (later, the frictionless box's free sliding takes up its motion)
    h = 1.0 / (f * 80)
    case["solver"] = {"method": "dynamic", "dt": h, "t_end": periods / f, "damping": 0.0}
    case["solver"]["rho_inf"] = 0.95
    dyn = build(parse_case(case))
    tilt, times = [], []

    def seen(step):
        _, R = frame.pose(step.x)
        tilt.append(R[0, 2])
        times.append(step.time)

    out = solve(dyn, Settings.of(dyn.case.solver), start=Start(x=x, v=v), on_step=seen)
    assert out.converged
    tilt, times = np.array(tilt), np.array(times)
    s = np.flatnonzero(np.diff(np.sign(tilt)) != 0)
    cross = times[s] - tilt[s] * (times[s + 1] - times[s]) / (tilt[s + 1] - tilt[s])
    period = 2 * float(np.mean(np.diff(cross)))
    assert 1 / period == pytest.approx(f, rel=5e-3)


def _turn(frame, modes, k, x):
    """(share of the mode's body motion in rotation, |its rotation's y component|)."""
    u = modes.shape[k][frame.nodes]
    mean = u.mean(axis=0)
    r = x[frame.nodes] - x[frame.nodes].mean(axis=0)
    w = np.linalg.lstsq(
        np.vstack([np.cross(np.eye(3), rk).T for rk in r]), (u - mean).ravel(), rcond=None
    )[0]
    norm = np.linalg.norm(w)
    return norm, (abs(w[1]) / norm if norm else 0.0)


def test_strain_modes_never_appear():
    """Every mode asked for (the dense solver): the box's modes are its rigid ones, no
    stretch or shear of the affine body among them (they are not physical)."""
    scene, ws, x = equilibrium(squeezed_box(density=500.0))
    frame = scene.rigid[0].frame
    red = Reduction(ws.system, x, body_frames(ws.system))
    every = red.n - 3  # all but the three zero modes
    modes = natural_modes(ws, x, every, method="dense")
    assert modes.count == every
    for k in range(modes.count):
        assert_rigid(frame, modes.shape[k], x)
    # the strings' own modes are the top ones: below their Gershgorin bound (no 1e6 x)
    top = float(modes.omega2.max())
    net = ws.system.net
    strings = EA / float(net.rest_length.min()) / float(net.mass[: net.n_net].max())
    assert top < 8 * strings


def test_frictionless_box_on_a_net_is_refused_as_unstable(tmp_path):
    """A frictionless box balanced on a pinned net's flat patch: the nodes under a flat
    face hold it up but not sideways, and a tilt turns their push (its weight W) into a
    sideways force: K has [[0, W], [W, k]] in (slide, tilt), indefinite. The static run
    warns, ``catenet modes`` refuses it naming the body; with friction it has modes
    (Lanczos as the dense solver), rigid on the body, the lowest one the box's."""
    case = {
        **net_under_gravity(6, 0.05),
        "obstacle": [
            {"kind": "box", "center": [0.0, 0.0, 0.022], "half_size": [0.15, 0.15, 0.02],
             "mass": 10.0, "distance": 0.005}
        ],
        "solver": {"method": "static"},
    }  # fmt: skip
    scene, ws, x = equilibrium(case)
    with pytest.raises(ConvergenceError, match=r"unstable.*obstacle\[0\].*slide, roll or tip"):
        natural_modes(ws, x, 4)
    case["obstacle"][0]["friction"] = 0.5
    scene, ws, x = equilibrium(case)
    modes = natural_modes(ws, x, 4)
    assert modes.count == 4 and modes.omega2[0] > 0
    assert modes.stats["method"] == "lanczos"
    dense = natural_modes(ws, x, 4, method="dense")  # the same modes, every one computed
    assert np.allclose(modes.omega2, dense.omega2, rtol=1e-8)
    frame = scene.rigid[0].frame
    for k in range(4):
        assert_rigid(frame, modes.shape[k], x)
    share = modes.node_share()[:, frame.nodes].sum(axis=1)
    assert share[0] > 0.5  # the lowest mode is the box's (its bounce on the net)


@pytest.mark.roundoff
def test_box_on_the_ground_bounce_and_rocking_closed_forms():
    """A 40 kg box (0.3 x 0.2 x 0.1 m) at rest on the ground (a plane's barrier on its
    corners, catenet.terms.body_plane), beside a short pinned cable. Each lower corner
    is a spring kappa b''(d) along the plane's normal, which does not turn with the box;
    turning about x by theta moves corner (y_i, -h) up by y_i theta and, at second
    order, by h theta^2 / 2, so its barrier force F = W / 4 adds -F h (the weight's
    overturning moment, W h in all):

        bounce      omega^2 = 4 k / m,
        rocking x   omega^2 = (4 k b^2 - W h) / I_xx,   I_xx = m (b^2 + h^2) / 3,
        rocking y   omega^2 = (4 k a^2 - W h) / I_yy,   I_yy = m (a^2 + h^2) / 3,

    (a, b, h the half sizes): the body's mass, inertia and the barrier's true stiffness,
    to 1e-8. Sliding and turning about z cost nothing: three zero-frequency modes."""
    a, b, h, m, g = 0.15, 0.1, 0.05, 40.0, 9.81
    case = {
        "geometry": {"kind": "cable", "start": [2, 0, 0], "end": [3, 0, 0], "nodes": 3},
        "material": {"EA": 1e5, "area": 1e-5, "density": 1000.0, "prestress": 100.0},
        "load": {"gravity": [0.0, 0.0, -g]},
        "obstacle": [
            {"kind": "plane", "point": [0.0, 0.0, -1.0], "distance": 0.002},
            {"kind": "box", "center": [0.0, 0.0, -1.0 + h + 0.0015], "half_size": [a, b, h],
             "mass": m, "distance": 0.005},
        ],
        "solver": {"method": "static"},
    }  # fmt: skip
    scene, ws, x = equilibrium(case)
    plane = next(t for t in scene.terms if type(t).__name__ == "BodyPlane")
    d = np.sort(plane.gap(x))[:4]
    assert np.allclose(d, d[0], rtol=1e-9)
    r = float(d[0]) - plane.dhat
    k = plane.kappa * (-2 * math.log(d[0] / plane.dhat) - 4 * r / d[0] + r * r / d[0] ** 2)
    weight = m * g
    expected = [
        4 * k / m,
        (4 * k * b**2 - weight * h) / (m * (b**2 + h**2) / 3),
        (4 * k * a**2 - weight * h) / (m * (a**2 + h**2) / 3),
    ]
    modes = natural_modes(ws, x, ws.system.n_free - 6 - 3, method="dense")
    assert modes.zero_modes == 3
    for target in expected:
        assert np.min(np.abs(modes.omega2 / target - 1)) < 1e-8, target
