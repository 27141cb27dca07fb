"""Running a Markdown page as written: the steps of its code blocks, in order.

- a shell line starting with ``$ `` in a plain (or ``console``, ``bash``, ``sh``) code
  block runs shlex-split, no shell: ``catenet`` commands through catenet's own entry
  point in this process (``catenet sweep`` and ``catenet bench``, which start processes
  of their own, and every other program as a subprocess); when the next line shows
  ``catenet: error: ...`` the command must fail with exit status 2 and that message,
  otherwise it must succeed;
- a ```python block is executed;
- a block right after the line ``<!-- file: NAME -->`` is written to NAME (a case file the
  page then runs);
- ```toml blocks must parse (``toml_blocks``); ```text blocks are shown, never run.

``run_page(path, directory)`` runs one page in ``directory`` (which holds a copy of
configs/), as a user following the page would.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
SHELLS = ("", "console", "bash", "sh")
FILE = re.compile(r"^<!-- file: (\S+) -->$")


@dataclass(frozen=True)
class Step:
    kind: str  # "shell", "python" or "file"
    text: str
    error: str | None = None  # shell: the expected "catenet: error: ..." line
    name: str | None = None  # file: where the block goes
    line: int = 0


def pages() -> list[Path]:
    """The README and every page under docs/."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def page_id(path: Path) -> str:
    return str(path.relative_to(ROOT))


def steps(path: Path) -> list[Step]:
    """The page's steps, in order."""
    out: list[Step] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    fence, block, target, start = None, [], None, 0
    for i, line in enumerate(lines):
        if line.startswith("```"):
            if fence is None:
                fence, block, start = line[3:].strip(), [], i + 1
                previous = lines[i - 1] if i else ""
                match = FILE.match(previous.strip())
                target = match.group(1) if match else None
                continue
            text = "\n".join(block) + "\n"
            if target is not None:
                out.append(Step("file", text, name=target, line=start))
            elif fence == "python":
                out.append(Step("python", text, line=start))
            fence = None
            continue
        if fence is None:
            continue
        block.append(line)
        if target is None and fence in SHELLS and line.startswith("$ "):
            command = re.sub(r"\s+#.*$", "", line[2:]).strip()
            following = lines[i + 1] if i + 1 < len(lines) else ""
            error = following if following.startswith("catenet: error:") else None
            out.append(Step("shell", command, error, line=i + 1))
    return out


def toml_blocks(path: Path) -> list[tuple[int, str]]:
    """(line, text) of every ```toml block."""
    out, fence, block, start = [], None, [], 0
    for i, line in enumerate(path.read_text(encoding="utf-8").splitlines()):
        if line.startswith("```"):
            if fence is None:
                fence, block, start = line[3:].strip(), [], i + 1
                continue
            if fence == "toml":
                out.append((start, "\n".join(block) + "\n"))
            fence = None
            continue
        if fence is not None:
            block.append(line)
    return out


def in_process(argv: list[str], directory: Path) -> subprocess.CompletedProcess:
    """``catenet ...`` run by the console script's entry point (``catenet.cli:main``) in
    this process, in ``directory``, as a completed process: what a subprocess would give,
    without a second start of the interpreter, NumPy, Numba and the JIT cache for each
    command (a page's commands share them). Numba's thread count is put back after."""
    from click.testing import CliRunner

    import catenet.cli

    numba = sys.modules.get("numba")
    threads = numba.get_num_threads() if numba is not None else None
    here = os.getcwd()
    os.chdir(directory)
    try:
        result = CliRunner().invoke(catenet.cli.main, argv[1:], catch_exceptions=True)
    finally:
        os.chdir(here)
        if threads is not None:
            numba.set_num_threads(threads)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return subprocess.CompletedProcess(argv, result.exit_code, result.stdout, result.stderr)


def run_page(path: Path, directory: Path) -> list[subprocess.CompletedProcess]:
    """Runs every step of ``path`` in ``directory`` (the current directory meanwhile);
    the commands' completed processes, in order (what they printed)."""
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    where = page_id(path)
    done_all = []
    for step in steps(path):
        if step.kind == "file":
            target = directory / step.name
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(step.text)
            continue
        if step.kind == "python":
            code = compile(step.text, f"{where}:{step.line}", "exec")
            exec(code, {"__name__": "docs"})
            continue
        argv = shlex.split(step.text)
        if argv[:1] == ["catenet"] and argv[1:2] not in (["sweep"], ["bench"]):
            done = in_process(argv, directory)
        else:
            done = subprocess.run(
                argv, cwd=directory, env=env, capture_output=True, text=True, timeout=900
            )
        done_all.append(done)
        context = f"{where}:{step.line}: $ {step.text}\n{done.stdout}\n{done.stderr}"
        if step.error is None:
            assert done.returncode == 0, context
        else:
            assert done.returncode == 2, context
            assert step.error in done.stderr, context
    return done_all
