"""The files behind a result file: checking an output path before a run, the hidden
spare copy the writer keeps beside it, publishing a new version atomically, and one-line
accounts of I/O errors.

A result file ``OUT.h5`` is only ever replaced whole (``os.replace``), never written in
place: a reader, or a run killed at any moment, always finds a complete, closed HDF5 file.
While a run goes on, ``.OUT.h5.spare`` (and for an instant ``.OUT.h5.prev``) beside it
holds the next version; both are removed when the run ends, and by ``catenet repair``.
"""

from __future__ import annotations

import errno
import os
import re
import shutil
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError, OutputError

__all__ = [
    "check_output_dir",
    "check_output_path",
    "copy_atomically",
    "describe",
    "detach",
    "publish",
    "remove_spares",
    "spare_paths",
    "WriteLock",
]


def check_output_path(path: str | Path, *, what: str = "output file") -> Path:
    """Checks, without creating anything, that ``path`` can be written: it is not a
    directory, an existing file there is writable, and its nearest existing parent is a
    writable directory (missing directories are created when the file is opened).
    Raises ConfigError naming the path; returns the path."""
    p = Path(path)
    text = str(path)
    if not text.strip():
        raise ConfigError(f"{what} = {text!r}: must be a file path")
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:  # bytes that are not UTF-8 (os.fsdecode's surrogates)
        raise ConfigError(
            f"{what} {text!r}: holds bytes that are not UTF-8 text: HDF5 and XDMF files name "
            "their paths in UTF-8; rename it"
        ) from None
    _check_name_lengths(p, what)
    if p.is_dir():
        raise ConfigError(f"{what} {text!r}: is a directory: give a file path such as out/run.h5")
    if p.suffix.lower() == ".xdmf":
        raise ConfigError(
            f"{what} {text!r}: .xdmf is the name of the ParaView sidecar: give the HDF5 file, "
            "such as out/run.h5"
        )
    for beside, name in ((p.with_suffix(".xdmf"), "its XDMF sidecar"), (spare_paths(p)[0], "")):
        if beside.is_dir() and beside != p:
            name = name or f"its hidden spare {beside.name}"
            raise ConfigError(f"{what} {text!r}: {name} {str(beside)!r} is a directory")
    if p.exists() or p.is_symlink():
        if not p.is_file():
            raise ConfigError(f"{what} {text!r}: exists and is not a regular file")
        if not os.access(p, os.W_OK):
            raise ConfigError(
                f"{what} {text!r}: exists and cannot be overwritten (permission denied)"
            )
    parent = p.absolute().parent
    while not parent.exists():
        if parent.is_symlink():  # a dangling link
            raise ConfigError(f"{what} {text!r}: {parent} is a broken symbolic link")
        parent = parent.parent
    if not parent.is_dir():
        raise ConfigError(f"{what} {text!r}: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ConfigError(f"{what} {text!r}: cannot write in {parent} (permission denied)")
    return p


def check_output_dir(path: str | Path, *, what: str = "output directory") -> Path:
    """Checks, without creating anything, that the directory ``path`` can be made or
    written in: no name in it too long, no regular file on the way, permission to write.
    Raises ConfigError naming the path; returns the path."""
    p = Path(path)
    text = str(path)
    if not text.strip():
        raise ConfigError(f"{what} = {text!r}: must be a directory path")
    _check_name_lengths(p / "results.h5", what)
    here = p.absolute()
    while not (here.exists() or here.is_symlink()):
        here = here.parent
    if not here.is_dir():
        raise ConfigError(f"{what} {text!r}: {str(here)!r} is not a directory")
    if not os.access(here, os.W_OK | os.X_OK):
        raise ConfigError(f"{what} {text!r}: cannot write in {str(here)!r} (permission denied)")
    return p


def _check_name_lengths(p: Path, what: str) -> None:
    """ConfigError when the file's name, or the hidden spare's beside it, or a directory
    on the way, is longer than the file system takes."""
    parent = p.absolute().parent
    limit = 255
    while parent != parent.parent:
        try:
            limit = os.pathconf(parent, "PC_NAME_MAX")
            break
        except (OSError, ValueError):  # missing yet, or a name too long itself
            parent = parent.parent
    longest = max(len(os.fsencode(part)) for part in p.parts) if p.parts else 0
    extra = len(HIDDEN_LONGEST.format(name=""))
    if max(longest, len(os.fsencode(p.name)) + extra) > limit:
        raise ConfigError(
            f"{what} {str(p)!r}: a name in it is too long for the file system (at most "
            f"{limit - extra} bytes for the file, whose hidden copies beside it, such as "
            f"{HIDDEN_LONGEST.format(name='NAME')}, must fit in {limit})"
        )


#: The longest name of the hidden files beside a result file (the spare's copy).
HIDDEN_LONGEST = "..{name}.spare.copy"


class WriteLock:
    """The lock a writer of ``path`` holds while the file is being written: an exclusive
    ``flock`` on ``.NAME.lock`` beside it, which the kernel releases when the process
    ends however it ends, so a killed run never blocks the next. A second run (or
    ``catenet repair``) on the same file is refused with a ConfigError instead of both
    writing the one spare. Where the file system has no locks, nothing is locked."""

    def __init__(self, path: str | Path):
        p = Path(path)
        self.target = p
        self.path = p.with_name(f".{p.name}.lock")
        self.fd: int | None = None

    def acquire(self) -> WriteLock:
        try:
            import fcntl
        except ImportError:  # not POSIX: no locks
            return self
        for _ in range(20):  # a lock file removed by its holder meanwhile: try the new one
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError:
                return self  # cannot even create it: the writer will say why
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                os.close(fd)
                if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise ConfigError(
                        f"output file {str(self.target)!r}: another catenet process is writing "
                        "it now: wait for it to end or give another file (-o)"
                    ) from None
                return self  # no locks on this file system
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except OSError:
                same = False
            if same:
                self.fd = fd
                return self
            os.close(fd)
        return self

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            self.path.unlink(missing_ok=True)  # while still held: the next one makes its own
        except OSError:
            pass
        os.close(self.fd)
        self.fd = None

    def __enter__(self) -> WriteLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


def write_image(path: Path, build, libver) -> None:
    """Builds an HDF5 file in memory (``build(h5)`` fills it) and writes its bytes to
    ``path`` with plain file I/O: a full disk is then an OSError and the partial file is
    removed, where HDF5 writing to the disk itself would fail in its destructors and crash
    the process."""
    import io

    import h5py

    buf = io.BytesIO()
    with h5py.File(buf, "w", libver=libver) as h5:
        build(h5)
    try:
        with open(path, "wb") as f:
            f.write(buf.getbuffer())
    except OSError:
        Path(path).unlink(missing_ok=True)
        raise


def header_bytes(net) -> int:
    """About the bytes of a result file before its first frame: the mesh's arrays (nodes,
    edges, rest lengths, EA, supports) and HDF5's own structures."""
    return 16 * 1024 + 40 * (int(net.n_nodes) + int(net.n_edges))


def check_free_space(path: str | Path, need: int) -> None:
    """OSError (ENOSPC) when the file system of ``path`` has fewer than ``need`` bytes free:
    HDF5 itself fails badly when the disk fills while a file is created."""
    here = Path(path).absolute().parent
    while not here.exists() and here != here.parent:
        here = here.parent
    try:
        free = shutil.disk_usage(here).free
    except OSError:
        return
    if free < need:
        raise OSError(
            errno.ENOSPC,
            f"No space left on device ({free} bytes free, at least {need} needed)",
            str(path),
        )


def describe(exc: BaseException | None) -> str:
    """A one-line account of an I/O error (HDF5's messages span lines and name buffers)."""
    text = str(exc)
    m = re.search(r"errno = (\d+), error message = '([^']*)'", text)
    if m:
        return f"{m.group(2)} (errno {m.group(1)})"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return text.splitlines()[0] if text else type(exc).__name__


def spare_paths(path: str | Path) -> tuple[Path, Path]:
    """The hidden files beside a result file while it is written: the spare (the next
    version, written while the published one stays untouched) and the previous version
    (an instant's hard link while they swap)."""
    p = Path(path)
    return p.with_name(f".{p.name}.spare"), p.with_name(f".{p.name}.prev")


def remove_spares(path: str | Path) -> list[Path]:
    """Removes the hidden files a killed writer left beside ``path``; returns them."""
    path = Path(path)
    spare, prev = spare_paths(path)
    copies = (path.with_name(f".{path.name}.copy"), spare.with_name(f".{spare.name}.copy"))
    gone = []
    for p in (spare, prev, *copies):
        if p.exists() or p.is_symlink():
            p.unlink(missing_ok=True)
            gone.append(p)
    return gone


def publish(spare: Path, path: Path, prev: Path) -> None:
    """Makes the closed file ``spare`` the result file ``path`` in one step (a reader sees
    the old version or the new, never a mix) and leaves the version it replaces at
    ``spare``, a separate file, to be brought up to date and published next time (a copy
    of the new version where there is no old one, or no hard links)."""
    linked = False
    if path.exists():
        try:
            prev.unlink(missing_ok=True)
            os.link(path, prev)
            linked = True
        except OSError:  # a file system without hard links
            pass
    os.replace(spare, path)
    if linked:
        os.replace(prev, spare)
    else:
        copy_atomically(path, spare)


def copy_atomically(src: Path, dst: Path) -> None:
    """Replaces ``dst`` by a copy of ``src`` in one step."""
    tmp = dst.with_name(f".{dst.name}.copy")
    try:
        shutil.copyfile(src, tmp)
        os.replace(tmp, dst)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise


def detach(h5) -> None:
    """Points HDF5's file descriptor of a file whose writes fail at /dev/null.

    HDF5 retries the failed writes when the file and its datasets are closed; when those
    fail again, it keeps their identifiers and crashes at interpreter exit. Writing the
    rest to /dev/null lets the close succeed. The writer only ever writes into its spare:
    the published result file keeps its last version.
    """
    try:
        fd = h5.id.get_vfd_handle()
        null = os.open(os.devnull, os.O_RDWR)
    except Exception:  # another file driver, or no /dev/null: leave it be
        return
    try:
        os.dup2(null, fd)
    except OSError:
        pass
    finally:
        os.close(null)


def check_finite(name: str, value, t: float) -> None:
    arr = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise OutputError(
            f"refusing to write a non-finite state at t = {t:.6g}: {name} has {bad} NaN or "
            "infinite values (the solution diverged); the frames before it are kept"
        )


def read_text(value) -> str:
    """A string attribute as read back: bytes decoded and bytes that are not UTF-8 (h5py
    hands them back as lone surrogates, which no font or file can take) shown as
    replacement characters."""
    if isinstance(value, str):
        value = value.encode("utf-8", "replace")
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    return str(value)


def utf8(value):
    """A string attribute as UTF-8 text: the bytes of a path that are not UTF-8 (the
    surrogates of os.fsdecode) written as \\xNN escapes; other values as they are."""
    if isinstance(value, str):
        return os.fsencode(value).decode("utf-8", "backslashreplace")
    return value
