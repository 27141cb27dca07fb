"""The memory guard's estimate (the scale study, tests/benchmarks/test_scale.py, checks it
against measured peaks)."""

from __future__ import annotations

import pytest

from catenet.case.guard import estimate_memory
from catenet.case.kinds.square_net import SquareNetConfig


def test_memory_estimate_is_the_process_plus_a_cost_per_node_edge_and_joint():
    own = estimate_memory(0.0, 0.0, 0.0)
    assert 100 * 2**20 < own < 400 * 2**20  # the process that has loaded NumPy, Numba, MKL
    one = estimate_memory(1e5, 1e5, 0.0) - own
    assert estimate_memory(2e5, 2e5, 0.0) - own == pytest.approx(2 * one)
    assert estimate_memory(1e5, 2e5, 0.0) - own == pytest.approx(1.5 * one)
    assert 0.5e3 < one / 2e5 < 4e3  # bytes per node and edge
    assert estimate_memory(1e5, 1e5, 1e4) == estimate_memory(1e5, 1e5, 0.0)  # see its doc
    small = SquareNetConfig(n=34, alpha=0.0, size=1.0, edge_length=0.01).estimate_size()
    large = SquareNetConfig(n=340, alpha=0.0, size=1.0, edge_length=0.001).estimate_size()
    grow = (estimate_memory(*large[:3]) - own) / (estimate_memory(*small[:3]) - own)
    assert 80 < grow < 120  # 100 times the DOF
