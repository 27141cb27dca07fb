"""Box, capsule and mesh obstacles: finite differences of their barrier terms, exact first
contact along a step, no node ever inside (static and dynamic, several step sizes), two
closed forms, bad input through the CLI, and the tether-net capture example.

Closed forms:
- A taut weightless cable over a capsule's cylinder (supports moved below the top of the
  cylinder, in its plane of symmetry): frictionless contact carries no tangential force,
  so the tension T is uniform, the free spans are straight lines tangent to the circle of
  radius R about the axis, and the cable lies on that circle between the tangent points.
  For a support S at distance s from the axis the tangent touches the circle at the
  polar angle (of S) + acos(R / s); the path length 2 sqrt(s^2 - R^2) + R alpha (alpha
  the wrap angle) fixes T = EA (path / L0 - 1), L0 the cable's rest length.
- A net pressed by a pressure onto a box face: the face is flat, every node on it carries
  its share of the load at the same gap below dhat, so those nodes lie in one plane
  parallel to the face, at gap < dhat.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from contact_cases import CAPTURE, capture_near, flat_case
from meshes import CUBE_T, CUBE_V, icosphere, write_stl

from catenet.case import build, dumps_toml, parse_case
from catenet.kernels.mesh import _cell
from catenet.solver.path import Settings, solve
from catenet.terms import check_derivatives
from catenet.terms.shapes import BoxBarrier, CapsuleBarrier, MeshBarrier, closed_surface, rotation


def near_surface(term, rng, n, lo, hi, dhat):
    """n random points at gaps between 0.05 and 1.4 dhat from ``term``'s surface."""
    out = []
    probe = type(term).__new__(type(term))
    probe.__dict__.update(term.__dict__)
    probe.nodes = np.zeros(1, dtype=np.int64)
    while len(out) < n:
        p = rng.uniform(lo, hi, 3)
        if 0.05 * dhat < probe.gap(p[None])[0] < 1.4 * dhat:
            out.append(p)
    return np.array(out)


def shapes(dhat=0.05, n=30):
    nodes = np.arange(n)
    R = rotation([1.0, 2.0, 3.0], 0.7)
    box = BoxBarrier(nodes, [0.1, 0.0, 0.0], [0.5, 0.3, 0.2], R, kappa=30.0, dhat=dhat)
    capsule = CapsuleBarrier(nodes, [0, 0, 0], [1.0, 0.5, 0.0], 0.3, kappa=30.0, dhat=dhat)
    cube = MeshBarrier(nodes, CUBE_V @ R.T, CUBE_T, kappa=30.0, dhat=dhat)
    V, T = icosphere(2)
    ball = MeshBarrier(nodes, 0.5 * V + 0.2, T, kappa=30.0, dhat=dhat)
    return {"box": box, "capsule": capsule, "cube mesh": cube, "sphere mesh": ball}


@pytest.mark.parametrize("kind", ["box", "capsule", "cube mesh", "sphere mesh"])
def test_shape_terms_pass_finite_differences(kind):
    """Points near faces, edges and vertices (random), inside and beyond dhat."""
    rng = np.random.default_rng(7)
    term = shapes()[kind]
    x = near_surface(term, rng, 30, -1.2, 1.7, term.dhat)
    assert np.all(term.gap(x) > 0) and np.any(term.gap(x) > term.dhat)
    grad_err, hess_err = check_derivatives(term, x, step=1e-7)
    assert grad_err < 1e-6 and hess_err < 1e-5


