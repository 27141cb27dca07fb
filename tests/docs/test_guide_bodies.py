"""docs/guide/bodies.md runs as written: its case files (```toml blocks whose first line
is ``# file: NAME``) are written, its shell lines (``$ ...``) run, a line
``catenet: error: ...`` after one is the message it must fail with (exit 2), and its
```python blocks run, all in one scratch directory, top to bottom."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "guide" / "bodies.md"


def page_steps(path: Path) -> list[tuple[str, str, str | None]]:
    """(kind, text, expected error) of a Markdown page: "file" (name and text), "shell",
    "python", in order."""
    steps = []
    lines = path.read_text(encoding="utf-8").splitlines()
    fence, block = None, []
    for i, line in enumerate(lines):
        if line.startswith("```"):
            if fence is None:
                fence, block = line[3:].strip(), []
                continue
            if fence == "python":
                steps.append(("python", "\n".join(block), None))
            elif fence == "toml" and block and block[0].startswith("# file: "):
                steps.append(("file", "\n".join(block[1:]) + "\n", block[0][8:].strip()))
            fence = None
            continue
        if fence is None:
            continue
        block.append(line)
        if fence in ("", "console") and line.startswith("$ "):
            command = re.sub(r"\s+#.*$", "", line[2:]).strip()
            following = lines[i + 1] if i + 1 < len(lines) else ""
            error = following if following.startswith("catenet: error:") else None
            steps.append(("shell", command, error))
    return steps


def test_the_bodies_guide_runs_as_written(tmp_path, monkeypatch):
    steps = page_steps(PAGE)
    kinds = [k for k, _, _ in steps]
    assert kinds.count("file") >= 4 and kinds.count("shell") >= 4 and "python" in kinds
    monkeypatch.chdir(tmp_path)
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"}
    for kind, text, extra in steps:
        if kind == "file":
            (tmp_path / extra).write_text(text, encoding="utf-8")
        elif kind == "python":
            exec(compile(text, str(PAGE), "exec"), {"__name__": "guide"})
        else:
            done = subprocess.run(
                shlex.split(text), cwd=tmp_path, env=env, capture_output=True, text=True,
                timeout=600,
            )  # fmt: skip
            out = f"$ {text}\n{done.stdout}\n{done.stderr}"
            if extra is None:
                assert done.returncode == 0, out
            else:
                assert done.returncode == 2, out
                assert extra in done.stderr, out
