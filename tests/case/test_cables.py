"""Graph cases with cables, node sets, per-edge arrays and the loads users give (issue 10,
items 1 and 5; contract §6): subdivision, per-cable material and prestress, loads by
node set, per unit length of cable and at a position along a cable, the per-cable results
(Result stats, the HDF5 file, the run summary), line meshes from files, and bad input."""

from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest
from cable_cases import one, straight, two_cables
from scipy.optimize import fsolve

from catenet.case import build, parse_case
from catenet.model.laws import LAWS
from catenet.solver.path import Settings, solve

TABLE = [[0.01, 100.0], [0.05, 300.0], [0.5, 900.0]]


def exact(scene, **kw):
    r = solve(scene, Settings(rtol=1e-12, **kw))
    assert r.converged
    return r


# --------------------------------------------------------------------------- subdivision


def test_cables_are_split_into_edges_no_longer_than_edge_length():
    """Each segment gets ceil(length / edge_length - 1e-9) equal edges: a segment of
    exactly k edge lengths gets k (contract §2's rule); new nodes follow the given
    ones, on the segment; the cable of every edge is recorded."""
    data = straight()
    seg = math.sqrt(1.5**2 + 0.5**2 + 1)
    data["geometry"]["edge_length"] = seg / 4  # exactly 4 edges a segment
    scene = build(parse_case(data))
    net = scene.net
    assert (net.n_nodes, net.n_edges) == (3 + 2 * 3, 8)
    assert np.allclose(net.rest_length, seg / 4, rtol=1e-12)
    assert np.array_equal(scene.cables.edge, np.zeros(8))
    assert scene.cables.names == ("c",)
    # every node on the chord, given nodes kept in place and joined through node 1
    t = net.nodes @ np.array([3, 1, 2]) / 14.0
    assert np.allclose(net.nodes, t[:, None] * np.array([3, 1, 2]), atol=1e-12)
    assert np.count_nonzero(net.edges == 1) == 2
    data["geometry"]["cable"][0]["edge_length"] = seg / 2.5  # per cable: 3 edges a segment
    assert build(parse_case(data)).net.n_edges == 6
    del data["geometry"]["edge_length"], data["geometry"]["cable"][0]["edge_length"]
    assert build(parse_case(data)).net.n_edges == 2  # no edge_length: a segment is an edge


def test_cables_share_joints_and_own_edges_come_first():
    data = two_cables()
    data["geometry"]["nodes"].append([2, 0, 0])
    data["geometry"]["cable"][0]["nodes"] = [0, 4, 1]
    data["geometry"]["cable"][1]["nodes"] = [2, 4, 3]
    data["geometry"]["edges"] = [[0, 2]]
    scene = build(parse_case(data))
    assert np.count_nonzero(scene.net.edges == 4) == 4  # the crossing is a joint
    assert scene.cables.edge[0] == -1 and np.array_equal(scene.net.edges[0], [0, 2])
    assert np.array_equal(np.bincount(scene.cables.edge + 1), [1, 8, 10])


def test_resolved_case_round_trips_with_cables_sets_and_loads():
    data = two_cables()
    data["load"] = {
        "point": [{"cable": "a", "at": 0.3, "force": [0, 0, -10]}],
        "line": [{"cable": "b", "force": [0, 0, -2]}],
    }
    case = parse_case(data)
    back = parse_case(tomllib.loads(case.to_toml()))
    assert back == case
    assert case.to_dict()["geometry"]["cable"][1]["material"] == {"EA": 5e4}
    assert case.to_dict()["geometry"]["sets"] == {"anchors": [0, 1, 2, 3], "west": [0]}


def test_size_estimate_counts_the_edges_cables_add():
    case = parse_case(two_cables())
    nodes, edges, _, key = case.geometry.estimate_size()
    net = build(case).net
    assert (nodes, edges, key) == (net.n_nodes, net.n_edges, "geometry.edge_length")


# --------------------------------------------------------------------------- prestress


