"""The lines ``catenet run`` prints after a run: the numbers of
``catenet.model.summary`` (the same as the /result attributes and the sweep columns), one
quantity a line; ``catenet run`` labels them in the case's ``units``
(``catenet.model.units.relabel``: the numbers are as the case wrote them, only the unit
names change)."""

from __future__ import annotations

import math

W = 12  # the label column


def vector(v) -> str:
    """A 3-vector as [x, y, z] with 4 significant digits (components below 1e-12 of the
    largest, round-off, as 0)."""
    v = [float(c) for c in v]
    big = max((abs(c) for c in v), default=0.0)
    return "[" + ", ".join(f"{c if abs(c) > 1e-12 * big else 0.0:.4g}" for c in v) + "]"


def _when(t: float, dynamic: bool | str) -> str:
    """When a peak happened: ``dynamic`` True (a time), False (a load factor) or "rest"
    (the pseudo-time of dynamic relaxation: the path to rest is not a physical motion)."""
    if not math.isfinite(t):
        return ""
    if dynamic == "rest":
        return f"pseudo-time t = {t:.4g} s of the relaxation, not a physical transient"
    return f"t = {t:.4g} s" if dynamic else f"load factor {t:.4g}"


def _more(peak: float, final: float) -> bool:
    """Whether a peak over the run is above the final value (beyond round-off)."""
    return peak > final + 1e-12 * max(abs(peak), abs(final))


