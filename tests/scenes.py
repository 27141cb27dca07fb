"""The suite's hard scenes: the paper's nets and cables, and the scenes of the stress test
(``tests/stress_matrix.py``, also run in full by ``benchmarks/stress.py``) with their checks.

Each scene function solves one scene and returns ``results`` (the solver's Result
objects), ``check``, ``value``, ``tol``, ``equilibrium_error`` and ``note``; it raises a
``CatenetError`` where the solver refuses the scene.
"""

from __future__ import annotations

import math
import time

# The paper's material and load (Sec. 3): E = 10 MPa, r = 1 cm, density 1000 kg/m^3.
PAPER_E = 10e6
PAPER_RADIUS = 0.01
PAPER_DENSITY = 1000.0
PAPER_PRESSURE = 100.0
PAPER_EDGE = 0.01

# --- scenes -------------------------------------------------------------------------------


def paper_material(tension_only: bool = True):
    from catenet.model.builders import Material

    return Material.from_E(
        PAPER_E, radius=PAPER_RADIUS, density=PAPER_DENSITY, tension_only=tension_only
    )


def paper_net(n: int, *, alpha: float = 0.0, edge: float = PAPER_EDGE, pressure=PAPER_PRESSURE):
    """The paper's square net (L = 1 m) and its pressure load: (SquareNet, Loads)."""
    from catenet.model.builders import pressure_force, square_net
    from catenet.model.net import Loads

    sq = square_net(n, alpha, 1.0, edge, paper_material())
    return sq, Loads(force=pressure_force(sq.net, pressure, 1.0))


def midpoint_cable(
    F: float,
    *,
    nodes: int = 21,
    EA: float | None = None,
    L: float = 1.0,
    line_density: float | None = None,
    tension_only: bool = True,
):
    """A straight cable of length L pinned at both ends, force F down on its midpoint
    node (``nodes`` odd): (Net, Loads, midpoint index)."""
    import numpy as np

    from catenet.model.builders import Material, cable
    from catenet.model.net import Loads

    mat = paper_material(tension_only)
    if EA is not None or line_density is not None:
        mat = Material(
            EA=mat.EA if EA is None else EA,
            line_density=mat.line_density if line_density is None else line_density,
            tension_only=tension_only,
        )
    net = cable([-L / 2, 0, 0], [L / 2, 0, 0], nodes, mat)
    mid = (nodes - 1) // 2
    f = np.zeros((nodes, 3))
    f[mid, 2] = -F
    return net, Loads(force=f), mid


def compressed_catenary(
    dL: float,
    *,
    nodes: int = 101,
    L: float = 1.0,
    ramp: float = 0.0,
    EA: float | None = None,
    tension_only: bool = True,
):
    """A cable of length L under its own weight whose ends move inward by dL/2 each (the
    paper's compressed catenary, Fig. 2a): (Net, Loads)."""
    import numpy as np

    from catenet.model.builders import Material, cable
    from catenet.model.net import Loads

    mat = paper_material(tension_only)
    if EA is not None:
        mat = Material(EA=EA, line_density=mat.line_density, tension_only=tension_only)
    net = cable([-L / 2, 0, 0], [L / 2, 0, 0], nodes, mat)
    d = np.zeros((nodes, 3))
    d[0, 0] = dL / 2
    d[-1, 0] = -dL / 2
    ramp_time = None
    if ramp > 0:
        ramp_time = np.zeros(nodes)
        ramp_time[[0, -1]] = ramp
    return net, Loads(
        gravity=np.array([0.0, 0.0, -9.81]), support_displacement=d, ramp_time=ramp_time
    )


# --- checks ---------------------------------------------------------------------------------


