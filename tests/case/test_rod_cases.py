"""Rods from a case file: material.EI (or "section"), natural_curvature, supports.clamped,
which edges bend in each geometry kind, the results (/result/bending_moment, curvature,
the summary's largest moment), natural modes, and bad input (exit 2, one message)."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.errors import ConfigError

CANTILEVER = {
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [2.0, 0.0, 0.0], "nodes": 21},
    "material": {"E": 70e9, "radius": 0.02, "inner_radius": 0.015, "EI": "section"},
    "supports": {"fixed": ["start"], "clamped": ["start"]},
    "load": {"point": [{"node": "end", "force": [0.0, 0.0, -50.0]}]},
}


def _invoke(tmp_path, data, *args, command="run"):
    tmp_path.mkdir(parents=True, exist_ok=True)
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    return CliRunner().invoke(main, [command, str(case), "-o", str(tmp_path / "r.h5"), *args])


def _bending(scene):
    return next(t for t in scene.terms if t.name == "bending")


def test_tube_cantilever_small_deflection_and_moment(tmp_path):
    """A tube (E pi (r^4 - ri^4) / 4) clamped at one end, a small end load: the tip
    deflection P L^3 / (3 EI) to the discretisation's O(h^2) and the moment at the clamp
    P times the tip's lever arm."""
    done = _invoke(tmp_path, CANTILEVER)
    assert done.exit_code == 0, done.output
    assert "bending      max moment" in done.output
    EI = 70e9 * math.pi * (0.02**4 - 0.015**4) / 4
    with h5py.File(tmp_path / "r.h5") as f:
        x = f["result/x"][:]
        moment = f["result/bending_moment"][:]
        kappa = f["result/curvature"][:]
        assert f["result"].attrs["max_bending_moment_node"] == 0
    tip = x[-1]
    assert -tip[2] == pytest.approx(50.0 * 2.0**3 / (3 * EI), rel=2e-3)
    assert moment[0] == pytest.approx(50.0 * tip[0], rel=2e-3)
    assert moment[-1] == 0.0  # a free end carries none
    assert kappa[10] == pytest.approx(moment[10] / EI, rel=1e-9)


def test_a_clamp_alone_holds_a_cantilever(tmp_path):
    """supports.fixed = [] with the clamp the only support: the clamp holds its node in
    place, so the cantilever is supported (it was refused: "[] only where rollers,
    sliders or springs hold the net") and bends as with the node fixed too."""
    both = _invoke(tmp_path / "both", CANTILEVER)
    data = {**CANTILEVER, "supports": {"fixed": [], "clamped": ["start"]}}
    alone = _invoke(tmp_path / "alone", data)
    assert both.exit_code == 0 and alone.exit_code == 0, (both.output, alone.output)
    with h5py.File(tmp_path / "both" / "r.h5") as f, h5py.File(tmp_path / "alone" / "r.h5") as g:
        assert np.array_equal(f["result/x"][:], g["result/x"][:])


def test_modes_include_the_bending_stiffness(tmp_path):
    """The cantilever's first frequency (1.87510407)^2 sqrt(EI / (rho A L^4)) / (2 pi)."""
    data = {**CANTILEVER, "material": {**CANTILEVER["material"], "density": 2700.0}}
    data = {k: v for k, v in data.items() if k != "load"}
    done = _invoke(tmp_path, data, command="modes")
    assert done.exit_code == 0, done.output
    EI = 70e9 * math.pi * (0.02**4 - 0.015**4) / 4
    rho_a = 2700.0 * math.pi * (0.02**2 - 0.015**2)
    exact = 1.87510407**2 * math.sqrt(EI / (rho_a * 2.0**4)) / (2 * math.pi)
    with h5py.File(tmp_path / "r.h5") as f:
        first = float(f["modes/frequency"][0])
    assert first == pytest.approx(exact, rel=3e-3)  # 20 edges: -2.1e-3 (O(h^2))


def test_rods_default_to_carrying_compression():
    case = parse_case(CANTILEVER)
    assert case.material.tension_only is False
    given = parse_case({**CANTILEVER, "material": {**CANTILEVER["material"], "tension_only": True}})
    assert given.material.tension_only is True
    plain = parse_case({**CANTILEVER, "material": {"EA": 1e6}, "supports": {}})
    assert plain.material.tension_only is True and not any(
        t.name == "bending" for t in build(plain).terms
    )


