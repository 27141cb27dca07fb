"""The guards of a case: the size of the net and the memory a solve needs, estimated from
the case alone before any array is made; and the scales of the built scene (stiffness,
forces, extent), which the arithmetic must carry."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from catenet.case.keys import MAGNITUDE, Checker, show, too_large
from catenet.case.kinds import GeometryConfig
from catenet.model.builders import MAX_NODES
from catenet.model.memory import (  # noqa: F401  (re-exported)
    MEMORY_SHARE,
    PER_ITEM_BYTES,
    PROCESS_BYTES,
    estimate_memory,
    physical_memory,
)

if TYPE_CHECKING:
    from catenet.case.material import MaterialConfig
    from catenet.case.parse import Case
    from catenet.case.sections import LoadConfig


def estimate_size(geometry: GeometryConfig) -> tuple[float, float, float, str]:
    """(nodes, edges, junctions, key path of what drives the size), estimated from the
    parameters alone (see each kind's ``estimate_size``)."""
    return geometry.estimate_size()


def guard_size(ck: Checker, geometry: GeometryConfig) -> None:
    """A problem when the net would have more than MAX_NODES nodes or need more than
    MEMORY_SHARE of this machine's memory; it names the key that drives the size."""
    nodes, edges, junctions, key = estimate_size(geometry)
    value = getattr(geometry, key.removeprefix("geometry."), None)
    shown = value is not None and not isinstance(value, (tuple, list))
    where = f"{key} = {show(value)}" if shown else key
    if not nodes <= MAX_NODES:
        ck.add(
            f"{where}: the net would have about {nodes:.2g} nodes; catenet builds at most "
            f"{MAX_NODES:.0e} nodes"
        )
        return
    total = physical_memory()
    need = estimate_memory(nodes, edges, junctions)
    if total is not None and not need <= MEMORY_SHARE * total:
        gib = 2.0**30
        ck.add(
            f"{where}: the net would have about {edges:.2g} edges and need about "
            f"{need / gib:.2g} GiB; this machine has {total / gib:.0f} GiB (at most "
            f"{MEMORY_SHARE:.0%} of it may be used)"
        )


#: The largest stiffness times length scale (a force) and force times length (an
#: energy) a scene may reach: their squares and sums stay finite in double precision.
FORCE_SCALE = 1e150
ENERGY_SCALE = 1e250
#: The largest ratio of the node forces to the smallest EA (a strain scale).
RATIO = 1e150


def _given(keys: tuple[tuple[str, Any], ...], prefix: str) -> str:
    """``prefix.key = value`` for each (key, value) of ``keys`` given (not None, not zero)."""
    parts = [
        f"{prefix}.{name} = {show(value)}" for name, value in keys if value not in (None, 0.0, ())
    ]
    return ", ".join(parts) or prefix


def _stiffness_keys(mat: MaterialConfig) -> str:
    """The [material] keys given that make EA, as a message names them."""
    keys = (("E", mat.E), ("radius", mat.radius), ("area", mat.area), ("EA", mat.EA))
    return _given((*keys, ("table", mat.table)), "material")


def _mass_keys(mat: MaterialConfig) -> str:
    """The [material] keys given that make the mass per length, as a message names them."""
    return _given(
        (("density", mat.density), ("radius", mat.radius), ("area", mat.area)), "material"
    )


def _load_keys(load: LoadConfig) -> str:
    """The [load] keys given that make the node forces, as a message names them."""
    keys = (("pressure", load.pressure), ("gravity", load.gravity))
    return _given((*keys, ("points", load.points), ("lines", load.lines)), "load")


def guard_material(case: Case) -> None:
    """ConfigError when the material's EA (E times the cross-section) or mass per length
    (density times it) is beyond MAGNITUDE, naming the keys given; before any net is built."""
    mat = case.material
    problems = []
    ea = mat.axial_stiffness
    if ea is not None and not abs(ea) <= MAGNITUDE:
        keys = _stiffness_keys(mat)
        problems.append(f"{keys}: EA = {ea:.3g} N: must be within {too_large()}")
    if not abs(mat.line_density) <= MAGNITUDE:
        keys = _mass_keys(mat)
        problems.append(
            f"{keys}: mass per length {mat.line_density:.3g} kg/m: must be within {too_large()}"
        )
    if problems:
        from catenet.errors import ConfigError

        raise ConfigError(problems)


def guard_scales(case: Case, net: Any, loads: Any) -> None:
    """ConfigError when the scene's numbers, each within MAGNITUDE, combine into forces
    or energies the arithmetic cannot carry: EA (from E and the cross-section), the
    stiffness EA / l0 over the net's extent, the node forces (pressure over the area,
    gravity on the mass, point and line loads) and the work they do over it."""
    import numpy as np

    problems: list[str] = []
    material = _stiffness_keys(case.material)
    ea = np.abs(net.EA)
    if ea.size and not float(ea.max()) <= MAGNITUDE:
        problems.append(f"{material}: EA = {float(ea.max()):.3g} N: must be within {too_large()}")
    nodes = net.nodes
    extent = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0))) if len(nodes) else 0.0
    extent = max(extent, float(np.max(net.rest_length, initial=0.0)))
    with np.errstate(all="ignore"):
        stiff = float(np.max(ea / net.rest_length, initial=0.0))
        force = loads.external_force(net)
        f_max = float(np.max(np.abs(force), initial=0.0))
    if not problems and not stiff * extent <= FORCE_SCALE:
        problems.append(
            f"{material}: the edges' stiffness EA / rest length (up to {stiff:.3g} N/m) over "
            f"the net's extent ({extent:.3g} m) makes forces of {stiff * extent:.3g} N: "
            f"beyond {FORCE_SCALE:.0e} the arithmetic overflows; check the units"
        )
    ea_min = float(np.min(ea, initial=math.inf))
    if not problems and f_max > 0 and not f_max <= RATIO * ea_min:
        problems.append(
            f"{material}: EA = {ea_min:.3g} N against node forces of up to {f_max:.3g} N: "
            f"their ratio is beyond {RATIO:.0e} (strains no arithmetic carries); check the units"
        )
    if not (f_max <= FORCE_SCALE and f_max * extent <= ENERGY_SCALE):
        load = _load_keys(case.load)
        masses = ", material.density" if case.material.density else ""
        problems.append(
            f"{load}{masses}: node forces of up to {f_max:.3g} N over the net's extent "
            f"({extent:.3g} m): beyond {FORCE_SCALE:.0e} N (or {ENERGY_SCALE:.0e} J of work) "
            "the arithmetic overflows; check the units"
        )
    if problems:
        from catenet.errors import ConfigError

        raise ConfigError(problems)
