"""Natural modes (catenet.solver.modes) against closed forms, published results and
themselves.

Closed forms: the taut string (lateral and axial), Irvine & Caughey's sagging cable and
the prestressed orthogonal net as a membrane, each with its derivation and an observed
order of the discretisation error where the closed form is the discrete model's limit.
Published: ANSYS VM53 (a string under tension) and code_aster SDNL138 (its cables).
Consistency: node numbering, M-orthonormality, dense against Lanczos, effective masses,
zero-frequency modes named.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import catenet
from catenet.errors import ConfigError
from catenet.model.builders import Material, cable
from catenet.model.net import Loads, Net
from catenet.solver.modes import natural_modes
from catenet.solver.path import Settings, workspace


def taut_cable(length, tension, EA, rho_a, edges, axis=0):
    """A straight cable of stretched length ``length`` along ``axis`` pinned at both ends
    whose rest length makes every edge carry ``tension`` (linear law: eps = T / EA)."""
    end = [0.0, 0.0, 0.0]
    end[axis] = length
    return cable(
        [0, 0, 0], end, edges + 1, Material(EA=EA, line_density=rho_a),
        length=length / (1 + tension / EA),
    )  # fmt: skip


def order(h, err) -> float:
    return float(np.polyfit(np.log(h), np.log(err), 1)[0])


# --------------------------------------------------------------------------------------
# Taut string
# --------------------------------------------------------------------------------------


def test_taut_string_lateral_and_axial_second_order():
    """A straight cable of stretched length L between pins, tension T, EA, rho A per
    unstressed length (mu = rho A / (1 + eps) per stretched length, eps = T / EA).

    Lateral: a small deflection w(s, t) obeys mu w_tt = T w_ss (the tension's vertical
    component T w_s; the axial strain changes at second order only), w = 0 at the pins:
    w = sin(n pi s / L) cos(omega t), f_n = n / (2 L) sqrt(T / mu), once in y and once in
    z (3D: each twice). Axial, in the unstressed coordinate S in [0, L0]: rho A u_tt =
    EA u_SS (the linear law N = EA (u_S + eps)), f_n = n / (2 L0) sqrt(EA / (rho A)).

    The discrete chain (lumped masses mu h, lateral springs T / h, axial springs EA / l0)
    has omega_n = 2 sqrt(k / m) sin(n pi / (2 N_e)), whose relative error against the
    continuum is (n pi h / L)^2 / 24: second order in the edge length h. Fitted over
    N_e = 20, 40, 80 the slope of log(error) against log(h) is 2.
    """
    L, EA, rho_a = 10.0, 1e6, 0.5
    T = 0.04 * EA  # axial modes among the lowest: f_ax / f_lat = sqrt(EA (1 + eps) / T) ~ 5
    eps = T / EA
    mu = rho_a / (1 + eps)
    lateral = np.arange(1, 6) / (2 * L) * math.sqrt(T / mu)
    axial = 1 / (2 * L / (1 + eps)) * math.sqrt(EA / rho_a)
    hs, err_lat, err_ax = [], [], []
    for edges in (20, 40, 80):
        modes = catenet.modes(taut_cable(L, T, EA, rho_a, edges), None, 11)
        dom = np.array(modes.dominant())
        f_lat = modes.frequency[dom != "x"][:10]
        f_ax = modes.frequency[dom == "x"][0]
        np.testing.assert_allclose(f_lat[0::2], f_lat[1::2], rtol=1e-10)  # y and z pairs
        assert set(dom[dom != "x"][:10]) == {"y", "z"}
        rel = np.abs(f_lat[0::2] / lateral - 1)
        hs.append(L / edges)
        err_lat.append(rel[0])
        err_ax.append(abs(f_ax / axial - 1))
        bound = (np.arange(1, 6) * np.pi / edges) ** 2 / 24  # the leading error term
        assert np.all(rel < 1.05 * bound) and err_ax[-1] < 1.05 * bound[0]
        # The discrete chain exactly: omega_n = 2 sqrt(T / (mu h^2)) sin(n pi / (2 N_e)).
        h = L / edges
        exact = np.sqrt(4 * T / (mu * h * h)) * np.sin(np.arange(1, 6) * np.pi / (2 * edges))
        np.testing.assert_allclose(f_lat[0::2], exact / (2 * np.pi), rtol=1e-9)
    assert order(hs, err_lat) == pytest.approx(2.0, abs=0.05)
    assert order(hs, err_ax) == pytest.approx(2.0, abs=0.05)


def test_lanczos_matches_dense_and_is_m_orthonormal():
    """The same modes by the shift-invert Lanczos path and by the dense solver; the
    shapes are M-orthonormal to 1e-10 (Phi^T M Phi = I) and every mode satisfies
    K phi = omega^2 M phi to round-off."""
    net = taut_cable(3.0, 200.0, 2e5, 0.3, 60, axis=1)
    ws = workspace(catenet.scene.Scene(net, Loads()), Settings())
    x = catenet.modes(net, None, 1).x
    dense = natural_modes(ws, x, 12, method="dense")
    lanczos = natural_modes(ws, x, 12, method="lanczos")
    np.testing.assert_allclose(lanczos.frequency, dense.frequency, rtol=1e-10)
    m = net.mass
    for found in (dense, lanczos):
        phi = found.shape.reshape(found.count, -1)
        gram = phi @ (np.repeat(m, 3)[:, None] * phi.T)
        np.testing.assert_allclose(gram, np.eye(found.count), atol=1e-10)
        assert found.stats["residual"] < 1e-9
    assert lanczos.stats["method"] == "lanczos" and dense.stats["method"] == "dense"
    assert lanczos.stats["solves"] >= 12  # one kept factorisation, many solves


def test_effective_masses_sum_to_the_free_mass():
    """Sum over all modes of Gamma_kd^2 = r_d^T M Phi Phi^T M r_d = r_d^T M r_d (Phi
    M-orthonormal and complete): the mass of the free nodes along every axis."""
    net = taut_cable(2.0, 50.0, 1e4, 0.2, 12)
    n_free = 3 * int(np.count_nonzero(~net.fixed))
    modes = catenet.modes(net, None, n_free)
    assert modes.count == n_free
    free_mass = float(net.mass[~net.fixed].sum())
    np.testing.assert_allclose(modes.effective_mass.sum(axis=0), free_mass, rtol=1e-10)
    np.testing.assert_allclose(modes.total_mass, free_mass)


# --------------------------------------------------------------------------------------
# Published: ANSYS VM53, code_aster SDNL138
# --------------------------------------------------------------------------------------


def test_ansys_vm53_string_under_tension():
    """ANSYS Mechanical APDL Verification Manual, VM53 "Vibration of a String Under
    Tension" (after W. T. Thomson, Vibration Theory and Applications, 1965, art. 8.2):
    a string of length 100 in, A = 0.00306796 in^2, E = 30e6 psi, rho = 0.00073
    lb-s^2/in^4, fixed at both ends and stretched to the initial strain 0.00543228.
    Targets: F = 500 lb, stress 162,974 psi, f1 = 74.708, f2 = 149.42, f3 = 224.12 Hz
    (lateral). E A eps0 is 499.98 lb, which VM53 rounds to 500 lb and its frequency
    targets use (f scales with sqrt(F): 2e-5 of the rounding); the targets have five
    digits (half a unit of the last: up to 3.3e-5): matched to 5e-5. Units in-lb-s are
    consistent. VM53's density is per stretched volume (the
    string at its strained length); catenet's is per unstressed volume, so it is given
    as rho (1 + eps0) (docs/guide/modes.md, "a mass per stretched length")."""
    E, A, rho, eps0, L = 30e6, 0.00306796, 0.00073, 0.00543228, 100.0
    net = cable(
        [0, 0, 0], [L, 0, 0], 1001,
        Material(EA=E * A, line_density=rho * (1 + eps0) * A), length=L / (1 + eps0),
    )  # fmt: skip
    modes = catenet.modes(net, None, 6)
    tension = modes.equilibrium.tension
    assert tension.mean() == pytest.approx(500.0, abs=0.05)
    assert tension.mean() / A == pytest.approx(162974.0, rel=1e-4)
    f = modes.frequency[::2]  # each lateral frequency twice (y and z)
    np.testing.assert_allclose(modes.frequency[1::2], f, rtol=1e-9)
    np.testing.assert_allclose(f[:3], [74.708, 149.42, 224.12], rtol=5e-5)


def test_code_aster_sdnl138_cable_frequencies():
    """code_aster validation manual V5.02.138, SDNL138 "Frequencies and natural modes of
    vibration of a self-stressed frame": its cables (E = 2.1e11 Pa, rho = 7800 kg/m^3,
    A = 5.026e-5 m^2, 1 m long between their nodes) are tensioned to 6171.050459855 N
    and 12345.2954376 N; the reference is the vibrating string, f = 62.73227096292042 Hz
    and 88.72830898253936 Hz. The frame's bars are rigid against these modes in the
    test's reference solution, so a cable pinned at both ends reproduces it. The
    reference's rho S is per length of the tensioned cable: given here as rho (1 + eps)
    per unstressed volume."""
    E, A, rho = 2.1e11, 5.026e-5, 7800.0
    for tension, reference in ((6171.050459855, 62.73227096292042),
                               (12345.2954376, 88.72830898253936)):  # fmt: skip
        eps = tension / (E * A)
        net = cable(
            [0, 0, 0], [1.0, 0, 0], 1201,
            Material(EA=E * A, line_density=rho * A * (1 + eps)), length=1.0 / (1 + eps),
        )  # fmt: skip
        f1 = catenet.modes(net, None, 2).frequency[0]
        assert f1 == pytest.approx(reference, rel=1e-6)


# --------------------------------------------------------------------------------------
# Irvine & Caughey: the sagging cable
# --------------------------------------------------------------------------------------


def irvine_symmetric(lambda2: float) -> float:
    """The first root in (pi, 3 pi) of tan(w/2) = w/2 - (4 / lambda^2) (w/2)^3."""
    g = lambda w: math.tan(w / 2) - w / 2 + 4 / lambda2 * (w / 2) ** 3  # noqa: E731
    return brentq(g, math.pi * (1 + 1e-12), 3 * math.pi * (1 - 1e-12), xtol=1e-14)


def sagging_cable(lambda2: float, span=100.0, sag=0.01, edges=200):
    """A cable between two supports at one level under its own weight, sag / span =
    ``sag``, EA chosen for Irvine's parameter ``lambda2`` (flat parabola estimate)."""
    g, rho_a = 9.81, 1.0
    H = rho_a * g * span / (8 * sag)
    EA = lambda2 * H / (rho_a * g * span / H) ** 2
    s = span * (1 + 8 / 3 * sag**2)
    net = cable(
        [0, 0, 0], [span, 0, 0], edges + 1, Material(EA=EA, line_density=rho_a),
        length=s / (1 + H / EA),
    )  # fmt: skip
    return net, Loads(gravity=np.array([0.0, 0.0, -g])), EA


