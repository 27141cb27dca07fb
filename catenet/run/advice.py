"""What a run is told besides its result: before it, the solver keys its method ignores and
the size of the trajectory it will write; after it, edges strained beyond the range their
material law is meant for.

Each check returns its message (None or an empty list when there is nothing to say); the
runner logs them as warnings, and ``catenet run`` shows them on stderr.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from catenet.case.timing import resolve_steps

if TYPE_CHECKING:
    from catenet.case.parse import Case
    from catenet.case.sections import SolverConfig
    from catenet.scene.scene import Scene

#: A trajectory estimated above this many bytes is warned about before the run.
WARN_BYTES = 1 << 30
#: ... and above this many, its estimate is named in the run's summary.
LARGE_BYTES = 100 << 20
#: The size ``output.every`` is suggested for.
TARGET_BYTES = 256 << 20

#: The trajectory estimate of a run to rest (solver.t_end = "rest"): its steps as a rule.
TYPICAL_REST_STEPS = 300


def _dynamic_only(solver: SolverConfig) -> dict[str, object]:
    """The [solver] keys only dynamic runs read, with their values in ``solver``."""
    return {
        "dt": solver.dt,
        "tolerance": solver.tolerance,
        "dt_max": solver.dt_max,
        "dt_min": solver.dt_min,
        "damping": solver.damping,
        "t_end": solver.t_end,
        "integrator": solver.integrator,
        "rho_inf": solver.rho_inf,
        "max_steps": solver.max_steps,
    }


def ignored_solver_keys(solver: SolverConfig) -> list[str]:
    """Messages for the [solver] keys that ``solver.method`` ignores and that the case sets
    to something else than their default (a default is ignored silently)."""
    default = resolve_steps(type(solver)())  # dt and integrator as a case resolves them
    method = solver.method
    out = []
    if method == "dynamic":
        if solver.integrator != "newmark" and solver.rho_inf != default.rho_inf:
            out.append(
                f"solver.rho_inf = {solver.rho_inf!r}: ignored with solver.integrator = "
                f"{solver.integrator!r} (it is the newmark integrator's high-frequency "
                "dissipation; set solver.integrator = 'newmark' or remove the key)"
            )
        if solver.tolerance is not None and not isinstance(solver.t_end, (int, float)):
            out.append(
                f"solver.tolerance = {solver.tolerance!r}: ignored with solver.t_end = "
                f"{solver.t_end!r} (a run to rest grows its own steps; steps chosen by "
                "accuracy need a number for t_end)"
            )
        for key, bound in (("dt_max", solver.dt_max), ("dt_min", solver.dt_min)):
            if bound is not None and solver.tolerance is None:
                out.append(
                    f"solver.{key} = {bound!r}: ignored without solver.tolerance (it bounds "
                    "the steps chosen by accuracy; steps are fixed at solver.dt)"
                )
        if solver.steps != default.steps:
            out.append(
                f"solver.steps = {solver.steps}: ignored with solver.method = 'dynamic' (load "
                "steps are for static runs; a dynamic run applies the full load from t = 0)"
            )
    else:
        defaults = _dynamic_only(default)
        for key, value in _dynamic_only(solver).items():
            if value != defaults[key]:
                out.append(
                    f"solver.{key} = {value!r}: ignored with solver.method = {method!r} (only "
                    "dynamic runs use it; set solver.method = 'dynamic' or remove the key)"
                )
    return out


def ignored_contact_radius(case: Case) -> list[str]:
    """A message where ``material.contact_radius`` is given without
    ``solver.edge_contact`` (the nodes alone meet the solids: it acts on nothing)."""
    radius = case.material.contact_radius
    if radius is None or case.solver.edge_contact:
        return []
    return [
        f"material.contact_radius = {radius!r}: ignored without solver.edge_contact = true "
        "(obstacles and bodies meet the nodes only; docs/guide/edge-contact.md)"
    ]


def ignored_histories(case: Case) -> list[str]:
    """Messages for what a static run ignores of a case's time dependence: every load's
    and support motion's ``history`` (a static run applies each load and displacement in
    full, at the load factor 1 of its last load step) and the initial velocities of
    ``[[mass]]`` (point masses still weigh under gravity)."""
    if case.solver.method != "static":
        return []
    from catenet.case.timing import load_histories

    paths = [f"{p}.history" for p, h in load_histories(case.load) if h is not None]
    moves = case.supports.moves
    paths += [f"supports.move[{k}].history" for k, m in enumerate(moves) if m.history is not None]
    out = [
        f"{path}: ignored with solver.method = 'static' (a static run applies the load or "
        "displacement in full, the history's factor only acts in dynamic runs; set "
        "solver.method = 'dynamic')"
        for path in paths
    ]
    for k, m in enumerate(case.masses):
        if m.velocity is not None:
            out.append(
                f"mass[{k}].velocity = {list(m.velocity)}: ignored with solver.method = "
                "'static' (initial velocities start dynamic runs only)"
            )
    return out


@dataclass(frozen=True)
class Trajectory:
    """The estimated size of a run's trajectory: at most ``frames`` frames of ``frame``
    bytes each (a dynamic run that reaches equilibrium early writes fewer)."""

    frames: int
    frame: int
    every: int

    @property
    def bytes(self) -> int:
        return self.frames * self.frame

    def suggestion(self) -> int:
        """An ``output.every`` that keeps the trajectory near TARGET_BYTES (a 1, 2 or 5
        times a power of ten)."""
        factor = self.bytes / TARGET_BYTES
        want = max(2, math.ceil(self.every * factor))
        exp = 10 ** int(math.floor(math.log10(want)))
        for m in (1, 2, 5, 10):
            if m * exp >= want:
                return m * exp
        return 10 * exp  # pragma: no cover - the loop always returns

    def message(self) -> str:
        k = self.suggestion()
        smaller = Trajectory(self._frames_with(k), self.frame, k)
        return (
            f"the trajectory will take up to {format_bytes(self.bytes)} ({self.frames} frames "
            f"of {format_bytes(self.frame)}, output.every = {self.every}): set output.every = "
            f"{k} to keep every {k}th step (about {format_bytes(smaller.bytes)}), or "
            "output.every = 0 to keep the final state only"
        )

    def _frames_with(self, every: int) -> int:
        return max(1, math.ceil(self.frames * self.every / every))


def trajectory(case: Case, net, t0: float = 0.0) -> Trajectory | None:
    """The size of the trajectory ``case`` will write for ``net`` (None: no trajectory,
    output.every = 0). Per frame: positions (N x 3), tensions (M), velocities (N x 3,
    dynamic), the newmark scheme's accelerations (N x 3), moving obstacles' poses and
    surfaces (``catenet.output.obstacles``) and the time, 8 bytes each.
    Frames: dynamic, the initial state, every ``every``-th of the (t_end - t0) / dt steps
    (t_end = "rest": of TYPICAL_REST_STEPS) and the last; static, every ``every``-th of
    the load steps and the last."""
    every = int(case.output.every)
    if every <= 0:
        return None
    solver = case.solver
    n, m = int(net.n_nodes), int(net.n_edges)
    if solver.method == "dynamic":
        if isinstance(solver.t_end, str):  # "rest": a few hundred steps as a rule
            steps = min(solver.max_steps, TYPICAL_REST_STEPS)
        else:
            steps = max(1, math.ceil((solver.t_end - t0) / solver.dt * (1 - 1e-12)))
        frames = 1 + math.ceil(steps / every)
        values = (9 if solver.integrator == "newmark" else 6) * n + m
        from catenet.output.obstacles import frame_values

        values += frame_values(case, n)  # moving obstacles: pose and surface
    else:
        frames = math.ceil(solver.steps / every)
        values = 3 * n + m
    return Trajectory(frames, 8 * (values + 1), every)


def format_bytes(n: float) -> str:
    """1536 -> '1.5 KiB'."""
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} TiB"  # pragma: no cover


def strain_beyond_law(net, x: np.ndarray, units: str = "SI") -> str | None:
    """A message when edges at positions ``x`` are strained beyond the range their law is
    meant for (``catenet.model.laws.LAWS[name].max_strain``; a table's last point), else None;
    in kN-m or N-mm, a load in N as a cause (a line load in N/m strained a strand 24 %)."""
    from catenet.model import measures
    from catenet.model.laws import LAWS, TABLE

    eps = measures.strain(net, x)
    limit = net.law.max_strain()
    over = eps > limit
    if not np.any(over):
        return None
    names = {info.id: name for name, info in LAWS.items()}
    worst = int(np.argmax(np.where(over, eps, -np.inf)))
    parts = []
    for kind in np.unique(net.law.kind[over]):
        on = over & (net.law.kind == kind)
        name = names.get(int(kind), str(kind))
        bound = float(np.min(limit[on]))
        count, of = int(np.count_nonzero(on)), int(np.count_nonzero(net.law.kind == kind))
        parts.append(f"{count} of {of} edges of the {name} law (meant for strains <= {bound:.3g})")
    kinds = set(int(k) for k in np.unique(net.law.kind[over]))
    advice = "extend material.table to larger strains or lower the load"
    if kinds != {TABLE}:
        advice = "use a large-strain law (material.law = 'neo_hookean') or lower the load"
    slip = {"kN-m": "kN and kN/m, not N and N/m", "N-mm": "N and N/mm, not N/m"}.get(units)
    if slip:  # the load's unit slip that strains a case's cables a thousandfold too far
        advice += f", or check that the loads are in the case's units ({slip})"
    if kinds != {TABLE}:
        advice += "; the result is not physical as it stands"
    return (
        f"strain {float(eps[worst]):.3g} at edge {worst} is beyond the material law's range: "
        f"{', '.join(parts)}: {advice}"
    )


# Real cable materials in SI, with a margin: E from rubber cords (the paper's nets: 10 MPa)
# through polyamide, polyester, aramid and HMPE ropes to steel strand and chain; density
# from HMPE (970) to steel (7850); EA per edge from a thin elastic cord to a bridge's main
# cable. A number outside is a unit slip far more often than a material.
MATERIAL_RANGES = {
    "E": (1e6, 3e11),
    "density": (500.0, 9000.0),
    "EA": (1.0, 1e12),
    "area": (1e-9, 1.0),  # m^2: a 0.03 mm fibre to a 1.1 m bridge cable
    "gravity": (1.0, 30.0),  # m/s^2: the Moon's 1.6 to Jupiter's 25
    "radius": (2e-5, 0.6),  # m
    "pressure": (1.0, 1e5),  # Pa: an area load, from a model's 1 Pa to 100 kPa
    "water": (900.0, 1300.0),  # kg/m^3: fresh water to brine (a density: its units)
}
# What one unit of each quantity is in SI, per unit system (top-level ``units``).
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "SI": {"E": 1.0, "density": 1.0, "EA": 1.0, "area": 1.0, "radius": 1.0, "gravity": 1.0},
    "kN-m": {"E": 1e3, "density": 1e3, "EA": 1e3, "area": 1.0, "radius": 1.0, "gravity": 1.0},
    "N-mm": {"E": 1e6, "density": 1e12, "EA": 1.0, "area": 1e-6, "radius": 1e-3, "gravity": 1e-3},
}
for _units, _factor in (("SI", 1.0), ("kN-m", 1e3), ("N-mm", 1e6)):  # (a pressure: as E)
    UNIT_FACTORS[_units]["pressure"] = _factor
# ... and the names of those units, as the case writes them
UNIT_NAMES: dict[str, dict[str, str]] = {
    "SI": {
        "E": "Pa",
        "density": "kg/m^3",
        "EA": "N",
        "area": "m^2",
        "radius": "m",
        "gravity": "m/s^2",
        "pressure": "Pa",
    },
    "kN-m": {
        "E": "kPa",
        "density": "t/m^3",
        "EA": "kN",
        "area": "m^2",
        "radius": "m",
        "gravity": "m/s^2",
        "pressure": "kPa",
    },
    "N-mm": {
        "E": "MPa",
        "density": "t/mm^3",
        "EA": "N",
        "area": "mm^2",
        "radius": "mm",
        "gravity": "mm/s^2",
        "pressure": "MPa",
    },
}


def unit_slips(case: Case, net) -> list[str]:
    """Warnings for material numbers far outside real cable materials (steel, stainless,
    aramid, polyester, polyamide, HMPE, chain) in the case's ``units``: E, density and
    each edge's EA, and for area loads' pressures far outside real ones, each with the
    power of 1000 that would bring it into range."""
    units = case.units or "SI"
    factors = UNIT_FACTORS.get(units, UNIT_FACTORS["SI"])
    names = UNIT_NAMES.get(units, UNIT_NAMES["SI"])
    material = case.material
    found = []
    checks = [
        ("E", material.E, "material.E"),
        ("area", material.area, "material.area"),
        ("radius", material.radius, "material.radius"),
    ]
    density = material.density
    if density:
        checks.append(("density", density, "material.density"))
    if case.water is not None:
        checks.append(("water", case.water.density, "water.density"))
    if material.added_mass:  # (modes' added mass)
        checks.append(("water", material.water_density, "material.water_density"))
    gravity = case.load.gravity
    if gravity is not None:
        checks.append(("gravity", float(np.linalg.norm(gravity)), "|load.gravity|"))
    for k, area in enumerate(case.load.areas):
        checks.append(("pressure", abs(area.pressure), f"load.area[{k}].pressure"))
    for i, lc in enumerate(case.load_cases):
        for k, area in enumerate(lc.areas):
            checks.append(("pressure", abs(area.pressure), f"load_case[{i}].area[{k}].pressure"))
    ea = np.asarray(net.EA, dtype=np.float64)
    if ea.size and material.E is None:  # E's own check says it else
        checks.append(("EA", float(np.min(ea)), "EA (the least of the edges')"))
        checks.append(("EA", float(np.max(ea)), "EA (the largest of the edges')"))
    for quantity, written, key in checks:
        if written is None or not written > 0:
            continue
        low, high = MATERIAL_RANGES[quantity]
        kind = "density" if quantity == "water" else quantity  # (its units)
        si = float(written) * factors[kind]
        if low <= si <= high:
            continue
        unit = names[kind]
        shift = _power_of_1000(si, low, high, TYPICAL[quantity])
        guess = ""
        if shift:
            meant = float(written) * 10.0**shift
            guess = f"; did you mean {meant:g} ({_si(meant * factors[kind], kind)})"
        found.append(
            f"check units: {key} = {float(written):g} {unit} ({units}) is far "
            f"{'below' if si < low else 'above'} {_REAL.get(quantity, 'real cables')} "
            f"({low:g} to {high:g} in SI units of {UNIT_NAMES['SI'][kind]}){guess}?"
            # ("in SI": not relabelled)
        )
    return list(dict.fromkeys(found))


_REAL = {"pressure": "real area loads", "water": "real water"}  # (measured against)


def _si(value: float, quantity: str) -> str:
    """A value in SI with a readable prefix (GPa for moduli)."""
    if quantity == "E":
        return f"{value / 1e9:g} GPa"
    if quantity == "density":
        return f"{value:g} kg/m^3"
    if quantity == "area":
        return f"{value * 1e6:g} mm^2"
    if quantity == "radius":
        return f"{value * 1e3:g} mm"
    if quantity == "gravity":  # (said to be SI: an N-mm case's labels leave it so)
        return f"{value:g} m/s^2 in SI"
    if quantity == "pressure":
        return f"{value / 1e3:g} kPa in SI"
    return f"{value / 1e3:g} kN"


# the middle of each range, in SI
TYPICAL = {
    "E": 1e11,
    "density": 2000.0,
    "EA": 1e6,
    "area": 1e-4,
    "radius": 5e-3,
    "gravity": 9.81,
    "pressure": 1e3,
    "water": 1025.0,
}


def _power_of_1000(si: float, low: float, high: float, typical: float) -> int:
    """The exponent 3k (|k| <= 4) that brings ``si`` into [low, high], nearest to
    ``typical`` on a log scale (0: none does)."""
    fits = [e for k in range(1, 5) for e in (3 * k, -3 * k) if low <= si * 10.0**e <= high]
    if not fits:
        return 0
    return min(fits, key=lambda e: abs(math.log10(si * 10.0**e / typical)))


def implausible(net, x: np.ndarray, size: float) -> tuple[str, bool]:
    """(message, extreme) for a state at ``x``: strains beyond the material law's range
    or a displacement beyond the structure's size; ``extreme``: beyond IMPLAUSIBLE times
    either (``catenet.model.measures``), which no cable structure survives (a unit slip, an
    unrestrained mechanism)."""
    from catenet.model.measures import IMPLAUSIBLE, implausible_edge

    parts, extreme = [], False
    beyond = strain_beyond_law(net, x)
    if beyond:
        parts.append(beyond)
        extreme = implausible_edge(net, x) >= 0
    free = ~net.fixed
    if np.any(free):
        move = np.linalg.norm(x[free] - net.nodes[free], axis=1)
        worst = float(move.max())
        if worst > size > 0:
            node = int(np.flatnonzero(free)[int(np.argmax(move))])
            parts.append(
                f"node {node} moves {worst:.4g} m, more than the structure's size {size:.4g} m"
            )
            extreme = extreme or worst > IMPLAUSIBLE * size
    return "; ".join(parts), extreme


def lines_without_catenary(case: Case, scene) -> list[str]:
    """Static runs: the cables (a graph's named cables, or a cable case's one) that lie
    from a support on a frictionless plane (a seabed) to a support above it under
    gravity, and whose unstretched length is at least the span along the plane plus the
    height: no catenary holds such a line (it would hang straight down from the upper
    support, its horizontal tension 0, the rest slack on the bed in no unique shape), so
    no static equilibrium exists to find. One message per such cable."""
    if case.solver.method != "static" or case.load.gravity is None:
        return []
    planes = [o for o in case.obstacles if o.kind == "plane" and not o.friction]
    if not planes:
        return []
    net = scene.net
    g = np.asarray(case.load.gravity, dtype=np.float64)
    cables = scene.cables
    if cables is not None:
        chains = [(n, np.flatnonzero(cables.edge == k)) for k, n in enumerate(cables.names)]
    else:
        chains = [("the cable", np.arange(net.n_edges))]
    out = []
    for plane in planes:
        normal = np.asarray(plane.normal, dtype=np.float64)
        normal = normal / np.linalg.norm(normal)
        if float(g @ normal) >= -0.5 * float(np.linalg.norm(g)):
            continue  # gravity does not press the line onto this plane
        for name, edges in chains:
            found = _too_long(net, edges, plane, normal)
            if found is not None:
                length, span, height = found
                out.append(
                    f"cable {name}: its unstretched length {length:.6g} m is at least the span "
                    f"along the seabed plus the height of its upper end ({span:.6g} + "
                    f"{height:.6g} = {span + height:.6g} m): no catenary holds it (it would "
                    "hang straight down with no horizontal tension and lie slack on the bed "
                    "in no unique shape), so no static equilibrium exists: shorten the line, "
                    "move the anchor away, or run it dynamically (solver.method = 'dynamic')"
                )
    return out


def _too_long(net, edges: np.ndarray, plane, normal: np.ndarray):
    """(length, span, height) of the chain ``edges`` between two supports, one on the
    plane, when it is too long for a catenary; else None."""
    from catenet.model.measures import sag

    chain = sag(net, net.nodes, edges) if len(edges) else None
    if chain is None:
        return None
    a, b = chain["ends"]
    if not (net.fixed[a] and net.fixed[b]):
        return None
    point = np.asarray(plane.point, dtype=np.float64)
    ha, hb = ((net.nodes[k] - point) @ normal for k in (a, b))
    low, high = (a, b) if ha <= hb else (b, a)
    reach = max(float(plane.distance or 0.0), 1e-9 * float(np.ptp(net.nodes)))
    if min(ha, hb) > 10.0 * reach:
        return None  # neither end rests on the bed
    d = net.nodes[high] - net.nodes[low]
    height = float(d @ normal)
    span = float(np.linalg.norm(d - height * normal))
    length = float(np.sum(net.rest_length[edges]))
    return (length, span, height) if length >= span + height else None


def peak_strain_beyond_law(net, peaks, dynamic: bool) -> str | None:
    """A message when an edge of the paper's linear law was strained beyond the law's
    range at some step of the run (its peak tension / EA), although the final state may
    not be (a rope in a drop test at 10 % for an instant); None otherwise."""
    if peaks is None:
        return None
    from catenet.kernels.law_ids import LINEAR

    arrays = peaks if isinstance(peaks, dict) else peaks.arrays()
    tension = np.asarray(arrays["peak_tension"], dtype=np.float64)
    linear = np.asarray(net.law.kind) == LINEAR
    ea = np.asarray(net.EA, dtype=np.float64)
    eps = np.where(linear & (ea > 0), tension / np.where(ea > 0, ea, 1.0), 0.0)
    limit = net.law.max_strain()
    over = eps > limit
    if not np.any(over):
        return None
    worst = int(np.argmax(np.where(over, eps, -np.inf)))
    when = float(np.asarray(arrays["peak_tension_time"])[worst])
    at = f"t = {when:.6g} s" if dynamic else f"load factor {when:.6g}"
    return (
        f"peak strain {eps[worst]:.3g} at edge {worst} ({at}) is beyond the linear law's "
        f"range (strains <= {float(limit[worst]):.3g}) on {int(np.count_nonzero(over))} edges "
        "during the run, though not necessarily at its end: use a large-strain law "
        "(material.law = 'neo_hookean'), a stiffer cable, or lower the load"
    )


#: A solid narrower than this share of the net's median edge can pass between its nodes.
NARROW_SHARE = 1.0


def between_nodes(scene: Scene) -> list[str]:
    """Warnings for each obstacle, ball or free body (not a plane) narrower than the
    net's median edge and near the net at the start (within the net's size of its
    bounding box): the net touches solids at its nodes only (the barriers act on
    nodes), so such a solid can pass between them, or sit across a strand. None where
    every edge meets them (``solver.edge_contact``). A solid farther off that comes to
    the net is watched in the run (catenet/run/crossings.py: it warns where an edge cut
    into one or one passed through)."""
    from catenet.scene.shapes import solid_width

    net = scene.net
    if not net.n_edges or scene.edge_radius is not None:
        return []
    ends = net.nodes[net.edges]
    edge = float(np.median(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)))
    own = net.nodes[: net.n_net]  # (a body's frame nodes and a ball's follow the net's)
    low, high = own.min(axis=0), own.max(axis=0)
    size = float(np.linalg.norm(high - low))
    solids = [(k, shape, "") for k, shape, _ in scene.obstacles]
    solids += [(m.index, m.shape, "a free " if m.free else "a moving ") for m in scene.movers]
    out = []
    for k, shape, what in sorted(solids, key=lambda s: s[0]):
        if shape.kind == "plane":
            continue
        width = solid_width(shape)
        gap = float(np.linalg.norm(np.clip(shape.origin, low, high) - shape.origin))
        if width < NARROW_SHARE * edge and gap - shape.reach < size:
            out.append(
                f"obstacle[{k}] ({what}{shape.kind}, {width:.3g} m across) is narrower than "
                f"the net's edges ({edge:.3g} m, the median): the net touches solids at its "
                "nodes only, so it may pass between them or lie across a strand unseen; "
                "refine the net (edges well below the solid's width) or set "
                "solver.edge_contact = true (docs/guide/edge-contact.md)"
            )
    return out
