"""A corpus of cable structures nobody tuned: seeded, realistic, well-posed case files.

Each model is what a structural engineer would write from the README's "Case files"
section alone: real dimensions, steel strand and rope stiffnesses, prestress that
balances the given geometry by statics, supports that make the structure stable, and
loads from zero to past the first slack member where the structure stays stable after it.
No solver key is set: every model ought to converge at catenet's defaults and close its
global equilibrium (reactions + applied loads + contact forces = 0, contract §5 and §7).

Families (``FAMILIES``), each drawn from its own ``numpy.random.Generator(seed)``:

- ``guyed_mast``: a pinned-foot strut mast (one bilateral edge per panel, EA 1e2-1e4 times
  a guy's), 1-4 guy levels of 3 or 4 guys, each level at a mast joint; guys prestressed to
  2-50 % of their breaking load (steel strand: 1770 MPa over E = 160 GPa, so 0.011 EA); the
  strut prestressed by statics to balance them, or unstressed on its pinned foot; a
  horizontal top load towards a guy up to twice the one that slackens the leeward top guy
  (1.25 times with three guys: near 1.45 the top panel folds over), the windward guys
  below 80 % of breaking.
- ``hypar``: a saddle roof of straight cables along the rulings of z = c x y, or of
  hanging and arching cables along the principal curvatures of z = c1 x^2 - c2 y^2, over a
  square or circular plan; boundary nodes fixed; snow as point loads by tributary plan
  area, up to 1.3 times the estimated load that slackens the arching family.
- ``cable_truss``: a sagging and a hogging cable joined at every panel point by vertical
  ties (sagging cable above) or struts (lens: hogging cable above, every panel point held
  sideways by a purlin, since a planar strut truss buckles out of its plane); vertical
  panel loads up to 0.9 of the load the prestress carries.
- ``spider_net``: radial cables and rings, centre free, outer ring fixed, prestress in
  equilibrium; a centre point load, tributary point loads or a line load on every edge.
- ``mooring``: a chain, wire or polyester line from an anchor on the seabed (``[[obstacle]]``
  plane) to a fairlead, under its submerged weight, part of it resting on the bed.
- ``square_net``: the paper's square net at pressures from 1e-3 to 1e3 Pa.

Every model is written in one of three consistent unit systems (``SCALES``): SI, mm-N-t
and km-MN-t (time in seconds throughout), so that the arithmetic must not care.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import h5py
import numpy as np
import tomli_w

FAMILIES = ("guyed_mast", "hypar", "cable_truss", "spider_net", "mooring", "square_net")

# Length and force units per metre and per newton.  Time stays in seconds, so the mass
# unit is force / length per (N / m): 1 t for mm-N and for km-MN.
SCALES = {"SI": (1.0, 1.0), "mm-N": (1e3, 1.0), "km-MN": (1e-3, 1e-6)}

G = 9.81  # m/s^2
BREAKING_STRAIN = 1770e6 / 160e9  # steel strand: breaking load / EA


def generate(seed: int, family: str | None = None) -> dict:
    """Model ``seed`` of ``family`` (drawn from the seed when None).

    Returns ``{"case": case tables, "family", "description", "scale", "seed", "edges"}``
    where ``edges`` is the estimated edge count and ``case`` is ready for :func:`write`.
    """
    rng = np.random.default_rng(seed)
    drawn = FAMILIES[int(rng.integers(len(FAMILIES)))]
    family = family or drawn
    if family not in FAMILIES:
        raise ValueError(f"family = {family!r}: must be one of {FAMILIES}")
    scale = str(rng.choice(list(SCALES), p=[0.5, 0.25, 0.25]))
    case, description, edges = _BUILDERS[family](rng)
    case = _scaled(_plain(case), *SCALES[scale])
    case["title"] = f"{description} [{scale}]"
    return {
        "case": case,
        "family": family,
        "description": description,
        "scale": scale,
        "seed": seed,
        "edges": edges,
    }


def write(model: dict, path: str | Path) -> Path:
    """Write a model's case as TOML to ``path``."""
    path = Path(path)
    path.write_bytes(tomli_w.dumps(model["case"]).encode())
    return path


