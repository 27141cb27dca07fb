"""The tables of a report (``catenet report``), from a result file's states
(``catenet.output.states``): for the base state, each load case and combination,
per cable the largest and least tension, the largest utilisation and the slack length;
per support set and supported node the reaction; per node set the largest
displacement; the applied loads against reactions and contact; the verdict and
warnings. A dynamic run adds its peaks with their times; the envelope over the cases
governs last. Every number is the file's (or a sum, maximum or minimum of the file's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from catenet.model.summary import first_extreme
from catenet.model.units import relabel, system
from catenet.output.states import State, States
from catenet.report.groups import Groups, groups

#: A state's supported nodes listed one by one up to this many (beyond: the largest).
MAX_NODE_ROWS = 40


@dataclass
class Table:
    """A table: ``key`` (its CSV file's stem), ``title``, ``columns`` (with units) and
    ``rows`` (plain values: str, int, float; NaN where a value is not known); ``note``
    says what a reader needs to know about it."""

    key: str
    title: str
    columns: tuple[str, ...]
    rows: list[list] = field(default_factory=list)
    note: str = ""


@dataclass
class Section:
    """One state's part of the report: its ``name``, ``kind`` ("base", "load_case",
    "combination", "envelope"), ``verdict`` (label -> text, in order), ``warnings``
    (``recorded``: False where the file keeps none) and ``tables``."""

    name: str
    kind: str
    verdict: dict[str, str]
    warnings: list[str]
    tables: list[Table]
    recorded: bool = True  # whether the file keeps the state's warnings

    @property
    def heading(self) -> str:
        """ "base state", "envelope", "load case NAME" or "combination NAME"."""
        if self.kind in ("base", "envelope"):
            return self.name
        return f"{self.kind.replace('_', ' ')} {self.name}"


@dataclass
class Report:
    """A whole report: the file's ``title``, its ``path``, what the run was (``about``:
    label -> text) and a section per state."""

    title: str
    path: str
    about: dict[str, str]
    sections: list[Section]
    groups: Groups
    units: str = "SI"  # the case's units system: the labels' names (catenet.model.units)


def build_report(states: States) -> Report:
    """The report of a result file's states."""
    g = groups(states)
    dynamic = states.method == "dynamic"
    sections = [_section(states, g, s, dynamic) for s in states.states]
    if states.envelope:
        sections.append(_envelope_section(states, g))
    about = {
        "file": str(states.path),
        "method": states.method,
        "net": f"{len(states.mesh.nodes)} nodes, {len(states.mesh.edges)} edges, "
        f"{len(g.names)} cable{'' if len(g.names) == 1 else 's'}",
        "states": ", ".join(_label(s) for s in states.states),
    }
    units = system(states.case.get("units"))
    return Report(states.title, str(states.path), about, sections, g, units)


def in_units(report: Report) -> Report:
    """``report`` with every unit name (columns, notes, verdicts, warnings) as its case's
    ``units`` name them (kN-m: kN, kPa; N-mm: mm, MPa): the numbers are the file's."""
    if report.units == "SI":
        return report

    def text(line: str) -> str:
        return relabel([line], report.units)[0]

    for sec in report.sections:
        sec.verdict = {k: text(v) for k, v in sec.verdict.items()}
        sec.warnings = [text(w) for w in sec.warnings]
        for t in sec.tables:
            t.columns = tuple(text(c) for c in t.columns)
            t.note = text(t.note)
    return report


def _label(s: State) -> str:
    return "base state" if s.kind == "base" else s.name


# --------------------------------------------------------------------------- one state


def _section(states: States, g: Groups, s: State, dynamic: bool) -> Section:
    peaks = dynamic and s.kind == "base" and s.get("peak_tension") is not None
    tables = [
        cable_table(states, g, s, peaks),
        support_table(states, g, s),
        displacement_table(states, g, s, peaks),
        balance_table(s),
    ]
    warnings = [w for w in str(s.attrs.get("warnings", "")).split("\n") if w]
    recorded = "warnings" in s.attrs  # (files of older versions keep none)
    return Section(_label(s), s.kind, _verdict(s, dynamic), warnings, tables, recorded)


