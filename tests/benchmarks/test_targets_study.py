"""benchmarks/targets.py (the hypar on its surface against a Newton iteration) on its
smallest roof: a row of every column, the roof on its surface (no timing assertions)."""

from __future__ import annotations

from benchmarks.targets import roof_row


def test_a_small_roof_gives_a_row_with_its_gradients_and_ratios():
    row = roof_row(4)
    assert row["met"] and row["force_densities"] == 24 and 1 <= row["gradients"] <= 30
    assert row["static_converged"] and row["per_newton_s"] > 0
    assert row["gradient_over_newton"] > 0 and row["steps"] >= 0


def test_the_first_order_search_meets_a_small_roof_with_more_gradients(monkeypatch):
    """--first-order: L-BFGS-B on adjoint gradients (one adjoint solve each, the
    Jacobian never formed) reaches the same surface, in more gradients than the damped
    steps take."""
    from benchmarks import targets
    from catenet.formfind import design

    damped = roof_row(4)
    monkeypatch.setattr(design, "_search", targets.first_order)
    monkeypatch.setattr(design, "DENSE", -1)
    row = roof_row(4)
    assert row["met"]  # every node on the surface to formfind.tol
    assert row["gradients"] > damped["gradients"]
    assert row["products"] == row["gradients"]  # one adjoint solve per gradient
    assert row["steps"] == 0 and row["cr_iterations"] == 0  # no damped step solved
