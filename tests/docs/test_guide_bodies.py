"""docs/guide/bodies.md runs as written (tests/docs/pages.py: its case files are written,
its shell lines run, a line ``catenet: error: ...`` after one is the message it must
fail with (exit 2), and its ```python blocks run, all in one scratch directory, top to
bottom)."""

from __future__ import annotations

import shutil

from pages import ROOT, run_page, steps

PAGE = ROOT / "docs" / "guide" / "bodies.md"


def test_the_bodies_guide_runs_as_written(tmp_path, monkeypatch):
    kinds = [s.kind for s in steps(PAGE)]
    assert kinds.count("file") >= 4 and kinds.count("shell") >= 4 and "python" in kinds
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    run_page(PAGE, tmp_path)
