"""The package's layers: every import of a catenet module, function-level ones included,
goes to the same layer or a lower one, and no two modules import each other (directly or
round a loop), so that no import inside a function hides a cycle.

    errors < kernels < model < terms < scene < solver < case, output < formfind, run < validate
    < sweep < plot, report < study < cli

(``catenet/__init__.py`` and ``__main__.py`` load any layer on first use.) Imports under
``if TYPE_CHECKING:`` are annotations only and do not count. Also: no module over
MAX_LINES, and the solver's public entry points load no case-file module.
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "catenet"
LAYERS = (
    ("errors",),
    ("kernels",),
    ("model",),
    ("terms",),
    ("scene",),
    ("solver",),
    ("case", "output"),
    ("formfind", "run"),
    ("validate",),
    ("sweep",),
    ("plot", "report"),
    ("study",),
    ("cli",),
)
MAX_LINES = 550


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def layer(module: str) -> int | None:
    parts = module.split(".")
    if len(parts) < 2:
        return None  # catenet/__init__.py: the lazy public face
    for rank, names in enumerate(LAYERS):
        if parts[1] in names:
            return rank
    return None  # __main__


def imports(path: Path) -> list[tuple[str, int]]:
    """The catenet modules a file imports (at any depth), with their line numbers."""
    tree = ast.parse(path.read_text())
    annotations = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                annotations.update(id(x) for x in ast.walk(child))
    found = []
    for node in ast.walk(tree):
        if id(node) in annotations:
            continue
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module.split(".")[0] != "catenet":
                continue
            subs = [f"{node.module}.{a.name}" for a in node.names]
            names = [s for s in subs if s in MODULES]
            if len(names) < len(subs):
                names.append(node.module)
            found += [(n, node.lineno) for n in names]
        elif isinstance(node, ast.Import):
            found += [(a.name, node.lineno) for a in node.names if a.name.startswith("catenet.")]
    return found


@functools.cache
def graph() -> dict[str, list[tuple[str, int]]]:
    """Each module's catenet imports (read once, by the tests that need it, not at
    collection: every pytest process collects this file)."""
    return {me: imports(path) for me, path in MODULES.items()}


def test_every_module_is_in_a_layer():
    """A new folder of the package is placed in LAYERS, or its imports go unchecked."""
    free = {"catenet", "catenet.__main__"}
    assert [m for m in MODULES if layer(m) is None and m not in free] == []


def test_every_import_goes_down_the_layers():
    wrong = []
    for me, found in graph().items():
        mine = layer(me)
        for target, line in found:
            theirs = layer(target)
            if mine is not None and theirs is not None and theirs > mine:
                wrong.append(f"{MODULES[me].relative_to(PACKAGE.parent)}:{line} imports {target}")
    assert not wrong, "imports up the layers:\n" + "\n".join(wrong)


def test_no_import_cycles():
    edges = defaultdict(set)
    for me, found in graph().items():
        edges[me].update(t for t, _ in found if t in MODULES and t != me)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in MODULES:
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_module_is_too_long(module):
    lines = len(MODULES[module].read_text().splitlines())
    assert lines <= MAX_LINES, f"{MODULES[module]}: {lines} lines"


def test_the_solver_loads_no_case_file_module():
    code = (
        "import sys\n"
        "import catenet.solver.path, catenet.solver.static, catenet.solver.dynamic\n"
        "print(sorted(m for m in sys.modules if m.startswith(('catenet.case', 'catenet.output'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