@pytest.mark.parametrize("lambda2", [1.0, 10.0, 0.9 * 4 * math.pi**2, 1.1 * 4 * math.pi**2, 100.0])
def test_irvine_caughey_sagging_cable(lambda2):
    """Irvine & Caughey (1974), "The linear theory of free vibrations of a suspended
    cable", Proc. R. Soc. Lond. A 341: a flat cable (sag d << span l) with horizontal
    tension H and mass m per length. The in-plane vertical motion v adds a tension h(t)
    to H: m v_tt = H v_xx + h y'' with y'' = -m g / H; h comes from the compatibility of
    the stretched length, h L_e / (EA) = (m g / H) int v dx, L_e = l (1 + 8 (d/l)^2).
    Antisymmetric modes have int v dx = 0, so h = 0 and they are the string's:
    w_bar = 2 n pi (w_bar = omega l / sqrt(H / m)). Symmetric ones solve
    tan(w_bar/2) = w_bar/2 - (4 / lambda^2)(w_bar/2)^3 with lambda^2 = (m g l / H)^2
    l / (H L_e / EA): from w_bar = pi (inextensible string) at small lambda^2 to
    3 pi at large, crossing the first antisymmetric mode 2 pi at lambda^2 = 4 pi^2.
    Out of plane, no stretching: w_bar = n pi.

    H, d and lambda^2 are measured from catenet's equilibrium (a discrete catenary), so
    the comparison carries the theory's flat-sag error (O((d/l)^2)) and the
    discretisation's ((w_bar h / l)^2 / 24 ~ 4e-5): at d / l = 0.01 both below 1e-3.
    The symmetric mode is the one whose midspan node moves vertically.
    """
    net, loads, EA = sagging_cable(lambda2)
    modes = catenet.modes(net, loads, 6)
    x, span, n = modes.x, 100.0, net.n_nodes
    mid = n // 2
    e = x[1] - x[0]
    H = modes.equilibrium.tension[0] * e[0] / np.linalg.norm(e)
    sag = -x[mid, 2]
    m = float(net.mass.sum()) / span  # per unit span
    l2 = (m * 9.81 * span / H) ** 2 * span / (H * span * (1 + 8 * (sag / span) ** 2) / EA)
    assert l2 == pytest.approx(lambda2, rel=0.02)
    wbar = 2 * math.pi * modes.frequency * span / math.sqrt(H / m)
    dom = modes.dominant()
    out = [w for w, d in zip(wbar, dom, strict=True) if d == "y"]
    inplane = [k for k, d in enumerate(dom) if d == "z"]
    sym = [k for k in inplane if abs(modes.shape[k, mid, 2]) > 1e-3 * np.abs(modes.shape[k]).max()]
    anti = [k for k in inplane if k not in sym]
    assert out[0] == pytest.approx(math.pi, rel=1e-3)
    assert wbar[anti[0]] == pytest.approx(2 * math.pi, rel=1e-3)
    assert wbar[sym[0]] == pytest.approx(irvine_symmetric(l2), rel=1e-3)
    # The crossover: below 4 pi^2 the first symmetric mode comes first, above it second.
    assert (sym[0] < anti[0]) == (l2 < 4 * math.pi**2)


