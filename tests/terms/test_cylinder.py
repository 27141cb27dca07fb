"""The cylinder obstacle (``catenet.scene.shapes.cylinder``, kernels in
``catenet.kernels.cylinder``), added in three files: its kernel, its shape module and its
declared keys. Finite differences of its barrier beside the side, above the ends and off
the rims, grown by a ball's radius or not; its first contact along a step against an
independent reference (exact for the cylinder, never later than the true one grown); a
closed form with nodes; a free cylinder standing and lying on a plane and dropped on a
net; its drawing; bad input.

Closed form: a taut weightless cable over the cylinder's curved side (as over the
capsule in test_shapes.py): uniform tension T, straight free spans tangent to the circle
of radius R, the cable on that circle between the tangent points, and
T = EA (path / L0 - 1) with path = 2 sqrt(s^2 - R^2) + R alpha.
"""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from catenet.case import build, parse_case
from catenet.cli import main
from catenet.run.runner import run_case
from catenet.scene.shapes import kinds, shape_class, shape_of
from catenet.scene.shapes.cylinder import OUTLINE, Cylinder, CylinderBarrier
from catenet.terms import check_derivatives
from tests.terms.test_shapes import brute_first_contact, near_surface, run, wrap_case

AXIS = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])


def barrier(n: int, offset: float = 0.0, dhat: float = 0.05) -> CylinderBarrier:
    """A cylinder of radius 0.3 and length 1 about a tilted axis through (0.1, 0, 0)."""
    return CylinderBarrier(
        np.arange(n), [0.1, 0.0, 0.0], AXIS, 0.5, 0.3, kappa=30.0, dhat=dhat, offset=offset
    )


def regions(term, x) -> set[str]:
    """Which of its features the points x are nearest: side, end, rim."""
    y = x - term.center
    z = y @ term.axis
    rho = np.linalg.norm(y - z[:, None] * term.axis, axis=1)
    dr, dz = rho - term.radius, np.abs(z) - term.half_length
    found = set()
    found |= {"side"} if np.any((dr > 0) & (dz < 0)) else set()
    found |= {"end"} if np.any((dr < 0) & (dz > 0)) else set()
    found |= {"rim"} if np.any((dr > 0) & (dz > 0)) else set()
    return found


def test_the_kinds_are_the_modules_of_the_shapes_package():
    assert kinds() == ("box", "capsule", "cylinder", "mesh", "plane", "sphere")
    assert shape_class("cylinder") is Cylinder
    with pytest.raises(ValueError, match="unknown obstacle kind 'torus'"):
        shape_class("torus")


@pytest.mark.parametrize("offset", [0.0, 0.1])
def test_the_barrier_passes_finite_differences_at_every_feature(offset):
    rng = np.random.default_rng(5)
    term = barrier(60, offset)
    x = near_surface(term, rng, 60, -1.2, 1.3, term.dhat)
    assert regions(term, x) == {"side", "end", "rim"}
    assert np.all(term.gap(x) > 0) and np.any(term.gap(x) > term.dhat)
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


def test_the_gap_is_the_distance_to_the_cylinder():
    """On its axis beyond an end, beside the middle of its side, diagonally off a rim, and
    inside (negative: the nearer of side and end)."""
    c, e, h, r = np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.5, 0.3
    term = CylinderBarrier(np.arange(4), c, e, h, r, kappa=1.0, dhat=0.01)
    x = np.array([[0, 0, 0.9], [0.7, 0, 0.1], [0.3 + 0.3, 0, -0.5 - 0.4], [0.0, 0.25, 0.2]])
    assert term.gap(x) == pytest.approx([0.4, 0.4, 0.5, -0.05], abs=1e-15)
    grown = CylinderBarrier(np.arange(4), c, e, h, r, kappa=1.0, dhat=0.01, offset=0.1)
    assert grown.gap(x)[:3] == pytest.approx([0.3, 0.3, 0.4], abs=1e-15)


