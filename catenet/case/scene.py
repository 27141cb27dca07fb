"""A case built (``build``): its ``catenet.scene.Scene``, the net, its loads, the probe
node, the length scale, the obstacles by the contact policy, the bodies, the load
cases."""

from __future__ import annotations

import dataclasses
import functools
import math
import types
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from catenet.case.coarse import coarse_case
from catenet.case.design import edge_design
from catenet.case.guard import guard_material, guard_scales
from catenet.case.keys import Checker, show
from catenet.case.kinds.base import expand, with_prefix
from catenet.case.kinds.cables import line_force
from catenet.case.kinds.warn import warn_once
from catenet.case.masses import point_masses
from catenet.case.material import model_material
from catenet.case.parse import Case
from catenet.case.rigid import movers
from catenet.case.rods import (
    bending_term,
    case_joints,
    case_rods,
    case_torsion,
    case_twist,
    clamped_nodes,
    rod_end_springs,
    with_clamps,
)
from catenet.case.shapes import check_motion
from catenet.case.supports import with_partial_supports
from catenet.errors import ConfigError
from catenet.model import builders as geo
from catenet.model.areas import area_load, beyond_outline, with_chains
from catenet.model.histories import History, Sine
from catenet.model.net import Loads, Net
from catenet.model.units import relabel
from catenet.scene.scene import Scene

if TYPE_CHECKING:  # the strands' kernels load only for a case with self-contact
    from catenet.terms.base import Term
    from catenet.terms.strands import SelfContact


def _coarser(case: Case, n_nodes: int, factor: float) -> Scene | None:
    """The case built with every edge length times ``factor``, with fewer nodes than
    ``n_nodes`` (the coarse net of a nested start, ``catenet.solver.nested``), or None
    where the case has no edge length to lengthen (``catenet.case.coarse``) or that net
    does not build."""
    coarse = coarse_case(case, factor)
    if coarse is None:
        return None
    try:
        scene = build(coarse)
    except ConfigError:
        return None
    return scene if scene.net.n_nodes < n_nodes else None


def build(case: Case) -> Scene:
    """The net, loads, probe node and length scale of a case."""
    try:
        return _build(case)
    except ConfigError as exc:  # (its lengths and forces named in the case's units)
        from catenet.model.units import relabel

        key = "supports.fixed" if case.supports.fixed is not None else "geometry.fixed"
        problems = [with_prefix(p, key) for p in exc.problems]
        raise ConfigError(relabel(problems, case.units or "SI")) from None


def _build(case: Case) -> Scene:
    guard_material(case)
    built = case.geometry.build_case(_with_case_points(case), model_material(case.material))
    clamped = clamped_nodes(case, built)
    flies = built.net.flies and case.solver.method == "dynamic"
    net = with_clamps(built.net, clamped)
    ends = rod_end_springs(case, built, net, clamped)
    net = with_partial_supports(case.supports, net, built.names, built.sets or {}, flies, ends)
    rods = case_rods(case, built, net, clamped)
    point_mass, velocity = point_masses(case.masses, net, built.names, built.sets)
    if point_mass is not None:
        net = net.with_point_mass(point_mass)
    loads = _loads(case, net, built.names, built.size, built)
    guard_scales(case, net, loads)
    check_motion(case)  # a moving box, capsule or mesh: dynamic runs only
    scene = Scene(
        net,
        loads,
        probe=_probe(case, built),
        size=float(built.size),
        velocity=velocity,
        cables=built.cables,
        sets=dict(built.sets or {}),
        at_nodes=dict(built.at_nodes or {}),
        names=dict(built.names),
        probe_auto=case.output.probe is None and case.geometry.kind == "graph",
        case=case,
        shown=show,
        edge_radius=_edge_radius(case),
    )
    for k, obs in enumerate(case.obstacles):  # the contact policy, as for a Python scene
        if not (obs.moves or obs.free):
            scene = scene.with_contact(obs.shape(), obs.contact(), index=k)
    scene = scene.with_movers(*movers(case))  # balls and free bodies
    if rods is not None:
        scene = scene.with_terms(bending_term(rods, scene.net.n_nodes))
    joints = case_joints(case, built, net, scene.net.n_nodes)
    if joints is not None:
        scene = scene.with_terms(joints)
    held = None if joints is None else joints.joints  # rigid joints hold the twist too
    twist = case_twist(case, built, net, rods, scene.net.n_nodes, held)
    if twist is not None:
        scene = scene.with_terms(twist)
    scene = dataclasses.replace(
        scene,
        cases=_load_cases(case, scene.net, built),
        design=edge_design(case, scene.net, built),
        coarsen=functools.partial(_coarser, case, scene.net.n_nodes),
        torsion=case_torsion(case, built, net, rods, twist, held),
    )
    if case.solver.self_contact:
        strands = self_contact(case.solver, scene.net, scene.loads, scene.edge_radius)
        scene = scene.with_terms(strands)
    if case.water is not None:
        from catenet.case.water import water_terms

        scene = scene.with_terms(*water_terms(case, scene))
    damping = axial_damping(case, scene)
    if damping is not None:
        scene = scene.with_terms(damping)
    return scene


