"""Surface targets on a smooth height field (`[[target]] smooth = true`: the C1 field
through the mesh's vertices), and the large search's pieces: its slopes are its
derivative and continuous across the triangles' edges (the flat triangles' jump), the
adjoint Jacobian on it against finite differences, a roof that meets it, the rows'
preconditioner kept between states (one analysis per search) and equal to its formula,
the self-weight's shape started from the last one's weight, and the summary's count of
products with the Jacobians.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from click.testing import CliRunner
from scenes import hypar_on_surface

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.formfind import krylov
from catenet.formfind.case import formfind_scene
from catenet.formfind.surface import read_height_field


def roof(tmp_path, n: int, smooth: bool = True) -> dict:
    data, _ = hypar_on_surface(tmp_path, n)
    data["target"][0]["smooth"] = smooth
    return data


def test_the_smooth_field_has_continuous_slopes_that_are_its_derivative(tmp_path):
    """On the hypar's mesh: f's slopes against central differences of f (inside the
    triangles), and across a triangle's edge the smooth slopes agree where the flat
    triangles' jump by the curvature times the mesh size."""
    hypar_on_surface(tmp_path, 8)  # (writes surface.obj: 16 x 16 squares of two triangles)
    file = str(tmp_path / "surface.obj")
    smooth, flat = read_height_field(file, True), read_height_field(file, False)
    rng = np.random.default_rng(1)
    p = np.column_stack([rng.uniform(-11.0, 11.0, (40, 2)), np.zeros(40)])
    f, grad = smooth.offset(p)
    h = 1e-6
    for c in range(2):
        e = np.zeros(3)
        e[c] = h
        fd = -(smooth.offset(p + e)[0] - smooth.offset(p - e)[0]) / (2 * h)
        assert np.abs(fd - grad[:, c]).max() <= 1e-6
    # A vertical grid line of the mesh (x = -10.5): both sides 1e-7 apart.
    side = np.array([[-10.5 - 1e-7, 0.2, 0.0], [-10.5 + 1e-7, 0.2, 0.0]])
    jump_smooth = np.abs(np.diff(smooth.offset(side)[1], axis=0)).max()
    jump_flat = np.abs(np.diff(flat.offset(side)[1], axis=0)).max()
    assert jump_flat > 1e-3 and jump_smooth < 1e-5


def test_the_adjoint_jacobian_on_a_smooth_surface_is_the_finite_differences_one(tmp_path):
    """The hypar's rows on the smooth field under self-weight: J by adjoint solves
    against central differences of the residual."""
    from catenet.formfind.design import _Search
    from catenet.formfind.fdm import _Shape
    from catenet.formfind.goals import resolve_goals

    case = parse_case(roof(tmp_path, 5), base_dir=tmp_path)
    scene = build(case)
    net = scene.net
    shape = _Shape(net, np.zeros((net.n_nodes, 3)), scene.loads.gravity, "auto", "q")
    goals = resolve_goals(case.targets, scene, shape.size, 1e-30)
    rng = np.random.default_rng(0)
    m = net.n_edges
    search = _Search(shape, goals, np.arange(m), np.log(1e4) + 0.1 * rng.standard_normal(m))
    s = 0.1 * rng.standard_normal(m)
    whole = np.asarray(search.jacobian(s))
    h = 1e-6
    fd = np.column_stack(
        [(search.residual(s + h * e) - search.residual(s - h * e)) / (2 * h) for e in np.eye(m)]
    )
    scale = np.abs(whole).max()
    assert np.abs(fd).max() > 1e-3 * scale
    assert np.abs(whole - fd).max() <= 1e-6 * scale


