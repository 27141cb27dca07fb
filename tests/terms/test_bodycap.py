"""A free box's step cap as one kernel with its candidates (catenet/kernels/bodycap.py):
the same cap, to round-off, as the term's own walk over every node where the body does
not turn (both exact there), and never beyond the first contact where it turns (no node of the path
sampled finely up to the cap is inside the box)."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.terms.rigid_contact import T_FAR, BodyContact

ROOT = Path(__file__).resolve().parents[2]


def _drop():
    case = tomllib.loads((ROOT / "benchmarks" / "peers" / "mujoco_drop.toml").read_text())
    scene = build(parse_case(case))
    (touch,) = [t for t in scene.terms if type(t) is BodyContact]
    x = scene.net.nodes.copy()
    x[touch.frame.nodes] += [0.0, 0.0, -0.149]  # the box 1 mm above the net
    return scene, touch, x


def _walk(touch: BodyContact, x, dx, far: float) -> float:
    """The term's own walk over every node (the path before the kernel)."""
    _, A, U = touch._local(x)
    X0 = touch._buf[touch.nodes].copy()
    dc, dA = touch.frame.state(dx)
    dU = np.asarray(dx)[touch.nodes] - dc
    return touch._advance(X0, dU @ A + U @ dA, dU @ dA, touch._floor(X0, U), far)


def test_a_translating_box_has_the_walks_exact_cap():
    scene, touch, x = _drop()
    rng = np.random.default_rng(5)
    free = ~scene.net.fixed
    hits = 0
    for _ in range(30):
        dx = np.zeros_like(x)
        dx[free] = rng.normal(0.0, 0.01, (int(free.sum()), 3))
        dx[touch.frame.nodes] = rng.normal(0.0, 0.01, 3)  # the box translates: W = 0
        for far in (4.5, T_FAR):
            cap = touch.max_step_within(x, dx, far)
            walk = _walk(touch, x, dx, far)
            assert cap == pytest.approx(walk, rel=1e-12) or (math.isinf(cap) and math.isinf(walk))
            hits += math.isfinite(cap)
    assert hits > 10  # steps that do reach the box


def test_a_turning_box_caps_before_any_node_enters():
    scene, touch, x = _drop()
    rng = np.random.default_rng(6)
    free = ~scene.net.fixed
    capped = 0
    for _ in range(30):
        dx = np.zeros_like(x)
        dx[free] = rng.normal(0.0, 0.01, (int(free.sum()), 3))
        dx[touch.frame.nodes] = rng.normal(0.0, 0.01, (4, 3))  # turns and strains
        cap = touch.max_step_within(x, dx, 4.5)
        walk = _walk(touch, x, dx, 4.5)
        if math.isinf(cap):
            assert math.isinf(walk) or walk >= 4.5 * 0.99
            continue
        capped += 1
        for t in np.linspace(0.0, cap, 400):
            assert touch.gap(x + t * dx).min() > 0.0
        assert walk >= 0.5 * cap and cap >= 0.5 * walk  # both near the first contact
    assert capped > 10


@pytest.mark.parametrize("kind", ["box", "capsule"])
def test_the_least_gap_by_bounds_is_the_least_of_every_gap(kind):
    """``_least_gap`` evaluates a candidate's gap only where its bound (its last gap less
    how far it has moved) does not exceed the least so far: over pieces of random
    quadratic paths that pass into and out of the shape, one fast point among slow ones
    (the case that made it), the same number as the least of every gap, to the bit."""
    from catenet.kernels.bodycap import _least_gap
    from catenet.kernels.shapes import BOX, CAPSULE, shape_feature

    rng = np.random.default_rng(11)
    if kind == "box":
        axes = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        geom = np.concatenate([[0.3, -0.2, 0.1], axes.ravel(), [0.5, 0.4, 0.3], [0.05]])
        code = BOX
    else:
        geom = np.array([-0.4, 0.0, 0.1, 0.5, 0.2, -0.1, 0.25])
        code = CAPSULE
    n, P3 = np.empty(3), np.empty((3, 3))
    for _ in range(40):
        X = rng.normal(0.0, 1.0, (30, 3))
        V = rng.normal(0.0, 0.3, (30, 3))
        W = rng.normal(0.0, 0.05, (30, 3))
        V[0] *= 10.0 ** rng.integers(0, 12)  # one fast point
        low = np.array([shape_feature(code, X[j], geom, n, P3) for j in range(30)])
        P = X.copy()
        for t in np.cumsum(rng.uniform(0.0, 0.3, 12)):
            least = _least_gap(code, geom, X, V, W, t, P, low, n, P3)
            points = X + t * V + t * t * W
            every = [shape_feature(code, points[j], geom, n, P3) for j in range(30)]
            assert least == min(every)
            assert np.array_equal(P, points)
            assert np.all(low <= np.array(every))
