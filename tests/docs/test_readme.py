"""Every command and every Python snippet of the README runs as written.

The README is read top to bottom: shell lines starting with ``$ `` (in plain code blocks)
run as subprocesses, ```python blocks are executed, all in one scratch directory that
holds a copy of configs/, so later snippets see the files earlier ones wrote (as a user
following the README would). A command whose next line shows ``catenet: error: ...``
must fail with exit status 2 and that message; every other command must succeed.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent


def readme_steps() -> list[tuple[str, str, str | None]]:
    """(kind, text, expected error) for each command and Python block, in order."""
    steps = []
    lines = (ROOT / "README.md").read_text().splitlines()
    fence = None
    block: list[str] = []
    for i, line in enumerate(lines):
        if line.startswith("```"):
            if fence is None:
                fence, block = line[3:].strip(), []
                continue
            if fence == "python":
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


def test_readme_has_steps():
    kinds = [kind for kind, _, _ in readme_steps()]
    assert kinds.count("shell") >= 10 and kinds.count("python") >= 3


@pytest.mark.slow
def test_readme_runs_as_written(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    for kind, text, error in readme_steps():
        if kind == "python":
            exec(compile(text, "README.md", "exec"), {"__name__": "readme"})
            continue
        done = subprocess.run(
            shlex.split(text),
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
        )
        if error is None:
            assert done.returncode == 0, f"$ {text}\n{done.stdout}\n{done.stderr}"
        else:
            assert done.returncode == 2, f"$ {text}\n{done.stdout}\n{done.stderr}"
            assert error in done.stderr, f"$ {text}\n{done.stderr}"
    assert (tmp_path / "out" / "catenary.png").exists()
    assert (tmp_path / "out" / "paper" / "report.md").exists()


@pytest.mark.parametrize("name", ["Makefile", ".ci/run"])
def test_setup_files_do_what_the_quick_start_says(name):
    text = (ROOT / name).read_text()
    if name == "Makefile":
        assert re.search(r"^run:.*\n\t.*catenet run$", text, re.M)
        assert re.search(r"^test:.*\n\t.*pytest", text, re.M)
        assert "-m venv" in text
    else:
        assert "make test" in text
