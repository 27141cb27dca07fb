"""docs/guide/modes.md runs as written: its case files (```toml blocks whose first line
is ``# file: NAME``) are written, its shell lines (``$ ...``) run in order in one
scratch directory, and its Python blocks are executed. A command followed by a line
``catenet: error: ...`` must fail with exit status 2 and that message."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "guide" / "modes.md"
BIN = Path(sys.executable).parent


def page_steps(page: Path) -> list[tuple[str, str, str | None]]:
    """(kind, text, expected error): "file" (text = NAME\\ncontent), "shell", "python"."""
    steps, fence, block = [], None, []
    lines = page.read_text().splitlines()
    for i, line in enumerate(lines):
        if line.startswith("```"):
            if fence is None:
                fence, block = line[3:].strip(), []
                continue
            if fence == "python":
                steps.append(("python", "\n".join(block), None))
            elif fence == "toml" and block and block[0].startswith("# file: "):
                steps.append(("file", block[0][8:].strip() + "\n" + "\n".join(block[1:]), None))
            fence = None
            continue
        if fence is None:
            continue
        block.append(line)
        if fence in ("", "console", "bash", "sh") and line.startswith("$ "):
            following = lines[i + 1] if i + 1 < len(lines) else ""
            error = following if following.startswith("catenet: error:") else None
            steps.append(("shell", re.sub(r"\s+#.*$", "", line[2:]).strip(), error))
    return steps


def test_page_has_steps():
    kinds = [kind for kind, _, _ in page_steps(PAGE)]
    assert kinds.count("file") >= 1 and kinds.count("shell") >= 4 and "python" in kinds


@pytest.mark.slow
def test_modes_guide_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    for kind, text, error in page_steps(PAGE):
        if kind == "file":
            name, _, content = text.partition("\n")
            (tmp_path / name).write_text(content + "\n")
            continue
        if kind == "python":
            exec(compile(text, str(PAGE), "exec"), {"__name__": "guide"})
            continue
        done = subprocess.run(shlex.split(text), cwd=tmp_path, env=env, capture_output=True,
                              text=True, timeout=600)  # fmt: skip
        if error is None:
            assert done.returncode == 0, f"$ {text}\n{done.stdout}\n{done.stderr}"
        else:
            assert done.returncode == 2, f"$ {text}\n{done.stdout}\n{done.stderr}"
            assert error in done.stderr, f"$ {text}\n{done.stderr}"
    assert (tmp_path / "out" / "stay-modes.png").exists()
    assert len(list((tmp_path / "out" / "stay-mode1").glob("*.vtu"))) == 16