def test_a_roof_meets_its_smooth_surface_by_conjugate_residuals(tmp_path, monkeypatch):
    """480 force densities (the steps by conjugate residuals, as at 10^4) put the 225
    free nodes on the smooth field, checked against matplotlib's own C1 interpolant of the
    mesh; the summary names the smooth surface and counts the products with the
    Jacobians; the rows' preconditioner was analysed once for the whole search."""
    from matplotlib.tri import CubicTriInterpolator, Triangulation

    monkeypatch.setattr(krylov, "FROM_DOFS", 0)
    data = roof(tmp_path, 16)
    got = formfind_scene(build(parse_case(data, base_dir=tmp_path)))
    d = got.design
    steps = d.extra["steps"]
    assert d.all_met and steps["iterative"] > 0 and steps["fallbacks"] == 0
    assert steps["products"] >= 2 * steps["iterations"]
    field = read_height_field(str(tmp_path / "surface.obj"), True)
    v, t = field.vertices, field.triangles
    f = CubicTriInterpolator(Triangulation(v[:, 0], v[:, 1], t), v[:, 2], kind="geom")
    x = got.x[~np.asarray(got.net.fixed)]
    size = float(np.linalg.norm(np.ptp(got.net.nodes, axis=0)))
    assert np.abs(x[:, 2] - f(x[:, 0], x[:, 1])).max() <= 1e-9 * size
    case = tmp_path / "roof.toml"
    case.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["formfind", str(case), "-o", str(tmp_path / "out.h5")])
    assert r.exit_code == 0, r.output
    assert "free nodes on surface.obj (smooth)" in r.output
    assert f"{steps['products']} products with the Jacobians (a solve each)" in r.output


def test_the_rows_preconditioner_is_its_formula_and_kept_between_states(tmp_path):
    """M^-1 = D (E E^T + mu D^2 + floor)^-1 D against dense algebra, at two states of one
    search: the same factors' object, analysed once, refilled."""
    from catenet.formfind.design import _Search
    from catenet.formfind.fdm import _Shape
    from catenet.formfind.goals import resolve_goals

    case = parse_case(roof(tmp_path, 6, smooth=False), base_dir=tmp_path)
    scene = build(case)
    net = scene.net
    shape = _Shape(net, np.zeros((net.n_nodes, 3)), scene.loads.gravity, "auto", "q")
    goals = resolve_goals(case.targets, scene, shape.size, 1e-30)
    m = net.n_edges
    search = _Search(shape, goals, np.arange(m), np.full(m, np.log(1e4)))
    rng = np.random.default_rng(2)
    kept = None
    for s in (np.zeros(m), 0.1 * rng.standard_normal(m)):
        search.residual(s)
        q, x, _, a = search.state(s)
        d_x, d_q = search.partials(x, q, a)
        from catenet.formfind.adjoint import Adjoint, jacobian_operator

        op = jacobian_operator(
            Adjoint(shape, q, x), d_x, d_q, sp.diags(q) @ search.p, kept=search.kept
        )
        rows = krylov.Rows.make(op)
        assert rows is not None
        keep = rng.random(m) > 0.2
        mu = 1e-3
        rows.factorize(mu, keep)
        if kept is None:
            kept = rows.factors
        assert rows.factors is kept and kept.solver.stats["analyse"] == 1
        dd = rows.d_rows.toarray()
        e = (op.d_x @ op.bs).toarray() * keep
        ee = e @ e.T
        mat = ee + mu * dd @ dd + 1e-12 * ee.diagonal().max() * np.eye(len(dd))
        z = rng.standard_normal(len(dd))
        expected = dd @ np.linalg.solve(mat, dd @ z)
        assert np.abs(rows(z) - expected).max() <= 1e-9 * np.abs(expected).max()


@pytest.mark.parametrize("weighs", [True, False])
def test_a_shape_after_another_is_the_shape_found_afresh(tmp_path, weighs):
    """The self-weight's fixed point starts from the last shape's weight: the shape at q
    after one at another q is the one found from no weight, to round-off."""
    from catenet.formfind.fdm import _Shape

    scene = build(parse_case(roof(tmp_path, 6, smooth=False), base_dir=tmp_path))
    net = scene.net
    gravity = scene.loads.gravity if weighs else None
    rng = np.random.default_rng(3)
    q1, q2 = 1e4 * np.exp(0.3 * rng.standard_normal((2, net.n_edges)))
    after = _Shape(net, np.zeros((net.n_nodes, 3)), gravity, "auto", "q")
    after(q1)
    x_after, load_after = after(q2)
    fresh = _Shape(net, np.zeros((net.n_nodes, 3)), gravity, "auto", "q")
    x_fresh, load_fresh = fresh(q2)
    assert np.abs(x_after - x_fresh).max() <= 1e-12 * np.abs(x_fresh).max()
    assert np.abs(load_after - load_fresh).max() <= 1e-12 * max(np.abs(load_fresh).max(), 1.0)