def run_in_process(case: str, result: str) -> tuple[int | str, str]:
    """``catenet run CASE -o RESULT -q`` through catenet's entry point in this process
    (a worker that runs many models starts the interpreter and the JIT cache once): its
    exit status and what it printed to stderr ("exception" and the traceback where the
    command raised)."""
    import traceback

    from click.testing import CliRunner

    from catenet.cli import main

    done = CliRunner().invoke(main, ["run", case, "-o", result, "-q"])
    if done.exception is not None and not isinstance(done.exception, SystemExit):
        return "exception", "".join(traceback.format_exception(done.exception))
    return done.exit_code, done.stderr


def check_equilibrium(path: str | Path) -> float:
    """Relative global force imbalance of a result file.

    |sum of reactions + applied loads + contact forces| over the force scale that Newton's
    tolerance is relative to: the largest of the three sums and of the norms of the
    reaction and contact fields (a prestressed net's reactions can dwarf its loads).
    Applied loads are rebuilt from the resolved case stored in the file (root attribute
    ``case``): pressure -p L^2 (square nets), point loads (times the size of a node set),
    line loads per unstressed length, gravity on the lumped masses.
    """
    with h5py.File(path, "r") as f:
        reaction = f["result/reaction"][()]
        contact = f["result/contact_force"][()] if "result/contact_force" in f else None
        applied = _applied_load(f, tomllib.loads(f.attrs["case"]))
    sums = [reaction.sum(axis=0), applied]
    if contact is not None:
        sums.append(contact.sum(axis=0))
    # The force scale that Newton's tolerance is relative to: the norm of all the forces
    # at the nodes (a prestressed net's reactions can dwarf its loads).
    fields = [reaction] if contact is None else [reaction, contact]
    scale = max(
        [float(np.linalg.norm(s)) for s in sums] + [float(np.linalg.norm(f)) for f in fields]
    )
    imbalance = float(np.linalg.norm(np.sum(sums, axis=0)))
    return imbalance / scale if scale > 0.0 else imbalance


# ---------------------------------------------------------------------------- families


def _guyed_mast(rng):
    height = _loguniform(rng, 20.0, 300.0)
    levels = int(rng.integers(1, 5))
    per_level = int(rng.choice([3, 4]))
    radius = height * rng.uniform(0.5, 0.8)  # anchors, shared by the levels
    ea_guy = _loguniform(rng, 1e7, 2e8)
    ea_mast = ea_guy * _loguniform(rng, 1e2, 1e4)
    fraction = rng.uniform(0.02, 0.5)  # unstressed guys leave the joints unstable
    tension = fraction * BREAKING_STRAIN * ea_guy
    balanced = rng.random() < 0.7  # else an unstressed strut on its pinned foot
    weight = rng.random() < 0.4  # guys in several edges under their self-weight

    z = height * np.arange(levels + 1) / levels  # foot, then one joint per guy level
    turn = rng.uniform(0.0, 2.0 * np.pi)
    azimuth = turn + 2.0 * np.pi * np.arange(per_level) / per_level
    anchors = [[radius * np.cos(a), radius * np.sin(a), 0.0] for a in azimuth]
    nodes = [[0.0, 0.0, float(zk)] for zk in z] + anchors
    sin_t = z / np.hypot(z, radius)  # guy angle above the horizontal, per joint

    guy_mat = {"EA": ea_guy}
    mast_mat = {"EA": ea_mast, "tension_only": False}
    if weight:
        guy_mat |= {"area": ea_guy / 160e9, "density": 7850.0 * 1.1}
        mast_mat |= {
            "area": ea_mast / 210e9,
            "density": _loguniform(rng, 50, 500) * 210e9 / ea_mast,
        }
    cables = []
    for k in range(1, levels + 1):
        above = per_level * tension * sin_t[k:].sum()  # vertical pull of guys at and above k
        cables.append(
            {
                "name": f"mast_{k}",
                "nodes": [k - 1, k],
                "prestress": -above if balanced else 0.0,
                "material": mast_mat,
            }
        )
        for a in range(per_level):
            guy = {"name": f"guy_{k}_{a}", "nodes": [levels + 1 + a, k], "prestress": tension}
            if weight:
                guy["edge_length"] = math.hypot(z[k], radius) / int(rng.integers(4, 16))
            cables.append(guy)

    # Leeward top guy slack at H = n T cos(theta) / 2 (stiff mast, linear guys).
    cos_top = math.sqrt(1.0 - sin_t[-1] ** 2)
    slack = per_level * tension * cos_top / 2.0
    # Past it the windward guys hold the top alone: keep them below 80 % of breaking
    # (H <= 0.8 B cos(theta)), and a three-guy top (two guys and a strut) below about 1.45 H
    # where its upright state buckles (the top panel folds over).
    limit = min(2.0 if per_level == 4 else 1.25, 1.6 / (per_level * fraction))
    factor = rng.uniform(0.0, 1.0) * limit
    lee = azimuth[int(rng.integers(per_level))]
    if per_level == 4 and rng.random() < 0.5:
        lee += np.pi / 4.0  # diagonal: two guys slacken, two and the strut hold the top
    push = [factor * slack * np.cos(lee), factor * slack * np.sin(lee), 0.0]
    case = {
        "geometry": _graph(nodes, [0, *range(levels + 1, len(nodes))], cable=cables),
        "material": guy_mat,
        "load": {"point": [{"node": levels, "force": push}]},
    }
    if weight:
        case["load"]["gravity"] = [0.0, 0.0, -G]
    description = (
        f"guyed mast {height:.0f} m, {levels} level(s) of {per_level} guys at "
        f"{100 * fraction:.0f} % of breaking, strut {'balanced' if balanced else 'unstressed'}"
        f"{', self-weight' if weight else ''}, top load {factor:.2f} x first slack"
    )
    edges = levels * (1 + per_level * (16 if weight else 1))
    return case, description, edges


