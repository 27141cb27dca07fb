"""Static and dynamic solvers: convergence, agreement with each other, with an
independent implementation and across linear-solver backends."""

from __future__ import annotations

import math

import numpy as np
import pytest

import catenet as cn
from catenet.solver.linear import pardiso_available
from catenet.solver.static import Workspace

MAT = cn.Material.from_E(10e6, radius=0.01, density=1000.0)  # the paper's cable
EA = MAT.EA
needs_pardiso = pytest.mark.skipif(not pardiso_available(), reason="MKL is not available here")


def net_scene(n=10, alpha=0.0, edge=0.05, p=100.0, gravity=False):
    sq = cn.square_net(n, alpha, 1.0, edge, MAT)
    g = np.array([0.0, 0.0, -9.81]) if gravity else None
    return sq, cn.Loads(force=cn.pressure_force(sq.net, p, 1.0), gravity=g)


def catenary_scene(nodes=21, dl=0.2):
    net = cn.cable([-0.5, 0, 0], [0.5, 0, 0], nodes, MAT)
    d = np.zeros((nodes, 3))
    d[0, 0], d[-1, 0] = dl / 2, -dl / 2
    return net, cn.Loads(gravity=np.array([0.0, 0.0, -9.81]), support_displacement=d)


def test_newton_converges_quadratically():
    """Near the solution the residual falls as r_{k+1} ~ C r_k^2: the observed order
    log(r_{k+1}/r_k) / log(r_k/r_{k-1}) reaches about 2 before the round-off floor."""
    sq, loads = net_scene(edge=0.02)
    r = cn.solve_static(sq.net, loads, rtol=1e-14)
    h = np.array(r.history)
    floor = 1e3 * h[-1]
    orders = [
        math.log(h[k + 1] / h[k]) / math.log(h[k] / h[k - 1])
        for k in range(1, len(h) - 1)
        if h[k + 1] > floor and h[k] < h[k - 1] and h[k + 1] < h[k]
    ]
    assert r.converged and r.iterations < 30
    assert max(orders) > 1.8


def test_paper_net_reference_deflection():
    """n = 34, alpha = pi/4, p = 100 Pa, 1 cm edges: delta/L = 0.0454 (an independent
    implementation of the same model gives 0.04539)."""
    sq, loads = net_scene(34, math.pi / 4, 0.01)
    r = cn.solve_static(sq.net, loads, rtol=1e-10)
    delta = -(r.x[sq.center, 2] - sq.net.nodes[sq.center, 2])
    assert delta == pytest.approx(0.0454, abs=5e-5)
    assert r.iterations < 40


def independent_equilibrium(nodes, edges, l0, ea, fixed, f):
    """A separate implementation of the same model: dense NumPy gradient and Hessian of
    the tension-only energy, Newton with a Levenberg-Marquardt shift and backtracking."""
    free = np.repeat(~fixed, 3)
    x = nodes.copy()

    def parts(x):
        e = x[edges[:, 1]] - x[edges[:, 0]]
        length = np.linalg.norm(e, axis=1)
        eps = length / l0 - 1
        taut = eps > 0
        energy = 0.5 * np.sum(ea * l0 * np.where(taut, eps, 0) ** 2) - np.sum(f * x)
        t = e / length[:, None]
        force = np.where(taut, ea * eps, 0)[:, None] * t
        g = np.zeros_like(x)
        np.add.at(g, edges[:, 1], force)
        np.subtract.at(g, edges[:, 0], force)
        g -= f
        H = np.zeros((x.size, x.size))
        for k in np.flatnonzero(taut):
            tt = np.outer(t[k], t[k])
            block = ea[k] / l0[k] * tt + ea[k] * eps[k] / length[k] * (np.eye(3) - tt)
            i, j = edges[k]
            for a, b, s in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
                H[3 * a : 3 * a + 3, 3 * b : 3 * b + 3] += s * block
        return energy, g.reshape(-1)[free], H[np.ix_(free, free)]

    lam = 1e-4 * np.max(ea / l0)
    energy, g, H = parts(x)
    for _ in range(2000):
        if np.linalg.norm(g) < 1e-11 * np.linalg.norm(f):
            return x
        trial = x.copy()
        trial.reshape(-1)[free] += np.linalg.solve(H + lam * np.eye(len(g)), -g)
        e_t, g_t, H_t = parts(trial)
        if e_t < energy or (
            abs(e_t - energy) < 1e-13 * abs(energy) and np.linalg.norm(g_t) < np.linalg.norm(g)
        ):
            x, energy, g, H = trial, e_t, g_t, H_t
            lam = lam / 3 if lam > 1e-14 * np.max(ea / l0) else 0.0
        else:
            lam = max(10 * lam, 1e-10 * np.max(ea / l0))
    raise AssertionError("the independent implementation did not converge")


