"""A case built: the net, its loads, the probe node and the length scale."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.bodies import add_bodies
from catenet.case.guard import guard_material, guard_scales
from catenet.case.keys import show
from catenet.case.kinds.base import expand, with_prefix
from catenet.case.kinds.cables import line_force
from catenet.case.masses import point_masses
from catenet.case.obstacles import obstacle_terms
from catenet.case.parse import Case
from catenet.case.shapes import check_motion
from catenet.errors import ConfigError
from catenet.model import builders as geo
from catenet.model.histories import History
from catenet.model.laws import Law, table_rows
from catenet.model.net import Loads, Net


@dataclass(frozen=True, eq=False)
class Scene:
    """A case built: the net, its loads, the probe node (whose z-deflection is "delta"),
    the length scale L of delta/L, and the energy terms the case adds to the stretching
    of the edges (``catenet.terms``; none for the paper's cases). ``cables`` names the
    cable of every edge of a graph with cables (a ``catenet.case.kinds.cables.CableIndex``;
    None: no cables). ``velocity`` (N, 3): the initial velocities of ``[[mass]]`` (None:
    at rest). ``bodies``: the moving spheres (``catenet.case.bodies.Body``), whose centres
    are the net's last nodes (``Net.bodies``)."""

    case: Case
    net: Net
    loads: Loads
    probe: int
    size: float
    terms: tuple = ()
    cables: Any = None
    velocity: np.ndarray | None = None
    bodies: tuple = ()


def build(case: Case) -> Scene:
    """The net, loads, probe node and length scale of a case."""
    try:
        return _build(case)
    except ConfigError as exc:
        key = "supports.fixed" if case.supports.fixed is not None else "geometry.fixed"
        raise ConfigError([with_prefix(p, key) for p in exc.problems]) from None


def _build(case: Case) -> Scene:
    guard_material(case)
    mat = case.material
    ea = mat.axial_stiffness
    material = geo.Material(
        EA=1.0 if ea is None else ea,  # None only for a graph with EA per edge
        line_density=mat.line_density,
        tension_only=mat.tension_only,
    )
    built = case.geometry.build_case(case, material)
    net = built.net if built.final else _with_law(case, built.net)
    point_mass, velocity = point_masses(getattr(case, "masses", ()), net, built.names, built.sets)
    if point_mass is not None:
        net = net.with_point_mass(point_mass)
    loads = _loads(case, net, built.names, built.size, built)
    guard_scales(case, net, loads)
    check_motion(case)  # a moving box, capsule or mesh: dynamic runs only
    net, loads, velocity, body_terms, bodies = add_bodies(
        case, net, loads, velocity, float(built.size)
    )
    terms = obstacle_terms(case.obstacles, net, loads, float(built.size)) + body_terms
    return Scene(
        case=case,
        net=net,
        loads=loads,
        probe=_probe(case, built),
        size=float(built.size),
        terms=terms,
        cables=built.cables,
        velocity=velocity,
        bodies=bodies,
    )


def _with_law(case: Case, net: Net) -> Net:
    """The net under the case's material law, with the rest lengths that give every edge
    ``material.prestress`` in the given geometry (U = EA l0 w(eps): the tension
    EA w'(eps) equals the prestress at eps = |e|/l0 - 1, so l0 = |e| / (1 + eps))."""
    mat = case.material
    if mat.law == "linear" and mat.prestress is None:
        return net  # the builders' default: the paper's law
    rows = table_rows(mat.table)[0] if mat.law == "table" else None
    law = Law.uniform(net.n_edges, mat.law, tension_only=net.law.tension_only, table=rows)
    rest = net.rest_length
    if mat.prestress is not None:
        length = np.linalg.norm(net.nodes[net.edges[:, 1]] - net.nodes[net.edges[:, 0]], axis=1)
        eps = law.strain_for_tension(mat.prestress, net.EA)
        bad = np.flatnonzero(~(np.isfinite(eps) & (eps > -1.0)))
        if bad.size:
            k = int(bad[0])
            raise ConfigError(
                f"material.prestress = {mat.prestress!r}: edge {k} cannot carry it under "
                f"law {mat.law!r} (EA = {net.EA[k]:.6g} N): its rest length would not be "
                "positive, or the law never reaches that tension"
            )
        rest = length / (1.0 + eps)
    return net.with_rest_length(rest, law)


def _probe(case: Case, built: Any) -> int:
    """The node whose z-deflection is delta: output.probe, else the geometry's."""
    ref = getattr(case.output, "probe", None)
    if ref is None:
        return int(built.probe)
    return int(expand(ref, built.names, built.sets or {})[0])


def _loads(case: Case, net: Net, names: dict[str, int], size: float, built: Any) -> Loads:
    """The loads: pressure, point loads (on a node, each node of a node set, or the node
    at a position along a cable), line loads along cables (lumped as the self-weight),
    gravity and support motion."""
    ld = case.load
    sets = built.sets
    constant = np.zeros((net.n_nodes, 3))
    timed: dict[tuple, np.ndarray] = {}  # a force per history table: loads that share one

    def target(history: tuple | None) -> np.ndarray:
        history = ld.history if history is None else history
        if history is None:
            return constant
        return timed.setdefault(history, np.zeros((net.n_nodes, 3)))

    if case.geometry.pressure and ld.pressure != 0.0:
        target(None)[:] += geo.pressure_force(net, ld.pressure, size)
    for k, pt in enumerate(ld.points):
        nodes = (built.at_nodes[k],) if pt.cable is not None else expand(pt.node, names, sets)
        for i in nodes:
            if not 0 <= i < net.n_nodes:
                raise ConfigError(
                    f"load.point[{k}].node = {show(pt.node)}: must be a node index in "
                    f"0..{net.n_nodes - 1}"
                )
            target(pt.history)[i] += pt.force
    for ln in ld.lines:
        on = np.ones(net.n_edges, dtype=bool)
        if ln.cable is not None:
            on = built.cables.edge == built.cables.names.index(ln.cable)
        line_force(net, on, ln.force, target(ln.history))
    force = constant if constant.any() else None
    parts = tuple((f, History(h)) for h, f in timed.items() if f.any())
    gravity = None if ld.gravity is None else np.array(ld.gravity, dtype=np.float64)
    g_history = History(ld.history) if gravity is not None and ld.history is not None else None
    disp = ramp = None
    moving: dict[tuple, list[int]] = {}
    if case.supports.moves:
        disp = np.zeros((net.n_nodes, 3))
        ramp = np.zeros(net.n_nodes)
        for k, mv in enumerate(case.supports.moves):
            for i in expand(mv.node, names, sets):
                if not (0 <= i < net.n_nodes and net.fixed[i]):
                    raise ConfigError(
                        f"supports.move[{k}].node = {show(mv.node)}: must be a fixed node"
                    )
                disp[i] = mv.displacement
                ramp[i] = mv.duration
                if mv.history is not None:
                    moving.setdefault(mv.history, []).append(i)
    return Loads(
        force=force,
        gravity=gravity,
        support_displacement=disp,
        ramp_time=ramp,
        parts=parts,
        gravity_history=g_history,
        support_history=tuple((np.array(n), History(h)) for h, n in moving.items()),
    )