def _hypar(rng):
    half = rng.uniform(10.0, 50.0)
    target = _loguniform(rng, 1e2, 1e4)
    circular = rng.random() < 0.5
    k = max(3, round(math.sqrt(target / (2.0 if not circular else 1.6))))  # cables per family
    spacing = 2.0 * half / (k + 1)
    lines = -half + spacing * np.arange(1, k + 1)
    rise = 2.0 * half * rng.uniform(1 / 20, 1 / 8)
    ruled = rng.random() < 0.5
    c1 = rise / half**2
    c2 = c1 * rng.uniform(0.5, 2.0)
    surface = (lambda x, y: c1 * x * y) if ruled else (lambda x, y: c1 * x * x - c2 * y * y)
    ea = [_loguniform(rng, 2e7, 2e8), 0.0]
    ea[1] = ea[0] * rng.uniform(0.5, 1.0)
    force = [rng.uniform(0.05, 0.25) * BREAKING_STRAIN * e for e in ea]  # x family, y family
    if not ruled:
        force[1] = force[0] * c1 / c2  # horizontal components balance: H1 c1 = H2 c2
        force[1] = min(force[1], 0.3 * BREAKING_STRAIN * ea[1])
        force[0] = force[1] * c2 / c1

    index, nodes, fixed = {}, [], []
    for i, x in enumerate(lines):  # shared joints
        for j, y in enumerate(lines):
            if not circular or math.hypot(x, y) < half - 0.25 * spacing:
                index[i, j] = len(nodes)
                nodes.append([x, y, surface(x, y)])
    edges, prestress, stiffness = [], [], []
    for family in (0, 1):  # 0: cables along x (hanging), 1: along y (arching)
        for m, c in enumerate(lines):
            joints = [
                index[(t, m) if family == 0 else (m, t)]
                for t in range(k)
                if ((t, m) if family == 0 else (m, t)) in index
            ]
            if not joints:
                continue
            end = math.sqrt(half**2 - c * c) if circular else half
            ends = []
            for s in (-end, end):
                x, y = (s, c) if family == 0 else (c, s)
                ends.append(len(nodes))
                fixed.append(len(nodes))
                nodes.append([x, y, surface(x, y)])
            chain = [ends[0], *joints, ends[1]]
            for a, b in zip(chain[:-1], chain[1:], strict=True):
                e = np.subtract(nodes[b], nodes[a])
                along = abs(e[family])
                edges.append([a, b])
                stiffness.append(ea[family])
                prestress.append(force[family] * (1.0 if ruled else np.linalg.norm(e) / along))

    free = len(index)
    areas = _tributary_areas(np.array(nodes[:free]), spacing, half if circular else None)
    if ruled:  # a membrane N grad^2 w = -q of square side 2a sags 0.0737 q (2a)^2 / N
        tension = min(force) / spacing
        q_slack = tension / (0.0737 * 25.0 * 2.0 * half)  # w = span / 25
    else:  # the arching family's share of the load, by its stiffness, takes away its H
        share = 1.0 / (1.0 + ea[0] * c1**2 / (ea[1] * c2**2))
        q_slack = 2.0 * c2 * force[1] / spacing / share
    factor = rng.uniform(0.0, 1.0 if ruled else 1.3)
    loads, full = [], [n for n in range(free) if areas[n] > 0.999 * spacing**2]
    if full:
        loads.append({"node": "snow", "force": [0.0, 0.0, -factor * q_slack * spacing**2]})
    loads += [
        {"node": n, "force": [0.0, 0.0, -factor * q_slack * areas[n]]}
        for n in range(free)
        if areas[n] <= 0.999 * spacing**2 and areas[n] > 0.0
    ]
    geometry = _graph(nodes, fixed, edges=edges, EA=stiffness, prestress=prestress)
    if full:
        geometry["sets"] = {"snow": full}
    layout = "rulings of z = c x y" if ruled else "principal curvatures of z = c1 x^2 - c2 y^2"
    description = (
        f"hypar roof {2 * half:.0f} m {'circular' if circular else 'square'} plan, cables along "
        f"the {layout}, {len(edges)} edges, snow {factor:.2f} x "
        f"{'w = span/25' if ruled else 'arching slack'}"
    )
    case = {"geometry": geometry, "material": {"EA": ea[0]}, "load": {"point": loads}}
    return case, description, len(edges)