def test_a_mesh_of_a_box_acts_as_the_box():
    """Same gaps, forces, Hessians and first contacts as the analytic box: the mesh's
    features (faces, edges, vertices) and pseudo-normal signs are the box's."""
    rng = np.random.default_rng(3)
    R = rotation([0.3, -1.0, 0.5], 1.1)
    box = BoxBarrier(np.arange(40), R @ [0.5, 0.5, 0.5], [0.5] * 3, R, kappa=5.0, dhat=0.05)
    mesh = MeshBarrier(np.arange(40), CUBE_V @ R.T, CUBE_T, kappa=5.0, dhat=0.05)
    x = near_surface(box, rng, 40, -0.5, 1.5, box.dhat)
    assert np.allclose(mesh.gap(x), box.gap(x), atol=1e-12)
    g1, g2 = np.zeros_like(x), np.zeros_like(x)
    assert mesh.gradient(x, g1) == pytest.approx(box.gradient(x, g2), rel=1e-12)
    assert np.allclose(g1, g2, rtol=1e-10, atol=1e-12)
    h1, h2 = np.zeros(9 * 40), np.zeros(9 * 40)
    mesh.hessian(x, h1)
    box.hessian(x, h2)
    assert np.allclose(h1, h2, rtol=1e-9, atol=1e-9 * np.abs(h2).max())
    inside = R @ [0.5, 0.5, 0.5] + rng.uniform(-0.4, 0.4, (40, 3)) @ R.T
    assert np.all(mesh.gap(inside) < 0) and np.all(box.gap(inside) < 0)
    for _ in range(20):
        dx = rng.standard_normal(x.shape)
        assert mesh.max_step(x, dx) == pytest.approx(box.max_step(x, dx), rel=1e-9)


def brute_first_contact(term, x, dx, t_far=50.0, samples=5000):
    """First t at which some node's gap changes sign along x + t dx (sampling, then
    bisection): an independent reference for max_step."""
    ts = np.linspace(0, t_far, samples)
    best = math.inf
    for k in range(len(x)):
        pts = x[k] + ts[:, None] * dx[k]
        probe = type(term).__new__(type(term))
        probe.__dict__.update(term.__dict__)
        probe.nodes = np.arange(samples)
        gaps = probe.gap(pts)
        hit = np.flatnonzero(gaps <= 0)
        if hit.size == 0:
            continue
        lo, hi = ts[hit[0] - 1], ts[hit[0]]
        one = np.zeros(1, dtype=np.int64)
        probe.nodes = one
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if probe.gap((x[k] + mid * dx[k])[None])[0] <= 0 else (mid, hi)
        best = min(best, hi)
    return best


@pytest.mark.parametrize("kind", ["box", "capsule", "sphere mesh"])
def test_max_step_is_the_first_contact_along_a_step(kind):
    rng = np.random.default_rng(11)
    term = shapes(n=6)[kind]
    hits = 0
    for _ in range(4):
        x = near_surface(term, rng, 6, -1.5, 2.0, 10.0)  # anywhere outside, up to 10 m
        aim = rng.uniform(-0.2, 0.6, (6, 3)) - x  # toward the body, most hit it
        dx = aim * rng.uniform(0.02, 0.5)
        t = term.max_step(x, dx)
        ref = brute_first_contact(term, x, dx)
        if math.isinf(ref):
            assert math.isinf(t) or t > 50.0
        else:
            hits += 1
            assert t == pytest.approx(ref, rel=1e-6, abs=1e-9)
            assert np.all(term.gap(x + 0.999 * t * dx) > 0)
    assert hits >= 3


def test_the_mesh_grid_finds_what_every_triangle_finds():
    """A fine mesh (1280 triangles) on a grid of many cells: energies, gradients and
    first contacts equal those of a one-cell grid (every triangle a candidate)."""
    rng = np.random.default_rng(5)
    V, T = icosphere(3)
    fine = MeshBarrier(np.arange(200), V, T, kappa=3.0, dhat=0.02)
    one = MeshBarrier(np.arange(200), V, T, kappa=3.0, dhat=0.02)
    one.h = float(np.ptp(V, axis=0).max()) + 1.0
    one.dims = np.ones(3, dtype=np.int64)
    one.start = np.array([0, len(T)], dtype=np.int64)
    one.items = np.arange(len(T), dtype=np.int64)
    assert fine.dims.prod() > 100 and len(fine.items) < 0.2 * fine.dims.prod() * len(T)
    x = near_surface(fine, rng, 200, -1.1, 1.1, 0.02)
    cells = [_cell(p, fine.lo, fine.h, fine.dims) for p in x]
    candidates = [fine.start[c + 1] - fine.start[c] for c in cells]
    assert np.mean(candidates) < 0.03 * len(T)  # a node looks at a few triangles, not all
    g1, g2 = np.zeros_like(x), np.zeros_like(x)
    assert fine.gradient(x, g1) == pytest.approx(one.gradient(x, g2), rel=1e-12)
    assert np.array_equal(g1, g2)
    far = rng.uniform(-3, 3, (200, 3))
    far = far[np.linalg.norm(far, axis=1) > 1.05]
    for _ in range(10):
        dx = rng.standard_normal(far.shape)
        assert fine.max_step(far, dx) == one.max_step(far, dx)


