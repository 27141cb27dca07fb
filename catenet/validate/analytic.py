"""Closed-form solutions of single cables, each with its derivation, for validation.

These are the reference answers of ``catenet validate`` (``catenet.validate.table``) and
of the tests (``tests/analytic.py`` re-exports this module): they live in the package because
the command needs them at run time.

Conventions. A cable is pinned at two supports at the same height, a span apart, with the
mid-span at x = 0 for the paper's formulas (Eqs. 14-17). The paper's ``z`` points up, so a
hanging cable has z <= 0 and its sag (mid-span deflection) ``delta = -z(0) >= 0``. The
elastic catenary (Irvine, *Cable Structures*, 1981) is written, as in that book, with a
Lagrangian coordinate ``s`` in [0, L0] from the left support and ``z`` measured DOWNWARD
from the supports; its sag is ``z(L0/2) >= 0``. Every root is found by bracketing and
``scipy.optimize.brentq`` on a monotone function, so each solve either returns the root to
round-off or raises ``ConfigError`` for arguments outside the range where a solution exists.

Contents
--------
- Cable pinned at both ends under a midpoint load (paper Eqs. 16-17):
  ``midpoint_load_force``, ``midpoint_load_deflection``, ``midpoint_load_shape``.
- Inextensible catenary with its ends moved inward by dL (paper Eqs. 14-15):
  ``catenary_parameter``, ``catenary_sag``, ``catenary_shape``.
- Exact elastic catenary: ``elastic_catenary`` -> ``ElasticCatenary`` (x(s), z(s), T(s),
  H, V, sag). ``EA = inf`` gives the inextensible catenary, which is Eqs. 14-15.
- Exact discrete elastic chain (the catenet model of the same cable, nodal weights):
  ``discrete_catenary`` -> ``DiscreteCatenary``. It separates the solver's error (catenet vs
  this chain: round-off) from the discretisation error (this chain vs the elastic catenary).
- Elastic catenary between supports at different heights: ``inclined_catenary`` ->
  ``InclinedCatenary``.
- Mooring line from an anchor on a frictionless horizontal seabed to a fairlead, part of
  it resting on the bed (or fully suspended, or taut): ``seabed_catenary`` ->
  ``SeabedCatenary`` (H, V, grounded length L_B, touchdown x_TD, anchor force, shape(s)).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError

__all__ = [
    "DiscreteCatenary",
    "ElasticCatenary",
    "InclinedCatenary",
    "catenary_parameter",
    "catenary_sag",
    "catenary_shape",
    "discrete_catenary",
    "elastic_catenary",
    "inclined_catenary",
    "midpoint_load_deflection",
    "midpoint_load_force",
    "midpoint_load_shape",
]

_RTOL = 4.0 * np.finfo(float).eps  # brentq's finest relative tolerance


def _positive(name: str, value: float, *, allow_inf: bool = False) -> float:
    value = float(value)
    ok = value > 0 and (math.isfinite(value) or (allow_inf and value == math.inf))
    if not ok:
        raise ConfigError(f"{name} = {value!r}: must be {'> 0' if allow_inf else 'finite and > 0'}")
    return value


def _increasing_root(f: Callable[[float], float], target: float, start: float) -> float:
    """The root u > 0 of f(u) = target for f continuous and increasing on (0, inf),
    searched in log u: the bracket [start 2^-k, start 2^k] grows until it holds the root."""
    from scipy.optimize import brentq

    def g(t: float) -> float:
        return f(math.exp(t)) - target

    lo = hi = math.log(start)
    g_lo = g_hi = g(lo)
    for _ in range(2100):
        if g_lo <= 0.0 <= g_hi:
            break
        if g_lo > 0:
            hi, g_hi = lo, g_lo
            lo -= math.log(2.0)
            g_lo = g(lo)
        else:
            lo, g_lo = hi, g_hi
            hi += math.log(2.0)
            g_hi = g(hi)
    else:  # pragma: no cover - the callers only pass solvable problems
        raise ConfigError(f"no root found for target {target!r}")
    if g_lo == 0.0:
        return math.exp(lo)
    if g_hi == 0.0:
        return math.exp(hi)
    return math.exp(brentq(g, lo, hi, xtol=1e-300, rtol=_RTOL, maxiter=500))


# --------------------------------------------------------------------------------------
# Midpoint load (paper Eqs. 16-17)
# --------------------------------------------------------------------------------------


def midpoint_load_force(delta, L: float, EA: float):
    """Midpoint force F [N] that holds a pinned cable at midpoint deflection ``delta`` (Eq. 17).

    Derivation. A cable of rest length L is pinned at both ends, a chord L apart, and a force
    F pulls its midpoint down. The cable carries no bending moment, so each half is a
    straight two-force member from a support to the midpoint: the shape is the zigzag of
    Eq. 16. With a = L/2 and r = sqrt(delta^2 + a^2) the stretched length of a half, both
    halves have the strain eps = (r - a)/a and the tension T = EA eps (linear elasticity,
    the energy 1/2 EA eps^2 l0 of the model). The vertical balance of the midpoint is
    F = 2 T sin(theta), sin(theta) = delta / r, which is Eq. 17:

        F = 2 EA [(sqrt(delta^2 + a^2) - a) / a] delta / sqrt(delta^2 + a^2).

    It is evaluated with r - a = delta^2 / (r + a) to avoid cancellation at small delta
    (there F ~ EA (2 delta / L)^3). F is odd and strictly increasing in delta:
    d/d(delta) [delta/a - delta/r] = 1/a - a^2/r^3 > 0 since r > a.

    The discrete model solves this problem exactly: with the load on a node (odd node
    count) every edge of a half carries the same tension and the unloaded interior nodes
    of a half are collinear, so its solution equals Eq. 17 up to round-off.
    """
    L = _positive("L", L)
    EA = _positive("EA", EA)
    d = np.asarray(delta, dtype=float)
    a = 0.5 * L
    r = np.sqrt(d * d + a * a)
    F = 2.0 * EA * (d * d / (r + a) / a) * d / r
    return float(F) if F.ndim == 0 else F


def midpoint_load_deflection(F: float, L: float, EA: float) -> float:
    """Midpoint deflection delta >= 0 [m] under a downward midpoint force F >= 0 (Eq. 17
    solved for delta by ``brentq``; see ``midpoint_load_force`` for the derivation).

    F(delta) is strictly increasing from F(0) = 0 to infinity, so the root is unique. The
    bracket starts from the small-load solution delta = (L/2) (F/EA)^(1/3), which Eq. 17
    gives for delta << L, and grows in log(delta) until it holds the root.
    """
    L = _positive("L", L)
    EA = _positive("EA", EA)
    F = float(F)
    if not (math.isfinite(F) and F >= 0):
        raise ConfigError(f"F = {F!r}: must be finite and >= 0 (a downward midpoint force)")
    if F == 0.0:
        return 0.0
    guess = 0.5 * L * (F / EA) ** (1.0 / 3.0)
    return _increasing_root(lambda d: midpoint_load_force(d, L, EA), F, guess)


def midpoint_load_shape(x, delta: float, L: float):
    """Shape z(x) of the pinned cable under a midpoint load, Eq. 16 (z up, x in [-L/2, L/2]):
    z = 2 delta |x| / L - delta, the two straight halves from the supports (z = 0 at
    x = +-L/2) to the loaded midpoint (z = -delta at x = 0)."""
    L = _positive("L", L)
    x = np.asarray(x, dtype=float)
    z = 2.0 * delta * np.abs(x) / L - delta
    return float(z) if z.ndim == 0 else z


# --------------------------------------------------------------------------------------
# Inextensible catenary (paper Eqs. 14-15)
# --------------------------------------------------------------------------------------


def _log_sinh_over_x(u: float) -> float:
    """log(sinh(u)/u) for u > 0 without overflow: log(sinh u) = u + log1p(-e^-2u) - log 2."""
    if u < 1e-4:
        return u * u / 6.0  # sinh(u)/u = 1 + u^2/6 + O(u^4)
    return u + math.log1p(-math.exp(-2.0 * u)) - math.log(2.0) - math.log(u)


def _check_dL(L: float, dL: float) -> tuple[float, float]:
    L = _positive("L", L)
    dL = float(dL)
    if not (math.isfinite(dL) and 0 <= dL < L):
        raise ConfigError(f"dL = {dL!r}: must be in [0, L) with L = {L!r}")
    return L, dL


def catenary_parameter(L: float, dL: float) -> float:
    """The catenary parameter A [m] of Eq. 15: 2 A sinh((L - dL) / (2 A)) = L.

    Derivation. An inextensible cable of length L and weight w per length hangs between
    supports c = L - dL apart. The horizontal tension H is constant (no horizontal load);
    the vertical component changes by the weight of the arc, so with the slope angle
    phi and the arc length p from mid-span, tan(phi) = w p / H = p / A with A = H / w.
    Then dx/dp = cos(phi) = 1/sqrt(1 + (p/A)^2), x = A asinh(p/A), p = A sinh(x/A), and
    dz/dx = tan(phi) = sinh(x/A): z = A cosh(x/A) + const, Eq. 14. The arc from -c/2 to
    c/2 has the cable's length: 2 A sinh(c/(2A)) = L, Eq. 15.

    Solved for u = c/(2A) > 0 from sinh(u)/u = L/c, an increasing function of u that runs
    from 1 to infinity, so the root is unique for 0 < dL < L. dL = 0 (a straight cable,
    A -> infinity) returns ``inf``.
    """
    L, dL = _check_dL(L, dL)
    if dL == 0.0:
        return math.inf
    c = L - dL
    target = math.log(L / c)
    guess = math.sqrt(6.0 * dL / L)  # sinh(u)/u ~ 1 + u^2/6
    u = _increasing_root(_log_sinh_over_x, target, max(guess, 1e-8))
    return c / (2.0 * u)


def catenary_sag(L: float, dL: float) -> float:
    """Mid-span sag delta >= 0 [m] of the inextensible catenary (Eqs. 14-15):
    delta = -z(0) = A cosh(c/(2A)) - A, c = L - dL, computed as 2 A sinh^2(c/(4A))
    (no cancellation when the cable is nearly straight)."""
    L, dL = _check_dL(L, dL)
    A = catenary_parameter(L, dL)
    if math.isinf(A):
        return 0.0
    c = L - dL
    return 2.0 * A * math.sinh(c / (4.0 * A)) ** 2


def catenary_shape(x, L: float, dL: float):
    """Shape z(x) of the inextensible catenary, Eq. 14 (z up, z <= 0, z = 0 at the supports
    x = +-(L - dL)/2): z = A cosh(x/A) - A cosh(c/(2A)), written with
    cosh a - cosh b = 2 sinh((a+b)/2) sinh((a-b)/2) to avoid cancellation."""
    L, dL = _check_dL(L, dL)
    x = np.asarray(x, dtype=float)
    A = catenary_parameter(L, dL)
    if math.isinf(A):
        z = np.zeros_like(x)
    else:
        u = (L - dL) / (2.0 * A)
        z = 2.0 * A * np.sinh((x / A + u) / 2.0) * np.sinh((x / A - u) / 2.0)
    return float(z) if z.ndim == 0 else z


# --------------------------------------------------------------------------------------
# Exact elastic catenary (Irvine 1981)
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ElasticCatenary:
    """The elastic catenary between supports at the same height (see ``elastic_catenary``).

    L0 unstretched length [m], EA axial stiffness [N] (inf: inextensible), w weight per
    unstretched length [N/m], span the support distance [m], H horizontal tension [N],
    V = w L0 / 2 the vertical reaction at each support [N].
    """

    L0: float
    EA: float
    w: float
    span: float
    H: float

    @property
    def V(self) -> float:
        return 0.5 * self.w * self.L0

    @property
    def beta(self) -> float:
        """V / H, the slope dz/dx at the left support of the inextensible cable."""
        return self.V / self.H

    def x(self, s):
        """Horizontal position [m] of the material point s (0 at the left support):
        x = H s/EA + (H/w) [asinh(V/H) - asinh((V - w s)/H)]."""
        s = np.asarray(s, dtype=float)
        b = self.beta
        x = self.H * s / self.EA + (self.H / self.w) * (
            np.arcsinh(b) - np.arcsinh(b * (1.0 - 2.0 * s / self.L0))
        )
        return float(x) if x.ndim == 0 else x

    def z(self, s):
        """Depth below the supports [m] of the material point s (z DOWNWARD, >= 0):
        z = (w s/EA)(V/w - s/2) + (H/w) [sqrt(1 + (V/H)^2) - sqrt(1 + ((V - w s)/H)^2)],
        the difference of square roots taken as (a^2 - b^2)/(sqrt(1+a^2) + sqrt(1+b^2))."""
        s = np.asarray(s, dtype=float)
        b = self.beta
        sig = s / self.L0
        a2_b2 = 4.0 * b * b * sig * (1.0 - sig)
        roots = math.sqrt(1.0 + b * b) + np.sqrt(1.0 + (b * (1.0 - 2.0 * sig)) ** 2)
        z = self.w * s * (self.L0 - s) / (2.0 * self.EA) + (self.H / self.w) * a2_b2 / roots
        return float(z) if z.ndim == 0 else z

    def tension(self, s):
        """Cable tension T(s) = sqrt(H^2 + (V - w s)^2) [N]."""
        s = np.asarray(s, dtype=float)
        t = np.hypot(self.H, self.V - self.w * s)
        return float(t) if t.ndim == 0 else t

    @property
    def sag(self) -> float:
        """Mid-span sag z(L0/2) = w L0^2/(8 EA) + (H/w)(sqrt(1 + (V/H)^2) - 1) [m]."""
        b = self.beta
        return self.w * self.L0**2 / (8.0 * self.EA) + (self.H / self.w) * b * b / (
            math.sqrt(1.0 + b * b) + 1.0
        )


def elastic_catenary(L0: float, EA: float, w: float, span: float) -> ElasticCatenary:
    """The exact elastic catenary (Irvine, *Cable Structures*, 1981, Sec. 2.2).

    Derivation. Let s in [0, L0] be the unstretched arc length from the left support,
    p the stretched arc length, x horizontal and z DOWNWARD. The cut at s carries the
    tension T along the tangent (dx/dp, dz/dp). The segment [0, s] is held by the left
    support, which pulls it with (-H, -V) (outward and up), by its own weight (0, +w s),
    and by the tension at s, (T dx/dp, T dz/dp). Its balance gives

        T dx/dp = H,        T dz/dp = V - w s,        T = sqrt(H^2 + (V - w s)^2),

    and symmetry (both supports at the same height) gives V = W/2, W = w L0. Hooke's law
    for the stretch is dp/ds = 1 + T/EA, the continuum limit of the model's edge law
    l = l0 (1 + T/EA). Hence

        dx/ds = (H/T)(1 + T/EA) = H/EA + H/sqrt(H^2 + (V - w s)^2),
        dz/ds = ((V - w s)/T)(1 + T/EA) = (V - w s)/EA + (V - w s)/sqrt(H^2 + (V - w s)^2).

    With u = (V - w s)/H, ds = -(H/w) du, and x(0) = z(0) = 0:

        x(s) = H s/EA + (H/w) [asinh(V/H) - asinh((V - w s)/H)],
        z(s) = (w s/EA)(V/w - s/2) + (H/w) [sqrt(1 + (V/H)^2) - sqrt(1 + ((V - w s)/H)^2)].

    z(L0) = 0 (the right support is at the same height) holds by symmetry; x(L0) = span
    fixes H:  span = H L0/EA + (2H/w) asinh(V/H).  With beta = V/H and eps_w = W/(2 EA):

        span / L0 = (asinh(beta) + eps_w) / beta,

    strictly decreasing in beta from infinity (beta -> 0) to 0 (beta -> infinity), since
    d/d(beta) [asinh(beta)/beta] < 0 (asinh b > b/sqrt(1+b^2)); so every span > 0 has
    exactly one H. The mid-span sag is z(L0/2) = w L0^2/(8EA) + (H/w)(sqrt(1 + beta^2) - 1).

    The inextensible limit EA -> infinity drops the H s/EA and w s(...)/EA terms: then
    span = (2H/w) asinh(w L0/(2H)), i.e. 2 A sinh(span/(2A)) = L0 with A = H/w, which is
    Eq. 15 with span = L - dL, and the sag is A (cosh(span/(2A)) - 1), Eq. 14 at x = 0.
    ``EA = inf`` evaluates that limit exactly (it needs span < L0); the difference from
    Eq. 15 at finite EA is O(W/EA).
    """
    L0 = _positive("L0", L0)
    EA = _positive("EA", EA, allow_inf=True)
    w = _positive("w", w)
    span = _positive("span", span)
    eps_w = 0.0 if math.isinf(EA) else 0.5 * w * L0 / EA
    if eps_w == 0.0 and span >= L0:
        raise ConfigError(
            f"span = {span!r}: an inextensible cable (EA = inf) needs span < L0 = {L0!r}"
        )

    # (asinh b + eps_w)/b decreases in b; solve for t = 1/beta, an increasing function.
    def ratio(t: float) -> float:
        return (math.asinh(1.0 / t) + eps_w) * t

    t = _increasing_root(ratio, span / L0, 1.0)
    H = 0.5 * w * L0 * t
    return ElasticCatenary(L0=L0, EA=EA, w=w, span=span, H=H)


# --------------------------------------------------------------------------------------
# Exact discrete chain (the catenet model of a cable under its own weight)
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DiscreteCatenary:
    """Equilibrium of the discrete elastic chain (see ``discrete_catenary``).

    x, z : (n+1,) node positions [m], x from the left support, z DOWNWARD;
    tension : (n,) edge tensions [N]; H : horizontal tension [N].
    """

    x: np.ndarray
    z: np.ndarray
    tension: np.ndarray
    H: float

    @property
    def sag(self) -> float:
        """Depth of the mid-span: of the middle node (n even), or of the middle edge's
        midpoint (n odd)."""
        n = len(self.z) - 1
        if n % 2 == 0:
            return float(self.z[n // 2])
        return float(0.5 * (self.z[n // 2] + self.z[n // 2 + 1]))


def discrete_catenary(
    L0: float, EA: float, w: float, span: float, n_edges: int
) -> DiscreteCatenary:
    """The exact equilibrium of catenet's model of a hanging cable: ``n_edges`` equal edges
    of rest length h = L0/n, lumped weights P = w h at the n - 1 interior nodes (the end
    nodes' half-weights go straight into the supports), supports ``span`` apart.

    Derivation. With z down, let (H, Q_k) be the components of the tension of edge k
    (nodes k, k+1) along its direction from node k to node k+1. H is the same in every
    edge (no horizontal load). Node k+1 is pulled by edge k with -(H, Q_k), by edge k+1
    with (H, Q_{k+1}) and by its weight (0, P): its vertical balance is
    Q_{k+1} = Q_k - P, and symmetry, Q_{n-1} = -Q_0, gives Q_k = P ((n-1)/2 - k). Edge k
    has the tension T_k = sqrt(H^2 + Q_k^2) and the length h (1 + T_k/EA); it points along
    (H, Q_k)/T_k:

        dx_k = h (H/T_k + H/EA),   dz_k = h (Q_k/T_k + Q_k/EA).

    The positions are the cumulative sums, and sum_k dx_k = span fixes H; the sum is
    L0 H/EA + h sum_k 1/sqrt(1 + (Q_k/H)^2), increasing in H, so the root is unique.
    Tension-only edges change nothing (every T_k > 0). The chain is the catenary with its
    distributed weight lumped by the trapezoidal rule, so it differs from
    ``elastic_catenary`` by O(h^2).
    """
    L0 = _positive("L0", L0)
    EA = _positive("EA", EA, allow_inf=True)
    w = _positive("w", w)
    span = _positive("span", span)
    n = int(n_edges)
    if n < 1 or n != n_edges:
        raise ConfigError(f"n_edges = {n_edges!r}: must be an integer >= 1")
    h = L0 / n
    P = w * h
    Q = P * (0.5 * (n - 1) - np.arange(n))
    inv_ea = 0.0 if math.isinf(EA) else 1.0 / EA

    def total(H: float) -> float:
        return L0 * H * inv_ea + h * float(np.sum(1.0 / np.hypot(1.0, Q / H)))

    if inv_ea == 0.0 and total(1e300) <= span:
        raise ConfigError(f"span = {span!r}: an inextensible chain needs span < L0 = {L0!r}")
    if total(1e-100 * P) >= span:  # only a middle edge with Q = 0 reaches across
        raise ConfigError(f"span = {span!r}: must exceed the middle edge's rest length {h!r}")
    H = _increasing_root(total, span, max(P, 1e-300))
    T = np.hypot(H, Q)
    dx = h * (H / T + H * inv_ea)
    dz = h * (Q / T + Q * inv_ea)
    x = np.concatenate([[0.0], np.cumsum(dx)])
    z = np.concatenate([[0.0], np.cumsum(dz)])
    return DiscreteCatenary(x=x, z=z, tension=T, H=H)


@dataclass(frozen=True)
class InclinedCatenary:
    """The elastic catenary between supports at different heights (or a buoyant line).

    z is UP here. ``H`` is the horizontal tension, ``V`` the upward force of the left
    support on the cable; ``x(s)``, ``z(s)`` the position of the material point at
    unstretched arc length s from the left support.
    """

    L0: float
    EA: float
    w: float
    span: float
    rise: float
    H: float
    V: float

    def x(self, s):
        s = np.asarray(s, dtype=float)
        H, V, w = self.H, self.V, self.w
        return H * s / self.EA + (H / w) * (np.arcsinh((w * s - V) / H) - np.arcsinh(-V / H))

    def z(self, s):
        s = np.asarray(s, dtype=float)
        H, V, w = self.H, self.V, self.w
        return (w * s * s / 2 - V * s) / self.EA + (
            np.sqrt(H * H + (w * s - V) ** 2) - np.sqrt(H * H + V * V)
        ) / w

    def tension(self, s):
        """Tension T(s) [N] of the material point at s."""
        s = np.asarray(s, dtype=float)
        return np.sqrt(self.H**2 + (self.w * s - self.V) ** 2)


def inclined_catenary(L0: float, EA: float, w: float, span: float, rise: float) -> InclinedCatenary:
    """The exact elastic catenary (Irvine, *Cable Structures*, 1981, Sec. 2.3) of a cable of
    unstretched length L0 and stiffness EA under a weight w per unstretched length (w < 0:
    a buoyant line, pushed up), its right support ``span`` to the side of and ``rise``
    above the left one.

    Derivation, z up. The segment [0, s] is held by the left support with (-H, V), carries
    its weight (0, -w s) and is pulled along the tangent at s by the tension, so the
    tension's components are (H, w s - V) and T = sqrt(H^2 + (w s - V)^2). With
    dp/ds = 1 + T/EA (Hooke, the continuum limit of the edge law):

        dx/ds = H/EA + H/T,   dz/ds = (w s - V)/EA + (w s - V)/T,

        x(s) = H s/EA + (H/w)[asinh((w s - V)/H) - asinh(-V/H)],
        z(s) = (w s^2/2 - V s)/EA + (sqrt(H^2 + (w s - V)^2) - sqrt(H^2 + V^2))/w.

    H and V solve x(L0) = span, z(L0) = rise (Newton from the level-support solution;
    the residual is checked). Equal heights and w > 0 give V = w L0 / 2 and the
    ``elastic_catenary`` above.
    """
    from scipy.optimize import root

    L0 = _positive("L0", L0)
    EA = _positive("EA", EA)
    span = _positive("span", span)
    if not (math.isfinite(w) and w != 0.0):
        raise ValueError(f"w = {w!r}: must be finite and non-zero")
    chord = math.hypot(span, rise)
    if not chord < L0 * (1 + abs(w) * L0 / EA):
        raise ValueError("the cable is too short to hang between the supports: no catenary")
    level = elastic_catenary(L0, EA, abs(w), chord)
    H0 = level.H * span / chord
    V0 = w * L0 / 2 - H0 * rise / span

    def residual(p):
        c = InclinedCatenary(L0, EA, w, span, rise, math.exp(p[0]), p[1])
        return [(c.x(L0) - span) / L0, (c.z(L0) - rise) / L0]

    sol = root(residual, [math.log(H0), V0], method="hybr", options={"xtol": 1e-15})
    cat = InclinedCatenary(L0, EA, w, span, rise, math.exp(sol.x[0]), float(sol.x[1]))
    err = max(abs(r) for r in residual(sol.x))
    if not err < 1e-12:
        raise ArithmeticError(f"inclined catenary: end conditions met only to {err:.1e}")
    return cat