def _verdict(s: State, dynamic: bool) -> dict[str, str]:
    a = s.attrs
    out = {"converged": _yes(a.get("converged"))}
    out["stability"] = str(a.get("stability", "")) or "not recorded"
    if s.kind == "combination" and a.get("factors"):
        out["factors"] = str(a["factors"])
    if "time" in a:
        t = float(a["time"])
        out["time" if dynamic and s.kind == "base" else "load factor"] = f"{t:.6g}"
    for key in ("error", "message"):
        if a.get(key):
            out[key] = str(a[key])
            break
    return out


def _yes(v) -> str:
    return "unknown" if v is None else ("yes" if bool(v) else "no")


def _strain(states: States, x: np.ndarray) -> np.ndarray | None:
    rest = states.mesh.rest_length
    if rest is None:
        return None
    e = states.mesh.edges
    length = np.linalg.norm(x[e[:, 1]] - x[e[:, 0]], axis=1)
    return length / rest - 1.0


def _at(values: np.ndarray, idx: np.ndarray, largest: bool) -> tuple[float, int | None]:
    """The largest (least) finite value among ``idx`` and its first index (NaN, None:
    none)."""
    known = idx[np.isfinite(values[idx])]
    if known.size == 0:
        return math.nan, None
    k = first_extreme(values, known, largest)  # ties at round-off: the first, as the summary
    v = values[known]
    return float(v.max() if largest else v.min()), int(k)


def cable_table(states: States, g: Groups, s: State, peaks: bool) -> Table:
    """Per cable: its edges, largest and least tension and their edges, the largest
    utilisation and its edge, the slack length (rest length of its slack edges) and
    slack edges; with ``peaks`` the largest peak tension over the run and its time."""
    columns = [
        "cable",
        "edges",
        "max tension [N]",
        "max tension edge",
        "least tension [N]",
        "least tension edge",
        "max utilisation [-]",
        "max utilisation edge",
        "slack length [m]",
        "slack edges",
    ]
    if peaks:
        columns += ["peak tension [N]", "peak tension t [s]", "peak utilisation [-]"]
    t = s.get("tension")
    m = len(states.mesh.edges)
    t = np.full(m, np.nan) if t is None else t
    use = s.get("utilisation")
    use = np.full(m, np.nan) if use is None else use
    eps = _strain(states, s.x)
    slack = np.zeros(m, bool) if eps is None else (eps < 0) & (t >= 0)
    rest = states.mesh.rest_length
    rows = []
    for k, name in enumerate(g.names):
        idx = g.edges(k)
        if idx.size == 0:
            continue
        top, top_e = _at(t, idx, True)
        low, low_e = _at(t, idx, False)
        u, u_e = _at(use, idx, True)
        loose = idx[slack[idx]]
        length = float(rest[loose].sum()) if rest is not None else math.nan
        row = [name, int(idx.size), top, top_e, low, low_e, u, u_e, length, int(loose.size)]
        if peaks:
            p, p_e = _at(s.arrays["peak_tension"], idx, True)
            row += [p, _when(s, "peak_tension_time", p_e)]
            pu = s.get("peak_utilisation")
            row += [_at(pu, idx, True)[0] if pu is not None else math.nan]
        rows.append(row)
    note = (
        "tension: the axial force [N], negative in a strut in compression; utilisation: "
        "design tension / design resistance (EN 1993-1-11 with the case's [design] "
        "factors), n/a where the material gives no breaking_load; slack length: the rest "
        "length of the cable's slack edges"
    )
    return Table("cables", "Cables", tuple(columns), rows, note)