def test_graph_cables_bend_each_along_itself():
    """Two cables meeting at a joint (node 1) and a brace of the graph's own: only the
    rod cable bends, and only along itself; the joint is a pin."""
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0], [1, 2, 0]],
            "edges": [[0, 3]],
            "fixed": [0, 2, 4],
            "edge_length": 0.25,
            "cable": [
                {"name": "rod", "nodes": [0, 1, 2], "material": {"EI": 10.0}},
                {"name": "rope", "nodes": [4, 3, 1]},
            ],
        },
        "material": {"EA": 1e5},
    }
    scene = build(parse_case(data))
    rods = _bending(scene).rods
    edge_cable = scene.cables.edge
    rod_edges = np.flatnonzero(edge_cable == 0)
    assert len(rods.hinges) == len(rod_edges) - 1
    rod_nodes = set(scene.net.edges[rod_edges].ravel().tolist())
    assert set(rods.hinges.ravel().tolist()) <= rod_nodes
    assert scene.net.law.tension_only[edge_cable == 1].all()  # the rope stays a cable
    assert not scene.net.law.tension_only[rod_edges].any()


@pytest.mark.parametrize(
    "own, area",
    [
        ({"area": 2.0e-4, "EI": 0.0}, 2.0e-4),  # a tie of given area (no round section)
        ({"radius": 0.008}, math.pi * 0.008**2),  # a solid bar
        ({"radius": 0.06, "inner_radius": 0.05}, math.pi * (0.06**2 - 0.05**2)),  # a tube
    ],
)
def test_a_cables_own_section_drops_the_cases_tube(own, area):
    """A tube (radius 60 mm, inner_radius 54 mm) in [material] and a tie of its own
    section beside it: the tie's area or radius replaces the tube's inner radius too (it
    was refused: "a tube needs its outer radius: give material.radius"), unless the tie
    gives an inner radius of its own."""
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [0, 0, 4], [2, 0, 4]],
            "fixed": [0, 2],
            "cable": [
                {"name": "post", "nodes": [0, 1]},
                {"name": "tie", "nodes": [1, 2], "material": {"E": 2.0e11, **own}},
            ],
        },
        "material": {"E": 2.1e11, "radius": 0.06, "inner_radius": 0.054, "EI": "section"},
    }
    scene = build(parse_case(data))
    tie = scene.cables.edge == 1
    assert scene.net.EA[tie] == pytest.approx(2.0e11 * area, rel=1e-12)
    post = math.pi * (0.06**2 - 0.054**2) * 2.1e11
    assert scene.net.EA[~tie] == pytest.approx(post, rel=1e-12)


def test_square_net_cables_bend_along_their_lines():
    data = {
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.3, "size": 1.0, "edge_length": 0.1},
        "material": {"EA": 1e4, "EI": 1.0},
    }
    scene = build(parse_case(data))
    rods = _bending(scene).rods
    net = scene.net
    i, j, k = rods.hinges.T
    t1 = net.nodes[j] - net.nodes[i]
    t2 = net.nodes[k] - net.nodes[j]
    assert np.allclose(np.cross(t1, t2), 0.0) and (np.einsum("ij,ij->i", t1, t2) > 0).all()
    assert len(rods.hinges) == net.n_edges - 4  # every cable's edges less one