@pytest.mark.parametrize("law", ["linear", "neo_hookean", "hencky", "table"])
def test_a_straight_cable_prestressed_per_cable_carries_it_exactly(law):
    """The cable's prestress (over [material]'s) is its tension in the given geometry:
    pinned and unloaded, every edge of it carries T0 and nothing moves."""
    material = {"law": law}
    if law == "table":
        material = {"law": "table", "table": TABLE}
    data = straight(prestress=150.0, material=material)
    data["material"]["prestress"] = 20.0
    scene = build(parse_case(data))
    assert set(scene.net.law.kind) == {LAWS[law].id}
    r = exact(scene)
    assert np.allclose(r.tension, 150.0, rtol=1e-12)
    assert np.array_equal(r.x, scene.net.nodes)


def test_two_table_cables_keep_their_own_tables():
    """Tables of several cables are stacked: each cable's edges read their own rows."""
    data = straight(prestress=150.0, material={"law": "table", "table": TABLE})
    data["geometry"]["nodes"] += [[0, 5, 0], [3, 5, 0]]
    data["geometry"]["fixed"] += [3, 4]
    other = [[0.02, 100.0], [0.3, 400.0]]
    data["geometry"]["cable"].append(
        {
            "name": "d",
            "nodes": [3, 4],
            "prestress": 250.0,
            "material": {"law": "table", "table": other},
        }
    )
    scene = build(parse_case(data))
    r = exact(scene)
    on_d = scene.cables.edge == 1
    assert np.allclose(r.tension[on_d], 250.0, rtol=1e-12)
    assert np.allclose(r.tension[~on_d], 150.0, rtol=1e-12)
    # the strain of d's edges follows d's table: 100 + (400 - 100)(eps - 0.02)/0.28 = 250
    eps = (
        scene.net.nodes[scene.net.edges[on_d, 1], 0] - scene.net.nodes[scene.net.edges[on_d, 0], 0]
    )
    assert np.allclose(eps / scene.net.rest_length[on_d] - 1, 0.02 + 150 * 0.28 / 300, rtol=1e-12)


def test_per_edge_prestress_overrides_material_prestress():
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0], [1, -1, 0]],
            "edges": [[0, 1], [1, 2], [1, 3], [4, 1]],
            "fixed": [0, 2, 3, 4],
            "prestress": [40.0, 40.0, 7.0, 7.0],
        },
        "material": {"EA": 1e4, "prestress": 5.0, "law": "neo_hookean"},
    }
    r = exact(build(parse_case(data)))
    assert np.allclose(r.tension, [40.0, 40.0, 7.0, 7.0], rtol=1e-12)
    del data["geometry"]["prestress"]
    assert np.allclose(exact(build(parse_case(data))).tension, 5.0, rtol=1e-12)


def test_per_edge_tension_only_makes_struts():
    """A bar 0-1-2 pinned at its ends, node 1 pushed along +x by F. With edge 1-2
    bilateral the two edges share F exactly (N0 = EA d/L = -N1, N0 - N1 = F); with it
    tension-only (and 0-1 a strut) it goes slack and edge 0-1 carries F alone."""
    F, EA = 30.0, 1e4
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0]],
            "edges": [[0, 1], [1, 2]],
            "fixed": [0, 2],
            "tension_only": [True, False],
        },
        "material": {"EA": EA},
        "load": {"point": [{"node": 1, "force": [F, 0, 0]}]},
    }
    scene = build(parse_case(data))
    assert scene.net.law.tension_only.tolist() == [True, False]
    # The straight bar is an unstable equilibrium: node 1's sideways stiffness is
    # N0 / l0 + N1 / l1 = -2 N d < 0 (its compressed half is the longer push), so the
    # loaded path is a collapse. Followed through, the path leaves the straight state
    # along its unstable mode (Newton alone stayed on it) for the bent equilibrium: node
    # 1 aside, where both edges' N / l are F / 2 (sideways N0 / l0 = -N1 / l1, along the
    # bar their sum F / 2 + F / 2), the tension-only half stretched more than the strut
    # is shortened.
    bent = exact(scene, post_collapse=True)
    assert bent.stability == "post-collapse"
    lengths = np.linalg.norm(np.diff(bent.x, axis=0), axis=1)
    assert np.allclose(bent.tension / lengths * [1, -1], F / 2, rtol=1e-8)
    assert abs(bent.x[1, 1]) + abs(bent.x[1, 2]) > 1e-3  # aside, not straight
    data["geometry"]["tension_only"] = [False, True]  # now 1-2 is the cable, compressed
    assert np.allclose(exact(build(parse_case(data))).tension, [F, 0.0], rtol=1e-10)


