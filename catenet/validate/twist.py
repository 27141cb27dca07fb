"""Twisted rods against closed forms: case (vi) of ``catenet validate``.

Rods of bending stiffness B = EI = 1 N m^2 and torsional stiffness C = GJ = 0.8 N m^2
(a round steel section has C / B = 1 / (1 + nu) = 0.77), twist eliminated
quasistatically (``catenet.terms.twist``):

(a) A straight rod, L = 1 m in 50 edges, clamped at both ends, the ends turned by 0.6
    and 0.4 rad ([[supports.twist]], as a case writes it): the straight rod is an
    equilibrium and its twisting moment is C (0.6 + 0.4) / L on every edge, exactly
    (tolerance 1e-9).
(b) A helix of radius R = 1 m and helix angle psi = 30 degrees (between the tangent and
    the axis), one turn, its material twisted at the rate tau = 1 rad/m, is an
    equilibrium of a naturally straight Kirchhoff rod under an axial force F and an axial
    moment M (Love, *A Treatise on the Mathematical Theory of Elasticity*, 4th ed., 1927,
    the rod bent into a helix; Chouaieb, Goriely and Maddocks, PNAS 103, 2006): with the
    curvature kappa = sin^2 psi / R and the torsion sin psi cos psi / R of the helix,

        F = (sin psi / R) (C tau - B sin psi cos psi / R),
        M = B kappa sin psi + C tau cos psi

    (from m' + t x n = 0 with m = B kappa b + C tau t, n = F e_z, e_z = cos psi t +
    sin psi b; F > 0 pulls the ends apart). The case clamps
    both ends where the helix ends and turns one by tau L; a clamp holds its end edge's
    given direction, so the end edges are given along the helix's tangent there (the
    chord's direction would hold the end straight). The reaction at the far end is F
    along the axis, and M from catenet's bending and twisting moments in the middle;
    second order in the edge length, tolerance 1e-3 at 200 edges.
(c) Greenhill's problem: a straight rod clamped at both ends, held apart, twisted by
    Phi: the straight rod buckles into a helix where the twisting moment reaches
    M L / B = 2 x 4.4934 = 8.9868 (twice the first positive root of tan x = x: the
    small deflections w = y + i z of B w'' - i M w' = a + b s clamped at both ends), so
    at Phi = 8.9868 B / C. catenet's stability verdict on the straight twisted rod turns
    at the Phi found by root finding on the least eigenvalue of its scaled tangent;
    tolerance 1e-3 at 100 edges.
(d) Michell's instability (Michell 1889; Goriely, J. Elasticity 84, 2006): a naturally
    straight rod closed into a circular ring with a twist Tw stays a stable circle while
    Tw < 2 pi sqrt(3) B / C (the twisting moment M = C Tw / (2 pi R) below sqrt(3) B / R).
    The ring (R = 1 m, n edges) is an equilibrium at every twist; its stiffness K + M G
    (G the twist's Hessian per unit moment) is positive on every motion but the six rigid
    ones up to the first M where it is singular: the generalised eigenvalue problem on
    the complement of the rigid motions. Tolerance 1e-3 at 200 edges.

(e) Torsional vibration (``catenet modes`` with the twist angles as DOFs,
    ``catenet.model.torsion``): a straight shaft, L = 1 m, of rotational inertia rho J_p
    = 0.01 kg m per length (``material.polar_inertia``; rho A = 1 kg/m), clamped at one
    end and free at the other: f_n = (2 n - 1) / (4 L) sqrt(C / (rho J_p)); clamped at
    both ends: f_n = n / (2 L) sqrt(C / (rho J_p)) (the wave equation of the twist angle,
    Timoshenko's shaft). Each mode whose kinetic energy lies mostly in the twist is
    torsional; the first against f_1. The angles live at the edges' midpoints, the
    clamps at the nodes: the discrete shaft's error is -(k h)^2 / 24 (k = (2 n - 1) pi /
    (2 L), n pi / L), second order; tolerance 1e-3 at 50 edges, order fitted over 25-100.

Nothing here prints; the rows are plain dicts of ``catenet.validate.table.Row``'s
fields.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from catenet.validate.rods import _row

EI = 1.0  # N m^2
GJ = 0.8  # N m^2
EA = 1e7  # N
RTOL = 1e-10
STRAIGHT_EDGES = 50
STRAIGHT_ANGLES = (0.6, 0.4)  # rad, the two ends' turns
EXACT_TOL = 1e-9
HELIX_RADIUS = 1.0  # m
HELIX_ANGLE = math.radians(30.0)
HELIX_TWIST = 1.0  # rad/m
HELIX_EA = 1e6  # N: F / EA = 2e-7
HELIX_EDGES = (50, 100, 200)
HELIX_TOL = 1e-3
GREENHILL = 2.0 * 4.493409457909064  # M L / B: twice the first root of tan x = x
GREENHILL_EDGES = (50, 100)
GREENHILL_TOL = 1e-3
MICHELL_EDGES = (50, 100, 200)
MICHELL_TOL = 1e-3
SHAFT_POLAR = 0.01  # rho J_p [kg m]
SHAFT_EDGES = (25, 50, 100)
SHAFT_TOL = 1e-3  # at 50 edges
SHAFT_ENDS = {"clamped-free": (["start"], 0.25), "clamped-clamped": (["start", "end"], 0.5)}


def straight_case(edges: int = STRAIGHT_EDGES) -> dict:
    """Case (a) as a case's tables."""
    return {
        "title": "a straight rod twisted between clamps",
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [1.0, 0.0, 0.0],
                     "nodes": edges + 1},
        "material": {"EA": EA, "EI": EI, "GJ": GJ},
        "supports": {
            "fixed": ["start", "end"],
            "clamped": ["start", "end"],
            "twist": [
                {"nodes": ["start"], "angle": STRAIGHT_ANGLES[0]},
                {"nodes": ["end"], "angle": STRAIGHT_ANGLES[1]},
            ],
        },
        "solver": {"rtol": RTOL},
    }  # fmt: skip