def test_square_net_matches_an_independent_implementation():
    sq, loads = net_scene(10, 0.5, 0.1)
    net = sq.net
    r = cn.solve_static(net, loads, rtol=1e-12)
    x = independent_equilibrium(
        net.nodes, net.edges, net.rest_length, net.EA, net.fixed, loads.external_force(net)
    )
    delta, delta_ref = -r.x[sq.center, 2], -x[sq.center, 2]
    assert abs(delta - delta_ref) <= 1e-6 * delta_ref
    assert np.abs(r.x - x).max() <= 1e-6 * delta_ref


def test_static_and_dynamic_equilibria_agree():
    sq, loads = net_scene(10, 0.0, 0.1, gravity=True)
    s = cn.solve_static(sq.net, loads, rtol=1e-12)
    d = cn.solve_dynamic(sq.net, loads, dt=0.05, damping=5.0, t_end=200.0, rtol=1e-11)
    assert d.equilibrium and d.converged and d.time < 200.0
    assert np.abs(d.x - s.x).max() <= 1e-8 * np.abs(s.x[:, 2]).max()


@pytest.mark.parametrize("mu", [0.1, 1.0, 10.0])
def test_damping_does_not_change_the_equilibrium(mu):
    """Paper App. A: the damping coefficient changes the transient, not the result."""
    net, loads = catenary_scene(21, 0.2)
    s = cn.solve_static(net, loads, rtol=1e-12)
    d = cn.solve_dynamic(net, loads, dt=0.05, damping=mu, t_end=2000.0, rtol=1e-11)
    assert d.equilibrium
    assert np.abs(d.x - s.x).max() <= 1e-8


def test_dynamic_follows_the_paper_time_step():
    """One implicit Euler step from rest under a force F on a free particle between two
    slack edges: M (q1 - q0)/h^2 + mu M (q1 - q0)/h = F, so q1 - q0 = F h^2 / (M (1 + mu h))."""
    net = cn.Net.from_arrays(
        [[-1, 0, 0], [0, 0, 0], [1, 0, 0]],
        [[0, 1], [1, 2]],
        EA=1.0,
        fixed=[0, 2],
        rest_length=2.0,
        line_density=1.0,
    )
    F, h, mu = 3.0, 0.01, 2.0
    f = np.zeros((3, 3))
    f[1, 2] = F
    r = cn.solve_dynamic(
        net, cn.Loads(force=f), dt=h, damping=mu, t_end=h, stop_at_equilibrium=False, rtol=1e-12
    )
    M = net.mass[1]
    assert r.x[1, 2] == pytest.approx(F * h**2 / (M * (1 + mu * h)), rel=1e-12)
    assert r.v[1, 2] == pytest.approx(F * h / (M * (1 + mu * h)), rel=1e-12)


def test_failed_dynamic_steps_are_retried_smaller():
    """With only two Newton iterations allowed, the long first steps of a sudden load
    fail; the solver halves them instead of accepting them, and still gets there."""
    sq, loads = net_scene(10, 0.0, 0.1)
    s = cn.solve_static(sq.net, loads, rtol=1e-10)
    d = cn.solve_dynamic(sq.net, loads, dt=1.0, damping=1.0, t_end=500.0, rtol=1e-9, max_iter=2)
    assert d.equilibrium
    assert d.steps > d.time / 1.0  # some steps were shorter than dt
    assert np.abs(d.x - s.x).max() <= 1e-6 * np.abs(s.x[:, 2]).max()


def test_dynamic_needs_mass():
    net = cn.cable([0, 0, 0], [1, 0, 0], 5, cn.Material(EA=10.0))
    with pytest.raises(cn.ConfigError, match="density"):
        cn.solve_dynamic(net, cn.Loads(), dt=0.1, damping=1.0, t_end=1.0)


