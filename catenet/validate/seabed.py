"""A mooring line on a frictionless seabed: the elastic catenary with a grounded part
(``seabed_catenary``), as MoorPy's catenary and the mooring texts give it, in every regime
(partly on the bed, fully suspended, taut)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError
from catenet.validate.analytic import _increasing_root, _positive

__all__ = ["SeabedCatenary", "seabed_catenary"]


@dataclass(frozen=True)
class SeabedCatenary:
    """A mooring line from an anchor on a frictionless seabed to a fairlead (see
    ``seabed_catenary``).

    z is UP, the seabed is z = 0, the anchor at (0, 0), the fairlead at (X, h). L the
    unstretched length [m], EA the axial stiffness [N] (inf: inextensible), w the submerged
    weight per unstretched length [N/m], H the horizontal tension [N] (the same all along
    the line), V the vertical tension at the fairlead [N] (the line pulls the fairlead with
    (-H, -V); the fairlead holds it with (H, V)).
    """

    L: float
    EA: float
    w: float
    X: float
    h: float
    H: float
    V: float

    @property
    def _inv_ea(self) -> float:
        return 0.0 if math.isinf(self.EA) else 1.0 / self.EA

    @property
    def suspended_length(self) -> float:
        """L_s = min(V/w, L): the unstretched length off the seabed [m]."""
        return min(self.V / self.w, self.L)

    @property
    def L_B(self) -> float:
        """Grounded unstretched length L_B = max(L - V/w, 0) [m] (0: fully suspended)."""
        return max(self.L - self.V / self.w, 0.0)

    @property
    def anchor_V(self) -> float:
        """Vertical force of the line on the anchor, up [N]: the uplift V - w L when the
        line is fully suspended, 0 when part of it rests on the seabed."""
        return max(self.V - self.w * self.L, 0.0)

    @property
    def x_TD(self) -> float:
        """Touchdown point, horizontal distance from the anchor in the stretched geometry:
        L_B (1 + H/EA) [m]; 0 (the anchor) when the line is fully suspended."""
        return self.L_B * (1.0 + self.H * self._inv_ea)

    @property
    def fairlead_tension(self) -> float:
        """sqrt(H^2 + V^2) [N]."""
        return math.hypot(self.H, self.V)

    @property
    def anchor_tension(self) -> float:
        """sqrt(H^2 + anchor_V^2) [N]: H (no seabed friction) when the line touches down."""
        return math.hypot(self.H, self.anchor_V)

    def tension(self, s):
        """Tension T(s) = sqrt(H^2 + Q(s)^2) [N], Q(s) = max(V - w (L - s), 0) the vertical
        component at the material point s (unstretched arc length from the anchor)."""
        s = np.asarray(s, dtype=float)
        t = np.hypot(self.H, np.maximum(self.V - self.w * (self.L - s), 0.0))
        return float(t) if t.ndim == 0 else t

    def shape(self, s):
        """Stretched position (x, z) [m] of the material point at unstretched arc length
        s in [0, L] from the anchor; each a float for a scalar s, else an array.

        Grounded (s <= L_B): x = s (1 + H/EA), z = 0. Suspended, sigma = s - L_B,
        Q = V_A + w sigma (V_A = anchor_V):
            x = L_B (1 + H/EA) + H sigma/EA + (H/w)[asinh(Q/H) - asinh(V_A/H)],
            z = (V_A sigma + w sigma^2/2)/EA + (H/w)[sqrt(1 + (Q/H)^2) - sqrt(1 + (V_A/H)^2)],
        both differences taken without cancellation (``_hang``)."""
        s = np.asarray(s, dtype=float)
        if np.any(~((s >= 0.0) & (s <= self.L * (1.0 + 1e-12)))):
            raise ValueError(f"s: must lie in [0, L = {self.L!r}]")
        H, w, k = self.H, self.w, self._inv_ea
        LB, VA = self.L_B, self.anchor_V
        sig = np.maximum(s - LB, 0.0)
        asinh_diff, root_diff = _hang(H, VA, w * sig)
        x = np.minimum(s, LB) * (1.0 + H * k) + H * sig * k + (H / w) * asinh_diff
        z = (VA * sig + 0.5 * w * sig * sig) * k + (H / w) * root_diff
        if x.ndim == 0:
            return float(x), float(z)
        return x, z


def _seabed_ends(L: float, inv_ea: float, w: float, H: float, V: float) -> tuple[float, float]:
    """(X, h) of the fairlead of the line with horizontal tension H > 0 and fairlead
    vertical tension V > 0 (``seabed_catenary``, Eqs. (X) and (h))."""
    Ls = min(V / w, L)
    VA = max(V - w * L, 0.0)  # the anchor's uplift, 0 while the line touches down
    asinh_diff, root_diff = _hang(H, VA, w * Ls)
    X = (L - Ls) + H * L * inv_ea + (H / w) * float(asinh_diff)
    h = (V * Ls - 0.5 * w * Ls * Ls) * inv_ea + (H / w) * float(root_diff)
    return X, h


def _hang(H, QA, dQ):
    """asinh(Q_B/H) - asinh(Q_A/H) and sqrt(1 + (Q_B/H)^2) - sqrt(1 + (Q_A/H)^2) for
    Q_B = Q_A + dQ, Q_A >= 0, dQ >= 0, without cancellation when dQ << Q_A (a taut line):
    with a = Q_B/H, b = Q_A/H and a - b = dQ/H taken as such,
    asinh a - asinh b = asinh((a - b)(a + b)/(a sqrt(1 + b^2) + b sqrt(1 + a^2))) and
    sqrt(1 + a^2) - sqrt(1 + b^2) = (a - b)(a + b)/(sqrt(1 + a^2) + sqrt(1 + b^2))."""
    b = QA / H
    d = dQ / H
    a = b + d
    ra, rb = np.sqrt(1.0 + a * a), np.sqrt(1.0 + b * b)
    num = d * (a + b)
    den = a * rb + b * ra  # 0 only where a = b = 0, and then num = 0
    return np.arcsinh(num / np.where(den > 0.0, den, 1.0)), num / (ra + rb)


def _seabed_flexibility(L: float, inv_ea: float, w: float, H: float, V: float) -> np.ndarray:
    """d(X, h)/d(H, V), symmetric positive definite (``seabed_catenary``). With
    T_F = sqrt(H^2 + V^2), T_A = sqrt(H^2 + V_A^2) (= H on the seabed):
    dX/dH = L/EA + [asinh(V/H) - asinh(V_A/H) - V/T_F + V_A/T_A]/w,
    dX/dV = dh/dH = (H/T_F - H/T_A)/w, dh/dV = L_s/EA + (V/T_F - V_A/T_A)/w,
    the same formulas in both regimes (on the seabed the -1/w of L_B = L - V/w is the
    -H/T_A/w)."""
    Ls = min(V / w, L)
    VA = V - w * Ls
    TF, TA = math.hypot(H, V), math.hypot(H, VA)
    XH = L * inv_ea + (math.asinh(V / H) - math.asinh(VA / H) - V / TF + VA / TA) / w
    XV = (H / TF - H / TA) / w
    hV = Ls * inv_ea + (V / TF - VA / TA) / w
    return np.array([[XH, XV], [XV, hV]])


def _seabed_newton(L, inv_ea, w, X, h, H, V) -> tuple[float, float] | None:
    """Newton on the end conditions from (H, V), each step cut to keep H, V > 0 (at most
    a factor 10 down) and halved until the residual falls; None if it stalls."""

    def res(H: float, V: float) -> np.ndarray:
        Xe, he = _seabed_ends(L, inv_ea, w, H, V)
        return np.array([(Xe - X) / L, (he - h) / L])

    r = res(H, V)
    for _ in range(100):
        err = float(np.max(np.abs(r)))
        if err < 1e-15:
            return H, V
        try:
            dH, dV = np.linalg.solve(_seabed_flexibility(L, inv_ea, w, H, V), -r * L)
        except np.linalg.LinAlgError:
            return None
        t = 1.0
        if dH < -0.9 * H:
            t = -0.9 * H / dH
        if t * dV < -0.9 * V:
            t = -0.9 * V / dV
        for _ in range(60):
            H1, V1 = H + t * dH, V + t * dV
            r1 = res(H1, V1)
            if float(np.max(np.abs(r1))) < err:
                break
            t *= 0.5
        else:
            return (H, V) if err < 1e-13 else None  # round-off floor: no further decrease
        if abs(t * dH) <= 1e-16 * H and abs(t * dV) <= 1e-16 * V:
            return (H1, V1) if float(np.max(np.abs(r1))) < 1e-13 else None
        H, V, r = H1, V1, r1
    return None


def _seabed_bracketed(L: float, inv_ea: float, w: float, X: float, h: float) -> tuple[float, float]:
    """(H, V) by nested bracketed brentq: V(H) from (h), increasing in V; then H from
    (X) along V(H), increasing in H (``seabed_catenary``)."""

    def V_of(H: float) -> float:
        return _increasing_root(lambda V: _seabed_ends(L, inv_ea, w, H, V)[1], h, w * min(h, L))

    def X_of(H: float) -> float:
        if inv_ea == 0.0 and H > 1e200:  # inextensible: X -> sqrt(L^2 - h^2) as H -> inf
            return math.inf
        return _seabed_ends(L, inv_ea, w, H, V_of(H))[0]

    # Start from the inextensible seabed catenary's scale a = H/w ~ h/2 ... X^2/(2h).
    H = _increasing_root(X_of, X, w * max(h, X * X / (2.0 * h)))
    return H, V_of(H)


def seabed_catenary(L: float, EA: float, w: float, X: float, h: float) -> SeabedCatenary:
    """The elastic catenary of a mooring line partly resting on a frictionless, horizontal
    seabed (Faltinsen, *Sea Loads on Ships and Offshore Structures*, 1990, Sec. 8.2;
    Jonkman, *Dynamics of Offshore Floating Wind Turbines*, NREL/TP-500-47535, 2009,
    Sec. 4.2.2, the quasi-static line of FAST and MAP; MoorPy's ``catenary`` with CB = 0).

    The anchor is on the seabed z = 0 at x = 0, the fairlead at (X, h), h > 0 above it,
    X > 0 from it; L the unstretched length, EA the axial stiffness (inf: inextensible),
    w > 0 the submerged weight per unstretched length. Returns H, V (the fairlead's
    vertical tension), the grounded length L_B, the touchdown point x_TD, the anchor's
    force and the shape: a ``SeabedCatenary``.

    Derivation, z up, s the unstretched arc length from the anchor. With no friction the
    seabed pushes only vertically, so the horizontal tension H is the same everywhere and
    the anchor holds the line with H (towards the anchor). The fairlead holds it with
    (H, V). Cut at s: the part [s, L] is held by the fairlead and carries its own weight
    w (L - s), so the vertical component of the tension at s is V - w (L - s) if that is
    positive. Where it would be negative the line cannot hang: it lies on the seabed,
    which carries its weight, with no vertical tension. So, if V < w L, the line is
    grounded on [0, L_B], L_B = L - V/w, suspended on [L_B, L] with L_s = V/w, and
    touches down tangentially (vertical tension 0 at s = L_B): V = w L_s, the weight of
    the suspended part. If V >= w L the line is fully suspended and pulls the anchor up
    with V_A = V - w L: the ordinary inclined elastic catenary (``inclined_catenary``,
    whose V, the upward force of its left support, is -V_A). Both cases are
    Q(s) = V_A + w max(s - L_B, 0) with (L_B, V_A) = (L - V/w, 0) or (0, V - w L).

    Grounded part: straight, tension H, stretched by Hooke's law dp/ds = 1 + H/EA:
    x = s (1 + H/EA), z = 0. Suspended part (sigma = s - L_B, tension (H, Q),
    T = sqrt(H^2 + Q^2), dx/ds = H (1/T + 1/EA), dz/ds = Q (1/T + 1/EA), as in
    ``inclined_catenary``):

        x = L_B (1 + H/EA) + H sigma/EA + (H/w)[asinh(Q/H) - asinh(V_A/H)],
        z = (V_A sigma + w sigma^2/2)/EA + (H/w)[sqrt(1 + (Q/H)^2) - sqrt(1 + (V_A/H)^2)].

    At s = L the fairlead conditions x = X, z = h are two equations for (H, V); on the
    seabed (V_A = 0, L_s = V/w) they are the textbook pair

        X = L - V/w + H L/EA + (H/w) asinh(V/H),                          (X)
        h = V^2/(2 w EA) + (H/w) [sqrt(1 + (V/H)^2) - 1],                 (h)

    and the touchdown point is x_TD = L_B (1 + H/EA). The two regimes meet with a
    continuous first derivative at V = w L (the line just lifts off: L_B = 0, V_A = 0).

    Existence, uniqueness and the solve. (X, h) is the gradient of the complementary
    energy P(H, V) = int_0^L [T + T^2/(2 EA)] ds with T = sqrt(H^2 + Q^2),
    Q = max(V - w (L - s), 0): dP/dH = int H (1/T + 1/EA) ds = X and
    dP/dV = int Q (1/T + 1/EA) ds = h (the grounded part adds L_B (1 + H/EA) to X and
    nothing to h). T is a norm of (H, Q), and Q a convex, non-negative function of V, so
    P is convex, and strictly so for H > 0: the flexibility matrix d(X, h)/d(H, V) is
    symmetric positive definite (on the seabed its determinant is
    [u asinh u - 2 (sqrt(1 + u^2) - 1)] / (w^2 sqrt(1 + u^2)) > 0, u = V/H, plus positive
    1/EA terms). Hence h(H, V) increases in V from 0 (V = 0) to infinity, giving one
    V(H) for each H, and X(H, V(H)) increases in H (its slope is det / (dh/dV) > 0) from
    X_min (H -> 0) to infinity (or, EA = inf, to sqrt(L^2 - h^2)). X_min is the slack
    limit: a line hanging vertically to h has V_0 = w L_v with h = L_v + w L_v^2/(2 EA)
    (if L_v <= L), and the rest, L - L_v, lies straight on the bed: X_min = L - L_v
    (0 if L_v >= L). For X <= X_min the grounded part would have to bunch up (H = 0 and
    no unique shape): ``ConfigError``. The solve of (X), (h) for (H, V): ``_seabed_solve``.

    Limits: EA = inf gives the inextensible seabed catenary, on the seabed
    X = L - sqrt(h^2 + 2 a h) + a acosh(1 + h/a), a = H/w; a taut line (H >> w L) tends
    to a straight elastic bar, sqrt(X^2 + h^2) = L (1 + T/EA) + O(w L).
    """
    L = _positive("L", L)
    EA = _positive("EA", EA, allow_inf=True)
    w = _positive("w", w)
    X = _positive("X", X)
    h = _positive("h", h)
    inv_ea = 0.0 if math.isinf(EA) else 1.0 / EA
    _check_reachable(L, inv_ea, w, X, h)
    H, V = _seabed_solve(L, inv_ea, w, X, h)
    return SeabedCatenary(L=L, EA=EA, w=w, X=X, h=h, H=H, V=V)


def _check_reachable(L: float, inv_ea: float, w: float, X: float, h: float) -> None:
    """ConfigError when no taut line reaches the fairlead: an inextensible line shorter
    than the chord, or X at or below the slack limit X_min (``seabed_catenary``)."""
    if inv_ea == 0.0 and not math.hypot(X, h) < L:
        raise ConfigError(
            f"X = {X!r}, h = {h!r}: an inextensible line (EA = inf) needs "
            f"sqrt(X^2 + h^2) < L = {L!r}"
        )
    # The slack limit H -> 0: the line hangs vertically over L_v, w L_v + w^2 L_v^2/(2 EA) = w h.
    Lv = h if inv_ea == 0.0 else 2.0 * h / (1.0 + math.sqrt(1.0 + 2.0 * w * h * inv_ea))
    X_min = max(L - Lv, 0.0)
    if not X > X_min:
        raise ConfigError(
            f"X = {X!r}: the line is slack (X must exceed {X_min!r}, the grounded length of "
            f"the line hanging vertically to h = {h!r}); with H = 0 its shape is not unique"
        )


def _jonkman_guess(L: float, w: float, X: float, h: float) -> tuple[float, float]:
    """The starting (H, V) of Jonkman's (FAST's) catenary routine, as in MoorPy."""
    chord = math.hypot(X, h)
    lam = math.sqrt(3.0 * ((L * L - h * h) / (X * X) - 1.0)) if L > chord else 0.2
    H0 = max(0.5 * w * X / lam, 1e-6 * w * L)
    V0 = 0.5 * w * (h / math.tanh(lam) + L)
    return H0, V0


def _seabed_solve(L: float, inv_ea: float, w: float, X: float, h: float) -> tuple[float, float]:
    """(H, V) of the line that meets the end conditions (X), (h) of ``seabed_catenary``.

    Newton on (X), (h) with the analytic flexibility matrix (``_seabed_flexibility``),
    from the starting guess of Jonkman's catenary routine (FAST, MoorPy) and with steps
    halved until the residual falls, is tried first and converges in a few steps. The
    fallback, should it stall, is a bracketed ``brentq`` on a monotone function in each
    solve (V for a given H inside, H outside, both in log scale), which returns the root
    to round-off. The end conditions are then checked to 1e-12 of L (ArithmeticError)."""
    sol = _seabed_newton(L, inv_ea, w, X, h, *_jonkman_guess(L, w, X, h))
    H, V = map(float, sol if sol is not None else _seabed_bracketed(L, inv_ea, w, X, h))
    Xe, he = _seabed_ends(L, inv_ea, w, H, V)
    err = max(abs(Xe - X), abs(he - h)) / L
    if not err < 1e-12:
        raise ArithmeticError(f"seabed catenary: end conditions met only to {err:.1e} of L")
    return H, V
