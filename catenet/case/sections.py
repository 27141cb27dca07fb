"""The sections of a case besides the geometry: material, supports, load, solver, output.

Each section is a frozen dataclass whose fields declare its keys (catenet/case/keys.py);
the parse functions add the rules between keys of one section.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from catenet.case.design import DesignConfig
from catenet.case.keys import (
    BAD,
    Checker,
    Context,
    Declared,
    boolean,
    choice,
    integer,
    key,
    names,
    node,
    parse_keys,
    parse_table,
    real,
    tables,
    text,
    vec3,
)
from catenet.case.kinds import KINDS
from catenet.case.material import EDGE_CONTACT, MaterialConfig, parse_material  # noqa: F401
from catenet.case.supports import (
    MoveConfig,
    RollerConfig,
    RotationalConfig,
    SliderConfig,
    SpringConfig,
    TwistConfig,
    fixed_list,
    history_key,
)
from catenet.case.supports import node_list as _node_list
from catenet.case.vessel import VesselConfig
from catenet.errors import ConfigError
from catenet.model.areas import DIRECTIONS as AREA_DIRECTIONS
from catenet.solver.integrators import INTEGRATORS
from catenet.solver.relax import REST
from catenet.solver.settings import INITIAL_STATES, MAX_ITER_SHOWN, METHODS, STARTS, Settings

LINEAR = ("auto", "pardiso", "scipy")
MAX_ITER = (
    "Newton iterations of one solve: a static equilibrium (a load step) or one time step "
    "(a step that fails is cut back and solved again, each part with its own budget: the "
    "summary counts them all)"
)

Vec3 = tuple[float, float, float]
NodeRef = int | str


# --------------------------------------------------------------------------- supports


@dataclass(frozen=True)
class SupportsConfig(Declared):
    """``fixed``: the pinned nodes, replacing the geometry's default supports (None: the
    defaults); ``moves``: prescribed motions of pinned nodes."""

    fixed: tuple[NodeRef, ...] | None = key(
        fixed_list,
        "an array of nodes (indices or names; empty where clamps, rollers, sliders or "
        "springs hold)",
        None,
        write="changed",
        shown="the geometry's own",
        doc="pinned nodes, replacing the geometry's default supports",
    )
    moves: tuple[MoveConfig, ...] = tables(
        MoveConfig, name="move", doc="moving supports: only fixed nodes move, each once"
    )
    vessels: tuple = tables(VesselConfig, name="vessel", doc="vessels moving supports together")
    clamped: tuple[NodeRef, ...] = key(
        _node_list,
        "a non-empty array of nodes (indices or names), each the end of a rod",
        (),
        write="given",
        shown="none",
        doc="rod ends held in place with their given tangent (material.EI > 0), and their "
        "twist where material.GJ > 0",
    )
    rigid_joints: tuple[NodeRef, ...] = key(
        _node_list,
        "a non-empty array of nodes (indices or names), each where rods of two lines meet",
        (),
        write="given",
        shown="none",
        doc="nodes where rods of two or more lines meet rigidly: their ends turn together, "
        "the angles between them kept (default: pinned to each other)",
    )
    rollers: tuple[RollerConfig, ...] = tables(
        RollerConfig, name="roller", doc="nodes held along a normal only (free in its plane)"
    )
    sliders: tuple[SliderConfig, ...] = tables(
        SliderConfig, name="slider", doc="nodes free along a direction only"
    )
    springs: tuple[SpringConfig, ...] = tables(
        SpringConfig, name="spring", doc="elastic supports toward the nodes' given positions"
    )
    twists: tuple[TwistConfig, ...] = tables(
        TwistConfig, name="twist", doc="clamped rod ends turned about the rod's axis (GJ > 0)"
    )
    rotationals: tuple[RotationalConfig, ...] = tables(
        RotationalConfig,
        name="rotational",
        doc="rod ends held elastically in their direction: a rotational spring (EI > 0)",
    )

    @property
    def partial(self) -> bool:
        """Whether there are rollers, sliders or springs."""
        return bool(self.rollers or self.sliders or self.springs)


# --------------------------------------------------------------------------- load


@dataclass(frozen=True, kw_only=True)
class PointLoadConfig(Declared):
    """A force [N] (constant, or along a history in dynamic runs) on one node, on each
    node of a node set, or at a position along a cable (``cable`` and ``at``: the edge
    there is split so that a node carries it)."""

    node: NodeRef | None = node(
        None, write="given", shown="none", doc="the loaded node, or a node set (each node)"
    )
    cable: str | None = text(
        None, nonempty=True, write="given", doc="graph: the loaded cable (instead of node)"
    )
    at: float | None = real(
        None,
        ge=0,
        need="finite, in 0..1",
        write="given",
        doc="with cable: where, as a fraction of the cable's length from its first node",
    )
    force: Vec3 = vec3(
        missing="[fx, fy, fz] [N]", unit="N", doc="[fx, fy, fz]; forces on one node add up"
    )
    history: tuple | None = history_key("dynamic: force times factor(t) (none: load.history)")


def _point_tables(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """The point loads, each on a node (or node set) or at a position along a cable."""
    items = []
    for k, t in enumerate(ck.array_of_tables(v, path)):
        here = f"{path}[{k}]"
        pt = parse_table(ck, t, PointLoadConfig, here, ctx)
        items.append(pt)
        if pt is BAD:
            continue
        if (pt.node is None) == (pt.cable is None):
            what = "both" if pt.node is not None else "neither"
            ck.add(
                f"{here}: gives {what} of node and cable: give a node (or node set), or a "
                "cable with at"
            )
        elif pt.cable is not None and pt.at is None:
            ck.add(f"{here}.at: missing: with cable, the position along it (0..1 of its length)")
        elif pt.cable is None and pt.at is not None:
            ck.add(f"{here}.at = {pt.at!r}: only with cable (a point load on a node needs none)")
        elif pt.at is not None and pt.at > 1.0:
            ck.bad(f"{here}.at", pt.at, "must be finite, in 0..1 (a fraction of the cable length)")
        else:
            continue
        items[-1] = BAD
    return BAD if BAD in items else tuple(items)


@dataclass(frozen=True, kw_only=True)
class LineLoadConfig(Declared):
    """A distributed force per unit unstressed length [N/m] along a cable (or along every
    edge), lumped to the nodes as the self-weight is: half of each edge's share to each
    of its ends."""

    cable: str | None = text(
        None,
        nonempty=True,
        write="given",
        shown="every edge",
        doc="graph: the loaded cable (without it, every edge: all cables)",
    )
    force: Vec3 = vec3(
        missing="[fx, fy, fz] [N/m]", unit="N/m", doc="[fx, fy, fz] per unit unstressed length"
    )
    history: tuple | None = history_key("dynamic: force times factor(t) (none: load.history)")


def _covered(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """The nodes an area load covers: a node set's name or an array of nodes."""
    if isinstance(v, str):
        return ck.node_ref(v, path, ctx.kind)
    if isinstance(v, (list, tuple)) and len(v) >= 3:
        return _node_list(ck, v, path, ctx)
    return ck.bad(
        path,
        v,
        'must be a node set (its name in [geometry.sets], or "cable:NAME") or an '
        "array of at least 3 nodes",
    )