def test_natural_curvature_as_given_keeps_an_arch_unstressed(tmp_path):
    """A half circle given as a graph cable, naturally curved as given: unloaded, it is
    at rest in its given shape; straight (the default) it pushes on its supports."""
    phi = np.linspace(0.0, math.pi, 9)
    nodes = np.column_stack([np.cos(phi), np.zeros(9), np.sin(phi)]).tolist()
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": nodes,
            "fixed": [0, 8],
            "cable": [{"name": "arch", "nodes": list(range(9))}],
        },
        "material": {"EA": 1e6, "EI": 5.0, "natural_curvature": "given"},
        "supports": {"clamped": [0, 8]},
    }
    scene = build(parse_case(data))
    g = np.zeros_like(scene.net.nodes)
    assert _bending(scene).gradient(scene.net.nodes, g) == pytest.approx(0.0, abs=1e-24)
    assert np.max(np.abs(g)) < 1e-9
    data["material"]["natural_curvature"] = "straight"
    straight = build(parse_case(data))
    assert _bending(straight).energy(straight.net.nodes) > 1.0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"material": {"EA": 1e6, "EI": -1.0}}, "material.EI = -1.0: must be >= 0"),
        ({"material": {"EA": 1e6, "EI": "stiff"}}, "material.EI = 'stiff': must be a number"),
        ({"material": {"EA": 1e6, "EI": "section"}}, 'material.EI = "section": needs material.E'),
        (
            {"material": {"E": 1e9, "radius": 0.01, "inner_radius": 0.02, "EI": "section"}},
            "material.inner_radius = 0.02: must be < material.radius = 0.01",
        ),
        (
            {"supports": {"fixed": ["start"], "clamped": ["midpoint"]}},
            "supports.clamped: node 10 is an interior node of a rod",
        ),
        (
            {"supports": {"fixed": ["start"], "clamped": ["top"]}},
            "supports.clamped[0] = 'top': must be a node index",
        ),
        (
            {"material": {"EA": 1e6}, "supports": {"fixed": ["start"], "clamped": ["start"]}},
            "no edge bends: a clamp holds a rod's end: give material.EI > 0",
        ),
        (
            {"material": {"EA": 1e6, "EI": 1.0, "natural_curvature": "bent"}},
            "material.natural_curvature = 'bent': must be one of 'straight', 'given'",
        ),
    ],
)
def test_bad_rod_input_exits_2_with_one_clear_message(tmp_path, change, message):
    done = _invoke(tmp_path, {**CANTILEVER, **change})
    assert done.exit_code == 2, done.output
    assert message in done.output, done.output
    assert "Traceback" not in done.output


def test_clamped_nodes_are_pinned():
    data = {**CANTILEVER, "supports": {"clamped": ["start"]}}  # the default supports: both ends
    data["supports"] = {"fixed": ["end"], "clamped": ["start"]}
    scene = build(parse_case(data))
    assert scene.net.fixed[0] and scene.net.fixed[-1]
    with pytest.raises(ConfigError, match="supports.clamped"):
        build(parse_case({**CANTILEVER, "supports": {"fixed": ["start"], "clamped": [5]}}))


def test_a_released_cantilever_keeps_its_energy_balance(tmp_path):
    """A rod clamped horizontally and released under gravity, undamped: the bending
    energy counts as elastic (not contact), and the integrator's remainder shrinks with
    the step as bdf2's order says (1.6 % of the largest energy at dt = 4 ms, 0.49 % at
    2 ms, over about half a period of the first mode)."""
    data = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1.0, 0, 0], "nodes": 11},
        "material": {"E": 70e9, "radius": 0.005, "density": 2700.0, "EI": "section"},
        "supports": {"fixed": ["start"], "clamped": ["start"]},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "dynamic", "integrator": "bdf2", "t_end": 0.08, "damping": 0.0},
    }
    found = []
    for dt in (0.004, 0.002):
        data["solver"]["dt"] = dt
        done = _invoke(tmp_path, data)
        assert done.exit_code == 0, done.output
        with h5py.File(tmp_path / "r.h5") as f:
            energy = f["trajectory/energy"][:]
            columns = list(f["trajectory/energy"].attrs["columns"])
            tip = f["trajectory/x"][:, -1, 2]
        stored = energy[:, columns.index("elastic")]
        assert np.all(energy[:, columns.index("contact")] == 0.0) and stored.max() > 0
        largest = np.max(np.abs(energy[:, :3]).sum(axis=1))
        found.append((abs(energy[-1, columns.index("numerical")]) / largest, tip.min()))
    (e1, z1), (e2, z2) = found
    assert e2 < 0.4 * e1 and e1 < 0.03
    assert z2 == pytest.approx(z1, rel=0.03)  # the tip's lowest point, to the step's error


def _guyed_mast(edges: int, guy_EA: float = 2.0e7) -> dict:
    """The guyed mast of configs/ (docs/howto/guyed-mast.md) as a rod in ``edges`` edges
    under a uniform wind w along it, with its guys' EA: what the tests below compare."""
    import tomllib

    from conftest import CONFIGS

    from catenet.solver.path import solve

    with open(CONFIGS / "structures" / "guyed_mast.toml", "rb") as f:
        data = tomllib.load(f)
    EI, w, L = 8.65e6, 1000.0, 20.0
    mast = data["geometry"]["cable"][0]
    mast["edge_length"] = L / edges
    mast["material"]["EI"] = EI
    data["material"]["EA"] = guy_EA
    data["load"] = {"line": [{"cable": "mast", "force": [w, 0.0, 0.0]}]}
    scene = build(parse_case(data))
    result = solve(scene)
    assert result.converged and result.stability == "stable"
    net = scene.net
    on = np.flatnonzero(scene.cables.edge == 0)
    guys = [float(np.mean(result.tension[scene.cables.edge == c])) for c in range(1, 5)]
    assert min(guys) > 0.0  # every guy taut: the linear hand calculation holds
    chain = [int(net.edges[on[0], 0])] + [int(e) for e in net.edges[on, 1]]
    return {
        "EI": EI,
        "w": w,
        "L": L,
        "d": result.x - net.nodes,
        "chain": chain,
        "P": -float(np.mean(result.tension[on])),
        "guys": guys,
    }


