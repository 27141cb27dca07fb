"""The ``[water]`` table of a case: the water a net hangs in (density, still surface,
depth, current, regular waves and a JONSWAP sea), and its terms on the built net
(``catenet.terms.water``), with each edge's hydrodynamic data from its material."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    choice,
    integer,
    key,
    parse_table,
    real,
    show,
    tables,
)
from catenet.errors import ConfigError
from catenet.model.limits import carried
from catenet.model.water import G_STANDARD, Hydro, Water, Wave, jonswap

#: A wave higher than this times its water's depth breaks (McCowan's limit, 0.78)
BREAKING = 0.78
MAX_SPEED = 1e6  # m/s: the water's speeds a case may give (the drag's energy goes as u^3)
CURRENT = "[[z, ux, uy], ...]: at least one row of three finite numbers, z all different"


def _check_current(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A current profile: rows (z, ux, uy), returned sorted by z."""
    if not isinstance(v, (list, tuple)) or not v:
        return ck.bad(path, v, f"must be {CURRENT}")
    rows = []
    for k, row in enumerate(v):
        ok = isinstance(row, (list, tuple)) and len(row) == 3
        ok = ok and all(isinstance(a, (int, float)) and not isinstance(a, bool) for a in row)
        if not ok or not all(carried(float(a)) for a in row):
            return ck.bad(f"{path}[{k}]", row, "must be [z, ux, uy]: three finite numbers [m, m/s]")
        rows.append(tuple(float(a) for a in row))
    fast = [k for k, r in enumerate(rows) if math.hypot(r[1], r[2]) > MAX_SPEED]
    if fast:
        k = fast[0]
        return ck.bad(f"{path}[{k}]", v[k], f"a speed beyond {MAX_SPEED:g} m/s (drag ~ u^3)")
    zs = [r[0] for r in rows]
    if len(set(zs)) != len(zs):
        return ck.bad(path, v, f"two rows at one depth z: must be {CURRENT}")
    return tuple(sorted(rows))


@dataclass(frozen=True)
class WaveConfig(Declared):
    """A regular (Airy) wave: linear kinematics below the still water level."""

    height: float = real(gt=0, missing="crest to trough [m]", unit="m", doc="crest to trough")
    period: float = real(gt=0, missing="its period [s]", unit="s", doc="period")
    direction: float = real(
        0.0, unit="deg", doc="the direction it travels, from +x toward +y (0: along +x)"
    )
    phase: float = real(0.0, unit="deg", doc="phase at the origin at t = 0 (0: a crest)")


@dataclass(frozen=True)
class WaterConfig(Declared):
    """Water around the net: buoyancy, drag and added mass on every wetted edge
    (the material's cd_n, cd_t, ca_n, ca_t, hydro_diameter; docs/howto/mooring-dynamics.md)."""

    density: float = real(
        1025.0, gt=0, unit="kg/m^3", doc="the water's density (default: sea water's, in its units)"
    )
    surface: float = real(0.0, unit="m", doc="z of the still water level")
    depth: float | None = real(
        None,
        gt=0,
        write="given",
        unit="m",
        shown="a horizontal plane obstacle below the surface (the seabed), else deep water",
        doc="waves: water depth below the still level",
    )
    current: tuple | None = key(
        _check_current,
        CURRENT,
        None,
        write="given",
        shown="none",
        unit="m, m/s",
        doc="current velocity against z, linear between the rows, constant beyond them",
    )
    waves: tuple[WaveConfig, ...] = tables(
        WaveConfig, name="wave", doc="regular waves (dynamic runs), added together"
    )
    spectrum: str | None = choice(
        None, ("jonswap",), write="given", shown="none", doc="an irregular sea (dynamic runs)"
    )
    hs: float | None = real(
        None, gt=0, write="given", unit="m", shown="none", doc="spectrum: significant height"
    )
    tp: float | None = real(
        None, gt=0, write="given", unit="s", shown="none", doc="spectrum: peak period"
    )
    gamma: float = real(3.3, ge=1, lt=100, unit="-", doc="spectrum: JONSWAP peak enhancement")
    seed: int = integer(0, ge=0, doc="spectrum: the seed of its random phases")
    components: int = integer(100, ge=1, le=10000, doc="spectrum: regular components summed")
    heading: float = real(0.0, unit="deg", doc="spectrum: the direction the sea travels")
    ramp: float | None = real(
        None,
        ge=0,
        write="given",
        unit="s",
        shown="the longest wave period (tp for a spectrum)",
        doc="waves grow smoothly from calm over this time (0: at full height from t = 0)",
    )