class PublicCalls:
    """An interpolant seen through its public calls alone."""

    def __init__(self, f):
        self._f = f

    def __call__(self, x, y):
        return self._f(x, y)

    def gradient(self, x, y):
        return self._f.gradient(x, y)


@pytest.mark.parametrize("smooth, public", [(False, False), (True, False), (True, True)])
def test_offsets_follow_points_from_triangle_to_triangle(tmp_path, monkeypatch, smooth, public):
    """The field keeps each point's last triangle and seeks anew only those that left it:
    points moved across many triangles, some onto the mesh's vertices, some off its plan,
    give matplotlib's interpolants' values and slopes (NaN off the plan). ``public``:
    also with matplotlib's public calls alone (should a version drop its private one)."""
    from matplotlib.tri import CubicTriInterpolator, LinearTriInterpolator, Triangulation

    hypar_on_surface(tmp_path, 6)
    field = read_height_field(str(tmp_path / "surface.obj"), smooth)
    if public:
        monkeypatch.setattr(field, "_f", PublicCalls(field._f))
    v, t = field.vertices, field.triangles
    tri = Triangulation(v[:, 0], v[:, 1], t)
    f = (
        CubicTriInterpolator(tri, v[:, 2], kind="geom")
        if smooth
        else LinearTriInterpolator(tri, v[:, 2])
    )
    rng = np.random.default_rng(4)
    p = np.column_stack([rng.uniform(-11.9, 11.9, (60, 2)), rng.uniform(-1.0, 1.0, 60)])
    for step in range(4):
        if step:
            p[:, :2] += rng.uniform(-3.0, 3.0, (60, 2))
            p[:5, :2] = v[rng.integers(len(v), size=5), :2]
        got, grad = field.offset(p)
        z = np.ma.filled(f(p[:, 0], p[:, 1]), np.nan)
        off = np.isnan(z)
        assert np.array_equal(np.isnan(got), off)
        assert np.abs(got[~off] - (p[~off, 2] - z[~off])).max() <= 1e-12
        inner = ~off
        inner[:5] = False  # (on a vertex the slope is one of its triangles')
        slopes = np.column_stack([np.ma.filled(g, np.nan) for g in f.gradient(p[:, 0], p[:, 1])])
        assert np.abs(grad[inner] - slopes[inner]).max() <= 1e-12


def test_the_guides_saddle_smooth_and_flat(tmp_path):
    """The form-finding guide's saddle roof mesh (vertices every 0.5 m on its formula): the
    smooth field departs from the flat triangles by 3.6 mm at most, from the formula by
    2.7 mm, the flat triangles by 3.5 mm (on a 0.05 m grid of points)."""

    def roof(x, y):
        return (x**2 - y**2) / 24 - 0.5 * (1 - x**2 / 36) * (1 - y**2 / 36)

    t = np.linspace(-6.0, 6.0, 25)
    x, y = np.meshgrid(t, t)
    lines = [f"v {a} {b} {roof(a, b)}" for a, b in zip(x.ravel(), y.ravel(), strict=True)]
    for j in range(24):
        for i in range(24):
            a = 25 * j + i + 1
            lines += [f"f {a} {a + 1} {a + 26}", f"f {a} {a + 26} {a + 25}"]
    (tmp_path / "roof.obj").write_text("\n".join(lines) + "\n")
    g = np.linspace(-6.0, 6.0, 241)
    gx, gy = np.meshgrid(g, g)
    p = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    smooth = -read_height_field(str(tmp_path / "roof.obj"), True).offset(p)[0]
    flat = -read_height_field(str(tmp_path / "roof.obj"), False).offset(p)[0]
    exact = roof(p[:, 0], p[:, 1])
    assert round(float(np.abs(smooth - flat).max()), 4) == 0.0036
    assert round(float(np.abs(smooth - exact).max()), 4) == 0.0027
    assert round(float(np.abs(flat - exact).max()), 4) == 0.0035