def state_lines(
    s: dict, dynamic: bool | str, n_edges: int, warn_strain: bool = False, water: bool = False,
    settled: bool = False,
) -> list[str]:  # fmt: skip
    """The summary's lines for the numbers ``s`` (``summarize_result`` plus
    ``delta_over_L`` and ``size``) of a run (``dynamic``: times in s, else load factors;
    "rest": a run to rest, whose peaks are on the relaxation's pseudo-time path;
    ``water``: a case in water, whose contact forces include its buoyancy and drag;
    ``settled``: a dynamic run from its static equilibrium, whose displacements are
    still measured from the given geometry)."""
    probe = s["probe"]
    how = "the free node that moves most; " if s.get("probe_auto") else ""
    lines = [
        f"{'delta':<{W}} {s['delta']:.6g} m   delta/L = {s['delta_over_L']:.6g}   "
        f"(node {probe}, {how}L = {s['size']:.6g} m; z-displacement, positive down)",
        f"{'probe':<{W}} node {probe} moves {vector(s['probe_displacement'])} m",
    ]
    if "sag_normal" in s:  # a net that is one cable: its sag, as engineers measure it
        vertical, rise = s["sag_vertical"], s.get("sag_rise", 0.0)
        plumb = "" if vertical != vertical else f", {vertical:.6g} m vertical"
        if rise > 0.0:  # (nan: no plan) a cable lifted over its chord: how far above
            above = f", {rise:.6g} m above it"
            plumb = f"{plumb}{above}" if vertical > 0.0 else above
        lines.append(
            f"{'sag':<{W}} {s['sag_normal']:.6g} m normal to the chord{plumb} (largest at "
            f"node {s['sag_node']}; the chord between the cable's ends in this state)"
        )
    cable = s.get("max_displacement_cable")
    where = (
        f"at node {s['max_displacement_node']}{f' (cable {cable})' if cable else ''}: "
        f"{vector(s['max_displacement_vector'])} m"
        if s["max_displacement_node"] >= 0
        else "(no free node of the net)"
    )
    line = f"{'max displ.':<{W}} {s['max_displacement']:.6g} m {where}"
    peak = s.get("peak_displacement")
    if peak is not None and _more(peak, s["max_displacement"]):
        line += (
            f"; peak over the run {peak:.6g} m at node {s['peak_displacement_node']} "
            f"({_when(s['peak_displacement_time'], dynamic)})"
        )
    if settled:  # (a peak at a time the motion hardly moves the node: its sag's)
        line += " (from the given geometry: the run starts from its static equilibrium)"
    lines.append(line)
    edge = f" (edge {s['max_tension_edge']})" if s["max_tension_edge"] >= 0 else ""
    strain = f" (edge {s['max_strain_edge']})" if s["max_strain_edge"] >= 0 else ""
    lines.append(
        f"{'max tension':<{W}} {s['max_tension']:.6g} N{edge}   max strain "
        f"{s['max_strain']:.4g}{strain}"
        + (" (beyond the material law's range: see the warning or error)" if warn_strain else "")
    )
    peak = s.get("peak_tension")
    if peak is not None and _more(peak, s["max_tension"]):
        lines.append(
            f"{'peak tension':<{W}} {peak:.6g} N at {_when(s['peak_tension_time'], dynamic)} "
            f"(edge {s['peak_tension_edge']}); the final state's max tension is "
            f"{s['max_tension']:.6g} N"
        )
    if s.get("compressed_edges", 0):
        n = s["compressed_edges"]
        what = "edge" if "max_bending_moment" in s else "strut"  # rods: not all struts
        lines.append(
            f"{'compression':<{W}} {s['max_compression']:.6g} N (edge "
            f"{s['max_compression_edge']}; {n} {what}{'' if n == 1 else 's'} in compression)"
        )
    if "max_bending_moment" in s:
        lines.append(
            f"{'bending':<{W}} max moment {s['max_bending_moment']:.6g} N m at node "
            f"{s['max_bending_moment_node']} (curvature {s['max_curvature']:.6g} 1/m there)"
        )
    if "max_twisting_moment" in s:
        lines.append(
            f"{'twist':<{W}} max moment {s['max_twisting_moment']:.6g} N m on edge "
            f"{s['max_twisting_moment_edge']}"
        )
    lines.append(
        f"{'slack':<{W}} {s['slack_edges']} of {n_edges} edges (tension-only, shorter than "
        "their rest length)"
    )
    if "applied_resultant" in s:  # beside the reactions: what they balance
        lines.append(f"{'loads':<{W}} resultant {vector(s['applied_resultant'])} N (applied)")
    if s["max_reaction_node"] >= 0:
        lines.append(
            f"{'reactions':<{W}} resultant {vector(s['reaction_resultant'])} N; largest "
            f"{s['max_reaction']:.6g} N at node {s['max_reaction_node']}"
        )
    if s.get("max_reaction_moment", 0.0) > 0.0:  # labelled where no force line came
        label = "" if s["max_reaction_node"] >= 0 else "reactions"
        lines.append(
            f"{label:<{W}} moment largest {s['max_reaction_moment']:.6g} N m at node "
            f"{s['max_reaction_moment_node']} (a rod end's support)"
        )
    contact = _contact_line(s, water)
    if contact:
        lines.append(f"{'contact':<{W}} {contact}")
    for name, c in s.get("cables", {}).items():
        lines.append(cable_line(name, c, dynamic))
    return lines


def _contact_line(s: dict, water: bool) -> str:
    """The summary's contact line ("" for none): the resultant of the contact forces, the
    nodes of the net they touch and the largest. With balls or free bodies (their
    contact with the net cancels over all nodes) the resultant over all nodes is what
    the fixed obstacles hold (the ground under a crate), shown where it is not 0, and
    the resultant on the net's own nodes is shown beside the nodes touched."""
    total = s.get("contact_resultant", [0.0, 0.0, 0.0])
    touched = s.get("contact_nodes", 0)
    on_net = s.get("contact_on_net")
    where = (
        f" on {touched} nodes; largest {s['max_contact']:.6g} N at node {s['max_contact_node']}"
        + (" (obstacles, bodies and the water)" if water else "")
    )
    if on_net is None:
        return f"resultant {vector(total)} N{where}" if touched else ""
    scale = max(math.hypot(*on_net), s.get("max_contact", 0.0))
    held = math.hypot(*total) > 1e-6 * scale
    parts = [f"resultant {vector(total)} N held by the fixed obstacles"] if held else []
    if touched:
        parts.append(f"on the net {vector(on_net)} N{where}")
    return "; ".join(parts)


