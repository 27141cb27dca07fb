"""benchmarks/targets.py (the hypar on its surface against a Newton iteration) on its
smallest roof: a row of every column, the roof on its surface (no timing assertions)."""

from __future__ import annotations

from benchmarks.targets import roof_row


def test_a_small_roof_gives_a_row_with_its_gradients_and_ratios():
    row = roof_row(4)
    assert row["met"] and row["force_densities"] == 24 and 1 <= row["gradients"] <= 30
    assert row["static_converged"] and row["per_newton_s"] > 0
    assert row["gradient_over_newton"] > 0 and row["steps"] >= 0