# --------------------------------------------------------------------------- materials


def test_a_cable_material_overrides_material_key_by_key():
    data = two_cables()
    data["material"] = {"E": 1e9, "radius": 0.01, "density": 1000.0}
    data["geometry"]["cable"][1]["material"] = {"EA": 5e4, "density": 2000.0, "law": "hencky"}
    scene = build(parse_case(data))
    on_b = scene.cables.edge == 1
    assert np.allclose(scene.net.EA[on_b], 5e4) and np.allclose(
        scene.net.EA[~on_b], 1e9 * np.pi * 1e-4
    )
    assert np.allclose(scene.net.line_density[on_b], 2000.0 * np.pi * 1e-4)
    assert set(scene.net.law.kind[on_b]) == {LAWS["hencky"].id}
    assert set(scene.net.law.kind[~on_b]) == {LAWS["linear"].id}


# --------------------------------------------------------------------------- loads


def test_node_sets_in_supports_moves_and_point_loads():
    """A set fixes, moves and loads each of its nodes."""
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]],
            "edges": [[0, 1], [1, 2], [2, 3]],
            "sets": {"ends": [0, 3], "inner": [1, 2]},
        },
        "supports": {"fixed": ["ends"], "move": [{"node": "ends", "displacement": [0, 0, 1]}]},
        "material": {"EA": 1e4},
        "load": {"point": [{"node": "inner", "force": [0, 0, -2]}]},
    }
    scene = build(parse_case(data))
    assert scene.net.fixed.tolist() == [True, False, False, True]
    assert scene.loads.force[:, 2].tolist() == [0, -2, -2, 0]
    assert np.allclose(scene.loads.support_displacement[:, 2], [1, 0, 0, 1])
    r = exact(scene)
    assert np.allclose(r.x[[0, 3], 2], 1.0)
    assert np.allclose(r.reaction.sum(axis=0) + scene.loads.external_force(scene.net).sum(0), 0)


def test_a_line_load_is_the_self_weight_when_it_equals_rho_a_g():
    """load.line with force = rho A g per unit unstressed length gives the same nodal
    forces, and the same equilibrium, as gravity on that cable."""
    rho, r, g = 7800.0, 0.002, 9.81
    base = straight(prestress=10.0)
    base["material"] = {"E": 2e9, "radius": r, "density": rho}
    heavy = copy.deepcopy(base)
    heavy["load"] = {"gravity": [0, 0, -g]}
    line = copy.deepcopy(base)
    line["load"] = {"line": [{"cable": "c", "force": [0, 0, -rho * math.pi * r**2 * g]}]}
    a, b = build(parse_case(heavy)), build(parse_case(line))
    fa, fb = a.loads.external_force(a.net), b.loads.external_force(b.net)
    assert np.allclose(fa, fb, rtol=1e-14, atol=1e-16)
    assert np.allclose(exact(a).x, exact(b).x, rtol=0, atol=1e-12)
    # without a cable name: every edge
    line["load"]["line"][0].pop("cable")
    assert np.allclose(build(parse_case(line)).loads.force, fb - 0, atol=1e-16)


