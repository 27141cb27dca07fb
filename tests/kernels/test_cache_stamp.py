"""The kernels' cache is cleared where it was compiled from other sources
(``catenet.kernels.fresh_cache``). Numba keys a kernel's cached machine code on its own
module's source only; ``segments.segment_ccd`` has ``accd`` (then in ``strands.py``)
compiled into it, and with ``strands.py`` changed (an iteration limit raised from 1 000
to 100 000) the cached ``segment_ccd`` still stopped at the old limit: 0.673 of the
step, where the Python function found no contact."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import catenet.kernels as kernels


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache directory with two kernels' index and data files and a foreign file."""
    monkeypatch.setattr(kernels, "_cache_dir", lambda: tmp_path)
    for name in ("segments.segment_ccd-378.py311.nbi", "segments.segment_ccd-378.py311.1.nbc",
                 "strands.accd-486.py311.nbi", "strands.accd-486.py311.1.nbc"):  # fmt: skip
        (tmp_path / name).write_bytes(b"cached")
    (tmp_path / "segments.cpython-311.pyc").write_bytes(b"bytecode")
    return tmp_path


def test_a_cache_without_a_stamp_or_with_another_is_cleared_and_stamped(cache):
    """No stamp (a cache from before, or compiled from other sources): every index and
    data file goes, the bytecode stays, and the stamp of these sources is written; a
    second call finds it and leaves the new files alone; another stamp clears again."""
    assert kernels.fresh_cache() == 4
    assert sorted(p.name for p in cache.iterdir()) == [
        kernels.STAMP,
        "segments.cpython-311.pyc",
    ]
    assert (cache / kernels.STAMP).read_text().strip() == kernels._sources_hash()
    (cache / "stretch.gradient-10.py311.nbi").write_bytes(b"new")
    assert kernels.fresh_cache() == 0
    assert (cache / "stretch.gradient-10.py311.nbi").exists()
    (cache / kernels.STAMP).write_text("0" * 64 + "\n")
    assert kernels.fresh_cache() == 1
    assert not (cache / "stretch.gradient-10.py311.nbi").exists()


def test_the_stamp_covers_every_kernel_module_and_numbas_version(monkeypatch):
    """The hash changes with any kernel module's source and with numba's version."""
    import numba

    before = kernels._sources_hash()
    monkeypatch.setattr(numba, "__version__", numba.__version__ + ".other")
    assert kernels._sources_hash() != before
    monkeypatch.undo()
    sources = sorted(Path(kernels.__file__).parent.glob("*.py"))
    assert {p.name for p in sources} >= {"strands.py", "segments.py", "__init__.py"}
    assert kernels._sources_hash() == before


def test_an_unwritable_or_missing_cache_is_left_to_numba(tmp_path, monkeypatch):
    """A cache directory that cannot be made (a file in its place) or with JIT off: no
    error, nothing removed."""
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    monkeypatch.setattr(kernels, "_cache_dir", lambda: blocked / "cache")
    assert kernels.fresh_cache() == 0
    monkeypatch.setattr(kernels, "_cache_dir", lambda: None)
    assert kernels.fresh_cache() == 0


def test_the_real_cache_is_stamped_on_import_where_numba_keeps_the_kernels():
    """In a fresh process, importing the kernels leaves the stamp of these sources in the
    directory where numba caches them (beside their cached files)."""
    code = (
        "import catenet.kernels as k, catenet.kernels.ccd as s\n"
        "print(k._cache_dir()); print(s.accd._cache._cache_path)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    where, accd = out.stdout.split()
    assert where == accd
    assert (Path(where) / kernels.STAMP).read_text().strip() == kernels._sources_hash()
