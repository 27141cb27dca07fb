"""Running a Markdown page of the documentation as a user would: a block right after the
line ``<!-- file: NAME -->`` is written to NAME, its shell lines (``$ ...`` in plain code
blocks) run in order in one scratch directory. A command whose next line shows
``catenet: error: ...`` must fail with exit status 2 and that message (the start of it);
every other command must succeed."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

BIN = Path(sys.executable).parent


def page_steps(path: Path) -> list[tuple[str, str, str | None]]:
    """(kind, text, expected) in order: ("file", name, content) and ("shell", command,
    expected error or None)."""
    steps: list[tuple[str, str, str | None]] = []
    lines = path.read_text().splitlines()
    fence = None
    name = None  # the file the next block goes to
    block: list[str] = []
    for i, line in enumerate(lines):
        marker = re.match(r"^<!-- file: (\S+) -->$", line)
        if marker and fence is None:
            name = marker.group(1)
            continue
        if line.startswith("```"):
            if fence is None:
                fence, block = line[3:].strip(), []
                continue
            if name is not None:
                steps.append(("file", name, "\n".join(block) + "\n"))
                name = None
            fence = None
            continue
        if fence is None:
            continue
        block.append(line)
        if name is None and fence in ("", "console", "bash", "sh") and line.startswith("$ "):
            command = re.sub(r"\s+#.*$", "", line[2:]).strip()
            following = lines[i + 1] if i + 1 < len(lines) else ""
            error = following if following.startswith("catenet: error:") else None
            steps.append(("shell", command, error))
    return steps


def run_page(path: Path, work: Path) -> int:
    """Runs every step of the page in ``work``; returns the number of commands run."""
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    commands = 0
    for kind, text, expected in page_steps(path):
        if kind == "file":
            (work / text).write_text(expected)
            continue
        done = subprocess.run(
            shlex.split(text), cwd=work, env=env, capture_output=True, text=True, timeout=600
        )
        commands += 1
        if expected is None:
            assert done.returncode == 0, f"$ {text}\n{done.stdout}\n{done.stderr}"
        else:
            assert done.returncode == 2, f"$ {text}\n{done.stdout}\n{done.stderr}"
            assert expected in done.stderr, f"$ {text}\n{done.stderr}"
    return commands