def _solved(case: dict):
    """The built scene of a case's tables and its static equilibrium."""
    from catenet.case import build, parse_case
    from catenet.solver import path

    scene = build(parse_case(case))
    result = path.solve(scene, path.Settings(rtol=RTOL))
    if not result.converged:
        raise ArithmeticError(f"{case['title']} did not converge: {result.message}")
    return scene, result


def straight_rows() -> list[dict]:
    """Case (a): the twisting moment of every edge against C Phi / L."""
    from catenet.model.summary import twisting_moments

    scene, result = _solved(straight_case())
    moment = twisting_moments(scene, result.x)
    if moment is None:
        raise ArithmeticError("the straight rod does not twist")
    exact = GJ * sum(STRAIGHT_ANGLES) / 1.0
    worst = float(moment[np.argmax(np.abs(moment - exact))])
    return [
        _row("twist: straight rod, ends turned", "M_t [N m]", STRAIGHT_EDGES + 1, worst,
             exact, tolerance=EXACT_TOL)
    ]  # fmt: skip


def helix_case(edges: int) -> dict:
    """Case (b) as a case's tables: one turn of the helix about z, its end edges along
    the tangent at its ends."""
    r, psi = HELIX_RADIUS, HELIX_ANGLE
    length = 2.0 * math.pi * r / math.sin(psi)
    phi = np.linspace(0.0, 2.0 * math.pi, edges + 1)
    nodes = np.column_stack([r * np.cos(phi), r * np.sin(phi), r / math.tan(psi) * phi])
    h = length / edges
    for node, neighbour, sign in ((0, 1, 1.0), (edges, edges - 1, -1.0)):
        p = phi[node]
        tangent = np.array([-math.sin(p) * math.sin(psi), math.cos(p) * math.sin(psi),
                            math.cos(psi)])  # fmt: skip
        nodes[neighbour] = nodes[node] + sign * h * tangent
    return {
        "title": "a twisted helix between clamps",
        "geometry": {"kind": "graph", "nodes": nodes.tolist(),
                     "cable": [{"name": "helix", "nodes": list(range(edges + 1))}]},
        "material": {"EA": HELIX_EA, "EI": EI, "GJ": GJ},
        "supports": {"fixed": [0, edges], "clamped": [0, edges],
                     "twist": [{"nodes": [edges], "angle": HELIX_TWIST * length}]},
        "solver": {"rtol": RTOL},
    }  # fmt: skip


def helix_wrench() -> tuple[float, float]:
    """Case (b)'s closed form (F [N], M [N m])."""
    r, psi, tau = HELIX_RADIUS, HELIX_ANGLE, HELIX_TWIST
    kappa = math.sin(psi) ** 2 / r
    force = math.sin(psi) / r * (GJ * tau - EI * math.sin(psi) * math.cos(psi) / r)
    moment = EI * kappa * math.sin(psi) + GJ * tau * math.cos(psi)
    return force, moment


def helix(edges: int) -> tuple[float, float, float]:
    """(F [N]: the far end's reaction along the axis, M [N m]: the axial moment from the
    middle's bending and twisting moments, the reaction across the axis [N])."""
    from catenet.model.rods import bending_moment
    from catenet.model.summary import scene_rods, twisting_moments

    scene, result = _solved(helix_case(edges))
    rods = scene_rods(scene)
    assert rods is not None  # the case's rod
    bend, _ = bending_moment(rods, result.x, scene.net.n_nodes)
    twist = twisting_moments(scene, result.x)
    if twist is None:
        raise ArithmeticError("the helix does not twist")
    mid = edges // 2
    psi = HELIX_ANGLE
    axial = float(bend[mid] * math.sin(psi) + twist[mid] * math.cos(psi))
    reaction = np.asarray(result.reaction)[edges]
    return float(reaction[2]), axial, float(np.hypot(reaction[0], reaction[1]))


