"""The CSR pattern built per row (catenet.kernels.pattern) is the one a global np.unique
of the keys row * n + col gives: same indptr, indices and position of every value."""

from __future__ import annotations

import numpy as np
import pytest

import catenet as cn
from catenet.solver.system import System
from catenet.terms import Stretch, Term
from catenet.terms.contact import PlaneBarrier
from catenet.terms.inertia import Inertia


@pytest.fixture(autouse=True)
def kernels_for_every_size(monkeypatch):
    """These tests check the kernels' ways, which System takes above SMALL_PATTERN."""
    import catenet.solver.system

    monkeypatch.setattr(catenet.solver.system, "SMALL_PATTERN", -1)


def reference(net, terms, upper):
    """The np.unique way (System._unique_pattern, which small systems take): keys of every
    kept entry, one np.unique over them all."""
    return System(net, terms, upper=upper)._unique_pattern()


def random_net(seed, n=40, m=60, fixed=(0, 3, 7)):
    """A chain through every node plus random chords, some edges from the higher node."""
    rng = np.random.default_rng(seed)
    nodes = rng.uniform(-1.0, 1.0, (n, 3))
    pairs = {(k, k + 1) for k in range(n - 1)}
    pairs |= {tuple(sorted(rng.choice(n, 2, replace=False))) for _ in range(m)}
    edges = np.array(sorted(pairs), dtype=np.int64)
    rng.shuffle(edges)
    edges[::3] = edges[::3, ::-1]
    return cn.Net.from_arrays(nodes, edges, EA=1.0, fixed=list(fixed))


class Coupling(Term):
    """Couples the x DOFs of two nodes (a term the pattern may lack)."""

    def __init__(self, i, j):
        self.rows = np.array([3 * i, 3 * j, 3 * i, 3 * j])
        self.cols = np.array([3 * i, 3 * j, 3 * j, 3 * i])

    def pattern(self):
        return self.rows, self.cols


@pytest.mark.parametrize("upper", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pattern_equals_the_global_unique_of_its_keys(upper, seed):
    net = random_net(seed)
    free = np.flatnonzero(~net.fixed)
    terms = [
        Stretch(net),
        PlaneBarrier(free[::2], [0, 0, -2.0], [0, 0, 1], kappa=1.0, dhat=0.1),
        Inertia(np.flatnonzero(np.repeat(~net.fixed, 3))[5:]),
    ]
    system = System(net, terms, upper=upper)
    indptr, indices, targets, diag = reference(net, terms, upper)
    assert system.indptr.dtype == indptr.dtype and system.indices.dtype == indices.dtype
    assert np.array_equal(system.indptr, indptr)
    assert np.array_equal(system.indices, indices)
    assert system.nnz == indices.size
    for term, target in zip(terms, targets, strict=True):
        assert np.array_equal(system.target(term), target)
    assert np.array_equal(system.diag_pos, diag)
    # the same from every entry (the path for terms that couple nodes without an edge)
    got = system._entry_pattern()
    assert np.array_equal(got[0], indptr) and np.array_equal(got[1], indices)
    for mine, target in zip(got[2], targets, strict=True):
        assert np.array_equal(mine, target)
    assert np.array_equal(got[3], diag)


def test_pattern_of_the_square_net_and_of_nets_without_free_nodes():
    sq = cn.square_net(6, 0.3, 1.0, 1 / 7, cn.Material(EA=1.0))
    system = System(sq.net)
    indptr, indices, targets, diag = reference(sq.net, [Stretch(sq.net)], True)
    assert np.array_equal(system.indptr, indptr) and np.array_equal(system.indices, indices)
    assert np.array_equal(system.target(system.stretch), targets[0])
    assert np.array_equal(system.diag_pos, diag)
    held = cn.Net.from_arrays(np.eye(3), [[0, 1], [1, 2]], EA=1.0, fixed=[0, 1, 2])
    empty = System(held)
    assert empty.n_free == 0 and empty.nnz == 0 and np.array_equal(empty.indptr, [0])
    assert np.all(empty.target(empty.stretch) == -1)


def test_a_term_outside_the_pattern_is_refused_and_one_inside_is_placed():
    net = random_net(3)
    system = System(net)
    free = np.flatnonzero(~net.fixed)
    ground = PlaneBarrier(free, [0, 0, -2.0], [0, 0, 1], kappa=1.0, dhat=0.1)  # node blocks: fit
    i, j = net.edges[5]
    along = Coupling(i, j)
    _, _, targets, _ = reference(net, [Stretch(net), ground, along], True)
    assert np.array_equal(system.target(ground), targets[1])
    assert np.array_equal(system.target(along), targets[2])
    linked = {tuple(e) for e in net.edges.tolist()} | {tuple(e[::-1]) for e in net.edges.tolist()}
    a, b = next((a, b) for a in free for b in free if a != b and (a, b) not in linked)
    with pytest.raises(ValueError, match="outside the workspace's sparsity pattern"):
        system.target(Coupling(a, b))
    terms = [Stretch(net), Coupling(a, b)]
    wide = System(net, terms)  # built from every entry: the edges' blocks lack (a, b)
    indptr, indices, targets, diag = reference(net, terms, True)
    assert np.array_equal(wide.indptr, indptr) and np.array_equal(wide.indices, indices)
    assert np.array_equal(wide.target(terms[1]), targets[1]) and (targets[1] >= 0).sum() == 3
    assert np.array_equal(wide.target(terms[0]), targets[0])
    assert np.array_equal(wide.diag_pos, diag)


@pytest.mark.parametrize("upper", [True, False])
def test_small_systems_take_np_unique_and_get_the_same_arrays(monkeypatch, upper):
    """Below SMALL_PATTERN values the pattern comes from one np.unique (no kernel to
    compile on a first run); the arrays are the kernels' to the last entry."""
    import catenet.solver.system

    net = random_net(5)
    free = np.flatnonzero(~net.fixed)
    terms = [Stretch(net), PlaneBarrier(free, [0, 0, -2.0], [0, 0, 1], kappa=1.0, dhat=0.1)]
    by_kernels = System(net, terms, upper=upper)
    monkeypatch.setattr(catenet.solver.system, "SMALL_PATTERN", 10**9)
    small = System(net, terms, upper=upper)
    assert small._entry_count() <= catenet.solver.system.SMALL_PATTERN
    for name in ("indptr", "indices", "diag_pos"):
        a, b = getattr(small, name), getattr(by_kernels, name)
        assert a.dtype == b.dtype and np.array_equal(a, b)
    for term in terms:
        assert np.array_equal(small.target(term), by_kernels.target(term))