def axial_damping(case: Case, scene: Scene) -> Term | None:
    """The cables' internal axial damping (``material.axial_damping``, each cable's
    own) in a dynamic run, or None (none given, or a static run: nothing moves)."""
    from catenet.case.kinds.cables import cable_materials
    from catenet.case.kinds.graph import GraphConfig
    from catenet.terms.axial import AxialDamping

    if case.solver.method != "dynamic":
        return None
    net = scene.net
    c = np.full(net.n_edges, case.material.axial_damping)
    listed = case.geometry.cables if isinstance(case.geometry, GraphConfig) else ()
    if scene.cables is not None and listed:
        mats = cable_materials(Checker(), case.material, listed)
        own = np.array([m.axial_damping for m in mats])
        on = scene.cables.edge >= 0
        c[on] = own[scene.cables.edge[on]]
    return AxialDamping(net, c) if np.any(c > 0.0) else None


def _edge_radius(case: Case) -> float | None:
    """The edges' contact radius where ``solver.edge_contact`` is on (None: off):
    ``material.contact_radius``, else the cable's radius, else 0."""
    if not case.solver.edge_contact:
        return None
    m = case.material
    return m.contact_radius if m.contact_radius is not None else (m.radius or 0.0)


#: The default activation distance of self-contact, per shortest edge.
STRAND_DISTANCE_SHARE = 1e-2


def self_contact(solver, net: Net, loads: Loads, radius: float | None = None) -> SelfContact:
    """The barrier between the net's strands (``solver.self_contact``): activation
    distance ``solver.self_contact_distance``, else STRAND_DISTANCE_SHARE of the shortest
    edge; stiffness such that two strands dhat/2 apart push each other with a node's
    mean share of the loads (without loads: the force that strains an average edge by
    dhat / l0); ``radius`` > 0 (``solver.edge_contact``): capsules of that radius, on
    their gap (ConfigError where two start closer than twice the radius)."""
    from catenet.terms.contact import default_stiffness
    from catenet.terms.strands import SelfContact, default_strand_stiffness

    edges = net.rest_length
    dhat = solver.self_contact_distance or STRAND_DISTANCE_SHARE * float(edges.min())
    force = loads.external_force(net)[np.unique(net.edges)]
    load = float(np.mean(np.linalg.norm(force, axis=1)))
    if not load > 0.0:
        load = float(np.mean(net.EA / edges)) * dhat
    if not radius:
        term = SelfContact(net, kappa=default_strand_stiffness(load, dhat), dhat=dhat)
    else:
        term = SelfContact(net, kappa=default_stiffness(load, dhat), dhat=dhat, radius=radius)
    term.key, term.label = "solver.self_contact_distance", "the strands' self-contact"
    if not radius:
        return term
    near = term.distances(net.nodes, 2.0 * radius)
    if near.size:
        raise ConfigError(
            f"solver.self_contact: two strands start {near[0]:.3g} m apart, closer than twice "
            f"the contact radius (material.contact_radius, {radius:.3g} m): they overlap; "
            "move them apart or give a smaller contact radius"
        )
    return term


