"""Mending result files: ``recover`` copies the readable part of a file into a clean one,
``repair`` (``catenet repair``) does what a file needs to open in every reader.

Files that need it: those written in place by earlier catenet versions and left by a killed run
(HDF5's "open for writing" mark, which ordinary readers refuse), a file whose disk filled
up (frames that never fully reached it), files without the per-frame views the sidecar
names, and any file whose sidecar is missing or lags. The hidden spare copies a killed
writer leaves beside its file are removed.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.output.files import WriteLock, remove_spares
from catenet.output.obstacles import grids as obstacle_grids
from catenet.output.reader import (
    DAMAGED,
    LIBVER,
    TRAJECTORY,
    damaged,
    is_dataset,
    open_result,
    trajectory_length,
)
from catenet.output.xdmf import VIEWS, sidecar_path, view_sources, write_views, write_xdmf

__all__ = ["Repair", "recover", "repair"]


def recover(path: str | Path, out: str | Path | None = None) -> Path:
    """Copies the readable part of a result file (complete frames only) into a clean file,
    ``out`` or ``path`` itself (replaced in one step), with the per-frame views, and
    rewrites the XDMF sidecar to match. Returns the clean file's path."""
    import h5py

    src = Path(path)
    dst = src if out is None else Path(out)
    tmp = dst.with_name(f".{dst.name}.recover-{os.getpid()}")
    try:
        with open_result(src) as h5, h5py.File(tmp, "w", libver=LIBVER) as clean:
            for key, value in h5.attrs.items():
                clean.attrs[key] = value
            n = trajectory_length(h5)
            for name in h5:
                if name == VIEWS:
                    continue  # written anew for the frames kept
                if name != "trajectory":
                    h5.copy(h5[name], clean, name=name)
                    continue
                _copy_frames(h5["trajectory"], clean.create_group("trajectory"), n)
            write_views(clean, 0, n)
        os.replace(tmp, dst)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    write_sidecar_for(dst)
    return dst


def _copy_frames(src, dst, n: int) -> None:
    """Copies the first n frames of every dataset in the group ``src`` (and its groups:
    the moving obstacles') into the empty group ``dst``, extendable as the writer made
    them."""
    for key, ds in src.items():
        if not is_dataset(ds):
            _copy_frames(ds, dst.create_group(key), n)
            continue
        copy = dst.create_dataset(
            key,
            data=ds[:n],
            maxshape=(None, *ds.shape[1:]),
            chunks=ds.chunks,
            compression=ds.compression,
            compression_opts=ds.compression_opts,
            shuffle=ds.shuffle,
            fillvalue=ds.fillvalue,
        )
        for attr, value in ds.attrs.items():
            copy.attrs[attr] = value


def write_sidecar_for(path: str | Path) -> Path | None:
    """Writes the XDMF sidecar of a result file from what the file holds (its complete
    frames, else /result); returns it (None: nothing to show)."""
    path = Path(path)
    with open_result(path) as h5:
        n_nodes, n_edges = len(h5["mesh/nodes"]), len(h5["mesh/edges"])
        n = trajectory_length(h5)
        times = list(np.asarray(h5["trajectory/time"][:n], dtype=float)) if n else []
        has_v = "trajectory" in h5 and "v" in h5["trajectory"]
        has_result = "result" in h5 and "x" in h5["result"]
        contact = has_result and "contact_force" in h5["result"]
        bodies = len(h5["mesh/bodies/node"]) if "mesh/bodies/node" in h5 else 0
        obstacles = obstacle_grids(h5)
    if not (times or has_result):
        return None
    side = sidecar_path(path)
    write_xdmf(
        side,
        path.name,
        n_nodes=n_nodes,
        n_edges=n_edges,
        times=times,
        velocities=has_v,
        bodies=bodies,
        obstacles=obstacles,
        contact=contact,
    )
    return side


@dataclass
class Repair:
    """What ``repair`` found and did: ``problems`` (empty: the file was fine), whether it
    ``rewrote`` the file, the complete ``frames`` it keeps, the ``sidecar`` written (None:
    the file holds no state to show) and the spare files ``removed``."""

    path: Path
    frames: int
    rewrote: bool
    problems: list[str] = field(default_factory=list)
    sidecar: Path | None = None
    removed: list[Path] = field(default_factory=list)


def _problems(path: Path) -> list[str]:
    """Why a result file needs rewriting (empty: it does not)."""
    import h5py

    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return [f"ordinary HDF5 readers refuse it ({first})"]
    with h5:
        n = trajectory_length(h5)
        g = h5.get("trajectory")
        if g is None:
            return []
        problems = []
        longest = max((g[k].shape[0] for k in ("time", *TRAJECTORY) if k in g), default=0)
        if longest > n:
            problems.append(f"{longest - n} incomplete frames after the {n} complete ones")
        views = h5.get(VIEWS)
        missing = [
            name
            for name in view_sources(g)
            if n and (views is None or f"{name}/{n - 1}" not in views)
        ]
        if missing:
            problems.append(f"no per-frame views of {', '.join(missing)} for the XDMF sidecar")
        return problems


def _readable(p: Path, path) -> None:
    try:
        with open_result(p) as h5:
            if "mesh" not in h5 or "nodes" not in h5["mesh"] or "edges" not in h5["mesh"]:
                raise ConfigError(
                    f"{path}: has no /mesh/nodes and /mesh/edges: not a catenet result file"
                )
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read, even as a killed run's file: {exc}") from None


def repair(path: str | Path) -> Repair:
    """Makes a result file open in every reader: rewrites it (``recover``) when ordinary
    HDF5 readers refuse it, it has incomplete frames or lacks the sidecar's views;
    rewrites the sidecar; removes spare copies a killed writer left. Raises ConfigError
    for a file that is missing or not HDF5."""
    import h5py

    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{path}: no such result file")
    try:
        if not h5py.is_hdf5(p):
            raise ConfigError(f"{path}: not an HDF5 file (expected a catenet result file)")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read: {exc}") from None
    with WriteLock(p):  # not while a run writes it
        try:
            _readable(p, path)
            problems = _problems(p)
            if problems:
                recover(p)
            side = write_sidecar_for(p)
            with open_result(p) as h5:
                frames = trajectory_length(h5)
        except DAMAGED as exc:
            raise damaged(path, exc) from None
        return Repair(p, frames, bool(problems), problems, side, remove_spares(p))