def _cable_truss(rng):
    span = rng.uniform(20.0, 100.0)
    panels = int(rng.integers(6, 41))
    sag, hog = span * rng.uniform(1 / 25, 1 / 10), span * rng.uniform(1 / 30, 1 / 12)
    lens = rng.random() < 0.5  # struts, hogging cable above; else ties, sagging cable above
    ea1 = _loguniform(rng, 2e7, 2e8)
    h1 = rng.uniform(0.05, 0.3) * BREAKING_STRAIN * ea1  # horizontal force, sagging cable
    h2 = h1 * sag / hog  # node by node, the members balance the two cables
    ea2 = max(ea1 * rng.uniform(0.3, 1.0), h2 / (0.4 * BREAKING_STRAIN))
    gap = 0.0 if lens else sag + hog + span * rng.uniform(1 / 30, 1 / 10)

    x = span * np.arange(panels + 1) / panels
    bump = 4.0 * x * (span - x) / span**2
    z_sag, z_hog = gap - sag * bump, hog * bump
    nodes = [[0.0, 0.0, 0.0], [span, 0.0, 0.0]]  # the stabilising (hogging) cable's anchors
    fixed = [0, 1]
    if not lens:
        nodes += [[0.0, 0.0, gap], [span, 0.0, gap]]
        fixed += [2, 3]
    inner = range(1, panels)
    sagging = [len(nodes) + i - 1 for i in inner]
    nodes += [[x[i], 0.0, z_sag[i]] for i in inner]
    hogging = [len(nodes) + i - 1 for i in inner]
    nodes += [[x[i], 0.0, z_hog[i]] for i in inner]
    member = h1 * 8.0 * sag * (span / panels) / span**2  # vertical pull of the sagging cable

    edges, stiffness, prestress, tension_only = [], [], [], []
    ends = (0, 1) if lens else (2, 3)
    for chain, ea, h in (([ends[0], *sagging, ends[1]], ea1, h1), ([0, *hogging, 1], ea2, h2)):
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            e = np.subtract(nodes[b], nodes[a])
            edges.append([a, b])
            stiffness.append(ea)
            prestress.append(h * np.linalg.norm(e) / e[0])
            tension_only.append(True)
    for a, b in zip(sagging, hogging, strict=True):
        edges.append([a, b])
        stiffness.append(ea1 * (rng.uniform(1.0, 10.0) if lens else rng.uniform(0.05, 0.2)))
        prestress.append(-member if lens else member)
        tension_only.append(not lens)

    if lens:  # a planar strut truss buckles sideways: purlins to the next truss hold it
        bay = span * rng.uniform(0.1, 0.2)
        for a in sagging + hogging:
            edges.append([a, len(nodes)])
            fixed.append(len(nodes))
            nodes.append([nodes[a][0], bay, nodes[a][2]])
            stiffness.append(ea1)
            prestress.append(0.0)
            tension_only.append(False)

    factor = rng.uniform(0.0, 0.9)  # of the panel load the prestress carries
    loaded = "top" if rng.random() < 0.7 else "all"
    top = hogging if lens else sagging
    targets = top if loaded == "top" else sagging + hogging
    force = -factor * member * len(top) / len(targets)
    arrays = {"edges": edges, "EA": stiffness, "prestress": prestress, "tension_only": tension_only}
    case = {
        "geometry": _graph(nodes, fixed, **arrays, sets={"loaded": targets}),
        "material": {"EA": ea1},
        "load": {"point": [{"node": "loaded", "force": [0.0, 0.0, force]}]},
    }
    kind = "lens with struts" if lens else "ties, sagging cable above"
    description = (
        f"cable truss {span:.0f} m, {panels} panels, {kind}, sag {sag / span:.3f} L, "
        f"hog {hog / span:.3f} L, load {factor:.2f} x prestress capacity on {loaded} nodes"
    )
    return case, description, len(edges)