def helix_rows() -> list[dict]:
    """Case (b): F and M at each resolution, the fitted orders."""
    force, moment = helix_wrench()
    found = [helix(n) for n in HELIX_EDGES]
    rows = []
    for k, (name, exact) in enumerate((("F [N]", force), ("M [N m]", moment))):
        errors = [abs(f[k] - exact) / abs(exact) for f in found]
        order = -float(np.polyfit(np.log(HELIX_EDGES), np.log(errors), 1)[0])
        for n, f in zip(HELIX_EDGES, found, strict=True):
            tol = HELIX_TOL if n == HELIX_EDGES[-1] else math.nan
            rows.append(_row("twist: helix, end force and moment", name, n + 1, f[k], exact,
                             order=order, tolerance=tol))  # fmt: skip
    return rows


def _straight_scene(edges: int):
    """Case (c)'s straight rod (L = 1 m along x, both ends clamped) and its Twist term."""
    from catenet.model.net import Loads, Net
    from catenet.model.rods import build_rods
    from catenet.model.twist import build_twists
    from catenet.scene import Scene
    from catenet.terms.bending import Bending
    from catenet.terms.twist import Twist

    n = edges
    x = np.zeros((n + 1, 3))
    x[:, 0] = np.linspace(0.0, 1.0, n + 1)
    pairs = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    net = Net.from_arrays(x, pairs, EA=EA, fixed=[0, n], tension_only=False)
    line = np.zeros(n, np.int64)
    rods = build_rods(net, np.full(n, EI), line, clamped=np.array([0, n]))
    twists = build_twists(net, np.full(n, GJ), line, rods.clamps, rods.tangent)
    twist = Twist(twists, net.n_nodes, x)
    return Scene(net, Loads(), (Bending(rods, net.n_nodes), twist)), twist


def greenhill(edges: int) -> float:
    """The twist Phi [rad] at which catenet's verdict on case (c)'s straight rod turns
    unstable."""
    from scipy.optimize import brentq

    from catenet.solver.tangent import tangent
    from catenet.solver.workspace import Workspace

    scene, twist = _straight_scene(edges)
    ws = Workspace(scene.net, terms=scene.terms)
    x = scene.net.nodes

    def least(phi: float) -> float:
        twist.imposed = ((0, phi, None),)
        return tangent(ws.system, ws.solver, x).least

    exact = GREENHILL * EI / GJ
    return float(brentq(least, 0.8 * exact, 1.2 * exact, xtol=1e-13, rtol=1e-13))


def greenhill_rows() -> list[dict]:
    """Case (c): the critical twist at each resolution."""
    exact = GREENHILL * EI / GJ
    found = [greenhill(n) for n in GREENHILL_EDGES]
    errors = [abs(f - exact) / exact for f in found]
    order = -float(np.polyfit(np.log(GREENHILL_EDGES), np.log(errors), 1)[0])
    return [
        _row("twist: Greenhill, clamped ends", "Phi_cr [rad]", n + 1, f, exact, order=order,
             tolerance=GREENHILL_TOL if n == GREENHILL_EDGES[-1] else math.nan)
        for n, f in zip(GREENHILL_EDGES, found, strict=True)
    ]  # fmt: skip


def _dense_hessian(terms, x: np.ndarray) -> np.ndarray:
    """The Hessian of the sum of ``terms`` at x over every DOF, dense."""
    n = x.size
    out = np.zeros((n, n))
    for term in terms:
        rows, cols = term.pattern()
        values = np.zeros(len(rows))
        term.hessian(x, values)
        np.add.at(out, (rows, cols), values)
    return 0.5 * (out + out.T)


