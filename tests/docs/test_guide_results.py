"""docs/guide/results.md runs as written (tests/docs/pages.py): its case files, commands
and Python blocks; the numbers it shows are the ones catenet prints."""

from __future__ import annotations

import shutil

import pytest
from pages import ROOT, run_page, steps

PAGE = ROOT / "docs" / "guide" / "results.md"


def test_the_page_has_examples():
    kinds = [s.kind for s in steps(PAGE)]
    assert kinds.count("file") >= 3 and kinds.count("shell") >= 8 and kinds.count("python") >= 4


@pytest.mark.slow  # a dozen catenet processes (as the README's test)
def test_the_page_runs_as_written(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    done = run_page(PAGE, tmp_path)
    assert (tmp_path / "out" / "cases.h5").exists() and (tmp_path / "out" / "mast.png").exists()
    printed = "\n".join(d.stdout for d in done)
    # the numbers the page shows are the ones catenet prints
    for line in (
        "peak tension 402.841 N at t = 0.45 s (edge 0); the final state's max tension is "
        "0.238085 N",
        "ULS_x                      0      15000      0.0260416      1         32508.6      1     "
        "63981.3",
        "probe        node 1 moves [0.01736, 0, -7.527e-06] m",
    ):
        assert line in printed
