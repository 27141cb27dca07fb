"""Copies of a net keep everything: ``Net.replace`` is the one way to copy a net, and
``Net.same_as`` compares every array, the material law's included. Two hand copies used
to drop the law (a square net refitted with new supports or a prestrain, a sweep's test
of whether its workspace still fits)."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.model.laws import Law
from catenet.model.net import Net


def net_with_everything() -> Net:
    nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [5.0, 5.0, 5.0]]
    law = Law.uniform(2, "hencky", tension_only=False)
    return Net.from_arrays(
        nodes,
        [[0, 1], [1, 2]],
        EA=[100.0, 200.0],
        fixed=[0, 2],
        line_density=0.5,
        law=law,
        point_mass=[0.0, 2.0, 0.0, 3.0],
        bodies=1,
    )


def keeps(copy: Net, net: Net, *, except_for=()) -> None:
    assert copy.law.kind.tolist() == net.law.kind.tolist()
    assert copy.law.tension_only.tolist() == net.law.tension_only.tolist()
    assert np.array_equal(copy.point_mass, net.point_mass)
    assert copy.bodies == net.bodies
    for name in ("nodes", "edges", "EA", "fixed", "rest_length", "line_density"):
        if name not in except_for:
            assert np.array_equal(getattr(copy, name), getattr(net, name)), name


def test_replace_with_rest_length_and_with_point_mass_keep_the_rest():
    net = net_with_everything()
    keeps(net.replace(), net)
    assert net.replace().same_as(net) and net.same_as(net.replace())
    keeps(net.replace(rest_length=[1.1, 1.2]), net, except_for=("rest_length",))
    keeps(net.with_rest_length([1.1, 1.2]), net, except_for=("rest_length",))
    moved = net.replace(nodes=net.nodes + 0.1)
    keeps(moved, net, except_for=("nodes",))
    heavier = net.with_point_mass([0.0, 4.0, 0.0, 3.0])
    assert heavier.law is net.law and heavier.bodies == 1
    assert not heavier.same_as(net)


@pytest.mark.parametrize(
    "change",
    [
        {"rest_length": [1.0, 1.5]},
        {"EA": [100.0, 201.0]},
        {"fixed": [0]},
        {"law": Law.uniform(2, "neo_hookean", tension_only=False)},
        {"law": Law.uniform(2, "hencky", tension_only=True)},
        {"point_mass": None},
        {"line_density": 0.6},
    ],
)
def test_same_as_sees_every_difference(change):
    net = net_with_everything()
    assert not net.replace(**change).same_as(net)


def test_replace_refuses_what_a_net_has_not():
    with pytest.raises(TypeError, match="unknown fields"):
        net_with_everything().replace(colour="red")


def test_a_refitted_square_net_keeps_its_material_law():
    """A square net given supports and a prestrain is refitted (case/kinds/base.refit):
    its law (here Hencky's) must survive, as the unrefitted net's does."""
    case = {
        "geometry": {"kind": "square_net", "n": 6, "alpha": 0.0, "size": 1.0, "edge_length": 0.1},
        "material": {"EA": 1e4, "law": "hencky"},
        "load": {"pressure": 10.0},
    }
    plain = build(parse_case(case)).net
    case["geometry"]["prestrain"] = 0.01
    refitted = build(parse_case(case)).net
    assert set(plain.law.kind.tolist()) == set(refitted.law.kind.tolist()) == {2}
    assert np.allclose(refitted.rest_length * 1.01, plain.rest_length)


def test_replace_tension_only_switches_every_edge_of_the_law():
    net = net_with_everything()
    assert net.replace(tension_only=True).law.tension_only.all()
    assert not net.replace(tension_only=False).law.tension_only.any()
    assert net.replace(tension_only=True).law.kind.tolist() == net.law.kind.tolist()


def test_tension_only_per_edge_is_honoured_and_a_wrong_one_refused():
    """``from_arrays(tension_only=...)`` takes a bool or one per edge (docs/guide/
    solvers.md); a list of four False was taken as True (a non-empty list is truthy), so a
    precompressed chain of struts came out slack instead of unstable; a string or a list
    of the wrong length or of integers is refused, naming the key."""
    import catenet as cn

    nodes = np.array([[float(i), 0.0, 0.0] for i in range(5)])
    edges = np.array([[i, i + 1] for i in range(4)])
    net = cn.Net.from_arrays(nodes, edges, EA=1e6, fixed=[0, 4], tension_only=[False] * 4)
    assert not net.law.tension_only.any() and not net.tension_only
    mixed = [True, False, True, False]
    net = cn.Net.from_arrays(nodes, edges, EA=1e6, fixed=[0, 4], tension_only=mixed)
    assert net.law.tension_only.tolist() == mixed
    assert not net.replace(tension_only=False).law.tension_only.any()
    for bad in ("no", [True, False], [1, 0, 1, 0]):
        with pytest.raises(cn.ConfigError, match="tension_only = .*: must be a bool or a"):
            cn.Net.from_arrays(nodes, edges, EA=1e6, fixed=[0, 4], tension_only=bad)
    with pytest.raises(cn.ConfigError, match="tension_only = 'x'"):
        net.replace(tension_only="x")
    chain = cn.Net.from_arrays(
        nodes, edges, EA=1e6, fixed=[0, 4], rest_length=[1.001] * 4, tension_only=[False] * 4
    )
    r = cn.solve_static(chain, cn.Loads())
    assert r.stable is False and (r.tension < -900.0).all()