def michell(edges: int) -> float:
    """The critical twist Tw [rad] of a naturally straight ring of ``edges`` edges
    (case (d)): the least M > 0 where K + M G turns singular on the complement of the
    rigid motions, times 2 pi R / C."""
    from scipy.linalg import eigh, null_space

    from catenet.model.net import Net
    from catenet.model.rods import build_rods
    from catenet.model.twist import build_twists
    from catenet.terms.bending import Bending
    from catenet.terms.stretch import Stretch
    from catenet.terms.twist import Twist

    k = np.arange(edges)
    a = 2.0 * np.pi * k / edges
    x = np.column_stack([np.cos(a), np.sin(a), np.zeros(edges)])
    pairs = np.column_stack([k, (k + 1) % edges])
    net = Net.from_arrays(x, pairs, EA=EA, fixed=[0], tension_only=False)
    line = np.zeros(edges, np.int64)
    rods = build_rods(net, np.full(edges, EI), line)
    twist = Twist(build_twists(net, np.full(edges, GJ), line, rods.clamps, rods.tangent),
                  edges, x)  # fmt: skip
    terms = (Stretch(net), Bending(rods, edges), twist)
    stiffness = _dense_hessian(terms, x)
    twist.imposed = ((0, 1.0, None),)  # M = 1 / C: G is the change per unit moment
    per_moment = (_dense_hessian(terms, x) - stiffness) * float(twist.twists.compliance[0])
    rigid = np.zeros((3 * edges, 6))
    for d in range(3):
        rigid[d::3, d] = 1.0  # translations
        axis = np.eye(3)[d]
        rigid[:, 3 + d] = np.cross(axis, x).ravel()  # rotations
    z = null_space(rigid.T)
    ratio = eigh(-(z.T @ per_moment @ z), z.T @ stiffness @ z, eigvals_only=True)
    moment = 1.0 / float(np.max(ratio))
    return moment * 2.0 * np.pi * 1.0 / GJ


def michell_rows() -> list[dict]:
    """Case (d): the critical twist at each resolution."""
    exact = 2.0 * math.pi * math.sqrt(3.0) * EI / GJ
    found = [michell(n) for n in MICHELL_EDGES]
    errors = [abs(f - exact) / exact for f in found]
    order = -float(np.polyfit(np.log(MICHELL_EDGES), np.log(errors), 1)[0])
    return [
        _row("twist: Michell's ring", "Tw_cr [rad]", n, f, exact, order=order,
             tolerance=MICHELL_TOL if n == MICHELL_EDGES[-1] else math.nan)
        for n, f in zip(MICHELL_EDGES, found, strict=True)
    ]  # fmt: skip


def shaft_case(edges: int, ends: str) -> dict:
    """Case (e) as a case's tables: the shaft clamped at "start" (and "end")."""
    held, _ = SHAFT_ENDS[ends]
    return {
        "title": f"a shaft, {ends}",
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [1.0, 0.0, 0.0],
                     "nodes": edges + 1},
        "material": {"EA": 1e5, "EI": EI, "GJ": GJ, "area": 1e-3, "density": 1000.0,
                     "polar_inertia": SHAFT_POLAR, "tension_only": False},
        "supports": {"fixed": held, "clamped": held},
    }  # fmt: skip


def shaft(edges: int, ends: str, count: int = 3) -> np.ndarray:
    """The ``count`` lowest torsional frequencies [Hz] of case (e) (the modes whose
    kinetic energy lies mostly in the twist)."""
    import logging

    from catenet.case import build, parse_case
    from catenet.solver.modes import modes

    quiet = logging.Filter("nothing")  # its warning: a free end untwists at rest
    logging.getLogger("catenet.case").addFilter(quiet)
    try:
        scene = build(parse_case(shaft_case(edges, ends)))
    finally:
        logging.getLogger("catenet.case").removeFilter(quiet)
    found = modes(scene, k=4 * count + 6, x=scene.net.nodes, method="lanczos")
    torsional: np.ndarray = found.frequency[found.twist_share() > 0.5][:count]
    if torsional.size < count:
        raise ArithmeticError(f"the {ends} shaft has {torsional.size} torsional modes")
    return torsional


def shaft_rows() -> list[dict]:
    """Case (e): the first torsional frequency of each shaft at each resolution."""
    rows = []
    for ends, (_, first) in SHAFT_ENDS.items():
        exact = first * math.sqrt(GJ / SHAFT_POLAR)
        found = [float(shaft(n, ends, 1)[0]) for n in SHAFT_EDGES]
        errors = [abs(f - exact) / exact for f in found]
        order = -float(np.polyfit(np.log(SHAFT_EDGES), np.log(errors), 1)[0])
        rows += [
            _row(f"twist: shaft {ends}", "f_1 [Hz]", n + 1, f, exact, order=order,
                 tolerance=SHAFT_TOL if n == 50 else math.nan)
            for n, f in zip(SHAFT_EDGES, found, strict=True)
        ]  # fmt: skip
    return rows


def twist_rows(progress: Callable[[str], None] | None = None) -> list[dict]:
    """Every row of case (vi)."""
    if progress:
        progress(
            "twisted rods: a straight rod, a helix, Greenhill's rod, Michell's ring, "
            "torsional vibration"
        )
    return straight_rows() + helix_rows() + greenhill_rows() + michell_rows() + shaft_rows()