def test_a_surface_that_is_not_closed_or_oriented_is_refused():
    V, T = CUBE_V, CUBE_T
    closed_surface(V, T)  # fine
    with pytest.raises(ValueError, match="is not closed: 3 edges"):
        closed_surface(V, T[1:])
    flipped = T.copy()
    flipped[0] = flipped[0, ::-1]
    with pytest.raises(ValueError, match="not consistently oriented"):
        closed_surface(V, flipped)
    Vi, Ti = closed_surface(V, T[:, ::-1])  # inward normals: turned outward
    assert np.all(
        MeshBarrier(np.arange(1), Vi, Ti, kappa=1, dhat=0.1).gap(np.array([[2.0, 0.5, 0.5]])) > 0
    )


# --------------------------------------------------------------------------- physics


def run(case: dict, **settings):
    parsed = parse_case(case)
    scene = build(parsed)
    gaps = []
    obstacles = [t for t in scene.terms if hasattr(t, "max_step")]
    r = solve(
        scene,
        Settings.of(parsed.solver, **settings) if settings else Settings.of(parsed.solver),
        on_step=lambda s: gaps.append(min(float(t.gap(s.x).min()) for t in obstacles)),
    )
    return r, scene, obstacles, gaps


def wrap_case(dhat=1e-3):
    """A cable from (-1, 0, -0.4) over an apex at (0, 0, -0.1) to (1, 0, -0.4), clear of
    the capsule, prestressed to 100 N in that shape: its rest length (2.088 m / 1.1) is
    shorter than the path over the capsule, so it pulls itself down onto it."""
    return {
        "title": "a cable pulled over a capsule",
        "geometry": {
            "kind": "graph",
            "nodes": [[-1, 0, -0.4], [0, 0, -0.1], [1, 0, -0.4]],
            "fixed": [0, 2],
            "edge_length": 0.01,
            "cable": [{"name": "cable", "nodes": [0, 1, 2]}],
        },
        "material": {"EA": 1000.0, "prestress": 100.0},
        "obstacle": [
            {
                "kind": "capsule",
                "start": [0, -0.5, -0.5],
                "end": [0, 0.5, -0.5],
                "radius": 0.3,
                "distance": dhat,
            }
        ],
        "solver": {"method": "static", "steps": 1},
    }


def test_a_taut_cable_over_a_capsule_wraps_on_a_circle():
    r, scene, (cap,), gaps = run(wrap_case())
    assert r.converged and min(gaps) > 0
    R, dhat = 0.3, cap.dhat
    C = np.array([0.0, 0.0, -0.5])
    S = np.array([1.0, 0.0, -0.4])
    s = float(np.linalg.norm((S - C)[[0, 2]]))
    tangent = math.atan2(S[2] - C[2], S[0] - C[0]) + math.acos(R / s)  # polar angle
    wrap = math.pi - 2 * tangent
    path = 2 * math.sqrt(s * s - R * R) + R * wrap
    L0 = 2 * math.hypot(1.0, 0.3) / 1.1
    T = 1000.0 * (path / L0 - 1.0)
    x = r.x
    assert np.abs(x[:, 1]).max() < 1e-9  # stays in its plane
    rel = x - C
    polar = np.arctan2(rel[:, 2], rel[:, 0])
    dist = np.hypot(rel[:, 0], rel[:, 2])
    on = (polar > tangent + 0.02) & (polar < math.pi - tangent - 0.02)
    assert on.sum() > 10
    assert np.all(dist[on] > R) and np.all(dist[on] - R < dhat)  # on the circle
    assert np.ptp(dist[on]) < 0.2 * dhat  # all at one gap: uniform tension, uniform load
    touching = np.zeros(len(x), bool)
    touching[cap.nodes] = cap.gap(x) < dhat
    assert np.all(touching[on])
    assert polar[touching].min() == pytest.approx(tangent, abs=0.03)  # the tangent points
    assert polar[touching].max() == pytest.approx(math.pi - tangent, abs=0.03)
    free = polar < tangent - 0.05  # the free span from the right support: straight
    tpt = C + R * np.array([math.cos(tangent), 0.0, math.sin(tangent)])
    line = (tpt - S) / np.linalg.norm(tpt - S)
    off = np.linalg.norm(np.cross(x[free] - S, line), axis=1)
    assert off.max() < 2 * dhat
    tension = scene.net.EA * (
        np.linalg.norm(x[scene.net.edges[:, 1]] - x[scene.net.edges[:, 0]], axis=1)
        / scene.net.rest_length
        - 1
    )
    assert tension.min() == pytest.approx(T, rel=0.01) and tension.max() == pytest.approx(
        T, rel=0.01
    )


