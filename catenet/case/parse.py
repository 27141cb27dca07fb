"""A whole case: the top-level table, the geometry by kind, the sections, the rules
between sections and the node references, all checked before anything is computed."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from catenet.case.design import DesignConfig
from catenet.case.formfind import FormfindConfig, check_formfind_case, parse_formfind
from catenet.case.guard import guard_size
from catenet.case.keys import (
    BAD,
    MISSING,
    Checker,
    Context,
    choice,
    declared,
    names,
    parse_table,
    show,
    text,
    value,
)
from catenet.case.kinds import KINDS, GeometryConfig
from catenet.case.loadcases import check_method, parse_combinations, parse_load_cases
from catenet.case.masses import parse_masses
from catenet.case.nodes import check_nodes
from catenet.case.obstacles import parse_obstacles
from catenet.case.sections import (
    LoadConfig,
    MaterialConfig,
    OutputConfig,
    SolverConfig,
    SupportsConfig,
    parse_material,
    parse_output,
    parse_solver,
)
from catenet.case.sine import check_move
from catenet.case.supports import check_fixed
from catenet.case.targets import parse_targets
from catenet.case.timing import default_t_end, newmark_refused, resolve_steps, time_dependence
from catenet.case.toml import apply_overrides, dumps_toml, parse_toml, read_case_bytes
from catenet.case.vessel import check_vessel
from catenet.case.water import parse_water, sea_water
from catenet.case.written import plain
from catenet.errors import ConfigError
from catenet.model.units import relabel
from catenet.solver.settings import STATIC_MAX_ITER

#: The unit systems a case may name (top-level ``units``).
UNITS = ("SI", "kN-m", "N-mm")

#: The most time steps a dynamic run may be asked for (t_end / dt).
MAX_TIME_STEPS = 1e8
#: The shortest time step [s] a case may give (dt, dt_min, dt_max): the step's inertia m /
#: dt^2 and the squares of its forces must stay finite numbers (they overflow from about
#: 1e-80 s; a run to rest has no t_end to bound its step count).
MIN_DT = 1e-50


@dataclass(frozen=True, kw_only=True)
class Case:
    """A validated case; ``source`` (the file it came from) is not compared."""

    title: str = text("", doc="free text")
    units: str = choice(
        "SI",
        UNITS,
        write="changed",
        doc="the units the case's numbers are in: SI (N, m, Pa, kg), kN-m (kN, m, kPa, t) or "
        "N-mm (N, mm, MPa, t); labels and plausibility ranges only, numbers stay as written",
    )
    geometry: GeometryConfig
    material: MaterialConfig
    supports: SupportsConfig
    load: LoadConfig
    solver: SolverConfig
    output: OutputConfig
    formfind: FormfindConfig | None = None  # read by `catenet formfind` only
    obstacles: tuple = ()  # [[obstacle]]: rigid bodies the net cannot enter
    masses: tuple = ()  # [[mass]]: point masses and initial velocities at nodes
    load_cases: tuple = ()  # [[load_case]]: loads solved from the base state
    combinations: tuple = ()  # [[combination]]: factored sums of load cases
    targets: tuple = ()  # [[target]]: what `catenet formfind` varies the force densities for
    design: DesignConfig | None = None  # [design]: partial factors (None: the defaults)
    water: Any = None  # [water]: catenet.case.water.WaterConfig, or None
    source: str = field(default="<dict>", compare=False)

    def to_dict(self) -> dict:
        """The resolved case: every default filled in, plain TOML types only."""
        load = self.load.to_dict()
        if not self.geometry.pressure:
            load.pop("pressure")
        out = {
            "title": self.title,
            "units": self.units,
            "geometry": self.geometry.to_dict(),
            "material": self.material.to_dict(),
            "supports": self.supports.to_dict(),
            "load": load,
            "solver": self.solver.to_dict(),
            "output": self.output.to_dict(),
        }
        if self.formfind is not None:
            out["formfind"] = self.formfind.to_dict()
        if self.obstacles:
            out["obstacle"] = [o.to_dict() for o in self.obstacles]
        if self.masses:
            out["mass"] = [m.to_dict() for m in self.masses]
        if self.load_cases:
            out["load_case"] = [c.to_dict() for c in self.load_cases]
        if self.combinations:
            out["combination"] = [c.to_dict() for c in self.combinations]
        if self.targets:
            out["target"] = [t.to_dict() for t in self.targets]
        if self.design is not None and self.design.to_dict():
            out["design"] = self.design.to_dict()
        if self.water is not None:
            out["water"] = self.water.to_dict()
        return plain(out)

    def to_toml(self) -> str:
        """The resolved case as TOML text; ``parse_case(tomllib.loads(text))`` gives it back."""
        return dumps_toml(self.to_dict())


#: The keys of the top-level table.
TOP_KEYS = (
    *names(Case),
    "geometry",
    "material",
    "supports",
    "load",
    "solver",
    "output",
    "formfind",
    "obstacle",
    "mass",
    "load_case",
    "combination",
    "target",
    "design",
    "water",
)


def load_case(path: str | Path | None, overrides: Sequence[str] = ()) -> Case:
    """Read, override and validate a case file; ``None`` is the bundled default case."""
    if path is None:
        resource = resources.files("catenet") / "data" / "default.toml"
        source = "catenet/data/default.toml"
        raw = resource.read_bytes()
        base_dir = Path.cwd()
    else:
        p = Path(path)
        source = str(p)
        raw = read_case_bytes(p)
        base_dir = p.parent
    data = parse_toml(raw, source, written=True)
    sweep = data.pop("sweep", None)  # the grid of `catenet sweep`; a single run ignores it
    if sweep is not None and not isinstance(sweep, dict):
        raise ConfigError(
            f"sweep = {sweep!r}: must be a table of key.path = [values] (read by catenet sweep)"
        )
    added: list = []  # tables --set appended to the case's arrays of tables
    if overrides:
        data = apply_overrides(data, overrides, written=True, added=added)
    try:
        return parse_case(data, source=source, base_dir=base_dir)
    except ConfigError as exc:
        if not added:
            raise
        hints = [
            f"{name}[{n}]: a new table that --set added (the case has {n}, {name}[0] to "
            f"{name}[{n - 1}]): give all its keys, or index an existing one"
            for name, n in added
        ]
        raise ConfigError(exc.problems + hints) from None


def parse_case(data: dict, *, source: str = "<dict>", base_dir: Path | None = None) -> Case:
    """Validate a case table (as read from TOML) and resolve every default.

    Raises ConfigError listing every problem. ``source`` names the case in messages and
    gives the default output file ``out/<stem>.h5``; ``base_dir`` (default: the current
    directory) is where ``geometry.file`` is looked up.
    """
    base_dir = Path.cwd() if base_dir is None else Path(base_dir)
    ck = Checker()
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source}: the case must be a table of sections, not {show(data)}")
    ck.keys(data, "", TOP_KEYS)

    title_key, units_key = declared(Case)
    title = value(ck, data, title_key, "", Context())
    units = value(ck, data, units_key, "", Context())

    geometry, kind = _parse_geometry(ck, data, base_dir)
    ctx = Context(kind=kind)
    material = parse_material(ck, data.get("material", MISSING), ctx, geometry)
    supports = parse_table(ck, data.get("supports", {}), SupportsConfig, "supports", ctx)
    load = parse_table(ck, data.get("load", {}), LoadConfig, "load", ctx)
    solver = parse_solver(ck, data.get("solver", {}), ctx)
    if isinstance(supports, SupportsConfig):  # [] only with rollers, sliders or springs,
        flight = isinstance(solver, SolverConfig) and solver.method == "dynamic"
        check_fixed(ck, supports, flight)  # or in a dynamic run (a net flying free)
    output = parse_output(ck, data.get("output", {}), ctx, source)
    obstacles = parse_obstacles(ck, data.get("obstacle"), ctx, base_dir)
    masses = parse_masses(ck, data.get("mass"), ctx)
    load_cases = parse_load_cases(ck, data.get("load_case"), ctx)
    combinations = parse_combinations(ck, data.get("combination"), ctx, load_cases)
    design = None
    if "design" in data:
        design = parse_table(ck, data["design"], DesignConfig, "design", ctx)
    system = units if isinstance(units, str) else "SI"
    water = parse_water(ck, data.get("water"), ctx, system)
    table = data.get("material")
    if isinstance(material, MaterialConfig) and "water_density" not in (
        table if isinstance(table, dict) else {}
    ):  # modes' added mass: sea water's in the case's units, as [water]'s
        material = dataclasses.replace(material, water_density=sea_water(system))
    for k, mv in enumerate(supports.moves if isinstance(supports, SupportsConfig) else ()):
        check_move(ck, mv, f"supports.move[{k}]")
    for k, vs in enumerate(supports.vessels if isinstance(supports, SupportsConfig) else ()):
        check_vessel(ck, vs, f"supports.vessel[{k}]")
    density = material.density if isinstance(material, MaterialConfig) else None
    check_method(ck, load_cases, combinations, solver, density)
    formfind = None
    targets = parse_targets(ck, data.get("target"), ctx, base_dir)
    if "formfind" in data:
        formfind = parse_formfind(ck, data["formfind"], ctx, bool(data.get("target")))
        check_formfind_case(ck, data)
    elif "target" in data:
        ck.add(
            "target: form finding's targets need a [formfind] table (its force_density, "
            "if given, is the start): add [formfind]"
        )

    if isinstance(material, MaterialConfig):  # rules between sections
        _check_prestress(ck, data, material)
        if geometry is not None:
            geometry.check_material(ck, material)  # a graph's cables override [material]
        _check_mass(ck, data, material, solver, load)
    dynamic = isinstance(solver, SolverConfig) and solver.method == "dynamic"
    given = data.get("solver")
    if dynamic and "damping" not in (given or {}):
        if water not in (None, BAD) and solver.t_end != "rest":  # (a run to rest: the
            solver = dataclasses.replace(solver, damping=0.0)  # default's) the water damps
        elif time_dependence(load, supports, solver, obstacles, masses):
            solver = dataclasses.replace(solver, damping=0.0)  # its motion is the answer
    if isinstance(solver, SolverConfig) and not dynamic and solver.max_iter is None:
        solver = dataclasses.replace(solver, max_iter=STATIC_MAX_ITER)  # a time step's: None
    if dynamic and solver.t_end is None:  # not given (a static case's stays None)
        t_end = default_t_end(load, supports, solver, obstacles, masses)
        solver = dataclasses.replace(solver, t_end=t_end)
    if isinstance(solver, SolverConfig):
        contact = (isinstance(obstacles, tuple) and bool(obstacles)) or solver.self_contact
        moving = bool(time_dependence(load, supports, solver, obstacles, masses))
        solver = resolve_steps(solver, contact or moving)  # fixed or adaptive steps
        if dynamic and contact and solver.integrator == "newmark":
            ck.add(newmark_refused(obstacles))
    if dynamic:
        _check_time_steps(ck, solver)

    # Node references need the node count (and, for square nets, the built topology):
    # only once the geometry itself is sound.
    if geometry is not None:
        check_nodes(ck, geometry, supports, load, output, dynamic)
        for k, lc in enumerate(load_cases if isinstance(load_cases, tuple) else ()):
            check_nodes(ck, geometry, None, lc, prefix=f"load_case[{k}]")

    if ck.problems:  # the keys' units as the case's ``units`` name them ([kN] in kN-m)
        raise ConfigError(relabel(ck.problems, units if isinstance(units, str) else "SI"))
    assert geometry is not None  # (else a problem says why)
    return Case(
        title=title,
        units=units,
        geometry=geometry,
        material=material,
        supports=supports,
        load=load,
        solver=solver,
        output=output,
        formfind=formfind,
        obstacles=obstacles,
        masses=masses,
        load_cases=load_cases,
        combinations=combinations,
        targets=targets,
        design=design,
        water=water,
        source=source,
    )


def _check_prestress(ck: Checker, data: Mapping, material: MaterialConfig) -> None:
    """A problem for each rest length the geometry gives besides material.prestress."""
    if material.prestress is None:
        return
    raw = data.get("geometry")
    g = raw if isinstance(raw, Mapping) else {}
    for other in ("length", "rest_length", "prestrain"):
        if other in g:
            ck.add(
                f"material.prestress = {material.prestress!r}: gives the rest lengths; "
                f"give it or geometry.{other}, not both"
            )


def _check_mass(
    ck: Checker, data: Mapping, material: MaterialConfig, solver: Any, load: Any
) -> None:
    """Problems where a dynamic run or gravity meets a massless material (``solver`` and
    ``load``: BAD when their sections failed)."""
    dens = material.density
    if isinstance(solver, SolverConfig) and solver.method == "dynamic" and dens == 0:
        ck.add(
            f"material.density = {dens!r}: solver.method = 'dynamic' needs mass: "
            "must be > 0 (with material.radius or material.area)"
        )
    if isinstance(load, LoadConfig) and _pulls(load.gravity) and dens == 0:
        ck.add(
            f"load.gravity = {show(data['load']['gravity'])}: gravity needs mass: "
            "set material.density > 0 (with material.radius or material.area)"
        )


def _pulls(gravity: Any) -> bool:
    """Whether a gravity vector (None: not given) is a load: [0, 0, 0] is none, and
    needs no mass."""
    return gravity is not None and any(float(g) != 0.0 for g in gravity)


def _check_time_steps(ck: Checker, solver: SolverConfig) -> None:
    """A problem when a dynamic run's dt exceeds its end time or makes too many steps, or
    adaptive steps' bounds contradict each other."""
    t_end = solver.t_end  # a number, or "rest"
    for key in ("dt", "dt_min", "dt_max"):
        value = getattr(solver, key)
        if value is not None and 0.0 < value < MIN_DT:
            ck.add(
                f"solver.{key} = {value!r}: too short to step with (the step's inertia m / "
                f"dt^2 and its forces overflow below about 1e-80 s): give at least {MIN_DT:g} s"
            )
            return
    adaptive = solver.tolerance is not None and isinstance(t_end, (int, float))
    if adaptive:
        low = 0.0 if solver.dt_min is None else solver.dt_min
        high = math.inf if solver.dt_max is None else solver.dt_max
        if not low <= high:
            ck.add(f"solver.dt_min = {solver.dt_min!r}: must be <= solver.dt_max = {high!r}")
        elif not low <= solver.dt <= high:
            ck.add(
                f"solver.dt = {solver.dt!r}: the first adaptive step must lie within "
                f"solver.dt_min = {low!r} and solver.dt_max = {high!r}"
            )
    if isinstance(t_end, (int, float)) and solver.dt > t_end:
        ck.add(f"solver.dt = {solver.dt!r}: must be <= solver.t_end = {t_end!r}")
    elif isinstance(t_end, (int, float)) and not adaptive:
        steps = t_end / solver.dt
        if not steps <= MAX_TIME_STEPS:
            ck.add(
                f"solver.t_end = {solver.t_end!r}, solver.dt = {solver.dt!r}: {steps:.3g} time "
                f"steps: at most {MAX_TIME_STEPS:.0e} (more would never finish): a larger dt "
                "or a smaller t_end"
            )


def _parse_geometry(
    ck: Checker, data: Mapping, base_dir: Path
) -> tuple[GeometryConfig | None, type[GeometryConfig] | None]:
    """The geometry (None when any key is bad) and its kind (None when unknown)."""
    kinds = " | ".join(map(repr, KINDS))
    if "geometry" not in data:
        ck.add(f"geometry: missing: the case needs a [geometry] table with kind = {kinds}")
        return None, None
    g = ck.table(data["geometry"], "geometry")
    if g is None:
        return None, None
    if "kind" not in g:
        ck.add("geometry.kind: missing: one of " + ", ".join(map(repr, KINDS)))
        return None, None
    name = ck.string(g["kind"], "geometry.kind", choices=tuple(KINDS))
    if name is BAD:
        return None, None
    kind = KINDS[name]
    ck.keys(g, "geometry", ("kind", *names(kind)), f" for kind {name!r}")
    before = len(ck.problems)
    cfg = kind.parse(ck, g, base_dir)
    if len(ck.problems) > before or cfg is None:
        return None, kind
    guard_size(ck, cfg)
    return (cfg if len(ck.problems) == before else None), kind


__all__ = ["Case", "load_case", "parse_case"]