@dataclass(frozen=True, eq=False)
class LoadCase:
    """A load case or combination built: its name, whether it is a combination and the
    force it adds to the base loads (N, 3) [N] (static: histories do not apply)."""

    name: str
    force: np.ndarray
    combination: bool = False


def _with_case_points(case: Case) -> Case:
    """The case whose point loads include the load cases' loads along cables (after its
    own, in order), so that the geometry puts a node under each: every case shares the
    base's net."""
    extra = tuple(pt for lc in case.load_cases for pt in lc.points)
    if not any(pt.cable is not None for pt in extra):
        return case
    load = dataclasses.replace(case.load, points=case.load.points + extra)
    return dataclasses.replace(case, load=load)


def _load_cases(case: Case, net: Net, built: Any) -> tuple:
    """The load cases' and combinations' added forces (``LoadCase``)."""
    from catenet.model.cases import combined

    out = []
    offset = len(case.load.points)
    forces = {}
    for k, lc in enumerate(case.load_cases):
        at = {
            j: built.at_nodes[offset + j]
            for j in range(len(lc.points))
            if offset + j in built.at_nodes
        }
        offset += len(lc.points)
        sub = dataclasses.replace(
            case, load=lc, supports=dataclasses.replace(case.supports, moves=(), vessels=())
        )
        try:
            loads = _loads(
                sub, net, built.names, float(built.size), built._replace(at_nodes=at),
                where=f"load_case[{k}].",
            )  # fmt: skip
        except ConfigError as exc:
            raise ConfigError(
                [p.replace("load.", f"load_case[{k}].", 1) for p in exc.problems]
            ) from None
        forces[lc.name] = loads.external_force(net)
        out.append(LoadCase(lc.name, forces[lc.name]))
    for combo in case.combinations:
        out.append(LoadCase(combo.name, combined(forces, combo.factors), True))
    return tuple(out)


def _probe(case: Case, built: Any) -> int:
    """The node whose z-deflection is delta: output.probe, else the geometry's."""
    ref = case.output.probe
    if ref is None:
        return int(built.probe)
    return int(expand(ref, built.names, built.sets or {})[0])


def _area_force(
    case: Case, net: Net, names: dict, sets: Any, size: float, k: int, quiet: bool = False,
    where: str = "load.",
) -> np.ndarray:  # fmt: skip
    """The nodal forces of load.area[k] (catenet/model/areas.py); the paper's pressure
    on a square net as a whole (its own lumping of p L^2)."""
    ar = case.load.areas[k]
    if ar.nodes is None:
        own = case.geometry.area_force(net, ar.pressure, size)
        if own is not None:
            return own
        covered = np.ones(net.n_nodes, dtype=bool)
        path = f"{where}area[{k}] (on the whole net)"
    else:
        refs = (ar.nodes,) if isinstance(ar.nodes, str) else ar.nodes
        covered = np.zeros(net.n_nodes, dtype=bool)
        covered[[i for r in refs for i in expand(r, names, sets or {})]] = True
        covered = with_chains(covered, case.geometry.given_nodes(net), net.edges)
        path = f"{where}area[{k}].nodes = {show(ar.nodes)}"
    covered[net.n_net :] = False  # (the bodies' centres)
    try:
        load = area_load(net.nodes, net.edges, covered, ar.pressure, ar.direction, net.fixed)
    except ConfigError as exc:
        raise ConfigError([f"{path}: {p}" for p in exc.problems]) from None
    if not quiet:
        _warn_beyond(path, net, covered, load, case.units)
    return load.force