def test_a_net_pressed_onto_a_box_face_lies_flat_on_it():
    r, scene, (box,), gaps = run(flat_case())
    assert r.converged and min(gaps) > 0
    x = r.x
    gap = np.full(len(x), np.inf)
    gap[box.nodes] = box.gap(x)
    assert gap.min() > 0
    top = -0.05
    inner = (np.abs(x[:, 0]) < 0.2) & (np.abs(x[:, 1]) < 0.15)  # well inside the top face
    inner &= ~scene.net.fixed
    assert inner.sum() > 20
    z = x[inner, 2]
    assert np.all(z > top) and np.all(z - top < box.dhat)  # on the face, gap < dhat
    assert np.ptp(z) < 0.1 * box.dhat  # flat: one plane
    assert np.all(gap[inner] == pytest.approx(z - top, abs=1e-12))


@pytest.mark.parametrize("dt", [1e-1, 1e-2, 1e-3])
@pytest.mark.parametrize("kind", ["box", "capsule", "mesh"])
def test_no_node_ever_enters_a_shape_a_net_falls_on(kind, dt, tmp_path):
    """The paper's net falls under its weight and a pressure onto a box, a capsule or a
    mesh (a sphere) below; at every accepted step of every step size each node stays
    outside, and it does touch."""
    case = flat_case(method="dynamic", dt=dt, t_end=0.25, damping=5.0)
    case["load"]["gravity"] = [0, 0, -9.81]
    if kind == "capsule":
        case["obstacle"] = [
            {
                "kind": "capsule",
                "start": [-0.2, -0.1, -0.3],
                "end": [0.2, 0.1, -0.3],
                "radius": 0.22,
                "distance": 0.01,
            }
        ]
    elif kind == "mesh":
        import meshio

        V, T = icosphere(2)
        meshio.write_points_cells(tmp_path / "ball.stl", 0.2 * V, [("triangle", T)])
        case["obstacle"] = [
            {
                "kind": "mesh",
                "file": str(tmp_path / "ball.stl"),
                "offset": [0, 0, -0.23],
                "distance": 0.01,
            }
        ]
    r, scene, (obstacle,), gaps = run(case)
    assert r.converged and len(gaps) >= 0.25 / dt
    assert min(gaps) > 0.0
    assert obstacle.gap(r.x).min() < obstacle.dhat  # it did touch


# --------------------------------------------------------------------------- input