#: A tonne per the unit of volume, in kg/m^3: the unit of density of each unit system
TONNE = {"kN-m": 1e3, "N-mm": 1e12}


def sea_water(units: str) -> float:
    """Sea water's density, 1025 kg/m^3, in ``units`` (a case's): the default of
    water.density and material.water_density."""
    return 1025.0 / TONNE.get(units, 1.0)


def parse_water(
    ck: Checker, value: Any, ctx: Context, units: str = "SI"
) -> WaterConfig | None | Any:
    """The ``[water]`` table (absent: None) and the rules between its keys; its density
    left out is sea water's, 1025 kg/m^3, in the case's ``units`` (1.025 t/m^3 in kN-m:
    1025 there made every line 1000 times buoyant)."""
    if value is None:
        return None
    w = parse_table(ck, value, WaterConfig, "water", ctx)
    if w is BAD:
        return BAD
    if isinstance(value, dict) and "density" not in value:
        w = dataclasses.replace(w, density=sea_water(units))
    spectral = [k for k in ("hs", "tp") if getattr(w, k) is not None]
    if w.spectrum is None and spectral:
        ck.add(f"water.{spectral[0]}: only with water.spectrum = 'jonswap' (none is given)")
        return BAD
    if w.spectrum is not None and len(spectral) < 2:
        missing = "hs" if w.hs is None else "tp"
        ck.add(f"water.{missing}: missing: water.spectrum = 'jonswap' needs hs and tp")
        return BAD
    heights = [(f"water.wave[{k}]", v.height, v.period) for k, v in enumerate(w.waves)]
    if w.spectrum is not None:
        heights.append(("water.hs", w.hs, w.tp))
    for path, height, period in heights:  # the orbital speed at the surface, pi H / T
        if not math.pi * height / period <= MAX_SPEED:
            ck.add(
                f"{path}: height {height:g} m in {period:g} s: its water moves faster than "
                f"{MAX_SPEED:g} m/s (drag ~ u^3)"
            )
            return BAD
    breaking = _breaking(heights, w.depth, "water.depth")
    if breaking:
        ck.add(breaking)
        return BAD
    return w


def _breaking(heights: list, depth: float | None, where: str) -> str:
    """Why a wave of ``heights`` (path, height, period) cannot run in water of ``depth``
    (named by ``where``): higher than BREAKING times it, it breaks (and linear waves'
    speeds grow as 1 / depth: a depth of 1e-300 m made them infinite); "" where all can."""
    if depth is None:
        return ""
    for path, height, _ in heights:
        if not height <= BREAKING * depth:
            return (
                f"{path}: height {height:g} m in {where} = {depth:g} m: a wave higher "
                f"than {BREAKING:g} times its depth breaks (linear waves need it lower: "
                "a deeper water.depth or a lower wave)"
            )
    return ""