def test_a_point_load_along_a_cable_splits_its_edge_and_matches_two_straight_pieces():
    """A pretensioned cable from (0,0,0) to (4,0,0), F down at a quarter of its length.
    The edge there is split so that a node carries F; the equilibrium is two straight
    pieces from the supports to that node at (u, 0, -d), with N_i = EA (s_i/l0_i - 1),
    l0_i = L_i / (1 + T0/EA): the horizontal and vertical balance of the node, solved
    here with fsolve, fixes u and d. Every other node lies on the two pieces."""
    EA, T0, F = 1e4, 100.0, 50.0
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [4, 0, 0]],
            "fixed": [0, 1],
            "edge_length": 0.3,
            "cable": [{"name": "c", "nodes": [0, 1], "prestress": T0}],
        },
        "material": {"EA": EA},
        "load": {"point": [{"cable": "c", "at": 0.25, "force": [0, 0, -F]}]},
        "solver": {"steps": 3},
    }
    scene = build(parse_case(data))
    k = int(np.flatnonzero(scene.loads.force[:, 2])[0])
    assert np.allclose(scene.net.nodes[k], [1, 0, 0], atol=1e-15)
    r = exact(scene, steps=3)
    l1, l2 = 1 / (1 + T0 / EA), 3 / (1 + T0 / EA)

    def balance(q):
        u, d = q
        s1, s2 = math.hypot(u, d), math.hypot(4 - u, d)
        n1, n2 = EA * (s1 / l1 - 1), EA * (s2 / l2 - 1)
        return [n1 * u / s1 - n2 * (4 - u) / s2, (n1 / s1 + n2 / s2) * d - F]

    u, d = fsolve(balance, [1.0, 0.1], xtol=1e-14)
    assert r.x[k] == pytest.approx([u, 0, -d], abs=1e-9)
    left = scene.net.nodes[:, 0] < 1 - 1e-12
    for side, end in ((left, [0, 0, 0]), (~left, [4, 0, 0])):
        v = np.asarray(end) - r.x[k]
        w = r.x[side] - r.x[k]
        assert np.allclose(np.cross(w, v), 0, atol=1e-9)
    assert np.allclose(r.reaction.sum(axis=0), [0, 0, F], atol=1e-8)


def test_point_loads_at_a_node_use_it_and_share_a_split():
    data = straight()
    data["load"] = {
        "point": [
            {"cable": "c", "at": 0.5, "force": [0, 0, -1]},  # the given middle node
            {"cable": "c", "at": 0.0, "force": [0, 0, -1]},  # the first node
            {"cable": "c", "at": 0.2, "force": [0, 0, -1]},
            {"cable": "c", "at": 0.2, "force": [0, 0, -2]},  # the same new node
        ]
    }
    scene = build(parse_case(data))
    f = scene.loads.force[:, 2]
    assert f[1] == -1 and f[0] == -1
    new = np.flatnonzero(f == -3)
    assert new.size == 1 and new[0] >= 3
    assert np.allclose(scene.net.nodes[new[0]], 0.2 * np.array([3, 1, 2]), atol=1e-14)


def test_load_steps_reach_the_same_equilibrium():
    data = two_cables()
    data["load"] = {"line": [{"force": [0, 0, -20]}]}
    one_step = exact(build(parse_case(data)))
    data["solver"] = {"steps": 5}
    scene = build(parse_case(data))
    assert np.allclose(exact(scene, steps=5).x, one_step.x, atol=1e-9)


def test_the_readme_example_runs():
    """The cable example of the case keys' page is a valid case; its loads and reactions
    balance."""
    from pathlib import Path

    page = Path(__file__).resolve().parents[2] / "docs" / "reference" / "case-keys.md"
    text = page.read_text(encoding="utf-8")
    blocks = [b.split("```", 1)[0] for b in text.split("```toml\n")[1:]]
    (example,) = [b for b in blocks if "[[geometry.cable]]" in b]
    scene = build(parse_case(tomllib.loads(example)))
    assert scene.cables.names == ("ridge", "valley")
    r = exact(scene)
    assert np.allclose(r.reaction.sum(axis=0) + scene.loads.external_force(scene.net).sum(0), 0)
    at = np.flatnonzero(scene.loads.force[:, 2] == -10.0)
    assert np.allclose(scene.net.nodes[at], [[1.2, 0, 0]])


def test_the_memory_guard_counts_cable_edges_before_building():
    data = two_cables()
    data["geometry"]["edge_length"] = 1e-9
    one(data, "geometry.edge_length = 1e-09: the net would have about")
    del data["geometry"]["edge_length"]
    data["geometry"]["cable"][1]["edge_length"] = 1e-9
    one(data, "geometry.cable[1].edge_length: the net would have about")