@pytest.mark.parametrize("offset", [0.0, 0.08])
def test_the_first_hit_along_a_step_is_the_first_contact(offset):
    """Exact for the cylinder; grown by a ball's radius, never later than the true first
    contact (sampling then bisection) and within 1e-6 of it."""
    rng = np.random.default_rng(17)
    term = barrier(6, offset)
    hits = 0
    for _ in range(8):
        x = near_surface(term, rng, 6, -1.5, 2.0, 10.0)
        aim = rng.uniform(-0.3, 0.5, (6, 3)) - x  # toward the cylinder: most hit it
        dx = aim * rng.uniform(0.02, 0.5)
        t = term.max_step(x, dx)
        ref = brute_first_contact(term, x, dx)
        if math.isinf(ref):
            assert math.isinf(t) or t > 50.0
            continue
        hits += 1
        assert t <= ref * (1 + 1e-12)
        assert t == pytest.approx(ref, rel=1e-6, abs=1e-9)
        assert np.all(term.gap(x + t * dx) >= -1e-12)
    assert hits >= 5
    for grow in (0.0, 0.05):  # a ray along the axis onto an end
        x = np.array([[0.1, 0.0, 0.0]]) + np.array([[2.0]]) * AXIS
        t = barrier(1, offset).first_hit(x, -AXIS[None] * 1.0, grow)
        assert t == pytest.approx(2.0 - 0.5 - offset - grow, abs=1e-9)


def cylinder_wrap() -> dict:
    case = wrap_case()
    case["obstacle"][0]["kind"] = "cylinder"
    return case


def test_a_taut_cable_over_a_cylinder_wraps_on_its_circle():
    r, scene, (cyl,), gaps = run(cylinder_wrap())
    assert r.converged and min(gaps) > 0
    R, dhat = 0.3, cyl.dhat
    C = np.array([0.0, 0.0, -0.5])
    S = np.array([1.0, 0.0, -0.4])
    s = float(np.linalg.norm((S - C)[[0, 2]]))
    tangent = math.atan2(S[2] - C[2], S[0] - C[0]) + math.acos(R / s)
    path = 2 * math.sqrt(s * s - R * R) + R * (math.pi - 2 * tangent)
    T = 1000.0 * (path / (2 * math.hypot(1.0, 0.3) / 1.1) - 1.0)
    x = r.x
    rel = x - C
    polar = np.arctan2(rel[:, 2], rel[:, 0])
    dist = np.hypot(rel[:, 0], rel[:, 2])
    on = (polar > tangent + 0.02) & (polar < math.pi - tangent - 0.02)
    assert on.sum() > 10
    assert np.all(dist[on] > R) and np.all(dist[on] - R < dhat)
    assert np.ptp(dist[on]) < 0.2 * dhat
    net = scene.net
    length = np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1)
    tension = net.EA * (length / net.rest_length - 1)
    assert tension.min() == pytest.approx(T, rel=0.01) and tension.max() == pytest.approx(
        T, rel=0.01
    )


def test_the_same_barrier_from_toml_and_from_python():
    """The case's cylinder is the shape built in Python: the same gaps and forces."""
    case = cylinder_wrap()
    scene = build(parse_case(case))
    (term,) = [t for t in scene.terms if isinstance(t, CylinderBarrier)]
    mine = Cylinder([0, -0.5, -0.5], [0, 0.5, -0.5], 0.3).barrier(term.nodes, term.kappa, term.dhat)
    x = scene.net.nodes
    assert np.array_equal(term.gap(x), mine.gap(x))
    g1, g2 = np.zeros_like(x), np.zeros_like(x)
    assert term.gradient(x, g1) == mine.gradient(x, g2) and np.array_equal(g1, g2)


def test_its_mass_properties_and_drawing():
    cyl = shape_of({"kind": "cylinder", "start": [0, 0, 0], "end": [0, 0, 2.0], "radius": 0.5})
    volume, com, inertia, axes = cyl.mass_properties()
    assert volume == pytest.approx(math.pi * 0.25 * 2.0)
    assert com == pytest.approx([0, 0, 1.0])
    assert np.diag(inertia) == pytest.approx([0.25 / 4 + 4 / 12] * 2 + [0.125])
    assert axes[:, 2] == pytest.approx([0, 0, 1])
    V, F = cyl.surface_mesh()
    tri = np.concatenate([F[:, [0, 1, 2]], F[:, [0, 2, 3]]])
    tri = tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])]
    a, b, c = V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]
    drawn = np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0  # outward: positive
    polygon = 36 * math.sin(2 * math.pi / 36) / (2 * math.pi)  # the inscribed 36-gon's share
    assert drawn == pytest.approx(volume * polygon, rel=1e-12)
    points, edges, radius = cyl.outline()
    assert radius == 0.0 and len(points) == 2 * OUTLINE and len(edges) == 3 * OUTLINE
    rho = np.hypot(points[:, 0], points[:, 1])
    assert rho == pytest.approx(0.5 / math.cos(math.pi / OUTLINE))  # it holds the cylinder
    mid = 0.5 * (points[edges[:OUTLINE, 0]] + points[edges[:OUTLINE, 1]])
    assert np.hypot(mid[:, 0], mid[:, 1]) == pytest.approx(0.5)  # its sides touch the rims


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write(tmp_path, text: str):
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


