"""A published mooring system: case (v) of ``catenet validate``.

The OC3-Hywind spar's three catenary lines (Jonkman, "Definition of the Floating System
for Phase IV of OC3", NREL/TP-500-47535, 2010, Table 5-1): water depth 320 m, fairleads
70 m below the still water at 5.2 m from the centreline, anchors at 853.87 m, lines at
180, 60 and 300 degrees, unstretched length 902.2 m, weight in water 698.094 N/m,
EA = 384.243 MN, a frictionless seabed. Its Eq. (5-3) gives the mooring system's
linearised restoring at the undisplaced platform, about the still-water centreline:
K11 = 41 180 N/m (surge), K33 = 11 940 N/m (heave), K66 = 11 560 000 N m/rad (yaw, the
lines alone: the crowfoot's extra yaw spring is apart).

catenet solves the three lines as written in a case (``[[geometry.cable]]`` from anchor
to fairlead with their rest lengths, the seabed a ``plane`` obstacle, gravity on the
weight in water), with the fairleads where the platform puts them, moved by +-d along
a surge, a heave and a yaw; each stiffness is the central difference of the fairleads'
total force (or moment about the centreline) over 2 d. The published numbers have four
significant digits; the discrete line (lumped weights) converges to the elastic
catenary at second order in the edge length (its fairlead tensions against
``seabed_catenary``: information rows). Tolerance 1e-3 at 150 edges a line.

Nothing here prints; the rows are plain dicts of ``catenet.validate.table.Row``'s
fields.
"""

from __future__ import annotations

import math

import numpy as np

DEPTH = 320.0  # m
FAIRLEAD_DEPTH = 70.0  # m below the still water
FAIRLEAD_RADIUS = 5.2  # m
ANCHOR_RADIUS = 853.87  # m
HEADINGS = (180.0, 60.0, 300.0)  # deg
LENGTH = 902.2  # m, unstretched
WEIGHT = 698.094  # N/m in water
EA = 384.243e6  # N
G = 9.81  # m/s^2: the weight in water is given as a line density under it
PUBLISHED = {  # Jonkman (2010), Eq. (5-3)
    "K11 surge [N/m]": 41_180.0,
    "K33 heave [N/m]": 11_940.0,
    "K66 yaw [N m/rad]": 11_560_000.0,
}
EDGES = 150  # a line
STEP = {"surge": 0.5, "heave": 0.5, "yaw": 0.01}  # m, m, rad
TOLERANCE = 1e-3
BED = 0.01  # m: the seabed barrier's activation distance
RTOL = 1e-10


def _lines(move: str = "", d: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Anchors and fairleads (3, 3) with the platform moved by ``d`` along ``move``."""
    a = np.radians(HEADINGS)
    u = np.column_stack([np.cos(a), np.sin(a), np.zeros(3)])
    anchors = ANCHOR_RADIUS * u + [0.0, 0.0, -DEPTH]
    fairleads = FAIRLEAD_RADIUS * u + [0.0, 0.0, -FAIRLEAD_DEPTH]
    if move == "surge":
        fairleads[:, 0] += d
    elif move == "heave":
        fairleads[:, 2] += d
    elif move == "yaw":
        c, s = math.cos(d), math.sin(d)
        fairleads[:, :2] = fairleads[:, :2] @ np.array([[c, s], [-s, c]])
    return anchors, fairleads


def oc3_case(move: str = "", d: float = 0.0, edges: int = EDGES) -> dict:
    """The three lines as a case: each from its anchor (on the bed) to its fairlead,
    given straight and slack (its rest length the line's), the seabed z >= -DEPTH."""
    anchors, fairleads = _lines(move, d)
    nodes: list[list[float]] = []
    cables: list[dict] = []
    t = np.linspace(0.0, 1.0, edges + 1)[:, None]
    for k, (a, f) in enumerate(zip(anchors, fairleads, strict=True)):
        a = a + [0.0, 0.0, 0.5 * BED]
        first = len(nodes)
        nodes += (a + t * (f - a)).tolist()
        cables.append(
            {
                "name": f"line {k + 1}",
                "nodes": list(range(first, first + edges + 1)),
                "rest_length": [LENGTH / edges] * edges,
            }
        )
    ends = [c["nodes"][i] for c in cables for i in (0, -1)]
    return {
        "title": "OC3-Hywind mooring lines",
        "geometry": {"kind": "graph", "nodes": nodes, "cable": cables, "fixed": ends},
        "material": {"EA": EA, "area": 1.0, "density": WEIGHT / G},
        "load": {"gravity": [0.0, 0.0, -G]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, -DEPTH], "distance": BED}],
        "solver": {"rtol": RTOL},
    }


def restoring(
    move: str = "", d: float = 0.0, edges: int = EDGES
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lines' total force on the platform [N] and moment about the still-water
    centreline [N m], and each fairlead's pull (3, 3) [N], the platform moved by ``d``."""
    from catenet.case import build, parse_case
    from catenet.solver import path

    scene = build(parse_case(oc3_case(move, d, edges)))
    result = path.solve(scene, path.Settings(rtol=RTOL))
    if not result.converged:
        raise ArithmeticError(f"the OC3 lines did not converge: {result.message}")
    ends = np.array([k * (edges + 1) + edges for k in range(3)])  # the fairleads
    pull = -result.reaction[ends]  # what the lines do to the platform
    arm = result.x[ends]
    return pull.sum(axis=0), np.cross(arm, pull).sum(axis=0), pull


def oc3_rows() -> list[dict]:
    """K11, K33 and K66 against the published ones; the fairlead tensions at rest
    against the elastic catenary on a frictionless seabed (information)."""
    from catenet.validate.rods import _row
    from catenet.validate.seabed import seabed_catenary

    found = {}
    for move, (name, axis) in zip(
        STEP,
        (("K11 surge [N/m]", 0), ("K33 heave [N/m]", 2), ("K66 yaw [N m/rad]", 5)),
        strict=True,
    ):
        d = STEP[move]
        plus, minus = (np.concatenate(restoring(move, s * d)[:2]) for s in (1.0, -1.0))
        found[name] = -(plus[axis] - minus[axis]) / (2 * d)
    case = "OC3-Hywind mooring (published)"
    rows = [
        _row(case, name, EDGES, found[name], value, tolerance=TOLERANCE)
        for name, value in PUBLISHED.items()
    ]
    _, _, pull = restoring()
    line = seabed_catenary(
        L=LENGTH, EA=EA, w=WEIGHT, X=ANCHOR_RADIUS - FAIRLEAD_RADIUS, h=DEPTH - FAIRLEAD_DEPTH
    )
    rows.append(_row(case, "fairlead H [N]", EDGES, float(np.hypot(*pull[0, :2])), line.H))
    rows.append(_row(case, "fairlead V [N]", EDGES, float(-pull[0, 2]), line.V))
    return rows
