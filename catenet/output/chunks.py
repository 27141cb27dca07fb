"""The trajectory's compressed chunks: the writer compresses each frame once itself and
writes the same chunk to both copies of a result file (``catenet.output.writer``)."""

from __future__ import annotations

import math
import zlib

import numpy as np

MAX_CHUNK_BYTES = 32 * 2**20  # a trajectory chunk holds one frame, split above this size
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


def create_trajectory(h5, shapes: dict[str, tuple[int, ...]]):
    """The empty /trajectory group of a new file: ``time`` and a dataset of each frame
    shape in ``shapes``, one frame a chunk (split above MAX_CHUNK_BYTES), with FILTERS.
    Fill value NaN: a frame that never fully reached the disk (a file written by a killed
    earlier catenet version, or copied while incomplete) reads as NaN, and readers skip it."""
    g = h5.create_group("trajectory")
    g.create_dataset(
        "time", shape=(0,), maxshape=(None,), dtype="f8", chunks=(1024,), fillvalue=np.nan
    )
    for name, tail in shapes.items():
        chunk = list(tail)
        while 8 * math.prod(chunk) > MAX_CHUNK_BYTES:
            chunk[0] = max(1, chunk[0] // 2)
        g.create_dataset(
            name,
            shape=(0, *tail),
            maxshape=(None, *tail),
            dtype="f8",
            chunks=(1, *chunk),
            compression="gzip",
            compression_opts=4,
            shuffle=True,
            fillvalue=np.nan,
        )
    g["time"].attrs["unit"] = "s (dynamic) or load factor (static)"
    return g


def append_frames(g, batch, encoded: dict[str, list[bytes]], n0: int, held: list) -> None:
    """Writes ``batch``'s frames as frames n0, n0 + 1, ... of /trajectory ``g``'s
    datasets (``encoded``: their chunks, see ``encode``), over any already there;
    ``held`` keeps the datasets open as long as the file (``files.detach``)."""
    n1 = n0 + len(batch)
    for name in batch[0][1]:
        held.append(ds := g[name])
        ds.resize(n1, axis=0)
        if ds.chunks == (1, *ds.shape[1:]) and FILTERS == filters(ds):
            zeros = (0,) * (ds.ndim - 1)
            for k, chunk in enumerate(encoded[name], start=n0):
                ds.id.write_direct_chunk((k, *zeros), chunk)
        else:  # frames split into several chunks: HDF5 compresses them
            ds[n0:n1] = np.stack([data[name] for _, data in batch])


def append_times(g, times: list[float], n0: int, held: list) -> None:
    """Writes ``times`` as /trajectory/time n0, n0 + 1, ...: a frame counts once its time
    is there, so this comes last."""
    held.append(ds := g["time"])
    ds.resize((n0 + len(times),))
    ds[n0 : n0 + len(times)] = times