@pytest.mark.parametrize(
    "obstacle, message",
    [
        (
            {"kind": "box", "center": [0, 0, -1], "half_size": [0.2, -0.1, 0.2]},
            "obstacle[0].half_size = [0.2, -0.1, 0.2]: must be 3 numbers > 0",
        ),
        ({"kind": "box", "center": [0, 0, -1]}, "obstacle[0].half_size: missing"),
        (  # every problem of the table at once: the bad history hid the half size
            {
                "kind": "box",
                "center": [0, 0, -1],
                "half_size": [0.2, -0.1, 0.2],
                "velocity": [0, 0, 1],
                "history": [[0.0, 0.0], [0.5, 1.0], [0.3, 1.0]],
            },
            "obstacle[0].half_size = [0.2, -0.1, 0.2]: must be 3 numbers > 0",
        ),
        (
            {"kind": "box", "center": [0, 0, -1], "half_size": [1, 1, 1], "axis": [0, 0, 0]},
            "obstacle[0].axis = [0, 0, 0]: must not be zero",
        ),
        (
            {"kind": "box", "center": [0, 0, 0], "half_size": [0.1, 0.1, 0.1]},
            "obstacle[0] (kind 'box'): node",
        ),
        (
            {"kind": "capsule", "start": [0, 0, -1], "end": [1, 0, -1], "radius": -0.2},
            "obstacle[0].radius = -0.2: must be finite and > 0",
        ),
        (
            {"kind": "capsule", "start": [0, 0, -1], "end": [0, 0, -1], "radius": 0.2},
            "obstacle[0].end = [0, 0, -1]: must differ from obstacle[0].start",
        ),
        (
            {"kind": "capsule", "start": [-1, 0, 0.1], "end": [1, 0, 0.1], "radius": 0.2},
            "obstacle[0] (kind 'capsule'): node",
        ),
        ({"kind": "mesh", "file": "nowhere.stl"}, "obstacle[0].file = 'nowhere.stl': no such file"),
        ({"kind": "mesh", "file": "open.stl"}, "obstacle[0].file = 'open.stl': is not closed"),
        (
            {"kind": "mesh", "file": "garbage.stl"},
            "obstacle[0].file = 'garbage.stl': meshio cannot",
        ),
        (
            {"kind": "mesh", "file": "lines.vtk"},
            "obstacle[0].file = 'lines.vtk': holds no triangles",
        ),
        ({"kind": "mesh", "file": "flipped.obj"}, "not consistently oriented"),
        ({"kind": "mesh"}, "obstacle[0].file: missing"),
        (
            {"kind": "mesh", "file": "cube.stl", "offset": [-0.5, -0.5, -0.9]},
            "obstacle[0] (kind 'mesh'): node",
        ),
        (
            {"kind": "mesh", "file": "cube.stl", "scale": 0},
            "obstacle[0].scale = 0: must be finite and > 0",
        ),
    ],
)
def test_bad_shapes_exit_2_with_their_key_path(tmp_path, obstacle, message):
    """Relative mesh paths are read beside the case file (the run starts elsewhere)."""
    import meshio
    from click.testing import CliRunner

    from catenet.cli import main

    cases = tmp_path / "cases"
    cases.mkdir()
    write_stl(cases / "open.stl", CUBE_V, CUBE_T[1:])
    write_stl(cases / "cube.stl", CUBE_V, CUBE_T)
    (cases / "garbage.stl").write_text("this is not a mesh\n")
    meshio.write_points_cells(cases / "lines.vtk", CUBE_V, [("line", np.array([[0, 1], [1, 2]]))])
    flipped = CUBE_T.copy()
    flipped[3] = flipped[3, ::-1]
    meshio.write_points_cells(cases / "flipped.obj", CUBE_V, [("triangle", flipped)])
    case = flat_case()
    case["obstacle"] = [obstacle]
    path = cases / "case.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert not (tmp_path / "out.h5").exists()


def test_a_mesh_path_is_relative_to_the_case_file_and_reads_back(tmp_path, monkeypatch):
    from catenet.case import load_case

    V, T = icosphere(1)
    (tmp_path / "cases").mkdir()
    write_stl(tmp_path / "cases" / "ball.stl", V, T)
    case = flat_case()
    case["obstacle"] = [{"kind": "mesh", "file": "ball.stl", "scale": 0.2, "offset": [0, 0, -0.25]}]
    (tmp_path / "cases" / "case.toml").write_text(dumps_toml(case))
    monkeypatch.chdir(tmp_path)
    parsed = load_case(tmp_path / "cases" / "case.toml")
    (obs,) = parsed.obstacles
    assert Path(obs.file) == (tmp_path / "cases" / "ball.stl").resolve()
    assert parse_case(__import__("tomllib").loads(parsed.to_toml())) == parsed
    (term,) = build(parsed).terms
    assert type(term).__name__ == "MeshBarrier" and len(term.triangles) == 80
    assert term.vertices[:, 2].min() == pytest.approx(-0.45)