@needs_pardiso
def test_backends_agree():
    sq, loads = net_scene(10, 0.3, 0.05)
    a = cn.solve_static(sq.net, loads, rtol=1e-12, linear="pardiso")
    b = cn.solve_static(sq.net, loads, rtol=1e-12, linear="scipy")
    assert a.stats.backend == "pardiso" and b.stats.backend == "scipy"
    assert np.abs(a.x - b.x).max() <= 1e-10


@needs_pardiso
@pytest.mark.parametrize("mtype", [2, -2, 11])
def test_pardiso_matrix_types_agree(mtype):
    sq, loads = net_scene(10, 0.3, 0.05)
    ref = cn.solve_static(sq.net, loads, rtol=1e-12, linear="scipy")
    ws = Workspace(sq.net, mtype=mtype)
    r = cn.solve_static(sq.net, loads, rtol=1e-12, workspace=ws)
    assert np.abs(r.x - ref.x).max() <= 1e-10
    assert ws.solver.stats["analyse"] == 1  # analysed once, refactorised per iteration
    assert ws.solver.stats["factorize"] >= r.iterations


def test_repeated_runs_are_bit_identical():
    sq, loads = net_scene(10, 0.3, 0.05, gravity=True)
    a = cn.solve_static(sq.net, loads, rtol=1e-10)
    b = cn.solve_static(sq.net, loads, rtol=1e-10)
    assert np.array_equal(a.x, b.x) and a.iterations == b.iterations


def test_continuation_traces_a_force_displacement_curve():
    sq, loads = net_scene(10, 0.0, 0.05)
    factors = [0.01, 0.1, 0.3, 1.0]
    seen = []
    curve = cn.continuation(sq.net, loads, factors, rtol=1e-10, on_step=lambda f, r: seen.append(f))
    deltas = [-r.x[sq.center, 2] for r in curve]
    assert seen == factors and np.all(np.diff(deltas) > 0)
    direct = cn.solve_static(sq.net, loads, rtol=1e-10)
    assert np.abs(curve[-1].x - direct.x).max() <= 1e-8 * deltas[-1]
    # The cable-net law: delta ~ p^(1/3) at small loads (stiffening membrane).
    slope = math.log(deltas[1] / deltas[0]) / math.log(10.0)
    assert slope == pytest.approx(1 / 3, abs=0.02)


@pytest.mark.parametrize("nodes, dl", [(21, 0.05), (161, 0.2), (641, 0.5)])
def test_compressed_catenary_in_tens_of_iterations(nodes, dl):
    """Supports moved inward: every edge starts slack. The smoothing continuation of the
    static solver reaches the round-off floor in tens of iterations at any resolution."""
    net, loads = catenary_scene(nodes, dl)
    r = cn.solve_static(net, loads, rtol=1e-10)
    assert r.converged and r.iterations <= 40
    assert r.tension.min() > 0  # a hanging cable is taut everywhere
    assert_balanced(r, loads, net)


def assert_balanced(r, loads, net):
    """Reactions and loads sum to the sum of the free nodes' residual forces: zero up to
    the converged residual (sum of n terms <= sqrt(n) |r|) and round-off."""
    total = r.reaction.sum(axis=0) + loads.external_force(net).sum(axis=0)
    bound = np.sqrt(3 * net.n_nodes) * r.residual + 1e-12 * np.abs(r.reaction).sum()
    assert np.linalg.norm(total) <= bound


@pytest.mark.parametrize("ea", [1e-2, 1e2, 1e9])
def test_stiff_and_soft_cables_converge(ea):
    net, loads = catenary_scene(51, 0.2)
    net = net.with_rest_length(net.rest_length)
    soft = cn.Net.from_arrays(
        net.nodes, net.edges, EA=ea, fixed=net.fixed, line_density=MAT.line_density
    )
    r = cn.solve_static(soft, loads, rtol=1e-10, max_iter=100)
    assert r.converged
    assert_balanced(r, loads, soft)
    # The residual is 1e-10 of the weight unless the strain round-off EA eps |x| / l0
    # (1e-5 N for EA = 1e9) is larger: no solver gets below that in double precision.
    weight = np.abs(loads.external_force(soft)).sum()
    assert r.residual <= max(1e-10 * weight, 4e-16 * ea * 0.5 / 0.02 * np.sqrt(50) * 2)


