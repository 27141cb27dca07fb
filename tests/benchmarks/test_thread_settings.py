"""Benchmark scripts set their thread counts (MKL_NUM_THREADS, NUMBA_NUM_THREADS, ...)
only when run as scripts, never on import: a test that imports one would otherwise set
them for every later test in its process, and catenet's own thread setting then fails
("Cannot set NUMBA_NUM_THREADS to a different value once the threads have been
launched": 300 failures after the dismech comparison's test had imported its script)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = sorted((ROOT / "benchmarks").rglob("*.py"))
THREADS = ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")


def _is_main_guard(node: ast.AST) -> bool:
    """``if __name__ == "__main__":``."""
    if not isinstance(node, ast.If) or not isinstance(node.test, ast.Compare):
        return False
    left, comparators = node.test.left, node.test.comparators
    return (
        isinstance(left, ast.Name)
        and left.id == "__name__"
        and len(comparators) == 1
        and isinstance(comparators[0], ast.Constant)
        and comparators[0].value == "__main__"
    )


def _unguarded_environ_writes(tree: ast.Module) -> list[int]:
    """Lines at module level, outside functions, classes and ``__main__`` guards, that
    write a thread count into os.environ (``os.environ[...] = ``, ``.setdefault``,
    ``.update`` in a statement naming one of THREADS; JAX's or XLA's own flags aside)."""
    found: list[int] = []

    def visit(nodes) -> None:
        for node in nodes:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            if _is_main_guard(node):
                continue
            for sub in ast.walk(node):
                writes = (
                    isinstance(sub, ast.Call)
                    and isinstance(sub.func, ast.Attribute)
                    and sub.func.attr in ("setdefault", "update")
                    and "environ" in ast.unparse(sub.func.value)
                ) or (
                    isinstance(sub, ast.Assign)
                    and any("environ" in ast.unparse(t) for t in sub.targets)
                )
                if writes and any(name in ast.unparse(node) for name in THREADS):
                    found.append(sub.lineno)

    visit(tree.body)
    return found


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_a_benchmark_sets_threads_only_when_run_as_a_script(script):
    text = script.read_text()
    if not any(name in text for name in THREADS):
        return
    lines = _unguarded_environ_writes(ast.parse(text))
    assert not lines, f"{script.relative_to(ROOT)} writes os.environ on import at lines {lines}"


def test_the_check_sees_an_unguarded_write():
    bad = ast.parse('import os\nos.environ.setdefault("NUMBA_NUM_THREADS", "1")\n')
    good = ast.parse(
        'import os\nif __name__ == "__main__":\n    os.environ["NUMBA_NUM_THREADS"] = "1"\n'
    )
    assert _unguarded_environ_writes(bad) == [2]
    assert _unguarded_environ_writes(good) == []