def _spider_net(rng):
    radius = _loguniform(rng, 1.0, 50.0)
    spokes = int(rng.integers(6, 49))
    rings = int(rng.integers(2, 31))  # ring m is the fixed outer ring
    while spokes * (2 * rings - 1) > 1e4:
        rings -= 1
    ea = _loguniform(rng, 1e4, 1e8)
    ring_t = rng.uniform(0.02, 0.2) * BREAKING_STRAIN * ea
    centre_t = rng.uniform(0.05, 0.2) * BREAKING_STRAIN * ea
    turn = rng.uniform(0.0, 2.0 * np.pi)
    r = radius * np.arange(rings + 1) / rings
    angle = turn + 2.0 * np.pi * np.arange(spokes) / spokes

    def node(k, j):
        return 0 if k == 0 else 1 + (k - 1) * spokes + j

    nodes = [[0.0, 0.0, 0.0]]
    nodes += [[r[k] * np.cos(a), r[k] * np.sin(a), 0.0] for k in range(1, rings + 1) for a in angle]
    edges, prestress = [], []
    radial = centre_t
    for k in range(rings):  # radial segment k -> k+1, growing by the rings' inward pull
        edges += [[node(k, j), node(k + 1, j)] for j in range(spokes)]
        prestress += [radial] * spokes
        if k + 1 < rings:
            edges += [[node(k + 1, j), node(k + 1, (j + 1) % spokes)] for j in range(spokes)]
            prestress += [ring_t] * spokes
            radial += 2.0 * ring_t * np.sin(np.pi / spokes)

    total = rng.uniform(0.0, 1.0) * 0.2 * spokes * centre_t
    kind = str(rng.choice(["centre point", "tributary", "line"]))
    load: dict = {}
    if kind == "centre point":
        load["point"] = [{"node": 0, "force": [0.0, 0.0, -total]}]
    elif kind == "line":
        length = sum(np.linalg.norm(np.subtract(nodes[b], nodes[a])) for a, b in edges)
        load["line"] = [{"force": [0.0, 0.0, -total / length]}]
    else:
        q = total / (np.pi * radius**2)
        half = np.append(0.0, (r[1:] + r[:-1]) / 2.0)
        load["point"] = [{"node": 0, "force": [0.0, 0.0, -q * np.pi * half[1] ** 2]}]
        ring = np.pi * (half[2:] ** 2 - half[1:-1] ** 2) / spokes  # area per node of ring k
        load["point"] += [
            {"node": f"ring_{k}", "force": [0.0, 0.0, -q * ring[k - 1]]} for k in range(1, rings)
        ]
    sets = {f"ring_{k}": [node(k, j) for j in range(spokes)] for k in range(1, rings)}
    outer = [node(rings, j) for j in range(spokes)]
    case = {
        "geometry": _graph(nodes, outer, edges=edges, prestress=prestress, sets=sets),
        "material": {"EA": ea},
        "load": load,
    }
    description = (
        f"spider net R = {radius:.1f} m, {spokes} radials, {rings - 1} free rings, "
        f"{kind} load {total / (spokes * centre_t):.3f} n T0"
    )
    return case, description, len(edges)