def _cable_peak(c: dict, dynamic: bool | str) -> str:
    """The cable line's ", peak P N at t = T s" when the cable's peak over the run is
    above its final max tension, else nothing."""
    peak = c.get("peak_tension")
    if peak is None or not math.isfinite(peak) or not _more(peak, c["max_tension"]):
        return ""
    when = _when(c.get("peak_tension_time", math.nan), dynamic)
    return f", peak {peak:.6g} N" + (f" at {when}" if when else "")


def cable_line(name: str, c: dict, dynamic: bool | str = True) -> str:
    """One cable's line: a tie's largest tension (and its peak over the run when that is
    higher) and slack share, a strut's compression."""
    bent = ""
    if c.get("rod"):  # edges that bend: the largest bending moment along it
        bent = f", largest bending moment {c['max_bending_moment']:.6g} N m"
    if c.get("strut"):
        kind = "a rod" if c.get("rod") else "a strut"
        if c["max_compression"] > 0:
            return f"{'cable':<{W}} {name}: {kind}, compression {c['max_compression']:.6g} N" + bent
        return (
            f"{'cable':<{W}} {name}: {kind}, max tension {c['max_tension']:.6g} N"
            + _cable_peak(c, dynamic)
            + bent
        )
    line = (
        f"{'cable':<{W}} {name}: max tension {c['max_tension']:.6g} N"
        f"{_cable_peak(c, dynamic)}, slack {100 * c['slack_fraction']:.3g} % of its length"
    )
    if math.isfinite(c.get("max_utilisation", math.nan)):
        line += f", utilisation {c['max_utilisation']:.4g}"
    if c.get("slack_edges"):
        line += f" ({c['slack_edges']} slack edges)"
    if c.get("max_compression", 0) > 0:
        line += f", compression {c['max_compression']:.6g} N in its struts"
    return line + bent


def utilisation_line(base: dict, cases: dict) -> str:
    """The largest utilisation (design tension / design resistance) of the base state
    ``base`` and the load cases ``cases`` (each the summary's numbers), with its edge,
    cable and case; or that no material gives a breaking load."""
    states = [("the base state", base), *cases.items()]
    known = [
        (s["max_utilisation"], name, s)
        for name, s in states
        if math.isfinite(s.get("max_utilisation", math.nan))
    ]
    if not known:
        return (
            f"{'utilisation':<{W}} not checked: no material gives breaking_load "
            "(material.breaking_load [N])"
        )
    value, name, s = max(known, key=lambda row: row[0])  # the first of equals
    cable = s.get("max_utilisation_cable", "")
    where = f"edge {s['max_utilisation_edge']}" + (f", cable {cable}" if cable else "")
    line = f"{'utilisation':<{W}} {value:.4g} ({where}; {name}"
    peak = s.get("peak_utilisation", math.nan)
    if math.isfinite(peak) and _more(peak, value):
        line += f"; peak over the run {peak:.4g} at t = {s['peak_utilisation_time']:.4g} s"
    verdict = "exceeds 1: the design resistance is exceeded" if value > 1.0 else "<= 1"
    return line + f"; F_Ed / F_Rd, EN 1993-1-11 with [design]'s factors: {verdict})"


def support_line(base: dict, cases: dict) -> str | None:
    """The largest support utilisation (|R| / capacity, [[design.support]]) of the base
    state and the cases, with its node and case; None where no support has a capacity."""
    states = [("the base state", base), *cases.items()]
    known = [
        (s["max_support_utilisation"], name, s)
        for name, s in states
        if math.isfinite(s.get("max_support_utilisation", math.nan))
    ]
    if not known:
        return None
    value, name, s = max(known, key=lambda row: row[0])
    verdict = "exceeds 1: a support's capacity is exceeded" if value > 1.0 else "<= 1"
    return (
        f"{'supports':<{W}} utilisation {value:.4g} (node {s['max_support_utilisation_node']}; "
        f"{name}; |R| / capacity of [[design.support]]: {verdict})"
    )


