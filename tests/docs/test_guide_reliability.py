"""docs/guide/reliability.md runs as written (tests/docs/pages.py): its case file is
written, its commands run and the refusals it shows are the messages catenet gives."""

from __future__ import annotations

import shutil

from pages import ROOT, run_page, steps

PAGE = ROOT / "docs" / "guide" / "reliability.md"


def test_reliability_page_runs_as_written(tmp_path, monkeypatch):
    found = steps(PAGE)
    assert any(s.kind == "file" for s in found)
    assert sum(1 for s in found if s.kind == "shell" and s.error) >= 3  # the refusals it shows
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    assert len(run_page(PAGE, tmp_path)) >= 6
