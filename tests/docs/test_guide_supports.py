"""docs/guide/supports.md runs as written, and what its scripts print is what the page
shows: the numbers on the page come from its commands."""

from __future__ import annotations

import re
import shutil

import pytest
from pages import ROOT, run_page, steps

PAGE = ROOT / "docs" / "guide" / "supports.md"


def _shown(text: str) -> list[str]:
    """The ```text blocks of the page, in order."""
    return re.findall(r"```text\n(.*?)```", text, flags=re.S)


@pytest.mark.slow  # six commands, each a fresh interpreter
def test_the_page_runs_and_prints_what_it_shows(tmp_path, monkeypatch):
    found = steps(PAGE)
    files = {s.name for s in found if s.kind == "file"}
    assert {"wall.toml", "wall.py", "anchor.toml", "anchor.py", "wall_tie.py"} <= files
    assert len([s for s in found if s.kind == "shell" and s.error]) == 1
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    done = run_page(PAGE, tmp_path)
    printed = {d.args[-1]: d.stdout for d in done if d.args[0] == "python"}
    shown = _shown(PAGE.read_text(encoding="utf-8"))
    for script, text in zip(("wall.py", "anchor.py", "wall_tie.py"), shown, strict=True):
        assert printed[script].split() == text.split(), (script, printed[script])