def _warn_beyond(path: str, net: Net, covered: np.ndarray, load: Any, units: str) -> None:
    """Warns of covered nodes no edge joins outside the loaded outline: the pressure
    between them and the net loads no node, and the resultant is less than the user
    may have reckoned (``catenet.model.areas.beyond_outline``)."""
    lonely, area = beyond_outline(net.nodes, net.edges, covered, load)
    if not len(lonely):
        return
    listed = ", ".join(str(int(i)) for i in lonely[:6]) + (", ..." if len(lonely) > 6 else "")
    share = 100.0 * area / (load.area + area)
    warn_once(
        relabel(
            [
                f"{path}: {len(lonely)} nodes that no edge joins (nodes {listed}) lie outside "
                f"the outline the load covers: the pressure on the {area:.4g} m^2 between "
                f"them and the net loads no node ({share:.3g} % of the {load.area + area:.4g} "
                f"m^2 they enclose; {load.area:.4g} m^2 is loaded): join them by edges (a "
                "border cable) if the net is to carry it"
            ],
            units,
        )[0]
    )


def loads_at(scene: Scene, nodes: np.ndarray, rest_length: np.ndarray) -> np.ndarray | None:
    """The case's constant [load] forces (N, 3) on its net moved to ``nodes`` with
    ``rest_length``: area loads lumped on that shape, line loads along those rest
    lengths, point loads and a square net's pressure as built (form finding's loads on
    the shape it found); None where the case has neither area nor line loads (its loads
    do not follow the shape)."""
    case = scene.case
    if case is None or not (case.load.areas or case.load.lines):
        return None
    net = scene.net.replace(nodes=nodes, rest_length=rest_length)
    built = types.SimpleNamespace(sets=scene.sets, at_nodes=scene.at_nodes, cables=scene.cables)
    loads = _loads(case, net, dict(scene.names), scene.size, built, quiet=True)
    return np.zeros((net.n_nodes, 3)) if loads.force is None else loads.force


def _loads(
    case: Case, net: Net, names: dict[str, int], size: float, built: Any, quiet: bool = False,
    where: str = "load.",
) -> Loads:  # fmt: skip
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
        if pt.cable is not None or pt.node is None:  # a position along a cable
            nodes: tuple[int, ...] = (built.at_nodes[k],)
        else:
            nodes = expand(pt.node, names, sets)
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
    for k, ar in enumerate(ld.areas):
        target(ar.history)[:] += _area_force(case, net, names, sets, size, k, quiet, where)
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
                if mv.sine is not None:  # amplitude times the sine's factor
                    disp[i] = mv.sine.amplitude
                    moving.setdefault(_sine_key(mv.sine), []).append(i)
                    continue
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
        support_history=tuple((np.array(n), _motion(h)) for h, n in moving.items()),
        vessels=_vessels(case, net, names, sets),
    )


def _vessels(case: Case, net, names, sets) -> tuple:
    """(node indices, Vessel) of each [[supports.vessel]]; ConfigError where a node it
    carries is not fixed."""
    from catenet.case.vessel import vessel_model

    out = []
    for k, vs in enumerate(case.supports.vessels):
        nodes = [i for r in vs.nodes for i in expand(r, names, sets)]
        loose = [i for i in nodes if not (0 <= i < net.n_nodes and net.fixed[i])]
        if loose:
            raise ConfigError(
                f"supports.vessel[{k}].nodes: node {loose[0]} is not a fixed node: a "
                "vessel carries supports only"
            )
        out.append((np.array(nodes, dtype=np.int64), vessel_model(vs)))
    return tuple(out)


def _sine_key(sine) -> tuple:
    """A sine motion as the key of the supports that share it."""
    ramp = sine.period if sine.ramp is None else sine.ramp
    return ("sine", sine.period, math.radians(sine.phase), ramp)


def _motion(key: tuple) -> History | Sine:
    """The factor(t) of a support motion: a history table, or a sine (``_sine_key``)."""
    if key and key[0] == "sine":
        return Sine(*key[1:])
    return History(key)
