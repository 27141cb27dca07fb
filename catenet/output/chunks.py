"""The trajectory's compressed chunks: the writer compresses each frame once itself and
writes the same chunk to both copies of a result file (``catenet.output.writer``)."""

from __future__ import annotations

import zlib

import numpy as np

# HDF5's filters on the trajectory's datasets (byte shuffle, then deflate level 4).
FILTERS = ((2, ()), (1, (4,)))  # (H5Z_FILTER_SHUFFLE, ...), (H5Z_FILTER_DEFLATE, level)


def filters(ds) -> tuple:
    """The filters of an HDF5 dataset, in the form of ``FILTERS``."""
    plist = ds.id.get_create_plist()
    out = []
    for i in range(plist.get_nfilters()):
        code, _, values, _ = plist.get_filter(i)
        out.append((code, tuple(values) if code != 2 else ()))
    return tuple(out)


def encode(batch) -> dict[str, list[bytes]]:
    """Each frame's arrays (``batch``: (time, {name: array}) pairs) as HDF5 stores a
    one-frame chunk with ``FILTERS``: bytes shuffled (all first bytes of the float64
    values, then all second bytes, ...), then zlib-compressed at level 4."""
    if not batch:
        return {}
    out: dict[str, list[bytes]] = {name: [] for name in batch[0][1]}
    for _, data in batch:
        for name, arr in data.items():
            raw = np.ascontiguousarray(arr, dtype="<f8").view(np.uint8).reshape(-1, 8)
            out[name].append(zlib.compress(raw.T.tobytes(), 4))
    return out
