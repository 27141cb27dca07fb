"""The numbers an engineer designs with, from one state (and the run's peaks): the one
source of the run's printed summary, the /result attributes and the sweep table's columns.

``summarize`` returns a flat dict of plain floats, ints and 3-vectors (lists), SI units:

- ``max_displacement`` [m], ``max_displacement_node``, ``max_displacement_vector`` (3,):
  the largest |x - X| of a free node of the net (not a support, not a body's centre);
- ``probe``, ``probe_displacement`` (3,) [m], ``delta`` (its z-displacement, positive
  down, the paper's) and ``probe_auto`` (True: no probe was named, and for a graph the
  probe is the free node that moves most);
- ``max_tension`` [N] (0 when no edge pulls) and ``max_tension_edge`` (-1: none);
  ``max_compression`` [N] (> 0: the largest compression of a strut, an edge that is not
  tension-only) and ``max_compression_edge``; ``compressed_edges`` (struts in compression);
- ``max_strain`` (|e|/l0 - 1, 0 when none is stretched) and ``max_strain_edge``;
- ``slack_edges``: tension-only edges shorter than their rest length (slack);
- with rods: ``max_bending_moment`` [N m], its node, ``max_curvature`` [1/m] there
  (``bending_moments``); twisted: ``max_twisting_moment`` [N m] (the largest |M|), its edge;
- ``reaction_resultant`` (3,) [N], ``max_reaction`` [N] and ``max_reaction_node``; where
  a support holds a rod end's direction ``max_reaction_moment`` [N m] (the largest |M| of
  ``/result/reaction_moment``) and ``max_reaction_moment_node``;
- ``contact_resultant`` (3,) [N] (over every node: a free body's or a ball's contact
  with the net cancels there, what is left is the fixed obstacles'), ``max_contact`` [N]
  and ``max_contact_node``, ``contact_nodes`` (the net's nodes touched: not a body's);
  with balls or free bodies ``contact_on_net`` (3,) [N], the resultant on the net's own
  nodes (a body resting on the net: its weight);
- with peaks: ``peak_tension`` [N], ``peak_tension_edge``, ``peak_tension_time`` (s, or
  the load factor of a static run), ``peak_displacement`` [m], ``peak_displacement_node``,
  ``peak_displacement_time``.

``summarize_result`` adds, where the scene's materials give a breaking load
(``catenet.model.design``), ``max_utilisation`` (design tension / design resistance),
``max_utilisation_edge`` and, with cables, ``max_utilisation_cable``; with peaks also
``peak_utilisation``, ``peak_utilisation_edge`` and ``peak_utilisation_time``; where
supports have a capacity, ``max_support_utilisation`` (|R| / capacity) and its node.

``cable_summary`` gives the same per cable of a graph with cables (with peaks: each
cable's ``peak_tension``, its time and edge; with utilisations: ``max_utilisation``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from catenet.model import measures, rodends
from catenet.model.joints import Joints, joint_bending
from catenet.model.net import Loads, Net
from catenet.model.rods import Rods, bending_moment, cable_bending
from catenet.model.twist import Twists, twisting_moment

if TYPE_CHECKING:  # a scene and its solved state, from the layers above
    from catenet.scene.scene import Scene
    from catenet.solver.result import Result

# the summary's scalars a sweep table carries (``flat`` names: a vector's components)
COLUMNS = (
    "max_displacement",
    "max_displacement_node",
    "max_tension",
    "max_tension_edge",
    "max_compression",
    "max_strain_edge",
    "max_reaction",
    "max_reaction_node",
    "reaction_resultant_x",
    "reaction_resultant_y",
    "reaction_resultant_z",
    "contact_resultant_x",
    "contact_resultant_y",
    "contact_resultant_z",
    "peak_tension",
    "peak_tension_time",
    "peak_displacement",
    "probe",
)


def flat(numbers: dict) -> dict:
    """The summary's scalars, each 3-vector ``name`` split into ``name_x``, ``name_y``,
    ``name_z`` (HDF5 attributes and table columns hold scalars); ``cables`` left out."""
    out = {}
    for key, value in numbers.items():
        if key == "cables":
            continue
        if isinstance(value, list):
            out.update({f"{key}_{a}": float(c) for a, c in zip("xyz", value, strict=True)})
        else:
            out[key] = value
    return out


def free_net_nodes(net: Net) -> np.ndarray:
    """The free nodes of the net itself (a body's centre is no node of the net)."""
    free = ~np.asarray(net.fixed, dtype=bool)
    free[net.n_net :] = False
    return np.flatnonzero(free)


def displacement(net: Net, x: np.ndarray) -> np.ndarray:
    """|x - X| of every node [m] from the reference positions X."""
    d = np.asarray(x) - net.nodes
    return np.sqrt(np.einsum("ij,ij->i", d, d))


def most_moved(net: Net, x: np.ndarray) -> int:
    """The free node of the net that moves most (-1 when none is free)."""
    free = free_net_nodes(net)
    if free.size == 0:
        return -1
    return int(free[np.argmax(displacement(net, x)[free])])


TIE = 1e-7  # values this close (relative) to the extreme tie (a solve's tolerance: mirror
# edges of a symmetric hypar came out 2e-9 apart): the first of them is named


def first_extreme(values: np.ndarray, idx: np.ndarray, largest: bool = True) -> int:
    """The first index of ``idx`` whose value is the largest (smallest) of them, values
    within TIE of it counted as equal: symmetric members that differ by the solve's
    convergence or round-off (two guys of a mast) name the same one on every machine and
    in every run."""
    v = np.asarray(values, dtype=np.float64)[idx]
    best = float(np.max(v) if largest else np.min(v))
    slack = TIE * abs(best)
    near = v >= best - slack if largest else v <= best + slack
    near |= v == best  # an infinite extreme (inf - inf is NaN): its first member
    return int(idx[np.flatnonzero(near)[0]])


def _largest(values: np.ndarray, where: np.ndarray | None = None) -> tuple[int, float]:
    """The index ``_argmax`` names and the largest value itself (0.0 when there is none):
    the value is the true extreme, the index the first member at it to round-off."""
    k = _argmax(values, where)
    if k < 0:
        return k, 0.0
    idx = np.arange(len(values)) if where is None else np.flatnonzero(where)
    return k, float(np.max(np.asarray(values, dtype=np.float64)[idx]))


def _argmax(values: np.ndarray, where: np.ndarray | None = None) -> int:
    """Index of the largest value (among ``where``; ties at round-off: the first), -1
    when there is none."""
    idx = np.arange(len(values)) if where is None else np.flatnonzero(where)
    if idx.size == 0:
        return -1
    return first_extreme(values, idx)


def _vector(v) -> list[float]:
    return [float(c) for c in np.asarray(v, dtype=np.float64).reshape(3)]


def summarize(
    net: Net,
    x: np.ndarray,
    tension: np.ndarray,
    reaction: np.ndarray | None,
    contact: np.ndarray | None,
    probe: int,
    *,
    probe_auto: bool = False,
    peaks=None,
) -> dict:
    """The summary of state x (see the module docstring); ``peaks`` a
    ``catenet.model.peaks.Peaks`` (or its ``arrays()``) of the run, or None."""
    x = np.asarray(x, dtype=np.float64)
    tension = np.asarray(tension, dtype=np.float64)
    out: dict = {}
    u = displacement(net, x)
    free = np.zeros(net.n_nodes, bool)
    free[free_net_nodes(net)] = True
    k, out["max_displacement"] = _largest(u, free)
    out["max_displacement_node"] = k
    out["max_displacement_vector"] = _vector(x[k] - net.nodes[k] if k >= 0 else np.zeros(3))
    out["probe"] = int(probe)
    out["probe_auto"] = bool(probe_auto)
    out["probe_displacement"] = _vector(x[probe] - net.nodes[probe])
    out["delta"] = measures.deflection(net.nodes, x, int(probe))
    only = np.asarray(net.law.tension_only, dtype=bool)
    e, out["max_tension"] = _largest(tension, tension > 0)
    out["max_tension_edge"] = e
    strut = (~only) & (tension < 0)
    e, out["max_compression"] = _largest(-tension, strut)
    out["max_compression_edge"] = e
    out["compressed_edges"] = int(np.count_nonzero(strut))
    eps = measures.strain(net, x)
    e, out["max_strain"] = _largest(eps, eps > 0)
    out["max_strain_edge"] = e
    out["slack_edges"] = int(np.count_nonzero(only & (eps < 0)))
    out.update(_forces("reaction", reaction, x, net.supported))
    own = np.arange(net.n_nodes) < net.n_net  # not a ball's or a free body's own nodes
    out.update(_forces("contact", contact, x, own))
    if net.bodies and contact is not None:  # what bodies and obstacles put on the net
        out["contact_on_net"] = _vector(np.asarray(contact, dtype=np.float64)[own].sum(axis=0))
    if peaks is not None:
        out.update(_peaks(peaks if isinstance(peaks, dict) else peaks.arrays(), free))
    return out


def _forces(name: str, force, x, where) -> dict:
    """Resultant, largest and its node of a nodal force field (N, 3) (None: zero)."""
    f = np.zeros_like(x) if force is None else np.asarray(force, dtype=np.float64)
    size = np.linalg.norm(f, axis=1)
    k, largest = _largest(size, (size > 0) if where is None else (np.asarray(where) & (size > 0)))
    out = {
        f"{name}_resultant": _vector(f.sum(axis=0)),
        f"max_{name}": largest,
        f"max_{name}_node": k,
    }
    if name == "contact":  # the net's nodes a contact touches
        out["contact_nodes"] = int(np.count_nonzero((size > 0) & np.asarray(where)))
    return out


def _peaks(p: dict, free: np.ndarray) -> dict:
    """The run's largest tension and displacement over time, where and when."""
    top, when = p["peak_tension"], p["peak_tension_time"]
    e, top_value = _largest(top, np.isfinite(top))
    u, u_when = p["peak_displacement"], p["peak_displacement_time"]
    k, u_value = _largest(u, free & np.isfinite(u))
    return {
        "peak_tension": max(top_value, 0.0),
        "peak_tension_edge": e if e >= 0 and top[e] > 0 else -1,
        "peak_tension_time": float(when[e]) if e >= 0 and top[e] > 0 else float("nan"),
        "peak_displacement": u_value,
        "peak_displacement_node": k,
        "peak_displacement_time": float(u_when[k]) if k >= 0 else float("nan"),
    }


def cable_summary(
    net: Net, x, tension, edge_cable: np.ndarray, names, peaks=None, utilisation=None
) -> dict[str, dict]:
    """Per cable (``edge_cable`` (M,): each edge's cable index, -1: none): ``max_tension``
    (the largest axial force, negative for a strut in compression: cable_max_tension),
    ``max_compression`` (>= 0), ``slack_fraction`` (share of its unstressed length slack),
    ``slack_edges`` (tension-only edges slack), ``strut`` (no edge of it is tension-only).
    With the run's ``peaks`` (a ``Peaks`` or its ``arrays()``) also ``peak_tension``: the
    largest of its edges' peak tensions over the run (``/result/cable_peak_tension``),
    ``peak_tension_time`` and ``peak_tension_edge``. With ``utilisation`` (M,) per edge
    (NaN: not known) also ``max_utilisation``: the largest of its edges' (NaN: none known)."""
    tension = np.asarray(tension, dtype=np.float64)
    n = len(names)
    top, slack = measures.cable_stats(net, x, tension, edge_cable, n)
    on = edge_cable >= 0
    c = edge_cable[on]
    only = np.asarray(net.law.tension_only, dtype=bool)
    loose = (measures.strain(net, x) < 0.0) & only
    count = np.bincount(c, weights=loose[on].astype(float), minlength=n)
    squeeze = np.zeros(n)
    np.maximum.at(squeeze, c, np.where(only[on], 0.0, -tension[on]))
    ties = np.bincount(c, weights=only[on].astype(float), minlength=n)
    out = {
        str(name): {
            "max_tension": float(top[k]),
            "slack_fraction": float(slack[k]),
            "max_compression": float(squeeze[k]),
            "slack_edges": int(count[k]),
            "strut": bool(ties[k] == 0),
        }
        for k, name in enumerate(names)
    }
    if peaks is not None:
        arrays = peaks if isinstance(peaks, dict) else peaks.arrays()
        for row, peak in zip(out.values(), _cable_peaks(arrays, edge_cable, n), strict=True):
            row.update(peak)
    if utilisation is not None:
        u = np.asarray(utilisation, dtype=np.float64)
        top_u = np.full(n, -np.inf)
        known = on & np.isfinite(u)
        np.maximum.at(top_u, edge_cable[known], u[known])
        for row, value in zip(out.values(), top_u, strict=True):
            row["max_utilisation"] = float(value) if np.isfinite(value) else float("nan")
    return out


def _cable_peaks(p: dict, edge_cable: np.ndarray, n: int) -> list[dict]:
    """Per cable the largest peak tension of its edges over the run, its edge and time
    (nan and edge -1 for a cable without edges)."""
    top, when = p["peak_tension"], p["peak_tension_time"]
    out = [
        {"peak_tension": float("nan"), "peak_tension_time": float("nan"), "peak_tension_edge": -1}
        for _ in range(n)
    ]
    idx = np.flatnonzero((edge_cable >= 0) & np.isfinite(top))
    # each cable's edges, the highest peak first: the first of each cable is its peak
    order = idx[np.lexsort((-top[idx], edge_cable[idx]))]
    cables, first = np.unique(edge_cable[order], return_index=True)
    for k, e in zip(cables, order[first], strict=True):
        out[k] = {
            "peak_tension": float(top[e]),
            "peak_tension_time": float(when[e]),
            "peak_tension_edge": int(e),
        }
    return out


def probe_of(scene, x: np.ndarray) -> tuple[int, bool]:
    """The probe node of a scene's state x and whether it was chosen for it: the scene's
    (``output.probe``, else its geometry's), or with ``scene.probe_auto`` (a graph without
    ``output.probe``) the free node that moves most."""
    if scene.probe_auto:
        k = most_moved(scene.net, x)
        if k >= 0:
            return k, True
    return int(scene.probe), False


def summarize_result(scene: Scene, res: Result, loads: Loads | None = None) -> dict:
    """``summarize`` of a solver Result of a scene (net, probe, cables), with its peaks;
    per cable under ``cables`` when the scene has cables. Also ``applied_resultant`` (3,)
    [N]: the resultant of the loads acting in the state (``loads``, default the
    scene's, at the result's load factor or time), and for a net that is one cable its
    ``sag_normal``, ``sag_vertical``, ``sag_rise`` [m] and ``sag_node``
    (``catenet.model.measures.sag``; not for a frame whose rods meet at rigid joints: its
    chord runs across the corners it is drawn with)."""
    probe, auto = probe_of(scene, res.x)
    out = summarize(
        scene.net,
        res.x,
        res.tension,
        res.reaction,
        res.contact_force,
        probe,
        probe_auto=auto,
        peaks=res.peaks,
    )
    out["applied_resultant"] = _applied(scene, res, loads)
    bent = bending_moments(scene, res.x)  # once: the summary's largest and each cable's
    out.update(_bending(bent))
    out.update(_twisting(scene, res.x))
    out.update(_support_moment(scene, res.x))
    framed = any(isinstance(getattr(t, "joints", None), Joints) for t in scene.terms)
    chain = None if scene.net.bodies or framed else measures.sag(scene.net, res.x)
    if chain is not None:
        out["sag_normal"] = chain["normal"]
        out["sag_vertical"] = chain["vertical"]
        out["sag_rise"] = chain["rise"]
        out["sag_node"] = chain["node"]
    cables = scene.cables
    design = scene.design if scene.design is not None and scene.design.given else None
    use = None if design is None else design.utilisation(res.tension)
    if use is not None:
        out.update(_utilisation(scene, use, design, res.peaks))
    anchored = scene.design is not None and scene.design.anchored and res.reaction is not None
    if anchored:  # supports with a capacity: the largest |R| / capacity
        k, value = _largest_known(scene.design.support_utilisation(res.reaction))
        out["max_support_utilisation"], out["max_support_utilisation_node"] = value, k
    if cables is not None:  # which cable the largest displacement belongs to
        out["max_displacement_cable"] = _cable_of(scene.net, cables, out["max_displacement_node"])
        out["cables"] = cable_summary(
            scene.net,
            res.x,
            res.tension,
            cables.edge,
            cables.names,
            peaks=res.peaks,
            utilisation=use,
        )
        _rod_cables(scene, bent, out["cables"])
    return out


def _rod_cables(scene: Scene, found, rows: dict) -> None:
    """Marks each cable whose edges bend (``rod``) in its summary ``rows`` and gives it
    ``max_bending_moment`` [N m] (``catenet.model.rods.cable_bending``, from ``found``:
    ``bending_moments``' moment and curvature per node); none without rods."""
    rods = scene_rods(scene)
    if rods is None or found is None:
        return
    pairs = [
        np.column_stack([np.repeat(j.node, np.diff(j.start)), j.other])
        for t in scene.terms
        if isinstance(j := getattr(t, "joints", None), Joints)
    ]
    joined = np.concatenate(pairs) if pairs else None
    edges, cable = scene.net.edges, scene.cables.edge
    rod, top = cable_bending(rods, edges, cable, found[0], len(rows), joined)
    for k, row in enumerate(rows.values()):
        row["rod"] = bool(rod[k])
        if rod[k]:
            row["max_bending_moment"] = float(top[k])


def scene_rods(scene: Scene) -> Rods | None:
    """The rods of a scene's ``Bending`` term (None: nothing bends)."""
    for term in scene.terms:
        rods = getattr(term, "rods", None)
        if isinstance(rods, Rods):
            return rods
    return None


def bending_moments(scene: Scene, x: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Per node (N,), the bending moment |M| [N m] and the curvature |kappa| [1/m] of the
    scene's rods (``catenet.model.rods.bending_moment``; a 6x6 support's at its rod end,
    ``catenet.model.rodends.end_bending``), at a rigid joint its members' largest
    (``catenet.model.joints.joint_bending``); None: nothing bends."""
    rods = scene_rods(scene)
    if rods is None:
        return None
    x = np.asarray(x, dtype=np.float64)
    moment, kappa = bending_moment(rods, x, scene.net.n_nodes)
    if (springs := scene.net.springs) is not None and springs.ends is not None:
        rodends.end_bending(springs.ends, rods, scene.net.nodes, x, moment, kappa)  # 6x6 ends
    twist = _twist_term(scene)
    carried = None
    for term in scene.terms:
        joints = getattr(term, "joints", None)
        if isinstance(joints, Joints):
            if carried is None and twist is not None and twist.twists.partner.max() >= 0:
                carried = np.zeros_like(x)  # the twist's forces: torques into partners
                twist.gradient(x, carried)
            joint_bending(joints, x, moment, kappa, carried)
    return moment, kappa


def _bending(found) -> dict:
    """The largest bending moment, its node and the curvature there, of ``found``
    (``bending_moments``'; none without rods)."""
    if found is None:
        return {}
    moment, kappa = found
    node = int(np.argmax(moment))
    return {
        "max_bending_moment": float(moment[node]),
        "max_bending_moment_node": node,
        "max_curvature": float(kappa[node]),
    }


def _support_moment(scene: Scene, x: np.ndarray) -> dict:
    """The largest moment a support exerts on a rod end and its node (none where no
    support holds a rod end's direction: ``support_moments``)."""
    moments = support_moments(scene, x)
    if moments is None:
        return {}
    size = np.linalg.norm(moments, axis=1)
    node = int(np.argmax(size))
    return {"max_reaction_moment": float(size[node]), "max_reaction_moment_node": node}


def _twist_term(scene: Scene):
    """The scene's ``Twist`` term (None: no rod twists)."""
    for term in scene.terms:
        if isinstance(getattr(term, "twists", None), Twists):
            return term
    return None


def twisting_moments(scene: Scene, x: np.ndarray) -> np.ndarray | None:
    """Per edge (M,), the signed twisting moment [N m] at x (> 0: a right-handed twist; 0
    where no rod twists), from the scene's ``Twist`` term (None: no rod twists)."""
    term = _twist_term(scene)
    if term is None:
        return None
    moment = term.moments(np.asarray(x, dtype=np.float64))
    return twisting_moment(term.twists, moment, scene.net.n_edges)


def support_moments(scene: Scene, x: np.ndarray) -> np.ndarray | None:
    """(N, 3) the moment [N m] each support exerts on its rod at the rod's end node: a
    clamp's, a rotational spring's or a 6x6 spring's turn of the end's direction
    (``catenet.model.rodends.support_moments``) and a clamp's torque about the rod's axis
    where it holds a twisted rod (``Twist.end_moments``); None where no support holds a
    rod end's direction."""
    x = np.asarray(x, dtype=np.float64)
    out = rodends.support_moments(scene.net, scene_rods(scene), x)
    term = _twist_term(scene)
    if term is None:
        return out
    twists = term.twists  # clamped ends (rings and rigid joints: no support holds them)
    clamped = ~twists.closed[:, None] & (twists.partner < 0)
    if not clamped.any():
        return out
    torque = np.zeros_like(x)
    np.add.at(torque, twists.ends[clamped], term.end_moments(x)[clamped])
    return torque if out is None else out + torque


def _twisting(scene: Scene, x: np.ndarray) -> dict:
    """The largest twisting moment |M| and its edge (none without twisted rods)."""
    moment = twisting_moments(scene, x)
    if moment is None:
        return {}
    edge = int(np.argmax(np.abs(moment)))
    return {"max_twisting_moment": float(abs(moment[edge])), "max_twisting_moment_edge": edge}


def _utilisation(scene: Scene, use: np.ndarray, design, peaks) -> dict:
    """The largest utilisation, its edge and cable ("" without one); with the run's
    peaks, the largest over the run (from each edge's peak tension), edge and time."""
    k, value = _largest_known(use)
    out: dict = {"max_utilisation": value, "max_utilisation_edge": k}
    if scene.cables is not None:
        out["max_utilisation_cable"] = _edge_cable(scene.cables, k)
    if peaks is not None:
        arrays = peaks if isinstance(peaks, dict) else peaks.arrays()
        top = design.utilisation(np.nan_to_num(arrays["peak_tension"], nan=0.0))
        e, peak = _largest_known(top)
        out["peak_utilisation"] = peak
        out["peak_utilisation_edge"] = e
        when = arrays["peak_tension_time"]
        out["peak_utilisation_time"] = float(when[e]) if e >= 0 else float("nan")
    return out


def _largest_known(values: np.ndarray) -> tuple[int, float]:
    """The first edge of the largest finite value and the value ((-1, NaN): none)."""
    known = np.flatnonzero(np.isfinite(values))
    if known.size == 0:
        return -1, float("nan")
    k = first_extreme(values, known)
    return k, float(np.max(values[known]))


def _edge_cable(cables, edge: int) -> str:
    """The name of the cable of ``edge`` ("" for none)."""
    if edge < 0:
        return ""
    c = int(np.asarray(cables.edge)[edge])
    return str(cables.names[c]) if c >= 0 else ""


def _applied(scene: Scene, res: Result, loads: Loads | None = None) -> list[float]:
    """The resultant of the applied loads in the state ``res`` [N] (a static state's at
    its load factor, a dynamic one's at its time)."""
    loads = scene.loads if loads is None else loads
    net = scene.net
    try:
        if res.v is not None:
            force = loads.external_force(net, time=float(res.time))
        else:  # a run's load factor (a Python solve's 0: its full load; a failure's own)
            factor = float(res.time)
            if factor == 0.0 and res.converged:
                factor = 1.0
            force = loads.external_force(net, factor)
    except (TypeError, ValueError):
        return [0.0, 0.0, 0.0]
    return _vector(np.asarray(force, dtype=np.float64).sum(axis=0))


def _cable_of(net: Net, cables, node: int) -> str:
    """The name of a cable with an edge at ``node`` ("" for none)."""
    if node < 0:
        return ""
    at = np.flatnonzero((net.edges == node).any(axis=1))
    named = [int(c) for c in np.asarray(cables.edge)[at] if c >= 0]
    return str(cables.names[min(named)]) if named else ""
