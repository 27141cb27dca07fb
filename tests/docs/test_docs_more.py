"""The other half of the pages of test_docs.py, each run as written (a file of its own,
so that the suite's two workers run the pages side by side)."""

from __future__ import annotations

import pytest
from test_docs import check_page, params


@pytest.mark.parametrize("path", list(params(1)))
def test_page_runs_as_written(path, tmp_path, monkeypatch):
    check_page(path, tmp_path, monkeypatch)