# --------------------------------------------------------------------------------------
# The prestressed orthogonal net as a membrane
# --------------------------------------------------------------------------------------


def square_net_case(tmp_path, n: int, size=6.0, prestress=500.0):
    """The paper's square net (alpha = 0) with one edge per segment between crossings
    (edge_length = d = L / (m + 1)), prestressed, without load."""
    from catenet.case import build, load_case

    m = n // 2
    text = f"""
[geometry]
kind = "square_net"
n = {n}
alpha = 0.0
size = {size}
edge_length = {size / (m + 1)!r}
[material]
EA = 1e6
area = 1e-4
density = 2000.0
prestress = {prestress}
"""
    path = tmp_path / f"net{n}.toml"
    path.write_text(text)
    return build(load_case(path, ()))


def test_prestressed_net_is_a_membrane(tmp_path):
    """An orthogonal net of cables at spacing d, each with tension T and mass rho A per
    length, over a square a = b = L = (m + 1) d pinned at its edge, is for lateral
    motion a membrane with tension N = T / d per unit width and mass m_a = 2 mu / d
    per unit area (two families; mu = rho A / (1 + T / EA) per stretched length):
    N (w_xx + w_yy) = m_a w_tt, w = sin(p pi x / a) sin(q pi y / b) cos(omega t),
    f_pq = (1/2) sqrt(N / m_a) sqrt((p/a)^2 + (q/b)^2).
    The discrete net is the five-point Laplacian on the crossings (node mass 2 mu d,
    lateral springs T / d): omega^2 = (2 T / (rho A d^2)) (sin^2(p pi / (2 (m+1))) +
    sin^2(q pi / (2 (m+1)))) with mu for rho A, second order in d. The lowest lateral modes: (1,1),
    (1,2) = (2,1), (2,2)."""
    T, rho_a = 500.0, 2000.0 * 1e-4
    mu = rho_a / (1 + T / 1e6)
    ds, errs = [], []
    for n in (10, 18, 34):
        scene = square_net_case(tmp_path, n, prestress=T)
        modes = catenet.modes(scene, k=6)
        L = scene.size
        d = L / (n // 2 + 1)
        membrane = 0.5 * math.sqrt((T / d) / (2 * mu / d)) / L
        pq = np.sqrt([2.0, 5.0, 5.0, 8.0])
        dom = np.array(modes.dominant())
        f = modes.frequency[dom == "z"][:4]
        np.testing.assert_allclose(f[1], f[2], rtol=1e-9)
        rel = np.abs(f / (membrane * pq) - 1)
        assert rel.max() < 0.05
        ds.append(d)
        errs.append(rel[0])
        m1 = n // 2 + 1
        exact = np.sqrt(2 * T / (mu * d * d) * 2 * np.sin(np.pi / (2 * m1)) ** 2)
        assert f[0] == pytest.approx(exact / (2 * np.pi), rel=1e-8)
    assert order(ds, errs) == pytest.approx(2.0, abs=0.1)


# --------------------------------------------------------------------------------------
# Numbering, zero modes, bad input
# --------------------------------------------------------------------------------------


def test_frequencies_do_not_depend_on_node_numbering(tmp_path):
    """The same net with its nodes renumbered by a random permutation (edges and supports
    mapped alike) has the same frequencies, and its shapes are the same up to the
    permutation and the sign."""
    scene = square_net_case(tmp_path, 10, prestress=300.0)
    net = scene.net
    rng = np.random.default_rng(7)
    perm = rng.permutation(net.n_nodes)  # new index of old node i: where[i]
    where = np.empty_like(perm)
    where[perm] = np.arange(net.n_nodes)
    other = Net.from_arrays(
        net.nodes[perm], where[net.edges], EA=net.EA, fixed=net.fixed[perm],
        rest_length=net.rest_length, line_density=net.line_density,
    )  # fmt: skip
    a = catenet.modes(net, None, 5)
    b = catenet.modes(other, None, 5)
    np.testing.assert_allclose(b.frequency, a.frequency, rtol=1e-10)
    k = 0  # the lowest mode is simple: its shape is the same, node for node
    np.testing.assert_allclose(np.abs(b.shape[k][where]), np.abs(a.shape[k]), atol=1e-8)


@pytest.mark.roundoff
def test_node_on_slack_edges_is_named_not_returned():
    """A node held only by a slack edge has no stiffness: its three zero-frequency modes
    are left out and named, the taut part's modes are the string's."""
    nodes = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0.5, 0]]
    edges = [[0, 1], [1, 2], [1, 3]]
    net = Net.from_arrays(
        nodes, edges, EA=1e5, fixed=[0, 2], rest_length=[0.999, 0.999, 0.6], line_density=1.0
    )
    for method in ("dense", "lanczos"):
        modes = catenet.modes(net, None, 2, method=method)
        assert modes.zero_modes == 3
        assert "nodes 3 hang on slack edges only" in modes.zero_message
        T = 1e5 * (1 / 0.999 - 1)
        m1 = float(net.mass[1])
        f = math.sqrt(2 * T / m1) / (2 * math.pi)
        np.testing.assert_allclose(modes.frequency, f, rtol=1e-9)