def _mooring(rng):
    kind = str(rng.choice(["chain", "wire", "polyester"]))
    ea, weight, depth = {
        "chain": (_loguniform(rng, 1e8, 1e9), rng.uniform(1000, 1500), rng.uniform(50, 300)),
        "wire": (_loguniform(rng, 5e7, 2e8), rng.uniform(100, 300), rng.uniform(100, 1000)),
        "polyester": (_loguniform(rng, 1e7, 1e8), rng.uniform(30, 100), rng.uniform(300, 2000)),
    }[kind]
    length = depth / rng.uniform(0.1, 0.6)
    hanging = rng.uniform(1.05 * depth, max(1.1 * depth, 0.9 * length))
    hanging = min(hanging, 0.95 * length)
    a = (hanging**2 - depth**2) / (2.0 * depth)  # inextensible catenary H / w, touching down
    reach = length - hanging + a * math.asinh(hanging / a)
    area = ea / (1e11 if kind != "polyester" else 1e10)
    nodes = int(rng.integers(50, 401))
    case = {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, 0.0],
            "end": [reach, 0.0, depth],
            "length": length,
            "nodes": nodes,
        },
        "material": {"EA": ea, "area": area, "density": weight / (G * area)},
        "load": {"gravity": [0.0, 0.0, -G]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}],
    }
    description = (
        f"{kind} mooring line {length:.0f} m in {depth:.0f} m of water (depth/length "
        f"{depth / length:.2f}), {1 - hanging / length:.0%} on the bed, {nodes} nodes"
    )
    return case, description, nodes - 1


def _square_net(rng):
    n = 2 * int(rng.integers(1, 18))
    alpha = float(rng.choice([0.0, np.pi / 6, np.pi / 4, rng.uniform(0.0, np.pi / 2)]))
    edge = float(rng.choice([0.01, 0.02, 0.05, 0.1]))
    pressure = _loguniform(rng, 1e-3, 1e3)
    edges = int(n / 2 * 2 / edge * 1.2)
    case = {
        "geometry": {
            "kind": "square_net",
            "n": n,
            "alpha": alpha,
            "size": 1.0,
            "edge_length": edge,
        },
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"pressure": pressure},
    }
    description = f"square net n = {n}, alpha = {alpha:.3f}, edges {edge} m, p = {pressure:.3g} Pa"
    return case, description, edges


_BUILDERS = {
    "guyed_mast": _guyed_mast,
    "hypar": _hypar,
    "cable_truss": _cable_truss,
    "spider_net": _spider_net,
    "mooring": _mooring,
    "square_net": _square_net,
}

# ------------------------------------------------------------------------------ helpers


def _graph(nodes, fixed, **keys):
    """A ``graph`` geometry table."""
    return {"kind": "graph", "nodes": nodes, "fixed": fixed, **keys}