def equilibrium_error(net, loads, res, factor: float = 1.0) -> float:
    """max(|residual at free nodes|, |sum reactions + sum loads|) / load scale, from the
    returned positions and reactions."""
    import numpy as np

    from catenet.solver.system import System

    system = System(net)
    _, g = system.gradient(res.x)
    f = loads.external_force(net, factor)
    free = ~net.fixed
    residual = float(np.linalg.norm(g[free] - f[free]))
    balance = float(np.linalg.norm(res.reaction.sum(axis=0) + f.sum(axis=0)))
    # Round-off of the internal forces: an error eps |x| in the coordinates makes a force
    # error EA eps |x| / l0 at each end of every edge (as in catenet.solver.newton).
    k_norm = float(np.sqrt(2.0 * np.sum((net.EA / net.rest_length) ** 2)))
    roundoff = 1e2 * np.finfo(float).eps * k_norm * float(np.max(np.abs(res.x)))
    if max(residual, balance) <= roundoff:
        return 0.0
    scale = max(float(np.linalg.norm(f)), float(np.linalg.norm(g)), 1e-300)
    return max(residual, balance) / scale


def finite(res) -> bool:
    import numpy as np

    arrays = [res.x, res.tension, res.reaction] + ([res.v] if res.v is not None else [])
    scalars = [res.residual]
    return all(bool(np.all(np.isfinite(a))) for a in arrays) and all(
        math.isfinite(s) for s in scalars
    )


def eq_row(check, value, tol, results, net, loads, note="", factor=1.0):
    """A row whose answer must also be an equilibrium (when the solver says so)."""
    eq = max(
        (equilibrium_error(net, loads, r, factor) for r in results if r.equilibrium), default=0.0
    )
    return {
        "results": results,
        "check": check,
        "value": value,
        "tol": tol,
        "equilibrium_error": eq,
        "note": note,
    }


# --- scenes ---------------------------------------------------------------------------------


def _solve(net, loads, method: str, *, dt: float, damping: float, t_end: float, budget: float):
    """A scene through catenet's solve path; dynamic runs stop after ``budget`` seconds."""
    from catenet.scene import Scene
    from catenet.solver import path as sv

    start = time.perf_counter()

    def stop(step: sv.Step) -> bool:
        return time.perf_counter() - start > budget

    settings = sv.Settings(method, dt=dt, damping=damping, t_end=t_end)
    return sv.solve(Scene(net, loads), settings, on_step=stop if method == "dynamic" else None)


def midpoint_load(
    F_bar: float | None = None,
    F: float | None = None,
    EA: float | None = None,
    nodes: int = 21,
    method: str = "static",
    h: float = 1e-2,
    damping: float = 1.0,
    steps: int | None = None,
    budget: float = 10.0,
):
    """Cable (L = 1) under a midpoint load, against Eq. 17."""
    from catenet.validate import analytic

    EA = paper_material().EA if EA is None else EA
    if F is None:
        if F_bar is None:
            raise ValueError("midpoint_load: give F or F_bar")
        F = F_bar * EA
    net, loads, mid = midpoint_cable(F, nodes=nodes, EA=EA)
    exact = analytic.midpoint_load_deflection(F, 1.0, EA)
    t_end = steps * h if steps else 1e6 * h
    res = _solve(net, loads, method, dt=h, damping=damping, t_end=t_end, budget=budget)
    delta = -float(res.x[mid, 2])
    strain = res.max_strain
    if method == "dynamic" and not res.equilibrium:
        # Stopped before equilibrium (few steps of a tiny h, or capped): bounded motion.
        ok_bound = 0.0 <= delta <= 2.5 * exact or abs(delta) < 1e-12
        return eq_row(
            "bounded",
            0.0 if ok_bound else delta / exact,
            1.0,
            [res],
            net,
            loads,
            note=f"{res.steps} steps to t = {res.time:.3g} s, {res.message}",
        )
    err = abs(delta - exact) / exact
    return eq_row(
        "eq17", err, 1e-6, [res], net, loads, note=f"delta/L = {delta:.4g}, max strain {strain:.3g}"
    )