def envelope_lines(env: dict) -> list[str]:
    """The envelope over the load cases: its extremes and the cases that give them."""
    lines = []
    for key, what, where, unit in (
        ("tension_max", "largest tension", "edge", "N"),
        ("tension_min", "least tension", "edge", "N"),
        ("displacement_max", "largest displacement", "node", "m"),
        ("utilisation_max", "largest utilisation", "edge", ""),
        ("support_utilisation_max", "largest support utilisation", "node", ""),
    ):
        if key in env:
            e = env[key]
            value = e["value"]
            if key == "tension_min" and value < 0:  # a strut: its compression
                what, value = "largest compression", -value
            lines.append(
                f"{'envelope':<{W}} {what} {value:.6g}{' ' if unit else ''}{unit} "
                f"({where} {e['at']}, {e['case']})"
            )
    return lines


def cases_table(cases: dict, n_edges: int) -> list[str]:
    """One row per load case and combination (``result.report.cases``): the largest
    displacement and its node, the largest tension and its edge, the largest strut
    compression, the slack edges and the largest reaction, SI units."""
    util = any(math.isfinite(s.get("max_utilisation", math.nan)) for s in cases.values())
    head = (
        f"{'load case':<16} {'load z [N]':>11} {'horiz. [N]':>10} {'max displ. [m]':>14} "
        f"{'node':>6} "
        f"{'max tension [N]':>15} {'edge':>6} {'compr. [N]':>11} {'slack':>6} "
        f"{'max reaction [N]':>16}" + (f" {'utilisation':>11}" if util else "") + "  converged"
    )
    rows = [head]
    for name, s in cases.items():
        fx, fy, fz = s.get("applied_resultant", [0.0, 0.0, 0.0])
        use = f" {s.get('max_utilisation', math.nan):>11.4g}" if util else ""
        rows.append(
            f"{name:<16} {fz:>11.6g} {math.hypot(fx, fy):>10.6g} {s['max_displacement']:>14.6g} "
            f"{s['max_displacement_node']:>6} {s['max_tension']:>15.6g} "
            f"{s['max_tension_edge']:>6} {s['max_compression']:>11.6g} {s['slack_edges']:>6} "
            f"{s['max_reaction']:>16.6g}{use}  "
            + ("yes" if s["converged"] else f"no: {s['error']}")
        )
    rows.append(
        f"{'':<16} (load z, horiz.: the resultant of each case's applied loads, its z "
        "component (up +) and its horizontal size, the base state's included; slack: "
        f"edges of {n_edges}; each solved from the base state above; "
        "results in /cases/<name>/, envelopes in /envelope/)"
    )
    return rows


def line_lines(records) -> list[str]:
    """A line per named cable of a dynamic run, from its /history
    (``catenet.report.lines.line_records``): its tension range over the run, its snap
    events, its anchor's largest uplift and its touchdown's range."""
    out = []
    for r in records:
        text = (
            f"{'line':<12} {r.name}: tension {r.least:.6g} N (t = {r.least_t:.4g} s) to "
            f"{r.largest:.6g} N (t = {r.largest_t:.4g} s) over the run"
        )
        n = int(r.snaps.size)
        text += f", {n} snap event{'' if n == 1 else 's'}"
        if n:
            text += f" (first at t = {float(r.snaps[0]):.4g} s)"
        text += f", anchor uplift up to {r.uplift:.3g} deg"
        if math.isfinite(r.touchdown[0]) and r.touchdown[1] > 0.0:
            text += f", touchdown {r.touchdown[0]:.4g} m to {r.touchdown[1]:.4g} m from the anchor"
        elif math.isfinite(r.touchdown[0]):
            text += ", no touchdown (off the seabed from its anchor)"
        out.append(text)
    return out
