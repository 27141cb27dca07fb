"""What a run that stops at its forces' round-off says where nodes sit deep in a
barrier (``catenet.solver.events.deep_contact``)."""

from __future__ import annotations

import numpy as np


def test_nodes_pressed_deep_into_a_barrier_are_named_with_what_holds_them_farther_out():
    """A net dropped 0.2 m onto a fixed sphere sank to 6e-10 m of its barrier's 8.3e-6 m
    and the run stopped at the forces' round-off, blaming the tolerance and a body's spin;
    it now names the obstacle, the depth and the keys (with the distance 100x, the run
    went through). Nodes within a thousandth of the distance only; keyless terms (a
    continuation's stages) are not named."""
    from catenet.solver.events import deep_contact
    from catenet.terms.contact import PlaneBarrier

    plane = PlaneBarrier(np.array([1]), [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], kappa=1.0, dhat=1e-3)
    plane.key, plane.label = "obstacle[2].distance", "obstacle[2] (kind 'plane')"
    x = np.array([[0.0, 0.0, 5.0], [0.0, 0.0, 5e-7]])
    said = deep_contact([plane], x)
    assert said.startswith("nodes are pressed to 5e-07 m of obstacle[2] (kind 'plane')")
    assert "obstacle[2].stiffness" in said and "obstacle[2].distance = 0.1, 100x" in said
    x[1, 2] = 2e-6  # a fifth of a thousandth: not deep
    assert deep_contact([plane], x) == ""
    plane.key = ""
    x[1, 2] = 5e-7
    assert deep_contact([plane], x) == ""


def test_strands_pressed_together_name_the_self_contact_distance():
    """A heavy rope dropped onto a cord net with self-contact stopped the same way, its
    strands 2e-11 m apart: the self-contact is named by its distance key."""
    import catenet as cn
    from catenet.solver.events import deep_contact
    from catenet.terms.strands import SelfContact

    nodes = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 5e-7], [0.0, 1.0, 5e-7]]
    net = cn.Net.from_arrays(nodes, [[0, 1], [2, 3]], EA=1e3, fixed=[0, 1, 2, 3])
    term = SelfContact(net, kappa=1.0, dhat=1e-3)
    term.key, term.label = "solver.self_contact_distance", "the strands' self-contact"
    said = deep_contact([term], net.nodes)
    assert said.startswith("strands are pressed to 5e-07 m of each other")
    assert "solver.self_contact_distance = 0.1, 100x" in said
    assert (
        deep_contact([term], net.nodes + [[0, 0, 0], [0, 0, 0], [0, 0, 1e-5], [0, 0, 1e-5]]) == ""
    )
