"""Running a Markdown page of the documentation as a user would, top to bottom: a fenced
block whose first line is ``# NAME.EXT`` (a case file, a net) is written to NAME.EXT;
shell lines starting with ``$ `` run as subprocesses (a command whose next line shows
``catenet: error: ...`` must fail with exit status 2 and that message, every other must
succeed); ```python blocks are executed. All in one scratch directory holding a copy of
configs/."""

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
FILE = re.compile(r"^# ([\w.-]+\.\w+)\s*$")


def page_steps(page: Path) -> list[tuple[str, str, str | None]]:
    """(kind, text, expected error or file name) for each step of ``page``, in order:
    kind "file" (text: its content, third: its name), "shell" or "python"."""
    steps = []
    lines = page.read_text().splitlines()
    fence = None
    block: list[str] = []
    for i, line in enumerate(lines):
        if line.startswith("```"):
            if fence is None:
                fence, block = line[3:].strip(), []
                continue
            named = FILE.match(block[0]) if block else None
            if named:
                steps.append(("file", "\n".join(block) + "\n", named.group(1)))
            elif fence == "python":
                steps.append(("python", "\n".join(block), None))
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


def run_page(page: Path, tmp_path: Path, monkeypatch) -> list[tuple[str, str, str | None]]:
    """Runs every step of ``page`` in ``tmp_path``; the steps, for the caller's checks."""
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    steps = page_steps(page)
    for kind, text, extra in steps:
        if kind == "file":
            (tmp_path / extra).write_text(text)
        elif kind == "python":
            exec(compile(text, str(page), "exec"), {"__name__": page.stem})
        else:
            done = subprocess.run(
                shlex.split(text),
                cwd=tmp_path,
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
    return steps
