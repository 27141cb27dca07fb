"""Potential.internal: the internal terms' gradient and energies at x, read from a time
step's last evaluation only while it stands (the same x, no step begun, no force changed
since), else computed: the same numbers either way."""

from __future__ import annotations

import numpy as np
from scenes import paper_net

from catenet.solver.workspace import Workspace
from catenet.terms import Inertia


def test_internal_reads_the_last_evaluation_only_while_it_stands():
    sq, loads = paper_net(6, edge=0.1)
    ws = Workspace(sq.net)
    free = ws.system.free_dofs
    inertia = Inertia(free)  # a time step's potential
    inertia.set_step(np.full(free.size, 1e3), sq.net.nodes.reshape(-1)[free])
    potential = ws.potential(loads, steps=(inertia,))
    static = ws.potential(loads)
    system = potential.system
    calls = []
    gradient = system.gradient
    system.gradient = lambda x: (calls.append(1), gradient(x))[1]  # counts the terms' runs
    x = sq.net.nodes.copy()
    x[:, 2] -= 0.01 * np.sin(np.pi * x[:, 0])

    def fresh(at):
        _, g = gradient(at)
        return g.copy(), list(system.energies)

    potential.evaluate(x)
    calls.clear()
    grad, energies = potential.internal(x)
    assert not calls  # the evaluation's, kept
    want, want_e = fresh(x)
    assert np.array_equal(grad, want) and energies == want_e
    moved = x.copy()
    moved[7, 2] += 1e-9
    grad, _ = potential.internal(moved)  # another x: computed
    assert calls and np.array_equal(grad, fresh(moved)[0])
    for change in (
        lambda: potential.begin_step(x, 1.0, 0.0),  # a new step (terms may change)
        lambda: potential.set_force(2.0 * potential.force),  # a new force (and factors)
        lambda: ws.potential(loads),  # another potential on the same terms
    ):
        potential.evaluate(x)
        change()
        calls.clear()
        potential.internal(x)
        assert calls  # no longer the evaluation's
    static.evaluate(x)  # a static potential keeps nothing: computed
    calls.clear()
    grad, _ = static.internal(x)
    assert calls and np.array_equal(grad, fresh(x)[0])
