"""docs/guide/modes.md runs as written (tests/docs/pages.py: its case file is written,
its commands run in order in one scratch directory), and leaves the figure and the
frames of the mode it exports."""

from __future__ import annotations

import shutil

import pytest
from pages import ROOT, run_page, steps

PAGE = ROOT / "docs" / "guide" / "modes.md"


def test_page_has_steps():
    kinds = [s.kind for s in steps(PAGE)]
    assert kinds.count("file") >= 1 and kinds.count("shell") >= 4 and "python" in kinds


@pytest.mark.slow
def test_modes_guide_runs_as_written(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    run_page(PAGE, tmp_path)
    assert (tmp_path / "out" / "stay-modes.png").exists()
    assert len(list((tmp_path / "out" / "stay-mode1").glob("*.vtu"))) == 16
