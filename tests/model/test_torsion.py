"""The rods' twist with its twist angles as DOFs (``catenet.model.torsion``): the vertex
gradients and the blocks H_x theta, H_theta theta and H_xx of the un-eliminated energy
against finite differences of that energy written from its definition (parallel
transport of each edge's frame, the material twist at each vertex), on a chain clamped
at both ends and twisted, a chain clamped at one end and a ring, all bent; and the
Schur complement of the blocks is the twist term's eliminated Hessian."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.model.net import Net
from catenet.model.rods import build_rods
from catenet.model.torsion import build_torsion
from catenet.model.twist import build_twists
from catenet.terms.twist import Twist

GJ = np.array([3.0, 2.0, 4.0, 3.5, 2.5, 3.0, 5.0])  # per edge: unequal compliances
RHO_J = 0.7  # kg m


def _transport(u, v, w):
    b = np.cross(u, v)
    return w + np.cross(b, w) + np.cross(b, np.cross(b, w)) / (1.0 + u @ v)


def _normal(t):
    a = np.eye(3)[int(np.argmin(np.abs(t)))]
    u = a - (a @ t) * t
    return u / np.linalg.norm(u)


def _wavy(n=5, seed=3):
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.linspace(0.0, 5.0, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    return x + 0.3 * rng.standard_normal(x.shape)


def _ring(m=6):
    a = 2.0 * np.pi * np.arange(m) / m
    return np.column_stack([np.cos(a), np.sin(a), 0.3 * np.sin(2.0 * a) + 0.1 * np.cos(3.0 * a)])


def _build(x, kind):
    """(net, torsion, twist term or None, its moment) of a chain along x: "both" clamped
    at both ends and turned by 0.9 rad, "one" clamped at its start, "ring" closed."""
    m = len(x) if kind == "ring" else len(x) - 1
    k = np.arange(m)
    edges = np.column_stack([k, (k + 1) % len(x)])
    clamped = {"both": [0, len(x) - 1], "one": [0], "ring": []}[kind]
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    line = np.zeros(m, np.int64)
    rods = build_rods(net, np.full(m, 2.0), line, clamped=np.array(clamped, dtype=np.int64))
    gj = GJ[:m]
    twists = build_twists(net, gj, line, rods.clamps, rods.tangent)
    term = Twist(twists, len(x), x, [(0, 0.9, None)]) if len(twists) else None
    torsion = build_torsion(net, gj, np.full(m, RHO_J), line, rods.clamps, rods.tangent, twists)
    return net, torsion, term


def _energy_function(torsion, x0, moment):
    """E(x, theta) from the definition (module docstring of catenet.model.torsion), with
    frames carried from x0 and each vertex's twist at (x0, theta = 0) c_v M (the
    eliminated state of moment M), and its gradient in x from the kernel's vertex
    gradients: sum_v (tw_v / c_v) dm_v / dx."""
    from catenet.kernels.twist import vertex_gradients

    t0 = _tangents(torsion, x0)
    frames = [_normal(t) for t in t0]
    n = torsion.count
    ring = bool(torsion.closed[0])

    def vertices(x, theta):
        t = _tangents(torsion, x)
        a = [_transport(t0[k], t[k], frames[k]) for k in range(len(t))]
        th = np.concatenate([[0.0], theta, [0.0]])  # a clamp's angle is held
        pairs = [(n, 1)] + [(v, v + 1) for v in range(1, n)] if ring else []
        if not ring:
            first = 0 if torsion.held[0, 0] else 1
            last = n + 1 if torsion.held[0, 1] else n
            pairs = [(v - 1, v) for v in range(first + 1, last + 1)]
        out = []
        for p, q in pairs:
            u = _transport(t[p], t[q], a[p])
            m_v = math.atan2(float(np.cross(u, a[q]) @ t[q]), float(u @ a[q]))
            c = 0.5 * (_c(torsion, p, n, ring) + _c(torsion, q, n, ring))
            out.append((m_v + th[q] - th[p], c))
        return out

    base = vertices(x0, np.zeros(n))

    def moments(x, theta):
        pairs = zip(vertices(x, theta), base, strict=True)
        return [((tw - tw0) / c + moment, c) for (tw, c), (tw0, _) in pairs]

    def energy(x, theta):
        return sum(0.5 * c * m * m for m, c in moments(x, theta))

    def gradient(x, theta):
        t = torsion
        args = (
            t.nodes,
            t.start,
            t.closed,
            t.head,
            t.tail,
            t.held,
            t.compliance,
            t.partner,
            t.end_compliance,
        )
        comp, who, grad, _ = vertex_gradients(np.ascontiguousarray(x), *args)
        g = np.zeros_like(x)
        for v, (m, c) in enumerate(moments(x, theta)):
            assert c == pytest.approx(comp[v], rel=1e-14)
            for j in range(3):
                if who[v, j] >= 0:
                    g[who[v, j]] += m * grad[v, j]
        return g.ravel()

    return energy, gradient


def _c(torsion, slot, n, ring):
    if ring:
        return torsion.compliance[(slot - 1) % n]
    return 0.0 if slot in (0, n + 1) else torsion.compliance[slot - 1]


def _tangents(torsion, x):
    """Tangent slots: a clamp's (or a zero), the edges', a clamp's (a ring: its last
    edge first as slot 0)."""
    nodes = torsion.nodes
    chain = list(nodes) + ([nodes[0]] if torsion.closed[0] else [])
    e = [x[b] - x[a] for a, b in zip(chain[:-1], chain[1:], strict=True)]
    t = [d / np.linalg.norm(d) for d in e]
    if torsion.closed[0]:
        return [t[-1], *t]
    head = torsion.head[0] if torsion.held[0, 0] else _normal(t[0])
    tail = torsion.tail[0] if torsion.held[0, 1] else _normal(t[-1])
    return [head, *t, tail]


def _dense_blocks(torsion, net, x, term):
    dk, kxt, ktt = torsion.blocks(x, None if term is None else term.twists)
    n = 3 * len(x)
    k_xx = dk.toarray()
    if term is not None:  # + the twist term's eliminated Hessian
        rows, cols = term.pattern()
        values = np.zeros(rows.size)
        term.hessian(x, values)
        np.add.at(k_xx, (rows, cols), values)
    return k_xx.reshape(n, n), kxt.toarray(), ktt.toarray()


@pytest.mark.parametrize("kind", ["both", "one", "ring"])
def test_blocks_match_finite_differences_of_the_energy(kind):
    """The vertex gradients sum_v (tw_v / c_v) dm_v / dx against central differences of
    the energy (at theta = 0 and at turned angles); then K_theta theta, K_x theta and
    H_xx (at the eliminated state, theta = 0) against central differences of the
    gradients in theta and x, each to 1e-6 of its scale."""
    x = _ring() if kind == "ring" else _wavy()
    net, torsion, term = _build(x, kind)
    moment = 0.0 if term is None else float(term.moments(x)[0])
    assert (term is None) == (kind == "one")
    energy, gradient = _energy_function(torsion, x, moment)
    n = torsion.count
    k_xx, k_xt, k_tt = _dense_blocks(torsion, net, x, term)
    h = 1e-6
    turned = np.random.default_rng(5).uniform(-0.3, 0.3, n)
    scale = np.abs(gradient(x, turned)).max()
    assert scale > 0.1
    for theta in (turned, np.zeros(n)):
        fd = np.zeros(x.size)
        for i in range(x.size):
            d = np.zeros(x.size)
            d[i] = h
            step = d.reshape(x.shape)
            fd[i] = (energy(x + step, theta) - energy(x - step, theta)) / (2 * h)
        assert np.abs(fd - gradient(x, theta)).max() < 1e-6 * scale

    def grad_t(theta):
        return np.array(
            [(energy(x, theta + h * e) - energy(x, theta - h * e)) / (2 * h) for e in np.eye(n)]
        )

    zero = np.zeros(n)
    assert np.abs(grad_t(zero)).max() < 1e-8  # theta = 0 is the eliminated state
    h = 1e-5
    fd_tt = np.column_stack([(grad_t(h * e) - grad_t(-h * e)) / (2 * h) for e in np.eye(n)])
    assert np.abs(fd_tt - k_tt).max() < 1e-6 * np.abs(k_tt).max()
    fd_xt = np.column_stack(
        [(gradient(x, h * e) - gradient(x, -h * e)) / (2 * h) for e in np.eye(n)]
    )
    assert np.abs(fd_xt - k_xt).max() < 1e-6 * np.abs(k_xt).max()
    fd_xx = np.zeros_like(k_xx)
    for i in range(x.size):
        d = np.zeros(x.size)
        d[i] = h
        step = d.reshape(x.shape)
        fd_xx[:, i] = (gradient(x + step, zero) - gradient(x - step, zero)) / (2 * h)
    assert np.abs(fd_xx - k_xx).max() < 1e-6 * np.abs(k_xx).max()


@pytest.mark.parametrize("kind", ["both", "ring"])
def test_the_schur_complement_is_the_eliminated_hessian(kind):
    """Eliminating the angles from the blocks (H_xx - H_xt H_tt^+ H_tx) gives the twist
    term's own Hessian g g^T / C + M Hess Theta (a ring's H_tt is singular on its
    spin, which H_xt does not reach: its pseudo-inverse)."""
    x = _ring() if kind == "ring" else _wavy()
    net, torsion, term = _build(x, kind)
    k_xx, k_xt, k_tt = _dense_blocks(torsion, net, x, term)
    schur = k_xx - k_xt @ np.linalg.pinv(k_tt) @ k_xt.T
    rows, cols = term.pattern()
    values = np.zeros(rows.size)
    term.hessian(x, values)
    eliminated = np.zeros_like(k_xx)
    np.add.at(eliminated, (rows, cols), values)
    assert np.abs(schur - eliminated).max() < 1e-10 * np.abs(eliminated).max()


def test_which_chains_carry_angles_and_their_inertia():
    """Every twisting chain whatever holds its ends; J = rho J_p l0 per edge; a chain of
    no rotational inertia keeps its twist eliminated; the spins: rings and chains held
    at no end."""
    x = _wavy()
    net, torsion, _ = _build(x, "one")
    assert torsion.count == 5 and torsion.held.tolist() == [[True, False]]
    assert torsion.inertia == pytest.approx(RHO_J * net.rest_length)
    assert torsion.spins == 0
    _, ring, _ = _build(_ring(), "ring")
    assert ring.spins == 1
    m = len(x) - 1
    edges = np.column_stack([np.arange(m), np.arange(1, m + 1)])
    free = Net.from_arrays(x, edges, EA=1.0, fixed=[0, m], tension_only=False)
    rods = build_rods(free, np.full(m, 2.0), np.zeros(m, np.int64))
    args = (np.zeros(m, np.int64), rods.clamps, rods.tangent, None)
    pinned = build_torsion(free, GJ[:m], np.full(m, RHO_J), *args)
    assert pinned.spins == 1 and not pinned.held.any()
    assert build_torsion(free, GJ[:m], np.zeros(m), *args) is None
