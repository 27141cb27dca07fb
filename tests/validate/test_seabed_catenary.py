"""The mooring line on a frictionless seabed: the closed form ``seabed_catenary`` and
catenet's model of the same line.

- Self-consistency of the closed form: its shape ends at the fairlead, carries the weight
  of its suspended part (V = w L_s, horizontal at the touchdown), stretches by Hooke's law;
  EA -> inf gives the inextensible seabed catenary; at lift-off it meets
  ``inclined_catenary``; Newton and the bracketed fallback agree.
- MoorPy's ``catenary`` (Jonkman's FAST routine): its published values, hard-coded below.
- An independent discretisation: the exact discrete chain on a rigid seabed converges to
  the closed form at second order.
- catenet: a graph case of the line with a plane seabed, at default solver and obstacle
  settings, against the closed form at 100, 1000 and 10000 edges statically, and at 100
  and 1000 edges by dynamic relaxation (``method = "dynamic"``, default t_end: to rest).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.optimize import brentq, root

import catenet.validate.seabed as seabed
from catenet.errors import ConfigError
from catenet.validate.analytic import inclined_catenary
from catenet.validate.seabed import seabed_catenary

G = 9.81
# The issue's line: a 300 m chain, submerged weight 1000 N/m, EA = 5e8 N, water depth
# (fairlead height above the bed) 100 m, horizontal span from anchor to fairlead 250 m.
ISSUE = dict(L=300.0, EA=5e8, w=1000.0, X=250.0, h=100.0)

# (L, EA, w, X, h): on the bed, nearly lifted off, fully suspended (anchor uplift), taut
# and stretched, EA = inf, and configs/friction/mooring_pulled.toml's line.
CASES = {
    "issue": (300.0, 5e8, 1000.0, 250.0, 100.0),
    "short suspended part": (300.0, 5e8, 1000.0, 210.0, 100.0),
    "nearly lifted off": (300.0, 5e8, 1000.0, 270.0, 100.0),
    "suspended, anchor uplift": (300.0, 5e8, 1000.0, 285.0, 100.0),
    "taut": (300.0, 5e7, 1000.0, 300.0, 100.0),
    "inextensible": (300.0, math.inf, 1000.0, 250.0, 100.0),
    "soft rope": (30.0, 1e4, 10.0, 27.0, 8.0),
    "mooring_pulled.toml": (30.0, 1e6, 10.0, 27.0, 8.0),
}


def rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


# --------------------------------------------------------------------------------------
# (1) The closed form on its own
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(CASES))
def test_the_shape_ends_at_the_fairlead_and_carries_the_suspended_weight(name):
    L, EA, w, X, h = CASES[name]
    c = seabed_catenary(L, EA, w, X, h)
    inv_ea = 0.0 if math.isinf(EA) else 1.0 / EA
    # End points: the anchor at the origin, the fairlead at (X, h).
    assert c.shape(0.0) == (0.0, 0.0)
    x, z = c.shape(L)
    assert abs(x - X) < 1e-12 * L and abs(z - h) < 1e-12 * L
    # Vertical balance: V is the weight of the suspended length (plus the anchor's uplift).
    assert c.V == pytest.approx(c.w * c.suspended_length + c.anchor_V, rel=1e-14)
    assert c.L_B + c.suspended_length == pytest.approx(L, rel=1e-14)
    assert (c.L_B == 0.0) == (c.V / w >= L) and (c.anchor_V > 0.0) == (c.V / w > L)
    assert c.x_TD == pytest.approx(c.L_B * (1.0 + c.H * inv_ea), rel=1e-14, abs=0.0)
    assert c.anchor_tension == pytest.approx(math.hypot(c.H, c.anchor_V), rel=1e-14)
    assert c.fairlead_tension == pytest.approx(math.hypot(c.H, c.V), rel=1e-14)
    # The grounded part lies on the bed, stretched by H/EA; the rest is above it.
    s = np.linspace(0.0, L, 3001)
    x, z = c.shape(s)
    on_bed = s <= c.L_B
    assert np.all(z[on_bed] == 0.0) and np.all(z[~on_bed] > 0.0)
    assert np.allclose(x[on_bed], s[on_bed] * (1.0 + c.H * inv_ea), rtol=1e-14, atol=0.0)
    # Equilibrium of every piece, by finite differences of the shape (central, step ds):
    # the tangent of the suspended part has the slope Q(s)/H, Q = V_A + w (s - L_B) the
    # weight it carries (0 at the touchdown), and the line stretches by 1 + T/EA.
    ds = 1e-4 * min(L, c.H / w)  # well below the radius of curvature at the touchdown
    mid = s[(s > ds) & (s < L - ds) & (np.abs(s - c.L_B) > 2 * ds)]  # not across the kink
    xp, zp = c.shape(mid + ds)
    xm, zm = c.shape(mid - ds)
    dx, dz = (xp - xm) / (2 * ds), (zp - zm) / (2 * ds)
    Q = np.maximum(c.V - w * (L - mid), 0.0)
    T = np.hypot(c.H, Q)
    assert np.allclose(dz * c.H, dx * Q, rtol=0.0, atol=1e-7 * c.fairlead_tension)
    assert np.allclose(np.hypot(dx, dz), 1.0 + T * inv_ea, rtol=0.0, atol=1e-7)
    assert np.allclose(c.tension(mid), T, rtol=1e-14)
    # At the fairlead the line pulls along its tangent: slope V/H.
    xl, zl = c.shape(L - ds)
    assert (h - zl) / (X - xl) == pytest.approx(c.V / c.H, rel=1e-3)


def test_ea_to_infinity_gives_the_inextensible_seabed_catenary():
    """Inextensible, on the bed: with a = H/w the suspended part is the catenary
    z = a (cosh(x'/a) - 1) from the touchdown, of length L_s = sqrt(h^2 + 2 a h) and
    horizontal extent a acosh(1 + h/a), so X = L - L_s + a acosh(1 + h/a) and V = w L_s
    (solved here by brentq, independently of seabed_catenary)."""
    L, w, X, h = ISSUE["L"], ISSUE["w"], ISSUE["X"], ISSUE["h"]

    def span(a: float) -> float:
        return L - math.sqrt(h * h + 2 * a * h) + a * math.acosh(1 + h / a) - X

    a = brentq(span, 1e-3, 1e5, xtol=1e-14, rtol=1e-15)
    Ls = math.sqrt(h * h + 2 * a * h)
    rigid = seabed_catenary(L, math.inf, w, X, h)
    assert rigid.H == pytest.approx(a * w, rel=1e-12)
    assert rigid.V == pytest.approx(w * Ls, rel=1e-12)
    assert rigid.L_B == pytest.approx(L - Ls, rel=1e-12)
    assert rigid.x_TD == pytest.approx(L - Ls, rel=1e-12)
    # Finite EA: the difference is O(T/EA), so it falls 100-fold for each 100-fold EA.
    errors = []
    for EA in (1e8, 1e10, 1e12):
        c = seabed_catenary(L, EA, w, X, h)
        errors.append(max(rel(c.H, rigid.H), rel(c.V, rigid.V), rel(c.x_TD, rigid.x_TD)))
        assert errors[-1] < 50.0 * c.fairlead_tension / EA
    assert errors[1] < 2e-2 * errors[0] and errors[2] < 2e-2 * errors[1]


def lift_off_span(L: float, EA: float, w: float, h: float) -> tuple[float, float]:
    """(X, H) at which the whole line just hangs: V = w L, zero slope at the anchor.
    From the suspended equations with V_A = 0: h = w L^2/(2 EA) + (H/w)(sqrt(1 +
    (w L/H)^2) - 1) fixes H, then X = H L/EA + (H/w) asinh(w L/H)."""

    def height(H: float) -> float:
        return w * L * L / (2 * EA) + (H / w) * (math.hypot(1.0, w * L / H) - 1.0) - h

    H = brentq(height, 1e-6 * w * L, 1e6 * w * L, xtol=1e-300, rtol=1e-15)
    return H * L / EA + (H / w) * math.asinh(w * L / H), H


def test_the_line_lifts_off_continuously_into_the_inclined_catenary():
    L, EA, w, h = ISSUE["L"], ISSUE["EA"], ISSUE["w"], ISSUE["h"]
    X_lift, H_lift = lift_off_span(L, EA, w, h)
    at = seabed_catenary(L, EA, w, X_lift, h)
    assert at.H == pytest.approx(H_lift, rel=1e-10)
    assert at.V == pytest.approx(w * L, rel=1e-10)
    assert at.L_B < 1e-9 * L and at.anchor_V < 1e-9 * w * L
    # Fully suspended (X beyond the lift-off): the ordinary inclined elastic catenary,
    # whose V (the upward force of its left support) is minus the anchor's uplift.
    # (inclined_catenary refuses chords beyond L (1 + w L/EA), so not the taut lines.)
    for X in (X_lift * (1 + 1e-6), X_lift * (1 + 1e-3), X_lift * 1.01):
        c = seabed_catenary(L, EA, w, X, h)
        ref = inclined_catenary(L, EA, w, X, h)
        assert c.L_B == 0.0 and c.anchor_V > 0.0
        assert c.H == pytest.approx(ref.H, rel=1e-10)
        assert c.anchor_V == pytest.approx(-ref.V, rel=1e-6, abs=1e-10 * c.fairlead_tension)
        s = np.linspace(0.0, L, 101)
        x, z = c.shape(s)
        assert np.allclose(x, ref.x(s), rtol=0, atol=1e-10 * L)
        assert np.allclose(z, ref.z(s), rtol=0, atol=1e-10 * L)
    # Either side of the lift-off H and V change at the same rate (the two regimes meet
    # with a continuous first derivative), and L_B, V_A leave 0 linearly.
    for d in (1e-5, 1e-7):
        lo = seabed_catenary(L, EA, w, X_lift * (1 - d), h)
        hi = seabed_catenary(L, EA, w, X_lift * (1 + d), h)
        assert lo.L_B > 0.0 and lo.anchor_V == 0.0 and hi.L_B == 0.0 and hi.anchor_V > 0.0
        for key in ("H", "V"):
            below = (getattr(at, key) - getattr(lo, key)) / (getattr(at, key) * d)
            above = (getattr(hi, key) - getattr(at, key)) / (getattr(at, key) * d)
            assert 0.0 < below < 100.0 and above == pytest.approx(below, rel=200 * d)
        assert lo.x_TD < 100 * d * L and hi.anchor_V < 100 * d * at.fairlead_tension


def test_a_taut_line_becomes_a_straight_elastic_bar():
    """H >> w L: the line is nearly straight, with sqrt(X^2 + h^2) = L (1 + T/EA) + O(wL)."""
    L, EA, w, h = 300.0, 5e8, 1.0, 100.0
    for strain in (1e-3, 1e-2):
        chord = L * (1 + strain)
        c = seabed_catenary(L, EA, w, math.sqrt(chord**2 - h**2), h)
        assert c.L_B == 0.0
        assert c.fairlead_tension == pytest.approx(EA * strain, rel=2 * w * L / (EA * strain))


@pytest.mark.parametrize("name", list(CASES))
def test_newton_and_the_bracketed_fallback_agree(name, monkeypatch):
    L, EA, w, X, h = CASES[name]
    newton = seabed_catenary(L, EA, w, X, h)
    monkeypatch.setattr(seabed, "_seabed_newton", lambda *args: None)
    bracketed = seabed_catenary(L, EA, w, X, h)
    assert rel(bracketed.H, newton.H) < 1e-12 * newton.fairlead_tension / newton.H
    assert rel(bracketed.V, newton.V) < 1e-12 * newton.fairlead_tension / newton.V


def test_a_sweep_of_lines_solves_to_round_off():
    rng = np.random.default_rng(7)
    for _ in range(300):
        L = 10 ** rng.uniform(0, 4)
        h = L * 10 ** rng.uniform(-3, -0.05)
        EA = 10 ** rng.uniform(4, 11)
        w = 10 ** rng.uniform(-2, 4)
        Lv = 2 * h / (1 + math.sqrt(1 + 2 * w * h / EA))
        X = L - Lv + (1.5 * L - (L - Lv)) * rng.uniform(1e-4, 1.0) ** 2
        c = seabed_catenary(L, EA, w, X, h)
        xf, zf = c.shape(L)
        assert abs(xf - X) < 1e-12 * L and abs(zf - h) < 1e-12 * L


@pytest.mark.parametrize(
    "args, message",
    [
        ((300.0, 5e8, 1000.0, 200.0, 100.0), "the line is slack"),
        ((300.0, math.inf, 1000.0, 290.0, 100.0), "needs sqrt(X^2 + h^2) < L"),
        ((-300.0, 5e8, 1000.0, 250.0, 100.0), "L = -300.0"),
        ((300.0, 5e8, 0.0, 250.0, 100.0), "w = 0.0"),
        ((300.0, 5e8, 1000.0, 250.0, 0.0), "h = 0.0"),
    ],
)
def test_bad_lines_are_refused(args, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        seabed_catenary(*args)


# --------------------------------------------------------------------------------------
# (2) MoorPy's catenary
# --------------------------------------------------------------------------------------

# Published reference values of MoorPy 1.3.0 (PyPI), moorpy.Catenary.catenary, which is
# Jonkman's FAST catenary routine: anchor on the seabed (CB = 0, no friction). Obtained with
#   pip install moorpy==1.3.0
#   python -c "from moorpy.Catenary import catenary; i = catenary(XF, ZF, L, EA, W, CB=0,
#              Tol=1e-12, MaxIter=500)[4]; print(i['HF'], i['VF'], i['LBot'], i['VA'])"
# (repr of each float). MoorPy is not a dependency of catenet: only these numbers are used.
# (XF, ZF, L, EA, W): (HF, VF, LBot, VA)
MOORPY = {
    (250.0, 100.0, 300.0, 5e8, 1000.0): (
        60224.44008891442,
        148451.42810570425,
        151.54857189429575,
        0.0,
    ),
    (270.0, 100.0, 300.0, 5e8, 1000.0): (
        214964.9618136215,
        230129.60328704244,
        69.87039671295756,
        0.0,
    ),
    (285.0, 100.0, 300.0, 5e8, 1000.0): (
        3326460.5028694486,
        1317878.1134474364,
        0.0,
        1017878.1134474364,
    ),
    (27.0, 8.0, 30.0, 1e6, 10.0): (102.77822940576348, 151.130215767897, 14.8869784232103, 0.0),
}


@pytest.mark.parametrize("key", list(MOORPY), ids=lambda k: f"X={k[0]},h={k[1]},L={k[2]}")
def test_matches_moorpy(key):
    X, h, L, EA, w = key
    HF, VF, LBot, VA = MOORPY[key]
    c = seabed_catenary(L, EA, w, X, h)
    T = math.hypot(HF, VF)
    assert rel(c.H, HF) < 1e-9 and rel(c.V, VF) < 1e-9
    assert abs(c.L_B - LBot) < 1e-9 * L
    assert abs(c.anchor_V - VA) < 1e-9 * T
    assert c.anchor_tension == pytest.approx(math.hypot(HF, VA), rel=1e-9)


# --------------------------------------------------------------------------------------
# An independent check: the exact discrete chain on a rigid frictionless bed
# --------------------------------------------------------------------------------------


def discrete_seabed_chain(L, EA, w, X, h, n):
    """Equilibrium of n equal edges (rest length l = L/n, weight P = w l lumped half to
    each end node) from a fixed anchor on a rigid frictionless bed to a fixed fairlead.

    H is the same in every edge (the bed pushes vertically). The vertical component of
    edge k is Q_k = max(q - (n - 1 - k) P, 0), q that of the last edge: going down from
    the fairlead each node's weight is taken off, and where that would turn negative the
    node rests on the bed, which carries the rest (its reaction P - (Q_k - Q_{k-1}) >= 0).
    Edge k has length l (1 + T_k/EA) along (H, Q_k)/T_k; the sums of its components are
    X and h: two equations for (H, q) (scipy's root from the closed form's answer). The
    fairlead holds (H, q + P/2) (its own half edge weight), the anchor's edge pulls it up
    with Q_0 (0 unless fully suspended); the touchdown is the last node with Q = 0 on
    both sides. Returns (H, V_fairlead, uplift, x_TD)."""
    ell, P = L / n, w * L / n
    k = np.arange(n)

    def components(H, q):
        Q = np.maximum(q - (n - 1 - k) * P, 0.0)
        f = ell * (1.0 / np.hypot(H, Q) + 1.0 / EA)
        return Q, H * f, Q * f

    guess = seabed_catenary(L, EA, w, X, h)

    def residual(p):
        Q, dx, dz = components(p[0] * guess.H, p[1] * guess.V)
        return [(dx.sum() - X) / L, (dz.sum() - h) / L]

    sol = root(residual, [1.0, 1.0], method="hybr", options={"xtol": 1e-15})
    H, q = sol.x[0] * guess.H, sol.x[1] * guess.V
    assert max(abs(r) for r in residual(sol.x)) < 1e-13
    Q, dx, dz = components(H, q)
    grounded = np.flatnonzero(Q == 0.0)
    x_TD = float(np.sum(dx[: grounded[-1] + 1])) if grounded.size else 0.0
    return H, q + 0.5 * P, float(Q[0]), x_TD


def test_the_exact_discrete_chain_on_a_rigid_bed_converges_to_the_closed_form():
    c = seabed_catenary(**ISSUE)
    errors = []
    for n in (100, 1000, 10000):
        H, V, uplift, x_TD = discrete_seabed_chain(*ISSUE.values(), n)
        errors.append(max(rel(H, c.H), rel(V, c.V)))
        assert uplift == 0.0
        assert abs(x_TD - c.x_TD) < ISSUE["L"] / n
    # Second order, with the touchdown's jump from node to node on top:
    # 4.3e-4, 2.0e-6, 1.5e-8 here.
    assert errors[0] < 1e-3 and errors[1] < 1e-5 and errors[2] < 1e-7


# --------------------------------------------------------------------------------------
# (3) catenet
# --------------------------------------------------------------------------------------


def mooring_line_case(L, EA, w, X, h, n, area=0.01, g=G, method="static") -> dict:
    """The catenet case of the mooring line: a graph whose one cable runs from the anchor
    (node 0, on the seabed z = 0) to the fairlead (node 1, at (X, 0, h)) in n equal edges
    (``edge_length`` = chord / n), both ends fixed, under ``[load] gravity``, with a plane
    seabed at z = 0 (normal +z) at its default barrier distance and stiffness, and the
    default solver of ``method`` (static, or dynamic: dynamic relaxation to rest).

    The line starts STRAIGHT from the anchor to the fairlead, with ``geometry.prestrain``
    = chord / L - 1 so that every rest length is L / n exactly. Not the closed form's
    shape, because a graph's rest lengths are its given edge lengths / (1 + prestrain):
    the closed form's curved, stretched shape split by ``edge_length`` would give chords
    of the stretched line, not L / n; and its grounded nodes lie on the bed, which catenet
    refuses (no free node may start on an obstacle). The straight line lies above the bed
    (only the fixed anchor is on it), and the equilibrium does not depend on the start:
    the energy (tension-only stretching, weight, planar barrier) is convex.

    The material gives w through area and density (w = density * area * g: the
    submerged weight as an effective density); EA directly."""
    chord = math.hypot(X, h)
    return {
        "title": f"mooring line on a frictionless seabed, {n} edges",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [X, 0.0, h]],
            "edge_length": chord / n,
            "prestrain": chord / L - 1.0,
            "sets": {"anchor": [0], "fairlead": [1]},
            "cable": [{"name": "line", "nodes": [0, 1]}],
        },
        "supports": {"fixed": ["anchor", "fairlead"]},
        "material": {"EA": EA, "area": area, "density": w / (g * area)},
        "load": {"gravity": [0.0, 0.0, -g]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}],
        "solver": {"method": method},
    }


def solve_mooring_line(L, EA, w, X, h, n, method="static"):
    """catenet's equilibrium of ``mooring_line_case``: (fairlead tension, horizontal
    tension, touchdown x, anchor uplift, accepted steps: time steps when dynamic).

    The fairlead's reaction is (H, 0, V) (it holds its own half edge's weight too, as the
    continuum's V = w L_s counts the weight up to the fairlead). The anchor's uplift is the
    vertical pull of the first edge on the anchor: minus its reaction and its own load.
    The touchdown is the last node, along the line from the anchor, that the bed acts on
    (gap below the barrier's activation distance)."""
    from catenet.case import build, parse_case
    from catenet.solver.path import Settings, solve

    case = parse_case(mooring_line_case(L, EA, w, X, h, n, method=method))
    scene = build(case)
    net = scene.net
    assert len(net.rest_length) == n
    assert np.allclose(net.rest_length, L / n, rtol=1e-12)
    r = solve(scene, Settings.of(case.solver))
    assert r.converged and r.equilibrium
    order = np.array([0, *range(2, n + 1), 1])  # the cable's nodes, anchor to fairlead
    edges = {tuple(sorted(e)) for e in np.asarray(net.edges).tolist()}
    assert all(
        tuple(sorted(p)) in edges for p in zip(order[:-1].tolist(), order[1:].tolist(), strict=True)
    )
    (bed,) = [t for t in scene.terms if type(t).__name__ == "PlaneBarrier"]
    touched = np.zeros(len(r.x), dtype=bool)
    touched[bed.nodes] = bed.gap(r.x) < bed.dhat
    on_bed = np.flatnonzero(touched[order])
    x_TD = float(r.x[order[on_bed[-1]], 0]) if on_bed.size else 0.0
    fair = r.reaction[1]
    load = scene.loads.external_force(net)
    uplift = -(r.reaction[0, 2] + load[0, 2])
    T, H = float(np.linalg.norm(fair)), float(math.hypot(fair[0], fair[1]))
    return T, H, x_TD, uplift, r.steps


# Statically and by dynamic relaxation at every size (the 10000-edge line relaxed
# dynamically: 43 pseudo-time steps, about 10 s).
METHODS = [(n, method) for method in ("static", "dynamic") for n in (100, 1000, 10000)]


@pytest.mark.parametrize("n, method", METHODS)
def test_mooring_line_on_the_seabed_matches_the_closed_form(n, method):
    """The issue's line at default solver and obstacle settings (no ``distance``),
    solved statically and by dynamic relaxation (default dt, damping and t_end: to rest).

    Two references: the exact equilibrium of the same n-edge chain on a rigid bed
    (``discrete_seabed_chain``: what the barrier alone gets wrong) to 1e-4 at every n,
    and the continuum's closed form to 1e-4 where the discretisation allows it: the
    rigid-bed chain of 100 edges is itself 4.3e-4 off in H (lumped weights; second order
    in the edge), so at n = 100 the closed form is held to that discretisation error."""
    exact = seabed_catenary(**ISSUE)
    T, H, x_TD, uplift, steps = solve_mooring_line(*ISSUE.values(), n, method=method)
    H_n, V_n, _, x_TD_n = discrete_seabed_chain(*ISSUE.values(), n)
    T_n = math.hypot(H_n, V_n)
    edge = ISSUE["L"] / n * (1.0 + exact.H / ISSUE["EA"])  # an edge on the bed, stretched
    errors = (
        f"{method}, n = {n}: fairlead tension {T / exact.fairlead_tension - 1:+.3e}, "
        f"H {H / exact.H - 1:+.3e} (relative), touchdown {x_TD - exact.x_TD:+.4f} m "
        f"(edge {edge:.4f} m), anchor uplift {uplift / exact.fairlead_tension:+.3e} of T; "
        f"against the rigid-bed chain: T {T / T_n - 1:+.3e}, H {H / H_n - 1:+.3e}"
    )
    assert rel(T, T_n) < 1e-4 and rel(H, H_n) < 1e-4, errors
    discretisation = max(rel(T_n, exact.fairlead_tension), rel(H_n, exact.H))
    assert rel(T, exact.fairlead_tension) < max(1e-4, 1.1 * discretisation), errors
    assert rel(H, exact.H) < max(1e-4, 1.1 * discretisation), errors
    if n >= 1000:
        assert rel(T, exact.fairlead_tension) < 1e-4 and rel(H, exact.H) < 1e-4, errors
    assert abs(x_TD - exact.x_TD) <= edge and abs(x_TD - x_TD_n) <= edge, errors
    assert uplift <= 1e-4 * exact.fairlead_tension, errors
    # pseudo-time: a few dozen steps at every size (the 10000-edge line once crawled
    # through 1000 steps of 2e-4 s after its stiffness stage, then never passed the rest test)
    assert method == "static" or steps <= 100, f"{method}, n = {n}: {steps} steps"


def test_the_mooring_line_by_dynamic_relaxation_matches_the_static_solve():
    """The same line relaxed dynamically (the paper's implicit Euler, damping 1/s, from
    the straight start) to rest, with an explicit t_end and dt (steps of dt, stopping at
    rest after about 36 s): the same equilibrium as the static solve."""
    from catenet.case import build, parse_case
    from catenet.solver.path import Settings, solve

    n = 100
    case = mooring_line_case(*ISSUE.values(), n)
    static = solve(build(parse_case(case)), Settings.of(parse_case(case).solver))
    case["solver"] = {"method": "dynamic", "dt": 0.5, "t_end": 300.0}
    parsed = parse_case(case)
    dynamic = solve(build(parsed), Settings.of(parsed.solver))
    assert dynamic.converged and dynamic.equilibrium and dynamic.time < 300.0
    T_static, T_dynamic = (float(np.linalg.norm(r.reaction[1])) for r in (static, dynamic))
    assert rel(T_dynamic, T_static) < 1e-6
    assert np.max(np.abs(dynamic.x - static.x)) < 1e-4  # m, on a 300 m line