def support_table(states: States, g: Groups, s: State) -> Table:
    """The reaction [N] of each support set (the sum over its nodes) and of each
    supported node (up to MAX_NODE_ROWS, the largest first beyond that)."""
    columns: tuple[str, ...] = ("support", "nodes", "Rx [N]", "Ry [N]", "Rz [N]", "|R| [N]")
    r = s.get("reaction")
    su = s.get("support_utilisation")
    fixed = states.mesh.fixed
    rows: list[list] = []
    note = "the force each support exerts on the net"
    if r is None or fixed is None:
        return Table("supports", "Support reactions", columns, rows, note + " (not stored)")
    if su is not None:
        columns += ("max utilisation [-]",)
        note += "; utilisation: |R| / capacity of [[design.support]], a set's largest node's"

    def use(nodes) -> list:
        return [] if su is None else [_at(su, np.atleast_1d(nodes), True)[0]]

    for name, nodes in g.supports.items():
        rows.append([name, int(nodes.size), *_force(r[nodes].sum(axis=0)), *use(nodes)])
    pinned = np.flatnonzero(fixed[: len(r)])
    size = np.linalg.norm(r[pinned], axis=1)
    shown = pinned
    if pinned.size > MAX_NODE_ROWS:
        shown = np.sort(pinned[np.argsort(-size, kind="stable")[:MAX_NODE_ROWS]])
        note += f"; the {MAX_NODE_ROWS} largest of {pinned.size} supported nodes"
    single = _one_node_sets(g)
    for i in shown:
        if int(i) not in single:  # a set of this node alone has its row already
            rows.append([_node(g, int(i)), 1, *_force(r[i]), *use(i)])
    rows.append(["all supports", int(pinned.size), *_force(r[pinned].sum(axis=0)), *use(pinned)])
    return Table("supports", "Support reactions", columns, rows, note)


def _one_node_sets(g: Groups) -> set[int]:
    """The nodes that are a support set of their own."""
    return {int(v[0]) for v in g.supports.values() if np.size(v) == 1}


def _node(g: Groups, i: int) -> str:
    """ "node I", with the support sets it belongs to."""
    within = [k for k, v in g.supports.items() if i in v]
    return f"node {i}" + (f" ({', '.join(within)})" if within else "")


def _force(f: np.ndarray) -> list[float]:
    f = np.asarray(f, dtype=np.float64)
    return [float(f[0]), float(f[1]), float(f[2]), float(np.linalg.norm(f))]


def _when(s: State, name: str, k: int | None) -> float:
    """The time of a peak at element ``k`` of the file's ``name`` (NaN where the file
    keeps none)."""
    times = s.get(name)
    return float(times[k]) if times is not None and k is not None else math.nan


def displacement_table(states: States, g: Groups, s: State, peaks: bool) -> Table:
    """The largest displacement |x - X| [m] of the free nodes and of each node set with
    a free node, where, and its components; with ``peaks`` the largest over the run."""
    columns = ["nodes", "max displacement [m]", "node", "ux [m]", "uy [m]", "uz [m]"]
    if peaks:
        columns += ["peak displacement [m]", "peak node", "peak t [s]"]
    X = states.mesh.nodes
    u = s.x - X
    size = np.linalg.norm(u, axis=1)
    fixed = states.mesh.fixed
    free = np.ones(len(X), bool) if fixed is None else ~fixed
    parts = {"all free nodes": np.flatnonzero(free)}
    parts.update({k: v[free[v]] for k, v in g.sets.items() if free[v].any()})
    rows = []
    for name, idx in parts.items():
        if idx.size == 0:
            continue
        value, k = _at(size, idx, True)
        row = [name, value, k, *(float(c) for c in (u[k] if k is not None else np.full(3, np.nan)))]
        if peaks:  # n/a where the file keeps no peak displacement
            peak = s.get("peak_displacement")
            p, pk = _at(peak, idx, True) if peak is not None else (math.nan, None)
            row += [p, pk, _when(s, "peak_displacement_time", pk)]
        rows.append(row)
    return Table("displacements", "Displacements", tuple(columns), rows, "")


def balance_table(s: State) -> Table:
    """The applied loads' resultant (the /result attribute) against the reactions'
    and contact forces' (sums of the file's arrays) and what is left [N]."""
    columns = ("forces", "Fx [N]", "Fy [N]", "Fz [N]")
    a = s.attrs
    applied = np.array([float(a.get(f"applied_resultant_{c}", math.nan)) for c in "xyz"])
    parts = {"applied loads": applied}
    for key, label in (("reaction", "reactions"), ("contact_force", "contact")):
        f = s.get(key)
        parts[label] = np.zeros(3) if f is None else f.sum(axis=0)
    total = np.sum(list(parts.values()), axis=0)
    rows = [[k, *(float(c) for c in v)] for k, v in parts.items()]
    rows.append(["sum (0 at equilibrium)", *(float(c) for c in total)])
    return Table("balance", "Loads against reactions and contact", columns, rows, "")


# --------------------------------------------------------------------------- envelope