def self_weight(
    dL: float = 0.0,
    nodes: int = 101,
    EA: float | None = None,
    method: str = "static",
    h: float = 1e-2,
    ramp: float = 1.0,
    tension_only: bool = True,
    budget: float = 20.0,
):
    """Cable of length 1 under its own weight, supports moved inward by dL (0: a straight
    zero-slack cable), against the exact discrete chain."""
    from catenet.validate import analytic

    net, loads = compressed_catenary(
        dL, nodes=nodes, EA=EA, tension_only=tension_only, ramp=ramp if method == "dynamic" else 0.0
    )
    EA_ = float(net.EA[0])
    w = float(net.line_density[0]) * 9.81
    exact = analytic.discrete_catenary(1.0, EA_, w, 1.0 - dL, nodes - 1).sag
    res = _solve(net, loads, method, dt=h, damping=1.0, t_end=1e4, budget=budget)
    if method == "dynamic":
        if not res.equilibrium:
            return eq_row(
                "chain",
                math.inf,
                1e-6,
                [res],
                net,
                loads,
                note=f"no equilibrium within {budget:g} s wall ({res.steps} steps, "
                f"t = {res.time:.3g} s)",
            )
    mid = (nodes - 1) // 2
    sag = -float(res.x[mid, 2])
    return eq_row(
        "chain",
        abs(sag - exact) / exact,
        1e-6,
        [res],
        net,
        loads,
        note=f"sag {sag:.6g} m, chain {exact:.6g} m",
    )