def test_unconverged_static_raises_with_history():
    sq, loads = net_scene(10, 0.0, 0.05)
    with pytest.raises(cn.ConvergenceError) as info:
        cn.solve_static(sq.net, loads, rtol=1e-12, max_iter=3)
    assert info.value.iterations == 3 and len(info.value.history) >= 2
    assert info.value.state.shape == sq.net.nodes.shape


def test_predictor_is_exact_for_linear_paths_and_cheapens_load_curves():
    from catenet.solver.start import predict

    a, b = np.array([[0.0, 1.0, 2.0]]), np.array([[1.0, 3.0, 2.0]])
    assert np.allclose(predict([a, b], [1.0, 2.0], 4.0), a + 3 * (b - a))
    assert np.allclose(predict([a, b], [2.0, 2.0], 4.0), b)  # no extrapolation
    sq, loads = net_scene(10, 0.0, 0.05)
    levels = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    curve = cn.continuation(sq.net, loads, levels, rtol=1e-10)
    later = [r.iterations for r in curve[2:]]
    assert max(later) <= 4  # each level from the extrapolated pair, not from scratch


def test_nodes_on_slack_edges_only_are_reported(caplog):
    """A cable whose ends moved inward, with no load: every edge is slack, any position
    of the free nodes is an equilibrium; the solver says so instead of pretending."""
    net = cn.cable([-0.5, 0, 0], [0.5, 0, 0], 5, MAT)
    d = np.zeros((5, 3))
    d[0, 0], d[-1, 0] = 0.1, -0.1
    with caplog.at_level("WARNING", logger="catenet.solver.endstate"):
        r = cn.solve_static(net, cn.Loads(support_displacement=d))
    assert r.converged and not r.tension.any()
    assert "3 free nodes hang on slack edges only" in caplog.text


@pytest.mark.parametrize("linear", ["auto", "scipy"])
@pytest.mark.roundoff
def test_an_unstable_equilibrium_is_flagged(linear, caplog):
    """A straight bilateral cable compressed by its supports is in equilibrium, an
    unstable one (no bending stiffness): flagged, not passed off as a plain answer."""
    net = cn.Net.from_arrays(
        [[x, 0, 0] for x in np.linspace(0, 1, 11)],
        [[k, k + 1] for k in range(10)],
        EA=100.0,
        fixed=[0, 10],
        tension_only=False,
    )
    d = np.zeros((11, 3))
    d[10, 0] = -0.1
    with caplog.at_level("WARNING", logger="catenet.solver.endstate"):
        r = cn.solve_static(net, cn.Loads(support_displacement=d), linear=linear)
    assert r.converged and r.stable is False
    assert "unstable" in caplog.text
    # Stretched instead of compressed: stable.
    r = cn.solve_static(net, cn.Loads(support_displacement=-d), linear=linear)
    assert r.stable is True


@pytest.mark.parametrize("nodes", [41, 161, 641])
def test_nearly_inextensible_cable_in_tens_of_iterations(nodes):
    """EA = 1e9 N under its own weight (strains of 1e-9): the stiffness continuation
    (EA scaled down, then raised a hundredfold per stage) keeps Newton within tens of
    iterations at any resolution."""
    mat = cn.Material(EA=1e9, line_density=MAT.line_density)
    net = cn.cable([0.0, 0.0, 0.0], [1.0, 0.0, -0.3], nodes, mat, length=1.3)
    loads = cn.Loads(gravity=np.array([0.0, 0.0, -9.81]))
    r = cn.solve_static(net, loads, rtol=1e-10)
    assert r.converged and r.iterations <= 60
    assert_balanced(r, loads, net)


def test_a_net_too_stiff_for_double_precision_is_explained():
    """EA = 1e12 N on 1.6 mm edges: the force round-off (EA eps |x| / l0, about 16 N)
    exceeds the whole weight (4 N); no solver can resolve it, and the error says why."""
    mat = cn.Material(EA=1e12, line_density=MAT.line_density)
    net = cn.cable([0.0, 0.0, 0.0], [1.0, 0.0, -0.3], 801, mat, length=1.3)
    with pytest.raises(cn.ConvergenceError, match="double precision"):
        cn.solve_static(net, cn.Loads(gravity=np.array([0.0, 0.0, -9.81])), max_iter=60)