def _envelope_section(states: States, g: Groups) -> Section:
    cases = [s for s in states.states if s.kind != "base"]
    verdict = {
        "over": ", ".join(states.envelope_cases) or ", ".join(s.name for s in cases),
        "converged": "yes" if all(s.attrs.get("converged") for s in cases) else "no",
    }
    tables = [envelope_cables(states, g), envelope_supports(states, g, cases)]
    tables.append(envelope_displacements(states, g))
    return Section("envelope", "envelope", verdict, [], tables)


def _case_name(states: States, key: str, edge: int | None) -> str:
    idx = states.envelope.get(f"{key}_case")
    if idx is None or edge is None or not 0 <= int(idx[edge]) < len(states.envelope_cases):
        return ""
    return states.envelope_cases[int(idx[edge])]


def envelope_cables(states: States, g: Groups) -> Table:
    """Per cable over the cases: the largest tension, least tension and largest
    utilisation (/envelope), their edges and the cases that give them."""
    env = states.envelope
    columns = (
        "cable",
        "max tension [N]",
        "max tension edge",
        "max tension case",
        "least tension [N]",
        "least tension edge",
        "least tension case",
        "max utilisation [-]",
        "max utilisation edge",
        "max utilisation case",
    )
    m = len(states.mesh.edges)
    rows = []
    for k, name in enumerate(g.names):
        idx = g.edges(k)
        if idx.size == 0:
            continue
        row: list = [name]
        for key, largest in (("tension_max", True), ("tension_min", False)):
            value, e = _at(env.get(key, np.full(m, np.nan)), idx, largest)
            row += [value, e, _case_name(states, key, e)]
        u, e = _at(env.get("utilisation_max", np.full(m, np.nan)), idx, True)
        row += [u, e, _case_name(states, "utilisation_max", e)]
        rows.append(row)
    return Table("envelope_cables", "Cables over the cases", columns, rows, "")


def envelope_supports(states: States, g: Groups, cases: list[State]) -> Table:
    """Per support set and supported node the largest reaction over the cases and the
    case that gives it (from each case's reactions)."""
    columns: tuple[str, ...] = ("support", "max |R| [N]", "case", "Rx [N]", "Ry [N]", "Rz [N]")
    su = states.envelope.get("support_utilisation_max")
    if su is not None:
        columns += ("max utilisation [-]", "utilisation case")
    fixed = states.mesh.fixed
    with_r = [s for s in cases if s.get("reaction") is not None]
    rows: list[list] = []
    if fixed is None or not with_r:
        return Table("envelope_supports", "Support reactions over the cases", columns, rows)
    parts = dict(g.supports)
    pinned = np.flatnonzero(fixed)
    if pinned.size <= MAX_NODE_ROWS:
        single = _one_node_sets(g)
        parts.update({_node(g, int(i)): np.array([i]) for i in pinned if int(i) not in single})
    for name, nodes in parts.items():
        forces = np.array([s.arrays["reaction"][nodes].sum(axis=0) for s in with_r])
        k = int(np.argmax(np.linalg.norm(forces, axis=1)))
        row = [name, float(np.linalg.norm(forces[k])), with_r[k].name, *map(float, forces[k])]
        if su is not None:
            u, i = _at(su, nodes, True)
            row += [u, _case_name(states, "support_utilisation_max", i)]
        rows.append(row)
    return Table("envelope_supports", "Support reactions over the cases", columns, rows)


def envelope_displacements(states: States, g: Groups) -> Table:
    """The largest displacement over the cases (/envelope) of the free nodes and of
    each node set, where and in which case."""
    columns = ("nodes", "max displacement [m]", "node", "case")
    d = states.envelope.get("displacement_max")
    fixed = states.mesh.fixed
    rows: list[list] = []
    if d is None:
        return Table("envelope_displacements", "Displacements over the cases", columns, rows)
    free = np.ones(len(d), bool) if fixed is None else ~fixed
    parts = {"all free nodes": np.flatnonzero(free)}
    parts.update({k: v[free[v]] for k, v in g.sets.items() if free[v].any()})
    for name, idx in parts.items():
        value, k = _at(d, idx, True)
        rows.append([name, value, k, _case_name(states, "displacement_max", k)])
    return Table("envelope_displacements", "Displacements over the cases", columns, rows)
