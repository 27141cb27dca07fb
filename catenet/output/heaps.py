"""The heaps of strings of an HDF5 file, checked before h5py reads it: HDF5 reads a
damaged global heap collection in an endless loop inside the library (``check_heaps``)."""

from __future__ import annotations

import functools
from pathlib import Path

#: A global heap collection (HDF5's store of variable-length data, e.g. the string
#: attributes): its signature, version 1, and the smallest size HDF5 writes.
GCOL = b"GCOL\x01"
GCOL_MIN = 4096


def check_heaps(path: str | Path) -> None:
    """``_check_heaps`` once per file as it stands (its size and modification time): a
    reader that opens one file several times (plot, export) scans it once."""
    stat = Path(path).stat()
    _check_heaps(str(Path(path).resolve()), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=64)
def _check_heaps(path: str, mtime: int, size: int) -> None:
    """OSError where a global heap collection of the file is damaged: its objects do not
    tile it (an object past its end, or free space of size 0 before it). HDF5 reads such
    a collection in an endless loop inside the library (no time limit or signal can stop
    it), the first time a string attribute is read; the fuzz run of seed 19 made one by
    damaging a result file. The whole file is scanned for the signature (a memory map,
    about a second per GB)."""
    import mmap
    import struct

    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
        at = m.find(GCOL)
        while at >= 0:
            if at + 16 <= len(m):
                size = struct.unpack_from("<Q", m, at + 8)[0]
                if GCOL_MIN <= size <= len(m) - at and not _tiled(m, at, size):
                    raise OSError(f"a global heap collection at byte {at} is damaged")
            at = m.find(GCOL, at + 1)


def _tiled(m, at: int, size: int) -> bool:
    """Whether the objects of the heap collection at ``at`` of ``size`` bytes tile it:
    each object's header (16 bytes) and data (padded to 8) within it, up to the free
    space (index 0) that runs to its end, or to its end exactly."""
    import struct

    p, end = at + 16, at + size
    while p + 16 <= end:
        index, _, _, length = struct.unpack_from("<HHIQ", m, p)
        if index == 0:  # the free space: the rest of the collection
            return length == end - p or (length > 0 and p + length <= end)
        p += 16 + (length + 7) // 8 * 8
    return p <= end