def water_model(config: WaterConfig, gravity: Any, obstacles: tuple) -> Water:
    """The ``catenet.model.water.Water`` of a [water] table, with the case's gravity (it
    must point along -z: the surface is a level z) and the seabed of its obstacles."""
    g = G_STANDARD
    if gravity is not None:
        gx, gy, gz = (float(a) for a in gravity)
        if gx != 0.0 or gy != 0.0 or not gz < 0.0:
            raise ConfigError(
                f"load.gravity = {show(list(gravity))}: with [water] gravity must point "
                "along -z (the still water level is a level z = water.surface)"
            )
        g = -gz
    waves = [
        Wave(
            0.5 * w.height,
            2.0 * math.pi / w.period,
            math.radians(w.direction),
            math.radians(w.phase),
        )
        for w in config.waves
    ]
    periods = [w.period for w in config.waves]
    if config.spectrum == "jonswap":
        assert config.hs is not None and config.tp is not None  # parse_water
        heading = math.radians(config.heading)
        waves += jonswap(
            config.hs, config.tp, config.gamma, config.seed, config.components, heading
        )
        periods.append(config.tp)
    ramp = config.ramp if config.ramp is not None else max(periods, default=0.0)
    depth = config.depth if config.depth is not None else seabed_depth(config, obstacles)
    if config.depth is None:  # (a given depth was checked with the table)
        heights = [(f"water.wave[{k}]", w.height, w.period) for k, w in enumerate(config.waves)]
        if config.spectrum is not None:
            assert config.hs is not None and config.tp is not None  # parse_water
            heights.append(("water.hs", config.hs, config.tp))
        breaking = _breaking(heights, depth, "the seabed's depth (a plane obstacle)")
        if breaking:
            raise ConfigError(breaking)
    current = None if config.current is None else np.array(config.current, dtype=np.float64)
    return Water(
        density=config.density,
        surface=config.surface,
        g=g,
        current=current,
        waves=tuple(waves),
        depth=depth,
        ramp=ramp,
    )


def seabed_depth(config: WaterConfig, obstacles: tuple) -> float | None:
    """The depth of the highest horizontal plane obstacle (normal +z) below the still
    level, None without one (deep water)."""
    depths = []
    for obs in obstacles:
        if getattr(obs, "kind", None) != "plane":
            continue
        nx, ny, nz = obs.normal
        if nx == 0.0 and ny == 0.0 and nz > 0.0 and obs.point[2] < config.surface:
            depths.append(config.surface - obs.point[2])
    return min(depths) if depths else None


def hydro_of(material: Any, path: str) -> dict[str, float]:
    """One material's hydrodynamic data: coefficients, diameter (hydro_diameter, else
    the cross-section's) and displaced area (the cross-section, else the diameter's
    circle). ConfigError where neither gives a diameter (EA alone)."""
    area = material.cross_section
    d = material.hydro_diameter
    if d is None:
        if area is None:
            raise ConfigError(
                f"{path}.hydro_diameter: missing: in [water] a cable needs a diameter: give "
                f"{path}.hydro_diameter, radius or area"
            )
        d = 2.0 * math.sqrt(area / math.pi)
    if area is None:
        area = 0.25 * math.pi * d * d
    return {
        "cd_n": material.cd_n,
        "cd_t": material.cd_t,
        "ca_n": material.ca_n,
        "ca_t": material.ca_t,
        "diameter": d,
        "area": area,
    }


def hydro_edges(case: Any, scene: Any) -> Hydro:
    """Each edge's hydrodynamic data (its cable's [material] in a graph with cables,
    else [material])."""
    from catenet.case.kinds.graph import GraphConfig

    net = scene.net
    base = hydro_of(case.material, "material")
    values = {k: np.full(net.n_edges, v) for k, v in base.items()}
    listed = case.geometry.cables if isinstance(case.geometry, GraphConfig) else ()
    cables = scene.cables
    if cables is not None and listed:
        from catenet.case.kinds.cables import cable_materials

        mats = cable_materials(Checker(), case.material, listed)
        rows = [hydro_of(m, f"geometry.cable[{c}].material") for c, m in enumerate(mats)]
        on = cables.edge >= 0
        for k in values:
            values[k][on] = np.array([r[k] for r in rows])[cables.edge[on]]
    return Hydro(**values)


def water_terms(case: Any, scene: Any) -> tuple:
    """The water's terms on a case's scene: buoyancy (under load.gravity) and the
    Morison forces (``catenet.terms.water``)."""
    from catenet.terms.water import Buoyancy, WaterForce

    water = water_model(case.water, case.load.gravity, case.obstacles)
    hydro = hydro_edges(case, scene)
    force = WaterForce(scene.net, water, hydro)
    if case.load.gravity is None:
        return (force,)
    return (Buoyancy(scene.net, water, hydro), force)
