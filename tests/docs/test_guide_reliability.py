"""docs/guide/reliability.md runs as written: its case file is written, its commands run
and the refusals it shows are the messages catenet gives."""

from __future__ import annotations

from pathlib import Path

import pytest
from guide_page import page_steps, run_page

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "guide"


@pytest.mark.parametrize("page", ["reliability.md"])
def test_reliability_page_runs_as_written(tmp_path, page):
    steps = page_steps(GUIDE / page)
    assert any(kind == "file" for kind, _, _ in steps)
    assert sum(1 for _, _, error in steps if error) >= 3  # the refusals it shows
    assert run_page(GUIDE / page, tmp_path) >= 6
