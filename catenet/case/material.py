"""The [material] section of a case: its keys (``MaterialConfig``) and the rules between
them (``parse_material``). Below the geometry kinds, whose cables take [material] keys."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from catenet.case.keys import (
    BAD,
    MISSING,
    Checker,
    Context,
    Declared,
    boolean,
    choice,
    key,
    names,
    parse_keys,
    real,
    show,
)
from catenet.errors import ConfigError
from catenet.model.builders import Material
from catenet.model.laws import LAWS, table_rows


def _check_table(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A monotone tension-strain table, as a tuple of (strain, tension) pairs."""
    if not isinstance(v, (list, tuple)) or not all(
        isinstance(p, (list, tuple)) and len(p) == 2 for p in v
    ):
        return ck.bad(path, v, "must be [[strain, tension], ...]: pairs of numbers")
    try:
        table_rows(v, path=path)
    except (ConfigError, TypeError, ValueError) as exc:
        own = exc.problems if isinstance(exc, ConfigError) else []
        problems = own or [f"{path} = {show(v)}: {exc}"]
        ck.problems.extend(problems)
        return BAD
    return tuple((float(a), float(b)) for a, b in v)


def _check_bending(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """EI or GJ [N m^2]: a number >= 0, or "section" (E times the round section's I, G
    times its polar J)."""
    if v == "section":
        return v
    if isinstance(v, str):
        return ck.bad(path, v, 'must be a number >= 0 [N m^2] or "section"')
    return ck.real(v, path, ge=0, need='>= 0 [N m^2], or "section"')


#: solver.edge_contact's doc (the key is the solver's, its radius the material's).
EDGE_CONTACT = (
    "obstacles, balls and free bodies meet the whole of every edge, a capsule of "
    "material.contact_radius, not only the nodes (docs/guide/edge-contact.md)"
)


@dataclass(frozen=True)
class MaterialConfig(Declared):
    """Either E with radius or area, or EA directly; density needs radius or area."""

    E: float | None = real(
        None, gt=0, write="given", unit="Pa", doc="Young's modulus (with radius or area), or EA"
    )
    radius: float | None = real(
        None, gt=0, write="given", unit="m", doc="radius of the round cross-section, A = pi r^2"
    )
    area: float | None = real(
        None, gt=0, write="given", unit="m^2", doc="cross-section A (instead of radius)"
    )
    EA: float | None = real(
        None,
        gt=0,
        write="given",
        unit="N",
        doc="axial stiffness directly, instead of E (radius or area then only give mass)",
    )
    density: float = real(
        0.0,
        ge=0,
        unit="kg/m^3",
        doc="needs radius or area; must be > 0 for dynamic runs and for gravity",
    )
    added_mass: float = real(
        0.0,
        ge=0,
        unit="-",
        write="changed",
        doc="modes: added-mass coefficient Ca of water moving with the cable sideways "
        "(1: a round cable); adds Ca water_density A per unstressed length, normal to it",
    )
    water_density: float = real(
        1025.0,
        gt=0,
        unit="kg/m^3",
        write="changed",
        doc="modes: the water's density (with added_mass; default: sea water's, in its units)",
    )
    cd_n: float = real(
        1.2,
        ge=0,
        unit="-",
        write="changed",
        doc="[water]: drag coefficient normal to the cable (on its projected area d l)",
    )
    cd_t: float = real(
        0.008,
        ge=0,
        unit="-",
        write="changed",
        doc="[water]: drag coefficient along the cable (on its surface pi d l, as MoorDyn's)",
    )
    ca_n: float = real(
        1.0, ge=0, unit="-", write="changed", doc="[water]: added-mass coefficient normal to it"
    )
    ca_t: float = real(
        0.0, ge=0, unit="-", write="changed", doc="[water]: added-mass coefficient along it"
    )
    hydro_diameter: float | None = real(
        None,
        gt=0,
        write="given",
        unit="m",
        shown="the cross-section's diameter",
        doc="[water]: the diameter drag acts on (a studless chain: 1.8 x its nominal one)",
    )
    contact_radius: float | None = real(
        None,
        ge=0,
        write="given",
        unit="m",
        shown="radius (0 without one)",
        doc="solver.edge_contact: every edge is a capsule of this radius where it meets "
        "obstacles, balls and free bodies (the [material] table's, for every cable)",
    )
    axial_damping: float = real(
        0.0,
        ge=0,
        write="changed",
        unit="N s",
        doc="dynamic runs: internal axial damping c, a tension c de/dt in parallel with the "
        "stretch (MoorDyn's BA): it damps the axial waves along the cable, not its motion "
        "as a whole (docs/howto/dynamic-runs.md)",
    )
    tension_only: bool = boolean(True, doc="cables go slack in compression")
    law: str = choice(
        "linear", tuple(LAWS), write="changed", doc="material law (see catenet validate)"
    )
    table: tuple | None = key(
        _check_table,
        "[[strain, tension], ...]: strains increasing from above 0, tensions not decreasing",
        None,
        write="given",
        unit="-, N",
        doc='law = "table": tension against strain; its first slope is EA',
    )
    prestress: float | None = real(
        None,
        write="given",
        unit="N",
        doc="tension of every edge in the given geometry (rest lengths derived from it)",
    )
    inner_radius: float | None = real(
        None,
        gt=0,
        write="given",
        unit="m",
        doc="a tube's inner radius (radius is then its outer one): A = pi (r^2 - ri^2)",
    )
    EI: float | str = key(
        _check_bending,
        'a number >= 0 [N m^2], or "section"',
        0.0,
        write="changed",
        unit="N m^2",
        doc="rods: bending stiffness (> 0: the cable's edges bend, see docs/howto/rods.md); "
        '"section": E pi (r^4 - ri^4) / 4 from E, radius and inner_radius',
    )
    GJ: float | str = key(
        _check_bending,
        'a number >= 0 [N m^2], or "section"',
        0.0,
        write="changed",
        unit="N m^2",
        doc="rods: torsional stiffness (> 0: the rod twists between clamped ends, see "
        'docs/howto/rods.md); "section": G pi (r^4 - ri^4) / 2 from G, radius and inner_radius',
    )
    G: float | None = real(
        None, gt=0, write="given", unit="Pa", doc='shear modulus, for GJ = "section"'
    )
    polar_inertia: float | None = real(
        None,
        ge=0,
        write="given",
        unit="kg m",
        shown="density pi (r^4 - ri^4) / 2 from radius",
        doc="modes of rods that twist (GJ > 0): the mass polar moment of inertia per length "
        "rho J_p, the twist's rotational inertia (0: none, the twist stays quasistatic)",
    )
    natural_curvature: str = choice(
        "straight",
        ("straight", "given"),
        write="changed",
        doc="rods: the unloaded shape: straight, or as given in the geometry",
    )
    breaking_load: float | None = real(
        None,
        gt=0,
        write="given",
        unit="N",
        doc="minimum breaking force F_min of the cable, for its utilisation (see [design]); "
        "none: the utilisation of its edges is NaN (not checked)",
    )
    proof_load: float | None = real(
        None,
        gt=0,
        write="given",
        unit="N",
        doc="characteristic proof force F_k (0.2 % or 0.1 % proof load), optional: "
        "F_Rd = min(k_e F_min / (1.5 gamma_R), F_k / gamma_R)",
    )

    @property
    def cross_section(self) -> float | None:
        """Area A [m^2] from radius or area, None when only EA is given."""
        if self.area is not None:
            return self.area
        if self.radius is not None:
            return math.pi * (self.radius**2 - (self.inner_radius or 0.0) ** 2)
        return None

    @property
    def second_moment(self) -> float | None:
        """I = pi (r^4 - ri^4) / 4 [m^4] of the round (or tube) section; None without a
        radius. Its polar moment J is 2 I."""
        if self.radius is None:
            return None
        return math.pi * (self.radius**4 - (self.inner_radius or 0.0) ** 4) / 4.0

    @property
    def bending_stiffness(self) -> float:
        """EI [N m^2]: as given, or E I of the round (or tube) section; 0: no bending."""
        if self.EI == "section":
            inertia = self.second_moment
            return 0.0 if self.E is None or inertia is None else self.E * inertia  # else refused
        return float(self.EI)

    @property
    def torsional_stiffness(self) -> float:
        """GJ [N m^2]: as given, or G J = 2 G I of the round (or tube) section; 0: no twist."""
        if self.GJ == "section":
            inertia = self.second_moment
            return 0.0 if self.G is None or inertia is None else 2.0 * self.G * inertia
        return float(self.GJ)

    @property
    def rotational_inertia(self) -> float | None:
        """rho J_p [kg m]: the mass polar moment per length, as given, or the density times
        the polar moment of the round (or tube) section, 2 I; None without either."""
        if self.polar_inertia is not None:
            return float(self.polar_inertia)
        inertia = self.second_moment
        return None if inertia is None else 2.0 * self.density * inertia

    @property
    def axial_stiffness(self) -> float | None:
        """EA [N]: E * A, or EA as given, or the table's first slope (None for a graph
        with EA per edge only)."""
        if self.table is not None:
            return table_rows(self.table)[1]
        if self.EA is not None:
            return self.EA
        if self.E is not None and self.cross_section is not None:
            return self.E * self.cross_section
        return None

    @property
    def line_density(self) -> float:
        """rho * A [kg/m]."""
        a = self.cross_section
        return 0.0 if a is None else self.density * a


def added_line_mass(config: MaterialConfig, path: str = "material") -> float:
    """Ca rho_w A [kg/m] (per unstressed length) of a [material] table: the water that a
    cable carries along as it moves sideways; 0 without added_mass. ConfigError where
    added_mass is given but no cross-section (EA alone)."""
    if not config.added_mass:
        return 0.0
    area = config.cross_section
    if area is None:
        raise ConfigError(
            f"{path}.added_mass = {config.added_mass!r}: the displaced water needs a "
            f"cross-section: give {path}.radius or {path}.area"
        )
    return config.added_mass * config.water_density * area


def model_material(config: MaterialConfig, *, prestress: bool = True) -> Material:
    """The ``catenet.model.builders.Material`` of a [material] table (or a cable's): its
    law and, unless ``prestress`` is False, its prestress; EA 1 where the geometry gives
    EA per edge (the builders then take those)."""
    ea = config.axial_stiffness
    return Material(
        EA=1.0 if ea is None else ea,
        line_density=config.line_density,
        tension_only=config.tension_only,
        law=config.law,
        table=config.table,
        prestress=config.prestress if prestress else None,
    )


def parse_material(ck: Checker, m_v: Any, ctx: Context, geometry: Any) -> MaterialConfig | Any:
    """The [material] table; ``geometry`` (None when broken) may give EA per edge."""
    if m_v is MISSING:
        if ctx.kind is not None and ctx.kind.gives_stiffness(geometry):
            m_v = {}  # EA per edge: the table's other keys keep their defaults
        else:
            ck.add(
                "material: missing: the case needs a [material] table (E with radius or "
                "area, or EA; or EA per edge in the geometry)"
            )
            return BAD
    m = ck.table(m_v, "material")
    if m is None:
        return BAD
    ck.keys(m, "material", names(MaterialConfig))
    v = parse_keys(ck, m, MaterialConfig, "material", ctx)
    given = {k for k in ("E", "radius", "area", "EA") if k in m}
    per_edge_ea = ctx.kind is not None and ctx.kind.gives_stiffness(geometry)
    if {"radius", "area"} <= given:
        ck.add(
            f"material.area = {show(m['area'])}: give material.radius or material.area, not both"
        )
    if "E" in given and "EA" in given:
        ck.add(
            f"material.EA = {show(m['EA'])}: give material.E (with radius or area) or "
            "material.EA, not both"
        )
    elif "E" in given and not given & {"radius", "area"}:
        ck.add(
            f"material.E = {show(m['E'])}: needs a cross-section: give material.radius or "
            "material.area (or give material.EA instead of E)"
        )
    elif not given & {"E", "EA"} and not per_edge_ea and v["law"] != "table":
        ck.add("material: missing stiffness: give E with radius or area, or EA")
    if v["law"] == "table":
        if "table" not in m:
            ck.add("material.table: missing: law = 'table' needs [[strain, tension], ...]")
        for k in sorted(given & {"E", "EA"}):
            ck.add(
                f"material.{k} = {show(m[k])}: the table gives the stiffness with law = "
                "'table' (radius or area give the mass only)"
            )
    elif "table" in m and v["law"] is not BAD:
        ck.add(f"material.table: only with material.law = 'table' (this is {v['law']!r})")
    _bending_rules(ck, m, v)
    prestress = v["prestress"]
    if prestress not in (None, BAD) and prestress < 0 and v["tension_only"] is True:
        ck.add(
            f"material.prestress = {prestress!r}: tension-only cables carry no compression: "
            "must be >= 0 (or set material.tension_only = false for struts)"
        )
    if v["proof_load"] not in (None, BAD) and v["breaking_load"] is None:
        ck.add(
            f"material.proof_load = {v['proof_load']!r}: needs material.breaking_load (the "
            "resistance F_Rd is min(k_e F_min / (1.5 gamma_R), F_k / gamma_R))"
        )
    density = v["density"]
    if density not in (BAD, 0.0) and "EA" in given and not given & {"radius", "area"}:
        ck.add(
            f"material.density = {density!r}: mass needs a cross-section: give "
            "material.radius or material.area (EA alone has no area)"
        )
    if BAD in v.values():
        return BAD
    return MaterialConfig(**v)


def _bending_rules(ck: Checker, m: dict, v: dict) -> None:
    """EI = "section" needs E and radius; inner_radius needs radius and is smaller; a rod
    carries compression unless tension_only is given (then v's default is changed)."""
    if v["EI"] == "section" and ("E" not in m or "radius" not in m):
        ck.add(
            'material.EI = "section": needs material.E and material.radius (a round '
            "section; a tube: inner_radius too), or give EI as a number (force times "
            "length^2 in the case's units)"
        )
        v["EI"] = BAD
    ri = v["inner_radius"]
    if ri not in (None, BAD):
        if "radius" not in m:
            ck.add(
                f"material.inner_radius = {ri!r}: a tube needs its outer radius: "
                "give material.radius"
            )
            v["inner_radius"] = BAD
        elif v["radius"] not in (None, BAD) and not ri < v["radius"]:
            ck.bad("material.inner_radius", ri, f"must be < material.radius = {v['radius']!r}")
            v["inner_radius"] = BAD
    if v["EI"] not in (0.0, BAD) and "tension_only" not in m:
        v["tension_only"] = False  # a rod carries compression
    _twist_rules(ck, m, v)


def _twist_rules(ck: Checker, m: dict, v: dict) -> None:
    """GJ = "section" needs G and radius, and a rod that twists bends."""
    if v["GJ"] == "section" and ("G" not in m or "radius" not in m):
        ck.add(
            'material.GJ = "section": needs material.G (the shear modulus) and '
            "material.radius (a tube: inner_radius too), or give GJ as a number (force "
            "times length^2 in the case's units)"
        )
        v["GJ"] = BAD
    if v["GJ"] not in (0.0, BAD) and v["EI"] in (0.0, None):
        ck.add(
            f"material.GJ = {show(m['GJ'])}: a rod that twists must bend: give material.EI "
            '> 0 (or "section") too'
        )
