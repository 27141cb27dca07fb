"""The form-finding study (``benchmarks/formfind.py``): its loaded roof and its table."""

from __future__ import annotations

import pytest


def test_bench_loaded_roof_row_and_report_line(tmp_path):
    """The formfind study's loaded roof (small here): form found, tension-only, loaded by
    snow, converged with reactions balancing the snow, and timed against a square net's
    static solve in the same run; the report prints its line."""
    from benchmarks.common import write_csv
    from benchmarks.formfind import SNOW, loaded
    from benchmarks.sections import formfind as section

    row = loaded(23, (10, 1 / 30), repeats=1)
    assert row["loaded_converged"] and row["loaded_dofs"] == 3 * 21 * 21
    assert row["loaded_reaction_balance_n"] <= 1e-8 * SNOW * 30.0**2
    assert 0.0 < row["loaded_max_deflection_m"] < 1.0
    assert row["loaded_over_square"] == pytest.approx(
        row["loaded_static_s"] / row["square_static_s"]
    )
    write_csv(
        [{"edges": 1012, "linear_s": 0.01, "scipy_s": 0.01, "plain_s": 0.01}, row],
        tmp_path / "formfind.csv",
    )
    text = "\n".join(section(tmp_path))
    assert f"A form-found roof of {row['loaded_dofs']} DOF (tension-only) under snow" in text