@pytest.mark.roundoff
def test_part_joined_by_slack_edges_is_named():
    """A taut cable with a bilateral strut (at its rest length) hanging from it by a
    slack edge: the strut floats (only a slack edge joins it to the supports), its
    rigid-body motions cost nothing: zero-frequency modes, named as such."""
    from catenet.model.laws import Law

    nodes = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0], [1.5, 1, 0]]
    edges = [[0, 1], [1, 2], [1, 3], [3, 4]]
    net = Net.from_arrays(
        nodes, edges, EA=1e5, fixed=[0, 2], rest_length=[0.999, 0.999, 1.2, 0.5],
        line_density=1.0, law=Law.uniform(4, tension_only=[True, True, True, False]),
    )  # fmt: skip
    modes = catenet.modes(net, None, 2, method="lanczos")
    assert modes.zero_modes >= 5
    assert "form a part that only slack edges join to the supports" in modes.zero_message
    assert set(modes.zero_nodes.tolist()) >= {3, 4}
    assert modes.count == 2


def test_bad_input():
    net = taut_cable(1.0, 10.0, 1e3, 0.1, 4)
    with pytest.raises(ConfigError, match="positive integer"):
        catenet.modes(net, None, 0)
    with pytest.raises(ConfigError, match="free DOFs"):
        catenet.modes(net, None, 100)
    massless = taut_cable(1.0, 10.0, 1e3, 0.0, 4)
    with pytest.raises(ConfigError, match="no mass"):
        catenet.modes(massless, None, 2)