def bilateral_compression(
    dL: float = 0.1,
    nodes: int = 21,
    gravity: bool = False,
    perturb: float = 0.0,
    method: str = "static",
):
    """A bilateral (tension_only=False) straight cable whose supports move inward by dL.

    Without a transverse load the straight, uniformly compressed state is an equilibrium,
    but an unstable one (its geometric stiffness is negative); with ``perturb`` the start is
    off the line. Right answers: a catenet error, or a state that is an equilibrium and not
    the unstable straight one (every edge back near its rest length: buckled), or, with
    gravity, the hanging chain. The straight compressed state returned as converged is
    reported (``unstable``) as a silent unstable answer unless the result flags it
    (``Result.stable is False``, with a warning), which is a right answer."""
    import numpy as np

    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import solve_static

    net, loads = compressed_catenary(
        dL, nodes=nodes, tension_only=False, ramp=0.5 if method == "dynamic" else 0.0
    )
    if not gravity:
        from catenet.model.net import Loads

        loads = Loads(support_displacement=loads.support_displacement, ramp_time=loads.ramp_time)
    x0 = None
    if perturb:
        rng = np.random.default_rng(0)
        x0 = net.nodes.copy()
        x0[1:-1, 2] += perturb * rng.standard_normal(nodes - 2)
    if method == "static":
        res = solve_static(net, loads, x0=x0)
    else:
        res = solve_dynamic(net, loads, dt=1e-2, damping=1.0, t_end=50.0, x0=x0)
    strain = res.tension / net.EA
    compressed = float(-np.min(strain))
    if gravity:
        from catenet.validate import analytic

        w = float(net.line_density[0]) * 9.81
        exact = analytic.discrete_catenary(1.0, float(net.EA[0]), w, 1.0 - dL, nodes - 1).sag
        sag = -float(res.x[(nodes - 1) // 2, 2])
        return eq_row(
            "chain",
            abs(sag - exact) / exact,
            1e-6,
            [res],
            net,
            loads,
            note=f"min strain {-compressed:.3g}",
        )
    straight = float(np.max(np.abs(res.x[:, 1:]))) < 1e-9
    flagged = getattr(res, "stable", None) is False
    value = 1.0 if (straight and compressed > 1e-6 and not flagged) else 0.0
    return eq_row(
        "unstable",
        value,
        0.5,
        [res],
        net,
        loads,
        note=(
            "straight compressed state (unstable) returned as converged"
            if value
            else "straight compressed state, flagged unstable"
            if flagged and straight
            else f"buckled or relaxed: min strain {-compressed:.3g}"
        )
        + f"; {res.message}",
    )


def bilateral_chain(ratio: float = 1e5, dL: float = 0.1, nodes: int = 41, rho_a: float = 1.0):
    """A bilateral cable (tension_only = false, the paper's own energy) of length 1 m under
    its own weight (rho A = ``rho_a`` kg/m, W = rho A g L), EA = ``ratio`` W, supports moved
    inward by dL, solved in one load step. Compressed at the start, it must reach the
    hanging chain, as the tension-only cable does: the exact discrete chain, converged,
    every edge ending in tension (else the check value is inf)."""
    import numpy as np

    from catenet.model.builders import Material, cable
    from catenet.model.net import Loads
    from catenet.validate import analytic

    w = rho_a * 9.81
    EA = ratio * w
    net = cable(
        [-0.5, 0, 0], [0.5, 0, 0], nodes, Material(EA=EA, line_density=rho_a, tension_only=False)
    )
    d = np.zeros((nodes, 3))
    d[0, 0], d[-1, 0] = dL / 2, -dL / 2
    loads = Loads(gravity=np.array([0.0, 0.0, -9.81]), support_displacement=d)
    res = _solve(net, loads, "static", dt=1.0, damping=1.0, t_end=1.0, budget=math.inf)
    exact = analytic.discrete_catenary(1.0, EA, w, 1.0 - dL, nodes - 1).sag
    sag = -float(res.x[(nodes - 1) // 2, 2])
    least = float(np.min(res.tension))
    value = abs(sag - exact) / exact if res.converged and least > 0.0 else math.inf
    return eq_row(
        "chain",
        value,
        1e-6,
        [res],
        net,
        loads,
        note=f"sag {sag:.6g} m, chain {exact:.6g} m, least tension {least:.3g} N, "
        f"{res.iterations} Newton iterations, {res.steps} load step",
    )


def net_point_load(F: float = 5.0, n: int = 10, h: float = 0.05):
    """A point load on one off-centre node of the paper's net (alpha = 0, 1 cm edges):
    static and dynamic agree and both are equilibria. Cables away from the load stay
    unstressed (no stiffness across them)."""
    import numpy as np

    from catenet.model.builders import square_net
    from catenet.model.net import Loads
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import solve_static

    sq = square_net(n, 0.0, 1.0, 0.01, paper_material())
    net = sq.net
    target = np.array([0.23, 0.11, 0.0])
    node = int(np.argmin(np.linalg.norm(net.nodes - target, axis=1) + 1e9 * net.fixed))
    f = np.zeros((net.n_nodes, 3))
    f[node, 2] = -F
    loads = Loads(force=f)
    rs = solve_static(net, loads)
    rd = solve_dynamic(net, loads, dt=h, damping=1.0, t_end=200.0)
    scale = max(float(np.max(np.abs(rs.x - net.nodes))), 1e-300)
    diff = float(np.max(np.abs(rs.x - rd.x))) / scale if rd.equilibrium else math.inf
    return eq_row(
        "static = dynamic",
        diff,
        1e-5,
        [rs, rd],
        net,
        loads,
        note=f"node {node}, dynamic: {rd.steps} steps, {rd.message}",
    )


def net_pressure(load_bar: float = 1e-3, n: int = 10, dynamic: bool = False):
    """The paper's net under p L^2 / EA = load_bar (1e-9 .. 0.5): equilibrium, and the
    dynamic relaxation agrees with the static solve."""
    import numpy as np

    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import solve_static

    EA = paper_material().EA
    sq, loads = paper_net(n, pressure=load_bar * EA)
    net = sq.net
    rs = solve_static(net, loads)
    results = [rs]
    diff = 0.0
    if dynamic:
        rd = solve_dynamic(net, loads, dt=0.1, damping=1.0, t_end=500.0)
        results.append(rd)
        scale = max(float(np.max(np.abs(rs.x - net.nodes))), 1e-300)
        diff = float(np.max(np.abs(rs.x - rd.x))) / scale if rd.equilibrium else math.inf
    return eq_row(
        "static = dynamic" if dynamic else "equilibrium",
        diff,
        1e-5,
        results,
        net,
        loads,
        note=f"delta/L = {-rs.x[sq.center, 2]:.4g}, max strain {rs.max_strain:.3g}",
    )


def random_graph(
    seed: int = 0, n_nodes: int = 60, support_share: float = 0.15, dynamic: bool = True
):
    """A random planar net (Delaunay edges of random points, random heights) with random
    supports and random point loads plus gravity. Right answers: a ConfigError (a part
    without support), or static and dynamic equilibria that agree."""
    import numpy as np
    from scipy.spatial import Delaunay

    from catenet.model.builders import graph
    from catenet.model.net import Loads
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import solve_static

    rng = np.random.default_rng(seed)
    pts = rng.random((n_nodes, 2))
    tri = Delaunay(pts).simplices
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]]]), axis=1)
    edges = np.unique(e, axis=0)
    # Thin the triangulation at random so that some nodes hang on few edges.
    keep = rng.random(len(edges)) > 0.3
    edges = edges[keep]
    used = np.unique(edges)
    remap = -np.ones(n_nodes, int)
    remap[used] = np.arange(len(used))
    nodes = np.column_stack([pts[used], 0.05 * rng.random(len(used))])
    edges = remap[edges]
    k = max(1, int(support_share * len(nodes)))
    fixed = rng.choice(len(nodes), size=k, replace=False)
    net = graph(nodes, edges, fixed, paper_material())
    f = np.zeros((net.n_nodes, 3))
    loaded = rng.choice(np.flatnonzero(~net.fixed), size=3, replace=False)
    f[loaded] = rng.normal(0.0, 5.0, (3, 3))
    loads = Loads(force=f, gravity=np.array([0.0, 0.0, -9.81]))
    rs = solve_static(net, loads)
    results = [rs]
    diff = 0.0
    note = f"{net.n_nodes} nodes, {net.n_edges} edges, {k} supports"
    if dynamic:
        rd = solve_dynamic(net, loads, dt=0.05, damping=1.0, t_end=500.0)
        results.append(rd)
        scale = max(float(np.max(np.abs(rs.x - net.nodes))), 1e-300)
        diff = float(np.max(np.abs(rs.x - rd.x))) / scale if rd.equilibrium else math.inf
        note += f"; dynamic {rd.steps} steps, {rd.message}"
    return eq_row(
        "static = dynamic" if dynamic else "equilibrium", diff, 1e-5, results, net, loads, note=note
    )


