"""The reuse study's table in docs/performance.md (``benchmarks/sections_reuse.py``)."""

from __future__ import annotations


def test_the_performance_section_reports_the_reuse_study(tmp_path):
    from benchmarks.common import write_csv
    from benchmarks.sections_reuse import reuse

    assert reuse(tmp_path) == []  # the study has not run
    common = {"dofs": 9555, "steps": 341, "repeats": 7, "iterations": 500}
    rows = [
        {"scene": "relax", "variant": "reuse", "reference": "fresh", "seconds": 0.8,
         "ratio": 3.1, "ratio_is": "speed-up", "factorizations": 99,
         "max_rel_difference": 4e-9, "static_rel_difference": 3e-7, **common},
        {"scene": "relax", "variant": "fresh", "reference": "fresh", "seconds": 2.48,
         "ratio": 1.0, "ratio_is": "speed-up", "factorizations": 496,
         "max_rel_difference": 0.0, **common},
        {"scene": "idle obstacle", "variant": "idle", "reference": "none", "seconds": 2.6,
         "ratio": 1.04, "ratio_is": "cost", "factorizations": 496,
         "max_rel_difference": 0.0, **common},
    ]  # fmt: skip
    write_csv(rows, tmp_path / "reuse.csv")
    text = "\n".join(reuse(tmp_path))
    assert "medians of 7 repeats" in text
    row = "| relax | reuse | 9555 | 341 | 0.8 | 3.10x faster | 99 | 500 | 4.0e-09 | 3.0e-07 |"
    assert row in text
    assert "| relax | fresh | 9555 | 341 | 2.48 | reference |" in text
    assert "| idle obstacle | idle | 9555 | 341 | 2.6 | +4.0 % time |" in text