@pytest.mark.roundoff
def test_unstable_equilibrium_is_refused():
    """A straight chain of bilateral edges held 1 % short of its rest length is an
    equilibrium in compression: its geometric stiffness N / |e| < 0 makes K indefinite
    (omega^2 < 0 sideways: it buckles). Both solvers refuse it with the nodes named,
    the Lanczos path from the inertia of K - sigma M before any iteration."""
    from catenet.errors import ConvergenceError

    net = cable([0, 0, 0], [1, 0, 0], 101, Material(EA=1e4, line_density=0.1), length=1.01)
    net = net.replace(tension_only=False)
    ws = workspace(catenet.scene.Scene(net, Loads()), Settings())
    for method in ("dense", "lanczos"):
        with pytest.raises(ConvergenceError, match="unstable.*compressed bilateral edges"):
            natural_modes(ws, net.nodes, 3, method=method)


def test_sagging_cable_converges_at_second_order():
    """The discrete sagging cable's first symmetric in-plane frequency converges to its
    continuum limit at second order in the edge length: with the differences between
    successive halvings of h (50, 100, 200, 400 edges), d_k = f(h_k) - f(h_k / 2), the
    observed order is log2(d_k / d_{k+1}) ~ 2 (a Richardson self-convergence study: the
    limit is the elastic catenary's, of which Irvine's flat-sag theory is the
    approximation checked above)."""
    f = []
    for edges in (50, 100, 200, 400):
        net, loads, _ = sagging_cable(10.0, edges=edges)
        modes = catenet.modes(net, loads, 3)
        dom = modes.dominant()
        f.append(next(fk for fk, d in zip(modes.frequency, dom, strict=True) if d == "z"))
    d = np.abs(np.diff(f))
    orders = np.log2(d[:-1] / d[1:])
    np.testing.assert_allclose(orders, 2.0, atol=0.1)