DRUM = """
title = "a drum on the ground"

[geometry]
kind = "graph"
nodes = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
edges = [[0, 1]]
fixed = [0, 1]

[material]
EA = 1000.0
density = 1000.0
area = 1e-4

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "plane"

[[obstacle]]
kind = "cylinder"
start = {start}
end = {end}
radius = 0.25
density = 500.0

[solver]
method = "dynamic"
dt = 0.01
damping = 5.0
t_end = 2.0
"""


@pytest.mark.parametrize(
    ("start", "end", "low", "high"),
    [
        ([3.0, 0.0, 0.02], [3.0, 0.0, 0.62], 0.3, 0.3),  # standing: its end on the ground
        ([3.0, -0.3, 0.27], [3.0, 0.3, 0.27], 0.25, 0.25 / math.cos(math.pi / OUTLINE)),
    ],
    ids=["standing", "lying"],
)
def test_a_free_cylinder_comes_to_rest_on_the_ground(tmp_path, start, end, low, high):
    """Dropped 2 cm: standing, its centre ends half its length up (exact: the outline's
    end rims lie in its end faces); lying, between its radius and the circumscribed
    outline's (module docstring of the shape), within the barrier's gap."""
    out = tmp_path / "drum.h5"
    r = invoke("run", write(tmp_path, DRUM.format(start=start, end=end)), "-o", out, "-q")
    assert r.exit_code == 0, r.output
    with h5py.File(out) as f:
        x = f["result/x"][()]
        dhat = 1e-3 * 2.0  # the default activation distance: 1e-3 of the scene
        assert f["mesh/obstacles/1"].attrs["kind"] == "cylinder"  # drawn for ParaView
    centre = x[-4:].mean(axis=0)  # the body's four nodes: their mean is its centre
    assert low - 1e-9 < centre[2] < high + dhat
    assert centre[:2] == pytest.approx([3.0, 0.0], abs=1e-3)


def test_a_free_cylinder_dropped_on_a_net_never_lets_a_node_in(tmp_path):
    case = {
        "geometry": {"kind": "square_net", "n": 10, "alpha": 0.0, "size": 1.0, "edge_length": 0.05},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [
            {
                "kind": "cylinder",
                "start": [-0.2, 0.0, 0.15],
                "end": [0.2, 0.0, 0.15],
                "radius": 0.1,
                "mass": 5.0,
                "velocity": [0.0, 0.0, -1.0],
            }
        ],
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.0, "t_end": 0.3},
        "output": {"every": 1},
    }
    parsed = parse_case(case)
    scene = build(parsed)
    out = tmp_path / "drop.h5"
    run_case(parsed, out)
    (body,) = scene.rigid
    cyl = Cylinder([-0.2, 0.0, 0.15], [0.2, 0.0, 0.15], 0.1)
    probe = cyl.barrier(np.arange(scene.net.n_nodes - 4), 1.0, 1.0)
    with h5py.File(out) as f:
        xs = f["trajectory/x"][()]
        energy = f["trajectory/energy"][()]
    touched = False
    for x in xs:
        c, A = body.frame.state(x)  # the net's nodes in the body's frame at t = 0
        local = cyl.origin + (x[:-4] - c) @ A
        gap = probe.gap(np.vstack([local, np.zeros((4, 3))]))
        assert gap.min() > 0.0
        touched |= bool(gap.min() < 0.01)
    assert touched
    assert energy[:, -1].max() <= 1e-9 * np.abs(energy[:, :4]).max()  # implicit Euler: loses only


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"end": [0.0, -0.5, -0.5]}, "obstacle[0].end = [0.0, -0.5, -0.5]: must differ from"),
        ({"radius": -1.0}, "obstacle[0].radius"),
        ({"start": None}, "obstacle[0].start: missing"),
    ],
)
def test_bad_cylinders_exit_2_with_their_key_path(tmp_path, change, message):
    case = cylinder_wrap()
    for k, v in change.items():
        if v is None:
            del case["obstacle"][0][k]
        else:
            case["obstacle"][0][k] = v
    path = tmp_path / "bad.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    r = invoke("run", path, "-o", tmp_path / "bad.h5")
    assert r.exit_code == 2, r.output
    assert message in r.output