def hypar_on_surface(folder, n: int, half=12.0, rise=1.5):
    """Form finding's hypar roof (a case dict with one [[target]]: every free node on a
    surface) and the surface z = f(x, y): an n x n grid net on [-half, half]^2 held on
    z = rise (x^2 - y^2) / half^2 along its border, under self-weight, 2 n (n - 1) force
    densities; the surface as ``folder``/surface.obj, 2n x 2n squares of two triangles
    each. Its free nodes start flat (tests/formfind, benchmarks/targets.py)."""
    from pathlib import Path

    import numpy as np

    def f(x, y):
        return rise * (x * x - y * y) / half**2

    s = np.linspace(-half, half, n + 1)
    gx, gy = np.meshgrid(s, s)
    border = (np.abs(gx) == half) | (np.abs(gy) == half)
    nodes = np.column_stack([gx.ravel(), gy.ravel(), np.where(border, f(gx, gy), 0.0).ravel()])
    k = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    edges = np.vstack(
        [
            np.column_stack([k[1:-1, :-1].ravel(), k[1:-1, 1:].ravel()]),
            np.column_stack([k[:-1, 1:-1].ravel(), k[1:, 1:-1].ravel()]),
        ]
    )
    m = 2 * n
    t = np.linspace(-half, half, m + 1)
    vx, vy = np.meshgrid(t, t)
    lines = [
        f"v {x!r} {y!r} {f(x, y)!r}"
        for x, y in zip(vx.ravel().tolist(), vy.ravel().tolist(), strict=True)
    ]
    a = (np.arange(m)[None, :] + (m + 1) * np.arange(m)[:, None]).ravel() + 1
    for i in a:
        lines += [f"f {i} {i + 1} {i + m + 2}", f"f {i} {i + m + 2} {i + m + 1}"]
    (Path(folder) / "surface.obj").write_text("\n".join(lines) + "\n")
    data = {
        "title": "hypar roof on a surface",
        "geometry": {
            "kind": "graph",
            "nodes": nodes.tolist(),
            "edges": edges.tolist(),
            "fixed": np.flatnonzero(border.ravel()).tolist(),
        },
        "material": {"E": 160e9, "radius": 0.006, "density": 7850.0},
        "load": {"gravity": [0, 0, -9.81]},
        "formfind": {"force_density": 1e4},
        "target": [{"surface": "surface.obj"}],
    }
    return data, f
