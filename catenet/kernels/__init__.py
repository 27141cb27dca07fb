"""Numba kernels: module-level @njit(cache=True) functions over flat contiguous arrays.

One module per physical term (``stretch``) plus the sparse scatter used by assembly.
``NUMBA_DISABLE_JIT=1`` runs them as plain Python for tracebacks.

Numba keys a kernel's cached machine code on its own module's source only, while a
kernel that calls one of another module (``segments.segment_ccd`` calls
``ccd.accd``) has that callee compiled into it: a changed callee module (an upgrade,
an edit) left its callers running the old code from the cache. So on import the cache
of this package is checked against a stamp of every kernel module's source and numba's
version (``STAMP`` in the cache's directory), and cleared where it differs
(``fresh_cache``): the kernels are then compiled afresh on first use.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

STAMP = "catenet-kernels.stamp"  # the sources' hash the cached kernels were compiled from


def _sources_hash() -> str:
    """A hash of every kernel module's source and of numba's version."""
    import numba

    digest = hashlib.sha256(numba.__version__.encode())
    for path in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _cache_dir() -> Path | None:
    """Where numba keeps this package's cached kernels (None: no caching)."""
    import numba

    if numba.config.DISABLE_JIT:
        return None

    @numba.njit(cache=True)
    def _probe():  # pragma: no cover - never compiled: its cache's place is asked
        return 0

    cache = getattr(_probe, "_cache", None)
    where = getattr(cache, "_cache_path", None)
    return None if where is None else Path(where)


def fresh_cache() -> int:
    """Clears the cached kernels (numba's index and data files in this package's cache
    directory) where they were compiled from other sources than these, then records
    these; returns how many files it removed. Never raises: a cache it cannot read or
    clear is left to numba (which recompiles what it cannot load)."""
    try:
        where = _cache_dir()
        if where is None:
            return 0
        where.mkdir(parents=True, exist_ok=True)
        stamp = where / STAMP
        current = _sources_hash()
        if stamp.is_file() and stamp.read_text().strip() == current:
            return 0
        removed = 0
        for path in list(where.glob("*.nbi")) + list(where.glob("*.nbc")):
            try:
                path.unlink()
                removed += 1
            except FileNotFoundError:
                pass  # another process cleared it first
        partial = where / f"{STAMP}.{os.getpid()}"
        partial.write_text(current + "\n")
        partial.replace(stamp)
        return removed
    except OSError:
        return 0


fresh_cache()
