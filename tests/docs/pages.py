"""Runs a Markdown page's examples as a reader would follow them (a helper for the
tests of docs/, not a test module).

In one scratch directory holding a copy of configs/: a ```toml block whose first line is
``# file: NAME`` is written to NAME; each ``$ `` line of a plain, console, bash or sh
block runs as a subprocess (a command whose next line starts with ``catenet: error:``
must fail with exit status 2 and that message on stderr, any other must succeed); a
```python block is executed.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent


def page_steps(page: Path) -> list[tuple[str, str, str | None]]:
    """(kind, text, expected error or file name) per example, in order: kind "file"
    (text the content, the third item its name), "shell" or "python"."""
    steps = []
    lines = Path(page).read_text(encoding="utf-8").splitlines()
    fence = None
    block: list[str] = []
    for i, line in enumerate(lines):
        if line.startswith("```"):
            if fence is None:
                fence, block = line[3:].strip(), []
                continue
            if fence == "python":
                steps.append(("python", "\n".join(block), None))
            elif fence == "toml" and block and block[0].startswith("# file: "):
                steps.append(("file", "\n".join(block) + "\n", block[0][8:].strip()))
            fence = None
            continue
        if fence is None:
            continue
        block.append(line)
        if fence in ("", "console", "bash", "sh") and line.startswith("$ "):
            command = re.sub(r"\s+#.*$", "", line[2:]).strip()
            following = lines[i + 1] if i + 1 < len(lines) else ""
            error = following if following.startswith("catenet: error:") else None
            steps.append(("shell", command, error))
    return steps


def run_page(page: Path, scratch: Path) -> list[subprocess.CompletedProcess]:
    """Runs every example of ``page`` in ``scratch`` (the current directory meanwhile);
    raises AssertionError naming the first that does not do what the page says."""
    shutil.copytree(ROOT / "configs", scratch / "configs", dirs_exist_ok=True)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    done_all = []
    here = os.getcwd()
    os.chdir(scratch)
    try:
        for kind, text, extra in page_steps(page):
            if kind == "file":
                (scratch / extra).write_text(text, encoding="utf-8")
                continue
            if kind == "python":
                exec(compile(text, str(page), "exec"), {"__name__": "page"})
                continue
            done = subprocess.run(
                shlex.split(text),
                cwd=scratch,
                env=env,
                capture_output=True,
                text=True,
                timeout=600,
            )
            if extra is None:
                assert done.returncode == 0, f"$ {text}\n{done.stdout}\n{done.stderr}"
            else:
                assert done.returncode == 2, f"$ {text}\n{done.stdout}\n{done.stderr}"
                assert extra in done.stderr, f"$ {text}\n{done.stderr}"
            done_all.append(done)
    finally:
        os.chdir(here)
    return done_all