# --- MKL's runtime, found once and directly (issue 13) -----------------------------------


@pytest.fixture
def fresh_mkl_lookup(monkeypatch):
    """A lookup that starts over (the runtime is found once per process and override)."""
    import catenet.solver.linear as ls

    ls._find_mkl.cache_clear()
    monkeypatch.setattr(ls, "_warned", set())
    yield ls
    ls._find_mkl.cache_clear()


def test_missing_mkl_falls_back_to_scipy_with_one_warning(fresh_mkl_lookup, monkeypatch, caplog):
    """CATENET_MKL_RT pointing nowhere: MKL is absent; 'auto' solves with SciPy and says
    so once, 'pardiso' is refused with the variable and what to do."""
    ls = fresh_mkl_lookup
    monkeypatch.setenv("CATENET_MKL_RT", "/nowhere/libmkl_rt.so.2")
    with caplog.at_level("WARNING", logger="catenet.solver.linear"):
        assert ls.resolve_backend("auto") == "scipy"
        assert ls.resolve_backend("auto") == "scipy"
        sq, loads = net_scene(6, edge=0.1)
        r = cn.solve_static(sq.net, loads)
    assert r.converged and r.stats.backend == "scipy"
    warnings = [m for m in caplog.messages if "CATENET_MKL_RT" in m]
    assert len(warnings) == 1, caplog.messages
    assert "/nowhere/libmkl_rt.so.2" in warnings[0] and "SciPy" in warnings[0]
    assert not ls.pardiso_available()
    with pytest.raises(cn.ConfigError, match="solver.linear = 'pardiso'.*CATENET_MKL_RT"):
        ls.resolve_backend("pardiso")