@pytest.mark.roundoff
def test_a_body_out_of_contact_is_named():
    """A rigid ball's centre (the net's last node, its mass a point mass) that touches
    nothing has no stiffness: three zero-frequency modes, named as the body's."""
    nodes = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 3.0]]
    net = Net.from_arrays(
        nodes, [[0, 1], [1, 2]], EA=1e5, fixed=[0, 2], rest_length=[0.999, 0.999],
        line_density=1.0, point_mass=[0, 0, 0, 5.0], bodies=1,
    )  # fmt: skip
    modes = catenet.modes(net, None, 2)
    assert modes.zero_modes == 3
    assert "nodes 3 are the centres of rigid bodies that touch nothing" in modes.zero_message
    assert modes.count == 2 and modes.frequency[0] > 0


def test_massless_cables_with_point_masses():
    """Massless edges carrying point masses: M is singular (its massless DOFs have
    infinite frequencies, left out). A weightless string at tension T with one mass m at
    midspan: omega^2 = (2 T / (L / 2)) / m laterally (twice), by both solvers; and a
    string half of whose edges are massless: the Lanczos path (M singular, shift-invert
    needs no M^-1) agrees with the dense one."""
    L, T, EA, m = 2.0, 100.0, 1e5, 3.0
    net = cable(
        [0, 0, 0], [L, 0, 0], 41, Material(EA=EA, line_density=0.0), length=L / (1 + T / EA)
    )
    point = np.zeros(net.n_nodes)
    point[20] = m
    net = net.with_point_mass(point)
    for method in ("dense", "lanczos"):
        modes = catenet.modes(net, None, 2, method=method)
        np.testing.assert_allclose(modes.frequency, math.sqrt(4 * T / (L * m)) / (2 * math.pi),
                                   rtol=1e-10)  # fmt: skip
    half = taut_cable(L, T, EA, 0.5, 200)
    density = np.where(np.arange(half.n_edges) < 100, 0.0, 0.5)
    half = half.replace(line_density=density)
    ws = workspace(catenet.scene.Scene(half, Loads()), Settings())
    x = catenet.modes(half, None, 1).x
    dense = natural_modes(ws, x, 6, method="dense")
    lanczos = natural_modes(ws, x, 6, method="lanczos")
    assert lanczos.stats["method"] == "lanczos"
    np.testing.assert_allclose(lanczos.frequency, dense.frequency, rtol=1e-9)


