"""`make lint` checks the package's type hints with mypy: its configuration is declared
in pyproject.toml (the kernels aside), mypy is a development dependency, and the lint
target runs it. (The suite does not need mypy installed: it checks the set-up only.)"""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_make_lint_runs_mypy_on_the_package_with_the_kernels_aside():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    mypy = project["tool"]["mypy"]
    assert mypy["files"] == ["catenet"]
    aside = [o for o in mypy.get("overrides", []) if o.get("ignore_errors")]
    assert [o["module"] for o in aside] == [["catenet.kernels.*"]]  # nothing else set aside
    assert any(d.startswith("mypy") for d in project["project"]["optional-dependencies"]["dev"])
    lint = (ROOT / "Makefile").read_text(encoding="utf-8").split("\nlint:", 1)[1]
    recipe = lint.split("\n\n", 1)[0]
    assert "/mypy" in recipe and "ruff check" in recipe


def test_type_ignores_in_the_package_are_few_and_say_what_they_ignore():
    """Every ``type: ignore`` names its error code; there are at most a handful."""
    found = [
        (path.relative_to(ROOT), line)
        for path in sorted((ROOT / "catenet").rglob("*.py"))
        for line in path.read_text(encoding="utf-8").splitlines()
        if "type: ignore" in line
    ]
    assert len(found) <= 3, found
    assert all("type: ignore[" in line for _, line in found), found