def _mast_bow(edges: int) -> tuple[float, float]:
    """The mast's bow at mid-height from the chord, and the beam-column's (see below)."""
    mast = _guyed_mast(edges)
    EI, w, L, d, chain, P = (mast[k] for k in ("EI", "w", "L", "d", "chain", "P"))
    bow = d[chain[edges // 2], 0] - 0.5 * (d[chain[0], 0] + d[chain[-1], 0])
    assert 0.1 < P / (math.pi**2 * EI / L**2) < 0.3  # the P-delta amplification shows
    u = 0.5 * L * math.sqrt(P / EI)
    return bow, 5 * w * L**4 / (384 * EI) * 12 * (2 / math.cos(u) - 2 - u * u) / (5 * u**4)


def test_guyed_mast_as_a_rod_meets_the_beam_column_under_wind():
    """configs/structures/guyed_mast.toml with its mast a rod (EI such that its
    compression is about a fifth of the Euler load) under a uniform wind w along it: the
    mast's deflection at mid-height from the chord between foot and top against the
    beam-column (Timoshenko and Gere: a pinned member under uniform load and compression
    P), 5 w L^4 / (384 EI) 12 (2 sec u - 2 - u^2) / (5 u^4), u = L / 2 sqrt(P / EI), P the
    mast's compression as solved (its bowing shortens the chord: the guys' prestress
    falls). Within 1 % at 20 edges (0.26 %), second order in the edge length."""
    (coarse, exact), (fine, same) = _mast_bow(10), _mast_bow(20)
    err_coarse, err_fine = abs(coarse / exact - 1), abs(fine / same - 1)
    assert err_fine < 1e-2
    assert 1.8 < math.log2(err_coarse / err_fine) < 2.2


@pytest.mark.parametrize("guy_EA", [2.0e7, 2.0e6])
def test_guyed_mast_as_a_rod_top_displacement_by_hand(guy_EA):
    """The same mast under wind: the top moves by the half of the wind that the top carries,
    w L / 2 (a pinned member's end reaction), over the guys' horizontal stiffness less the
    mast's P-delta, u = (w L / 2) / (K - P / L). K is the guys' tangent: EA / l0 cos^2 along
    each guy in the wind's plane (0.6 of its unit vector horizontal) plus T / l_g across it
    (all four), at the tensions and the compression P as solved (the bow shortens the chord
    and the guys relax). Within 1 % (7e-4 and 8e-4: the top's 11 mm drop turns the guys),
    with the docs' steel strand and with guys ten times softer, where the P-delta and the
    guys' geometric stiffness are 5 % and 4 % of K (so the check sees both). Split into 10 or
    20 edges, the top moves the same to 1e-4 (8e-6 and 1.5e-5)."""
    tops = []
    for edges in (10, 20):
        mast = _guyed_mast(edges, guy_EA)
        w, L, P, guys = mast["w"], mast["L"], mast["P"], mast["guys"]
        l_g, T0 = 25.0, 20.0e3  # each guy's length, its prestress in the drawn geometry
        axial = guy_EA / (l_g / (1.0 + T0 / guy_EA))  # EA over the rest length
        K = 2 * 0.36 * axial + 0.64 * (guys[0] + guys[1]) / l_g + (guys[2] + guys[3]) / l_g
        by_hand = 0.5 * w * L / (K - P / L)
        top = mast["d"][mast["chain"][-1]]
        assert abs(top[0] / by_hand - 1.0) < 1e-2
        assert abs(top[1]) < 1e-9 * abs(top[0])
        tops.append(top[0])
    assert tops[1] == pytest.approx(tops[0], rel=1e-4)
    if guy_EA < 1e7:
        assert P / L > 0.03 * K  # the mast's P-delta is larger than the tolerance