def test_modes_at_the_eigensolver_s_round_off_pass_and_inaccurate_ones_do_not():
    """The accuracy check (``modes._residual``, ``_check_found``): a pencil whose low
    mode sits beside a stiffness 1e12 times its own has a relative residual of order
    n eps times that ratio however it is computed, and passes while within
    ROUNDOFF_SAFETY of that round-off; the same mode off by 1e-4 is refused."""
    from types import SimpleNamespace

    import scipy.sparse as sp

    from catenet.errors import ConvergenceError
    from catenet.solver import modes

    n = 40
    k = np.full(n, 1.0)
    k[::2] = 1e12  # stiff springs beside soft ones, in a chain
    main = np.append(k[:-1] + k[1:], k[-1])
    K = sp.diags([main, -k[1:], -k[1:]], [0, 1, -1], format="csr")
    M = sp.identity(n, format="csr")
    lam, vec = np.linalg.eigh(K.toarray())
    op = SimpleNamespace(k=K, mm=M, n=n)
    exact = modes._residual(op, lam[:3], vec[:, :3])
    assert exact["residual"] > 1e3 * modes.RESIDUAL_TOL  # far above the relative bound ...
    assert exact["roundoff_ratio"] < 1.0  # ... and at LAPACK's own round-off
    found = SimpleNamespace(stats=exact, count=3)
    modes._check_found(found, 3)  # passes, whatever its relative residual
    rng = np.random.default_rng(1)
    off = vec[:, :3] + 1e-4 * rng.normal(size=(n, 3))
    wrong = modes._residual(op, lam[:3], off)
    assert wrong["residual"] > modes.RESIDUAL_TOL and wrong["roundoff_ratio"] > 1e3
    with pytest.raises(ConvergenceError, match="inaccurate"):
        modes._check_found(SimpleNamespace(stats=wrong, count=3), 3)


@pytest.mark.parametrize("stiff", [1e2, 1e3])
def test_a_near_rigid_girder_keeps_its_modes_on_its_bearings(stiff):
    """A 6 m girder (253 kg) on bearings at both ends (springs 1e7, 1e7, 5e6 N/m along
    x, y, z) bounces, sways and rocks on them as a rigid body: sqrt(2 k / m) and
    sqrt(2 k (L/2)^2 / I) / (2 pi) for its bounce and rocking (I its lumped masses'),
    to its own stiffness's share. As a
    near-rigid transfer girder (EA 9e11 N, EI 1.75e12 N m^2) these modes lie at 5e-12
    of the stiffness scale, below the margin band of round-off zero modes by a gap of
    1e4: they were dropped as "a mechanism of the taut edges", and the girder's own
    12 kHz mode came first."""
    from catenet.case import build, parse_case

    BEARING = [1e7, 1e7, 5e6]  # N/m along x, y, z
    case = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [6, 0, 0], "nodes": 61},
        "material": {"EA": 9e8 * stiff, "area": 5.38e-3, "density": 7850.0, "EI": 1.75e9 * stiff},
        "supports": {"fixed": [], "spring": [{"nodes": ["start", "end"], "stiffness": BEARING}]},
    }  # fmt: skip
    modes = catenet.modes(build(parse_case(case)), k=5)
    mass = 7850.0 * 5.38e-3 * 6.0
    assert modes.zero_modes == 0
    bounce, sway = math.sqrt(2 * 5e6 / mass), math.sqrt(2 * 1e7 / mass)
    share = np.full(61, 1.0 / 60)
    share[[0, -1]] /= 2  # the lumped masses' moment of inertia about the middle
    inertia = mass * np.sum(share * (np.linspace(0.0, 6.0, 61) - 3.0) ** 2)
    rocking = [math.sqrt(2 * k * 9.0 / inertia) for k in (5e6, 1e7)]
    expected = np.sort([bounce, sway, sway, *rocking]) / (2 * math.pi)
    np.testing.assert_allclose(modes.frequency, expected, rtol=2e-2 / stiff)  # its own give