# --------------------------------------------------------------------------- the capture scene


@pytest.mark.slow
def test_the_capture_example_runs_short_and_makes_a_figure_and_a_trajectory(tmp_path):
    """The example as a user runs it, shortened by --set: a result with a trajectory,
    its XDMF sidecar, a figure, and no node inside the box in any written frame."""
    from click.testing import CliRunner

    from catenet.case import load_case
    from catenet.cli import main
    from catenet.output.reader import read_frame, read_result

    assert CAPTURE.read_text().startswith("# ")
    out = tmp_path / "capture.h5"
    args = ["run", str(CAPTURE), "-o", str(out), "--set", "solver.t_end=0.6", "-q"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert out.with_suffix(".xdmf").is_file()
    count = len(read_result(out).times)
    frames = np.array([read_frame(out, k).x for k in range(count)])
    assert len(frames) > 20 and np.all(np.isfinite(frames))
    (box,) = build(load_case(CAPTURE)).terms
    times = read_result(out).times
    gaps = []
    for t, f in zip(times, frames, strict=True):
        box.set_pose(float(t))  # the box tumbles (catenet/terms/moving.py)
        gaps.append(float(box.gap(f).min()))
    assert min(gaps) > 0.0
    assert min(gaps) < box.dhat  # the net hit the box
    res = CliRunner().invoke(main, ["plot", str(out), "-o", str(tmp_path / "capture.png")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "capture.png").stat().st_size > 10_000
    # the figure draws the box where it is at the end of the run (catenet/plot/obstacles.py)
    from catenet.plot.obstacles import plotted_time, shapes

    assert plotted_time(read_result(out)) == pytest.approx(0.6)
    (drawn,) = shapes(read_result(out))
    box.set_pose(0.6)
    signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    corners = box.world(box.shape.center + (signs * box.shape.half) @ box.shape.axes.T)
    got = np.concatenate(drawn.polys)
    assert all(np.min(np.linalg.norm(got - c, axis=1)) < 1e-9 for c in corners)


@pytest.mark.parametrize("dt", [1e-5, 1e-4, 1e-3, 1e-2, 1e-1])
def test_the_capture_scene_is_stable_from_1e5_to_1e1_s_steps(dt):
    """At every step size: every accepted step is a converged implicit Euler step (its
    residual, computed here independently, is at the solver's tolerance), no state has
    a NaN or a node inside the box, and the net touches the box."""
    parsed = parse_case(capture_near(dt))
    scene = build(parsed)
    settings = Settings.of(parsed.solver)
    (box,) = scene.terms
    net = scene.net
    from catenet.solver.path import workspace

    system = workspace(scene, settings).system
    mass = net.mass[:, None]
    free = ~net.fixed
    v0 = np.zeros_like(net.nodes) if scene.velocity is None else scene.velocity
    prev = {"x": net.nodes.copy(), "v": v0.copy(), "t": 0.0}
    steps = []

    def check(s):
        x = s.x
        assert np.all(np.isfinite(x)) and np.all(np.isfinite(s.v))
        gap = float(box.gap(x).min())
        h = s.time - prev["t"]
        _, g = system.gradient(x)
        inertia = mass * ((x - prev["x"]) / h**2 - prev["v"] / h)
        inertia += settings.damping * mass * (x - prev["x"]) / h
        r = (inertia + g)[free]
        scale = np.abs(g[free]).max() + np.abs(inertia[free]).max()
        steps.append((gap, float(np.abs(r).max() / scale)))
        prev.update(x=x.copy(), v=s.v.copy(), t=s.time)

    r = solve(scene, settings, on_step=check)
    assert r.converged and np.all(np.isfinite(r.x))
    assert len(steps) >= 2
    gaps, residuals = zip(*steps, strict=True)
    assert min(gaps) > 0.0 and min(gaps) < box.dhat
    assert max(residuals) < 1e-6
