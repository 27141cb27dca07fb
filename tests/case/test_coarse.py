"""The same case at longer edges (catenet.case.coarse, Scene.coarser): the coarse net of
the nested start, only where the case has edge lengths and names no renumbered node."""

from __future__ import annotations

import pytest
from conftest import CONFIGS
from meshes import hypar_roof

from catenet.case import build, load_case, parse_case
from catenet.case.coarse import coarse_case, node_indices

N34 = CONFIGS / "fig4g_n34_alpha_0.toml"


def test_a_square_net_at_longer_edges():
    case = load_case(N34, ["geometry.edge_length=0.002"])
    coarse = coarse_case(case, 5.0)
    assert coarse.geometry.edge_length == pytest.approx(0.01)
    assert coarse.load == case.load and coarse.solver == case.solver
    fine = build(case)
    scene = fine.coarser(5.0)
    assert scene.net.n_nodes < fine.net.n_nodes
    assert scene.net.n_nodes == build(load_case(N34, ["geometry.edge_length=0.01"])).net.n_nodes


def test_cables_with_edge_lengths_at_longer_edges():
    data = hypar_roof(edge_length=0.5)
    data["geometry"]["cable"][0]["edge_length"] = 0.25  # a cable's own
    case = parse_case(data)
    coarse = coarse_case(case, 2.0)
    assert coarse.geometry.edge_length == 1.0
    assert coarse.geometry.cables[0].edge_length == 0.5
    assert coarse.geometry.cables[-1].edge_length == case.geometry.cables[-1].edge_length * 2
    assert coarse.geometry.nodes == case.geometry.nodes
    fine = build(case)
    assert fine.coarser(2.0).net.n_nodes < fine.net.n_nodes


def test_no_coarse_net_without_edge_lengths():
    assert coarse_case(load_case(CONFIGS / "catenary.toml"), 2.0) is None  # kind = "cable"
    data = hypar_roof()  # only the ring's edge_length, longer than its segments
    assert coarse_case(parse_case(data), 2.0) is not None
    assert build(parse_case(data)).coarser(2.0) is None  # no fewer nodes
    del data["geometry"]["cable"][-1]["edge_length"]  # none: a segment is one edge
    assert coarse_case(parse_case(data), 2.0) is None
    assert coarse_case(load_case(N34), 1.0) is None  # not longer


def test_nodes_named_by_an_index_refinement_changes():
    """A square net's nodes are renumbered by refinement: a support or load at an index
    would be elsewhere on the coarse net. A graph's given nodes keep their indices."""
    case = load_case(N34, ["supports.fixed=[0, 1, 2]"])
    assert node_indices(case) == [0, 1, 2]
    assert coarse_case(case, 2.0) is None
    assert coarse_case(load_case(N34, ['supports.fixed=["center"]']), 2.0) is not None
    data = hypar_roof(edge_length=0.5)
    data["load"] = {"point": [{"node": len(data["geometry"]["nodes"]) - 1, "force": [0, 0, -1]}]}
    assert coarse_case(parse_case(data), 2.0) is not None
