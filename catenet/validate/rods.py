"""Rods against closed forms: case (iv) of ``catenet validate``.

A straight rod of length L = 1 m, EI = 1 N m^2, EA = 1e7 N (EA L^2 / EI = 1e7: the
axial strain at the largest load here is 1e-6, so the rod is inextensible to that
share), in n equal edges (``catenet.terms.bending``):

(a) Euler buckling of a pinned strut. Both ends pinned, the far one moved towards the
    other, so the straight strut carries the compression P = EA (l / l0 - 1). The
    straight state is an equilibrium at every shortening; catenet's stability verdict
    (``catenet.solver.tangent.tangent``: the least eigenvalue of its scaled tangent)
    turns from stable to unstable at the critical load, found by root finding on that
    eigenvalue, against pi^2 EI / L^2. The discrete strut's exact critical load is
    pi^2 EI / L^2 (sin(h') / h')^2, h' = pi / (2 n): the error is -(pi / 2n)^2 / 3,
    3.3e-4 at 50 edges; tolerance 1e-3 there, order fitted over n = 12, 25, 50.
(b) A cantilever under a transverse end load P (clamped at one end, ``supports.clamped``'s
    clamp): the tip against the elastica (Bisshopp and Drucker 1945, by the exact
    integrals of ``elastica_tip``), at P L^2 / EI = 1 and 3 (tip angles 26 and 56
    degrees). The error is second order in the edge length; tolerance 1e-4 of L at
    100 edges for both coordinates of the tip, information at 50. (At 10, tip angle 82
    degrees, the errors at 100 edges are 5.4e-5 and 7.0e-5:
    tests/validate/test_rod_closed_forms.py.)
(c) The first natural frequency (``catenet.solver.modes``, lumped masses rho A l0 / 2,
    rho A = 1 kg/m, EA = 1e5 N: the straight rod's bending modes do not depend on it)
    of a simply supported rod (beta L = pi), a cantilever (beta L = 1.87510407) and a
    rod clamped at both ends (beta L = 4.73004074), omega = (beta L)^2 sqrt(EI / (rho A
    L^4)); tolerance 1e-3 (at 50 edges, 100 for the clamped one).
(d) A thin ring (radius R = 1 m, EI = 1 N m^2, EA = 1e6 N, naturally curved as drawn)
    under a diametral load P = 1e-4 N (P R^2 / EI = 1e-4: linear), as a case writes it
    (a closed ``[[geometry.cable]]``, ``natural_curvature = "given"``): its lowest node
    fixed, its highest on a vertical slider under the load, every other node on a roller
    in the ring's plane. The loaded diameter shortens by (pi / 4 - 2 / pi) P R^3 / EI and
    the one across lengthens by (2 / pi - 1 / 2) P R^3 / EI (Roark's thin ring, case 1);
    the moment under the load is P R / pi. The error falls about as the square of the
    edge length (fitted orders 1.7 and 1.9 over 100-400 edges); tolerance 1e-3 at 400.

Nothing here prints; the rows are plain dicts of ``catenet.validate.table.Row``'s
fields.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

EI = 1.0  # N m^2
LENGTH = 1.0  # m
EA = 1e7  # N
LINE_DENSITY = 1.0  # kg/m
RTOL = 1e-10
BUCKLING_EDGES = (12, 25, 50)
BUCKLING_TOL = 1e-3
CANTILEVER_LOADS = (1.0, 3.0)  # P L^2 / EI
CANTILEVER_EDGES = (50, 100)
CANTILEVER_TOL = 1e-4  # of L, at the finest resolution
FREQUENCY_TOL = 1e-3
#: The straight rod's bending modes do not depend on EA (its axial modes, above 1e2
#: rad/s, are apart); a stiffness contrast of 1e7 would only spread the spectrum beyond
#: what the eigensolver's residual check accepts.
FREQUENCY_EA = 1e5
RING_EDGES = (100, 200, 400)
RING_LOAD = 1e-4  # N: P R^2 / EI = 1e-4: linear to that share
#: EI / (EA R^2) = 1e-6: the hoop strain's share of the deflection; the forces' round-off
#: (EA eps |x| / l0, 1e-8 N at 400 edges) stays far below the load
RING_EA = 1e6
RING_TOL = 1e-3
#: (name, supports: "pinned" or "clamped" per end (None: free), beta L, edges)
FREQUENCY_CASES = (
    ("simply supported", ("pinned", "pinned"), math.pi, 50),
    ("cantilever", ("clamped", None), 1.87510407, 50),
    ("clamped-clamped", ("clamped", "clamped"), 4.73004074, 100),
)


def elastica_tip(alpha: float) -> tuple[float, float, float]:
    """Tip angle theta0 [rad] and tip position (x / L, y / L) of an inextensible
    cantilever under a transverse end load, alpha = P L^2 / EI (below about 1e3).

    EI theta'' = -P cos(theta), theta(0) = 0, theta'(L) = 0 integrate to
    EI theta'^2 / 2 = P (sin theta0 - sin theta), so that sqrt(2 alpha) =
    int_0^theta0 dtheta / sqrt(sin theta0 - sin theta), x / L = sqrt(2 sin theta0 /
    alpha) and y / L = int_0^theta0 sin theta dtheta / sqrt(sin theta0 - sin theta) /
    sqrt(2 alpha). With t = theta0 - theta, sin theta0 - sin theta = 2 cos(theta0 -
    t / 2) sin(t / 2): the integrals are t^(-1/2) times a smooth function (QUADPACK's
    algebraic weight). alpha = 1 gives theta0 = 0.46135, x = 0.94357, y = 0.30172;
    alpha = 10: 1.43029, 0.44500, 0.81061 (Bisshopp and Drucker's table)."""
    from scipy.integrate import quad
    from scipy.optimize import brentq

    def integral(theta0: float, f: Callable[[float], float]) -> float:
        def smooth(t: float) -> float:
            ratio = 1.0 if t == 0.0 else 0.5 * t / math.sin(0.5 * t)
            return f(theta0 - t) * math.sqrt(ratio / math.cos(theta0 - 0.5 * t))

        value = quad(smooth, 0.0, theta0, weight="alg", wvar=(-0.5, 0.0), limit=200)
        return float(value[0])

    target = math.sqrt(2.0 * alpha)
    theta0 = brentq(
        lambda th: integral(th, lambda s: 1.0) - target, 1e-12, 0.5 * math.pi - 1e-9, xtol=1e-15
    )
    x = math.sqrt(2.0 * math.sin(theta0) / alpha)
    y = integral(theta0, math.sin) / target
    return theta0, x, y


def _rod(
    edges: int,
    *,
    end: float = LENGTH,
    ends=("pinned", "pinned"),
    density: float = 0.0,
    axial: float = EA,
):
    """A straight rod along x from 0 to ``end`` (rest length L), its ends pinned,
    clamped or free (None), of axial stiffness ``axial``, and its Scene (the rod's
    ``Bending`` term)."""
    from catenet.model.net import Loads, Net
    from catenet.model.rods import build_rods
    from catenet.scene import Scene
    from catenet.terms.bending import Bending

    n = edges
    x = np.zeros((n + 1, 3))
    x[:, 0] = np.linspace(0.0, end, n + 1)
    pairs = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    held = [i for i, kind in zip((0, n), ends, strict=True) if kind is not None]
    net = Net.from_arrays(
        x,
        pairs,
        EA=axial,
        fixed=held,
        rest_length=np.full(n, LENGTH / n),
        tension_only=False,
        line_density=density,
    )
    clamped = [i for i, kind in zip((0, n), ends, strict=True) if kind == "clamped"]
    rods = build_rods(net, np.full(n, EI), np.zeros(n, np.int64), clamped=np.array(clamped))
    return Scene(net, Loads(), (Bending(rods, net.n_nodes),))


def _row(case: str, quantity: str, nodes: int, value: float, exact: float, **kw) -> dict:
    error = abs(value - exact) / abs(exact) if "error" not in kw else kw.pop("error")
    tol = kw.pop("tolerance", math.nan)
    passed = None if math.isnan(tol) else bool(error <= tol)
    return dict(
        case=case,
        quantity=quantity,
        resolution=nodes,
        catenet=value,
        analytic=exact,
        error=error,
        tolerance=tol,
        passed=passed,
        **kw,
    )


def critical_load(edges: int) -> float:
    """The compression [N] at which catenet's verdict on the straight pinned strut of
    ``edges`` edges turns unstable (module docstring, (a))."""
    from scipy.optimize import brentq

    from catenet.solver.tangent import tangent
    from catenet.solver.workspace import Workspace

    scene = _rod(edges)
    ws = Workspace(scene.net, terms=scene.terms)

    def least(shortening: float) -> tuple[float, float]:
        x = scene.net.nodes * np.array([1.0 - shortening / LENGTH, 1.0, 1.0])
        _, grad = ws.system.gradient(x)  # the straight state: an equilibrium, every shortening
        if not np.max(np.abs(grad[~scene.net.fixed])) <= 1e-6 * EA * shortening / LENGTH:
            raise ArithmeticError("the straight strut is not in equilibrium")
        found = tangent(ws.system, ws.solver, x)
        return found.least, -float(np.mean(ws.system.tension(x)))

    euler = math.pi**2 * EI / LENGTH**2
    d = brentq(lambda s: least(s)[0], 0.5 * euler / EA, 1.5 * euler / EA, xtol=1e-17, rtol=1e-14)
    return least(d)[1]


def buckling_rows() -> list[dict]:
    """Case (a): the critical load at each resolution and the fitted order."""
    euler = math.pi**2 * EI / LENGTH**2
    loads = [critical_load(n) for n in BUCKLING_EDGES]
    errors = [abs(p - euler) / euler for p in loads]
    order = float(np.polyfit(np.log(BUCKLING_EDGES), np.log(errors), 1)[0]) * -1.0
    rows = []
    for n, p in zip(BUCKLING_EDGES, loads, strict=True):
        tol = BUCKLING_TOL if n == BUCKLING_EDGES[-1] else math.nan
        rows.append(
            _row("rod: Euler buckling", "P_cr", n + 1, p, euler, order=order, tolerance=tol)
        )
    return rows


def tip(edges: int, alpha: float) -> np.ndarray:
    """The cantilever's tip (x, y) / L under P L^2 / EI = ``alpha`` (case (b))."""
    from catenet.model.net import Loads
    from catenet.scene import Scene
    from catenet.solver import path

    rod = _rod(edges, ends=("clamped", None))
    force = np.zeros((edges + 1, 3))
    force[edges, 2] = -alpha * EI / LENGTH**2
    scene = Scene(rod.net, Loads(force=force), rod.terms)
    result = path.solve(scene, path.Settings(rtol=RTOL, steps=max(1, int(alpha) // 2)))
    if not result.converged:
        raise ArithmeticError(f"the cantilever did not converge: {result.message}")
    end = result.x[edges]
    return np.array([end[0], -end[2]]) / LENGTH


def cantilever_rows() -> list[dict]:
    """Case (b): the tip's x and y against the elastica at each load and resolution."""
    rows = []
    for alpha in CANTILEVER_LOADS:
        _, x_ex, y_ex = elastica_tip(alpha)
        tips = [tip(n, alpha) for n in CANTILEVER_EDGES]
        for k, name, exact in ((0, "tip x/L", x_ex), (1, "tip y/L", y_ex)):
            errors = [abs(t[k] - exact) for t in tips]
            order = -float(np.polyfit(np.log(CANTILEVER_EDGES), np.log(errors), 1)[0])
            for n, t, err in zip(CANTILEVER_EDGES, tips, errors, strict=True):
                tol = CANTILEVER_TOL if n == CANTILEVER_EDGES[-1] else math.nan
                rows.append(
                    _row(
                        f"rod: cantilever PL^2/EI={alpha:g}",
                        name,
                        n + 1,
                        float(t[k]),
                        exact,
                        error=err,
                        order=order,
                        tolerance=tol,
                    )
                )
    return rows


def frequency_rows() -> list[dict]:
    """Case (c): the first natural frequency of three rods."""
    from catenet.solver.modes import modes

    rows = []
    for name, ends, beta, edges in FREQUENCY_CASES:
        scene = _rod(edges, ends=ends, density=LINE_DENSITY, axial=FREQUENCY_EA)
        found = modes(scene, k=2, x=scene.net.nodes)
        omega = 2.0 * math.pi * float(found.frequency[0])
        exact = beta**2 * math.sqrt(EI / (LINE_DENSITY * LENGTH**4))
        rows.append(
            _row(f"rod: {name}", "omega_1", edges + 1, omega, exact, tolerance=FREQUENCY_TOL)
        )
    return rows


def ring_case(edges: int, load: float = RING_LOAD) -> dict:
    """The ring of case (d) as a case's tables (radius 1 m in the x-z plane, node 0 at
    the bottom, node edges / 2 at the top under the load)."""
    k = np.arange(edges)
    nodes = np.column_stack(
        [np.sin(2 * np.pi * k / edges), np.zeros(edges), -np.cos(2 * np.pi * k / edges)]
    )
    top = edges // 2
    others = [int(i) for i in k if i not in (0, top)]
    return {
        "title": "thin ring under diametral load",
        "geometry": {
            "kind": "graph",
            "nodes": nodes.tolist(),
            "cable": [{"name": "ring", "nodes": [*range(edges), 0]}],
        },
        "material": {
            "EA": RING_EA,
            "EI": EI,
            "natural_curvature": "given",
            "tension_only": False,
        },
        "supports": {
            "fixed": [0],
            "slider": [{"nodes": [top], "direction": [0.0, 0.0, 1.0]}],
            "roller": [{"nodes": others, "normal": [0.0, 1.0, 0.0]}],
        },
        "load": {"point": [{"node": top, "force": [0.0, 0.0, -load]}]},
        "solver": {"rtol": RTOL},
    }


def ring(edges: int) -> tuple[float, float, float]:
    """(shortening of the loaded diameter, lengthening of the other [m], the moment
    under the load [N m]) of the ring of case (d)."""
    from catenet.case import build, parse_case
    from catenet.model.rods import bending_moment
    from catenet.solver import path
    from catenet.terms.bending import Bending

    scene = build(parse_case(ring_case(edges)))
    result = path.solve(scene, path.Settings(rtol=RTOL))
    if not result.converged:
        raise ArithmeticError(f"the ring did not converge: {result.message}")
    x, x0 = result.x, scene.net.nodes
    top, side = edges // 2, edges // 4
    (bend,) = [t for t in scene.terms if isinstance(t, Bending)]
    moments, _ = bending_moment(bend.rods, x, scene.net.n_nodes)
    return (
        float(x0[top, 2] - x[top, 2]),
        float(x[side, 0] - x[edges - side, 0] - (x0[side, 0] - x0[edges - side, 0])),
        float(abs(moments[top])),
    )


def ring_rows() -> list[dict]:
    """Case (d): both diameters' changes at each resolution, the fitted order, and the
    moment under the load."""
    scale = RING_LOAD * 1.0**3 / EI
    exact = {
        "loaded diameter": (math.pi / 4 - 2 / math.pi) * scale,
        "diameter across": (2 / math.pi - 0.5) * scale,
    }
    found = [ring(n) for n in RING_EDGES]
    rows = []
    for k, (name, value) in enumerate(exact.items()):
        errors = [abs(f[k] - value) / value for f in found]
        order = -float(np.polyfit(np.log(RING_EDGES), np.log(errors), 1)[0])
        for n, f in zip(RING_EDGES, found, strict=True):
            tol = RING_TOL if n == RING_EDGES[-1] else math.nan
            rows.append(
                _row("rod: ring, diametral load", name, n, f[k], value, order=order, tolerance=tol)
            )
    moment = RING_LOAD * 1.0 / math.pi
    rows.append(
        _row("rod: ring, diametral load", "M under the load", RING_EDGES[-1], found[-1][2],
             moment, tolerance=RING_TOL)
    )  # fmt: skip
    return rows


def rod_rows(progress: Callable[[str], None] | None = None) -> list[dict]:
    """Every row of case (iv)."""
    if progress:
        progress("rods: Euler buckling, cantilever elastica, natural frequencies, a ring")
    return buckling_rows() + cantilever_rows() + frequency_rows() + ring_rows()