@dataclass(frozen=True, kw_only=True)
class AreaLoadConfig(Declared):
    """A pressure [Pa] over the area the net covers (or the part ``nodes`` covers),
    lumped to the nodes by tributary area (docs/guide/loads.md): on plan, vertical per
    unit plan area (snow); normal, per unit surface area along the surface's normal
    (wind)."""

    pressure: float = real(
        need="finite (> 0 pushes down on plan, against the upward normal)",
        missing="the pressure [Pa]",
        unit="Pa",
        doc="> 0: down on plan; normal: against the net's upward normal (suction < 0)",
    )
    direction: str = choice(
        "plan",
        AREA_DIRECTIONS,
        doc="plan: vertical, per plan area (snow); normal: per surface area, normal to "
        "the net in the given geometry (wind)",
    )
    nodes: Any = key(
        _covered,
        "a node set (name) or an array of at least 3 nodes",
        None,
        write="given",
        shown="the whole net",
        doc="the part it covers: the cells of the edges between these nodes (list every node "
        "of the part, not its corners alone), inside the outline through its outer ones",
    )
    history: tuple | None = history_key("dynamic: pressure times factor(t) (none: load.history)")


def _pressure(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    p = ck.real(v, path)
    kind = ctx.kind
    if p not in (BAD, 0.0) and kind is not None and not kind.pressure:
        takes = " or ".join(repr(name) for name, cls in KINDS.items() if cls.pressure)
        table = path.rsplit(".", 1)[0]  # load, or load_case[k]
        ck.add(
            f"{path} = {p!r}: only for geometry.kind = {takes} "
            f"(this is {kind.kind!r}): give a pressure as {table}.area (area loads on the "
            f"net's cells), or use {table}.point or {table}.gravity"
        )
    return p


@dataclass(frozen=True)
class LoadConfig(Declared):
    """Pressure p [Pa] (square_net), gravity [m/s^2] (None: none), point loads,
    distributed loads along cables and area loads."""

    pressure: float = key(
        _pressure,
        "a number, finite (square nets only)",
        0.0,
        unit="Pa",
        doc="-p L^2 / N in z on every node",
    )
    gravity: Vec3 | None = vec3(
        None, write="given", shown="none", unit="m/s^2", doc="[gx, gy, gz] on the lumped masses"
    )
    points: tuple[PointLoadConfig, ...] = key(
        _point_tables,
        "an array of tables",
        (),
        section=PointLoadConfig,
        write="given",
        name="point",
        doc="point loads",
    )
    lines: tuple[LineLoadConfig, ...] = tables(
        LineLoadConfig, name="line", doc="distributed loads per unit length of cable"
    )
    areas: tuple[AreaLoadConfig, ...] = tables(
        AreaLoadConfig,
        name="area",
        doc="pressures over the area the net covers, on plan or normal to it",
    )
    history: tuple | None = history_key(
        "dynamic: pressure and gravity (with buoyancy, the displaced water's weight) times "
        "factor(t), and each point or line load without its own history (none: constant)"
    )


# --------------------------------------------------------------------------- solver


def _check_unit_interval(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """A number in [0, 1]."""
    f = ck.real(v, path, ge=0.0, need="in [0, 1]")
    if f is not BAD and f > 1.0:
        return ck.bad(path, v, "must be in [0, 1]")
    return f


def _check_t_end(ck: Checker, v: Any, path: str, ctx: Context) -> Any:
    """An end time > 0, or "rest"."""
    if isinstance(v, str):
        return v if v == REST else ck.bad(path, v, f"must be a number > 0 or {REST!r}")
    return ck.real(v, path, gt=0.0, need=f"finite and > 0, or {REST!r}")


@dataclass(frozen=True)
class SolverConfig(Declared):
    """How to solve: see docs/DESIGN.md (solver section) for the meaning of each key."""

    method: str = choice(
        Settings.method,
        METHODS,
        doc="equilibrium directly, or in time: the paper's damped implicit Euler to rest, "
        "bdf2 at steps chosen by accuracy where anything depends on time (solver.integrator)",
    )
    dt: float = real(
        None,  # not given: catenet/case/parse.py decides (fixed, or the first adaptive step)
        gt=0,
        write="given",
        unit="s",
        shown="`0.01`; with solver.tolerance (or contact): t_end / 1000",
        doc="dynamic: the time step (fixed); with solver.tolerance, the first step",
    )
    tolerance: float | None = real(
        None,
        gt=0,
        lt=1,
        write="given",
        shown="none: fixed steps; `3e-3` with contact or motion in time, and no dt",
        doc="dynamic, a number for t_end: steps chosen by accuracy: each step's local error "
        "in positions, strains and bodies' momenta, as a share of how far the motion goes, "
        "the largest strain and momentum, and the energy its integrator removes or creates "
        "(over the run, 5 % of the motion's at 3e-3, in proportion at others) "
        "(docs/howto/dynamic-runs.md)",
    )
    dt_max: float | None = real(
        None, gt=0, write="given", unit="s", shown="t_end", doc="adaptive steps: the longest"
    )
    dt_min: float | None = real(
        None,
        gt=0,
        write="given",
        unit="s",
        shown="t_end / 2^40",
        doc="adaptive steps: the shortest (a step there is taken, its error counted)",
    )
    damping: float = real(
        Settings.damping,
        ge=0,
        unit="1/s",
        shown="`1.0` where nothing depends on time; `0.0` where anything does, or with [water]",
        doc="dynamic: mass damping mu (of the paper's dynamic relaxation)",
    )
    integrator: str | None = choice(
        None,  # not given: bdf2 where steps adapt, else implicit Euler (parse.py)
        INTEGRATORS,
        write="given",
        shown='`"implicit_euler"`; `"bdf2"` with solver.tolerance (or its default)',
        doc="dynamic: the paper's implicit Euler (first order, damps numerically), "
        "newmark (second order; refused with contact) or bdf2 (second order, L-stable: right in "
        "contact)",
    )
    rho_inf: float = key(
        _check_unit_interval,
        "a number in [0, 1]",
        Settings.rho_inf,
        write="changed",
        doc="newmark: spectral radius at h omega -> inf (1: average acceleration, "
        "no numerical damping)",
    )
    t_end: float | str = key(
        _check_t_end,
        f"a number > 0, or {REST!r}",
        None,  # not given: catenet/case/timing.py decides for a dynamic case (parse_case)
        write="given",
        shown=f'`"{REST}"` if nothing depends on time, else `10.0`',
        unit="s",
        doc='dynamic: end time, or "rest": dynamic relaxation until the net is at rest '
        '(its steps grow as the motion decays: pseudo-time). Default "rest" unless a load '
        "or support motion has a history or duration, an obstacle moves or is a free body, "
        "a node starts with a velocity, or damping = 0; then 10 s",
    )
    max_steps: int = integer(
        Settings.max_steps,
        ge=1,
        le=10**8,
        write="changed",
        doc='dynamic, t_end = "rest": the most time steps before the run fails as not '
        "coming to rest",
    )
    reuse: bool = boolean(
        Settings.reuse,
        write="changed",
        doc="dynamic: keep the factorisation across Newton iterations and time steps while "
        "it converges (modified Newton: same answer to rtol, 1.5-2x faster; a --restart then "
        "repeats the uninterrupted run only to rtol)",
    )
    rtol: float = real(Settings.rtol, gt=0, lt=1, doc="Newton tolerance")
    self_contact: bool = boolean(
        False,
        write="changed",
        doc="dynamic: the net never passes through itself (a barrier between strands that "
        "share no node; docs/guide/self-contact.md)",
    )
    self_contact_distance: float | None = real(
        None,
        gt=0,
        write="given",
        unit="m",
        shown="1e-2 x the shortest edge",
        doc="self_contact: the barrier's activation distance: strands touching rest closer "
        "than this, and no farther pair feels the other",
    )
    edge_contact: bool = boolean(False, write="changed", doc=EDGE_CONTACT)
    linear: str = choice(
        Settings.linear,
        LINEAR,
        doc="linear solver (auto: PARDISO where available, below 700 unknowns a banded Cholesky)",
    )
    threads: int = integer(1, ge=1, doc="threads of MKL, OpenBLAS and Numba")
    max_iter: int | None = integer(
        None, ge=1, le=10**6, write="given", shown=MAX_ITER_SHOWN, doc=MAX_ITER
    )
    start: str = choice(
        Settings.start,
        STARTS,
        write="changed",
        doc="static: where Newton starts from a flat, unstressed net: the stretched start, "
        "the nested start (the same case solved at longer edges: square nets, cables with "
        "an edge_length), or auto: nested from 70 000 free DOFs, else stretched "
        "(docs/guide/starts.md)",
    )
    steps: int = integer(
        Settings.steps, ge=1, le=10**6, doc="static: load steps (equilibria at k/steps of the load)"
    )
    energy_tolerance: float = real(
        Settings.energy_tolerance,
        gt=0,
        write="changed",
        doc="dynamic: the energy the integrator may create, as a share of the largest energy "
        "of the run (kinetic, elastic, contact or work); beyond it the run stops with exit 1 "
        "(the balance is /trajectory/energy)",
    )
    initial_state: str = choice(
        Settings.initial_state,
        INITIAL_STATES,
        write="changed",
        doc='dynamic: "given" (the geometry as given, or a restart\'s state) or '
        '"equilibrium": the static equilibrium under the loads, supports and water at t = 0, '
        "at rest (velocities as [[mass]] gives them)",
    )
    post_collapse: bool = boolean(
        Settings.post_collapse,
        write="changed",
        doc="static: a load path that loses its stability (a mechanism folding, a snap-"
        "through, a member falling) is followed through to the far equilibrium, labelled "
        "post-collapse (/result stability), instead of ending with exit 1 at the last stable "
        "state (docs/guide/stability.md)",
    )


def parse_solver(ck: Checker, s_v: Any, ctx: Context) -> SolverConfig | Any:
    s = ck.table(s_v, "solver")
    if s is None:
        return BAD
    ck.keys(s, "solver", names(SolverConfig))
    v = parse_keys(ck, s, SolverConfig, "solver", ctx)
    if v["linear"] == "pardiso":
        from catenet.solver.linear import resolve_backend

        try:
            resolve_backend("pardiso")
        except ConfigError as exc:
            ck.problems.extend(exc.problems)
    if v["self_contact"] is True and v["method"] == "static":
        ck.add(
            "solver.self_contact = true: is for dynamic runs: set solver.method = "
            '"dynamic" (or self_contact = false)'
        )
        return BAD
    if BAD in v.values():
        return BAD
    return SolverConfig(**v)


# --------------------------------------------------------------------------- output


@dataclass(frozen=True)
class OutputConfig(Declared):
    """Result file, trajectory stride (0: final state only), XDMF sidecar switch and the
    probe node (None: the geometry's)."""

    file: str = text(
        None,
        nonempty=True,
        computed=True,
        shown='`"out/<case file name>.h5"`',
        doc="the result file (HDF5)",
    )
    every: int = integer(1, ge=0, doc="keep every k-th step (0: the final state only)")
    xdmf: bool = boolean(True, doc="write the XDMF sidecar (for ParaView)")
    probe: NodeRef | None = node(
        None,
        write="given",
        shown="the geometry's own (e.g. `center`)",
        doc="the node whose z-deflection is reported as delta: an index, a node name, "
        "or a node set of one node",
    )


def parse_output(ck: Checker, o_v: Any, ctx: Context, source: str) -> OutputConfig | Any:
    """The [output] table; the file defaults to out/<stem of the case file>.h5."""
    o = ck.table(o_v, "output")
    if o is None:
        return BAD
    ck.keys(o, "output", names(OutputConfig))
    v = parse_keys(ck, o, OutputConfig, "output", ctx)
    if v["file"] is None:
        stem = "case" if source.startswith("<") else (Path(source).stem or "case")
        v["file"] = f"out/{stem}.h5"
    if BAD in v.values():
        return BAD
    return OutputConfig(**v)


#: The sections after the geometry, in the order they are parsed and written.
SECTIONS: dict[str, type] = {
    "material": MaterialConfig,
    "supports": SupportsConfig,
    "load": LoadConfig,
    "solver": SolverConfig,
    "output": OutputConfig,
    "design": DesignConfig,
}