def test_mkl_missing_everywhere_names_the_override(fresh_mkl_lookup, monkeypatch):
    """No library in any place searched (the lookup simulated empty): the message says
    where catenet looked and which variable points it to the library."""
    ls = fresh_mkl_lookup
    for var in ("CATENET_MKL_RT", "PYPARDISO_MKL_RT"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setattr(ls, "mkl_candidates", lambda: (None, ["/nowhere/libmkl_rt.so.9"]))
    with pytest.raises(ls.MklNotFound, match="CATENET_MKL_RT"):
        ls.mkl_runtime()
    assert ls.mkl_problem().startswith("MKL's runtime library (libmkl_rt) was not found")


@needs_pardiso
def test_mkl_is_found_directly_and_without_pypardiso(fresh_mkl_lookup, monkeypatch, caplog):
    """The mkl wheel's library is found under sys.prefix (or where the override points),
    without a warning, and PARDISO solves through it; pypardiso is never imported."""
    import subprocess
    import sys

    ls = fresh_mkl_lookup
    monkeypatch.delenv("CATENET_MKL_RT", raising=False)
    monkeypatch.delenv("PYPARDISO_MKL_RT", raising=False)
    path = ls.mkl_runtime().path
    monkeypatch.setenv("CATENET_MKL_RT", path)
    with caplog.at_level("WARNING", logger="catenet.solver.linear"):
        assert ls.resolve_backend("auto") == "pardiso"
        sq, loads = net_scene(6, edge=0.1)
        assert cn.solve_static(sq.net, loads).stats.backend == "pardiso"
    assert ls.mkl_runtime().path == path and not caplog.messages
    code = (
        "import sys, catenet as cn, numpy as np\n"
        "sq = cn.square_net(6, 0.0, 1.0, 0.1, cn.Material(EA=1e4, line_density=0.1))\n"
        "r = cn.solve_static(sq.net, cn.Loads(force=cn.pressure_force(sq.net, 1.0, 1.0)))\n"
        "assert r.stats.backend == 'pardiso'\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'pypardiso'"
        " or m.startswith('scipy.sparse')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_components_label_every_part_of_a_graph():
    """Union-find in NumPy (no SciPy): labels agree with SciPy's connected components on
    random graphs, numbered in order of their first node."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(7)
    for n, m in [(1, 0), (2, 1), (40, 25), (500, 300), (3000, 3200)]:
        for _ in range(5):
            edges = rng.integers(0, n, (m, 2)) if m else np.zeros((0, 2), dtype=np.int64)
            edges = edges[edges[:, 0] != edges[:, 1]] if m else edges
            stub = type("Stub", (), {"n_nodes": n, "edges": edges})()
            labels = cn.Net.components(stub)
            ref = connected_components(
                coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), (n, n)),
                directed=False,
            )[1]
            _, first, inverse = np.unique(ref, return_index=True, return_inverse=True)
            rank = np.argsort(np.argsort(first))
            assert np.array_equal(labels, rank[inverse])
    # A net with an unsupported part is refused (the check that uses the labels).
    with pytest.raises(cn.ConfigError, match="has no support"):
        cn.Net.from_arrays(
            [[0, 0, 0], [1, 0, 0], [5, 0, 0], [6, 0, 0]],
            [[0, 1], [2, 3]],
            EA=1.0,
            fixed=[0],
        )


def test_linear_nets_use_kernels_without_the_other_laws():
    """Every edge linear: the kernels get law None and compile without the other laws;
    the numbers are those of the general kernels, bit for bit."""
    from catenet.kernels.stretch import stretch_gradient, stretch_hessian, stretch_tension
    from catenet.model.laws import Law

    sq, loads = net_scene(6, edge=0.1)
    net = sq.net
    law = net.law
    assert law.kernel_kind is None
    rng = np.random.default_rng(3)
    x = net.nodes + 0.01 * rng.standard_normal(net.nodes.shape)
    args = (net.edges, net.rest_length, net.EA)
    for smooth in (0.0, 1e-3):
        for kind in (None, law.kind):
            g = np.zeros_like(x)
            e = stretch_gradient(x, *args, kind, law.params, law.table, law.tension_only,
                                 smooth, g)  # fmt: skip
            h = np.zeros(36 * net.n_edges)
            stretch_hessian(x, *args, kind, law.params, law.table, law.tension_only, smooth, h)
            t = np.zeros(net.n_edges)
            stretch_tension(x, *args, kind, law.params, law.table, law.tension_only, t)
            if kind is None:
                ref = (e, g, h, t)
            else:
                assert e == ref[0]
                for a, b in zip((g, h, t), ref[1:], strict=True):
                    assert np.array_equal(a, b)
    mixed = Law.uniform(net.n_edges, "hencky")
    assert mixed.kernel_kind is mixed.kind


# --- bilateral cables compressed by their supports (issue 13) ----------------------------


@pytest.mark.parametrize(
    "ratio, dL", [(1e2, 0.9), (1e6 / 9.81, 0.1), (1e5, 0.5), (1e9, 0.01), (1e9, 0.3)]
)
def test_compressed_bilateral_cable_hangs_like_the_tension_only_one(ratio, dL):
    """A bilateral cable (the paper's own energy) under light self-weight whose supports
    moved inward, in one load step: the hanging chain, every edge in tension, the same
    state as the tension-only cable's (it used to stall near the unstable straight state:
    200 iterations, residual 50 N, for EA = 1e6 N, rho A = 1 kg/m, 10 %)."""
    from catenet.validate import analytic

    nodes, w = 41, 9.81
    results = []
    for tension_only in (True, False):
        mat = cn.Material(EA=ratio * w, line_density=1.0, tension_only=tension_only)
        net = cn.cable([-0.5, 0, 0], [0.5, 0, 0], nodes, mat)
        d = np.zeros((nodes, 3))
        d[0, 0], d[-1, 0] = dL / 2, -dL / 2
        loads = cn.Loads(gravity=np.array([0.0, 0.0, -9.81]), support_displacement=d)
        r = cn.solve_static(net, loads)
        assert r.converged and r.iterations < 100
        assert np.min(r.tension) > 0.0
        results.append(r)
    bilateral = results[1]
    assert bilateral.stable is True
    exact = analytic.discrete_catenary(1.0, ratio * w, w, 1.0 - dL, nodes - 1).sag
    assert -bilateral.x[nodes // 2, 2] == pytest.approx(exact, rel=1e-6)
    assert np.max(np.abs(bilateral.x - results[0].x)) < 1e-6 * exact