def _loguniform(rng, low, high):
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def _tributary_areas(points, spacing, radius=None, samples=12):
    """Plan area of each grid node's cell, clipped to a circle of ``radius`` if given."""
    if radius is None:
        return np.full(len(points), spacing**2)
    u = (np.arange(samples) + 0.5) / samples - 0.5
    du, dv = np.meshgrid(u * spacing, u * spacing)
    x = points[:, :1] + du.reshape(1, -1)
    y = points[:, 1:2] + dv.reshape(1, -1)
    return spacing**2 * np.mean(x**2 + y**2 <= radius**2, axis=1)


# Dimensions (length exponent, force exponent) of the keys the corpus writes; time in s.
_LENGTHS = ("nodes", "start", "end", "length", "size", "edge_length", "radius", "point", "gravity")
_DIMENSIONS = dict.fromkeys(_LENGTHS, (1, 0)) | {
    "area": (2, 0), "E": (-2, 1), "EA": (0, 1), "prestress": (0, 1), "density": (-4, 1),
    "pressure": (-2, 1), "mass": (-1, 1),
}  # fmt: skip


def _scaled(case, length, force, path=()):
    """The case in units of ``length`` per metre and ``force`` per newton."""
    if isinstance(case, dict):
        return {k: _scaled(v, length, force, (*path, k)) for k, v in case.items()}
    if isinstance(case, list) and case and isinstance(case[0], dict):
        return [_scaled(v, length, force, path) for v in case]
    key = path[-1] if path else ""
    if "sets" in path or key == "nodes" and ("cable" in path or not isinstance(case, list)):
        return case  # node indices, or a cable's node count
    dims = ((-1, 1) if "line" in path else (0, 1)) if key == "force" else _DIMENSIONS.get(key)
    return case if dims is None else _times(case, length ** dims[0] * force ** dims[1])


def _times(value, factor):
    if isinstance(value, list):
        return [_times(v, factor) for v in value]
    return value * factor if isinstance(value, float) else value


def _plain(value):
    """Python floats, ints, bools, lists and dicts only (what tomli_w writes)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value.tolist() if isinstance(value, np.generic | np.ndarray) else value


def _applied_load(f, case) -> np.ndarray:
    """Total applied force [force units] of a result file's resolved case."""
    load, geometry = case.get("load", {}), case["geometry"]
    total = np.zeros(3)
    if load.get("pressure"):
        total[2] -= load["pressure"] * geometry["size"] ** 2
    sets = geometry.get("sets", {})
    for p in load.get("point", []):
        node = p.get("node")
        count = len(sets[node]) if isinstance(node, str) and node in sets else 1
        total += count * np.asarray(p["force"], float)
    l0 = f["mesh/rest_length"][()]
    names = [str(n) for n in f["mesh"].attrs.get("cable_names", [])]
    cable = f["mesh/cable"][()] if "mesh/cable" in f else np.full(len(l0), -1)
    for line in load.get("line", []):
        on = cable == names.index(line["cable"]) if "cable" in line else slice(None)
        total += l0[on].sum() * np.asarray(line["force"], float)
    if "gravity" in load:
        total += _total_mass(f, case, l0, cable, names) * np.asarray(load["gravity"], float)
    return total


def _total_mass(f, case, l0, cable, names) -> float:
    """Lumped mass of the net: /mesh/mass when written, else rho A l0 per edge + [[mass]]."""
    if "mesh/mass" in f:
        return float(f["mesh/mass"][()].sum())
    cables = {c["name"]: c.get("material", {}) for c in case["geometry"].get("cable", [])}
    per_cable = [cables.get(name, {}) for name in names]
    density = np.empty(len(l0))
    for group in np.unique(cable):
        mat = dict(case.get("material", {}))
        for k, v in (per_cable[group] if group >= 0 else {}).items():
            mat.pop({"area": "radius", "radius": "area"}.get(k, ""), None)
            mat[k] = v
        area = mat.get("area", math.pi * mat.get("radius", 0.0) ** 2)
        density[cable == group] = mat.get("density", 0.0) * area
    sets = case["geometry"].get("sets", {})
    points = sum(m.get("mass", 0.0) * len(sets.get(m["node"], [0])) for m in case.get("mass", []))
    return float(density @ l0) + points
