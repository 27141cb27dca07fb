"""Writing a result file (the layout in ``catenet.output``) while a run goes on.

``ResultWriter`` writes the mesh when it opens, appends trajectory frames as a run goes
and the final state (``/result``) at the end; the XDMF sidecar follows it.

Crash safety: the file is created with ``libver=LIBVER`` and the trajectory is written
in SWMR mode (single writer, multiple readers), flushed after every frame. HDF5 then
orders its metadata writes so that the file on disk is consistent at every moment: a run
killed at any point (SIGKILL, power loss) leaves a file with every frame up to the last
flushed one. Such a file still carries HDF5's "open for writing" mark, which ordinary
readers refuse; ``open_result`` reads it in SWMR mode, and ``recover`` (or HDF5's
``h5clear -s``) turns it into an ordinary file. A run that ends, fails or is interrupted
closes the file properly. ``/result`` is written after the SWMR phase (HDF5 cannot create
objects in SWMR mode), so a killed run has no ``/result``.

Nothing non-finite is ever written: a frame or result with NaN or inf is refused with
``OutputError`` and the frames before it are kept. When writing fails mid-run (a full
disk), the writer stops writing frames and, at the end, saves the final state to a file in
the system's temporary directory, naming it in the ``OutputError`` it raises.
"""

from __future__ import annotations

import datetime
import errno
import logging
import math
import os
import re
import tempfile
import time
from pathlib import Path

import numpy as np

from catenet import measures
from catenet.errors import ConfigError, OutputError
from catenet.output.metadata import environment, result_attrs
from catenet.output.reader import LIBVER, TRAJECTORY
from catenet.output.xdmf import sidecar_path, write_xdmf

log = logging.getLogger(__name__)

# While running, the sidecar is rewritten at most once a second, and (for long runs, whose
# sidecar takes a while to write) at most 5 % of the time.
XDMF_REWRITE_SECONDS = 1.0
XDMF_SHARE = 0.05
MAX_CHUNK_BYTES = 32 * 2**20  # a trajectory chunk holds one frame, split above this size

__all__ = ["ResultWriter", "check_output_path"]


# --------------------------------------------------------------------------------------------
# Paths and errors
# --------------------------------------------------------------------------------------------


def check_output_path(path: str | Path, *, what: str = "output file") -> Path:
    """Checks, without creating anything, that ``path`` can be written: it is not a
    directory, an existing file there is writable, and its nearest existing parent is a
    writable directory (missing directories are created when the file is opened).
    Raises ConfigError naming the path; returns the path."""
    p = Path(path)
    text = str(path)
    if not text.strip():
        raise ConfigError(f"{what} = {text!r}: must be a file path")
    if p.is_dir():
        raise ConfigError(f"{what} {text!r}: is a directory: give a file path such as out/run.h5")
    if p.suffix.lower() == ".xdmf":
        raise ConfigError(
            f"{what} {text!r}: .xdmf is the name of the ParaView sidecar: give the HDF5 file, "
            "such as out/run.h5"
        )
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


def describe(exc: BaseException) -> str:
    """A one-line account of an I/O error (HDF5's messages span lines and name buffers)."""
    text = str(exc)
    m = re.search(r"errno = (\d+), error message = '([^']*)'", text)
    if m:
        return f"{m.group(2)} (errno {m.group(1)})"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return text.splitlines()[0] if text else type(exc).__name__


def _check_finite(name: str, value, t: float) -> None:
    arr = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise OutputError(
            f"refusing to write a non-finite state at t = {t:.6g}: {name} has {bad} NaN or "
            "infinite values (the solution diverged); the frames before it are kept"
        )


# --------------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------------


class ResultWriter:
    """Writes a run's result file (and its XDMF sidecar) while the run goes on.

    ``every``: the run keeps every k-th step as a trajectory frame (0: only the final
    state, and the file has no /trajectory group). The writer stores what it is given:
    ``frame`` appends (the caller picks which steps, see ``wants``), ``result`` writes
    /result. ``velocities`` (default: dynamic cases) adds /trajectory/v and /result/v;
    ``attrs`` are extra root attributes.

    Use it as a context manager; the file is complete and closed on exit, also when the
    block raises (frames kept, no /result unless ``result`` was called).
    """

    def __init__(
        self,
        path: str | Path,
        scene,
        *,
        every: int,
        xdmf: bool = True,
        velocities: bool | None = None,
        attrs: dict | None = None,
    ):
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 0:
            raise ConfigError(f"output.every = {every!r}: must be an integer >= 0")
        self.path = Path(path)
        self.scene = scene
        self.every = int(every)
        self.xdmf = bool(xdmf)
        if velocities is None:
            solver = getattr(getattr(scene, "case", None), "solver", None)
            velocities = getattr(solver, "method", "static") == "dynamic"
        self.velocities = bool(velocities)
        self.attrs = dict(attrs or {})
        self.frames = 0
        self.times: list[float] = []
        self.error: BaseException | None = None  # a failed write: frames stop there
        self.saved_to: Path | None = None  # where the result went instead
        self._h5 = None
        self._datasets: dict = {}
        self._swmr = False
        self._result_written = False
        self._next_xdmf = -math.inf

    # --- context ---------------------------------------------------------------------------
    def __enter__(self) -> ResultWriter:
        self.open()
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        self.close()
        return False

    @property
    def has_result(self) -> bool:
        """Whether /result was written (to this file)."""
        return self._result_written

    @property
    def sidecar(self) -> Path:
        return sidecar_path(self.path)

    def wants(self, step: int) -> bool:
        """Whether step ``step`` (0 = the initial state) is a trajectory frame."""
        return self.every > 0 and step % self.every == 0

    # --- opening ---------------------------------------------------------------------------
    def open(self) -> None:
        """Creates the file (and missing parent directories) and writes the mesh."""
        import h5py

        check_output_path(self.path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ConfigError(
                f"output file {str(self.path)!r}: cannot create its directory: "
                f"{exc.strerror or exc}"
            ) from None
        try:
            self._h5 = h5py.File(self.path, "w", libver=LIBVER)
        except OSError as exc:
            hint = ""
            if "lock" in str(exc).lower():
                hint = " (is it open in another program, such as ParaView or HDFView?)"
            raise ConfigError(
                f"output file {str(self.path)!r}: cannot be created{hint}: {exc}"
            ) from None
        try:
            self._write_header(self._h5)
            if self.every > 0:
                self._create_trajectory(self._h5)
                # Dataset objects live as long as the file: a temporary one closed while
                # writes fail would make HDF5 keep its identifier (see _detach).
                g = self._h5["trajectory"]
                self._datasets = {name: g[name] for name in g}
                self._h5.swmr_mode = True
                self._swmr = True
            self._h5.flush()
        except OSError as exc:
            self._abandon()
            raise OutputError(f"{self.path}: cannot be written: {describe(exc)}") from None
        # A sidecar left from an earlier run of this file would now lie: remove it.
        if self.xdmf:
            self.sidecar.unlink(missing_ok=True)

    def _abandon(self) -> None:
        """Closes and removes a file that could not even get its header."""
        try:
            if self._h5 is not None:
                self._h5.close()
        except Exception:  # best effort: the file is being removed
            pass
        self._h5 = None
        self.path.unlink(missing_ok=True)

    def _write_header(self, h5) -> None:
        scene = self.scene
        net = scene.net
        env = environment()
        h5.attrs["catenet_version"] = env["catenet"]
        h5.attrs["case"] = scene.case.to_toml() if scene.case is not None else ""
        h5.attrs["created"] = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        title = getattr(scene.case, "title", "")
        if title:
            h5.attrs["title"] = title
        for name, ver in env.items():
            if name != "catenet" and ver:
                h5.attrs[f"{name}_version"] = ver
        for key, value in self.attrs.items():
            h5.attrs[key] = value
        mesh = h5.create_group("mesh")
        mesh.create_dataset("nodes", data=np.asarray(net.nodes, dtype=np.float64))
        mesh.create_dataset("edges", data=np.asarray(net.edges, dtype=np.int64))
        mesh.create_dataset("rest_length", data=np.asarray(net.rest_length, dtype=np.float64))
        mesh.create_dataset("EA", data=np.asarray(net.EA, dtype=np.float64))
        mesh.create_dataset("fixed", data=np.asarray(net.fixed, dtype=bool))
        mesh.attrs["probe"] = int(scene.probe)
        mesh.attrs["size"] = float(scene.size)

    def _create_trajectory(self, h5) -> None:
        n, m = self.scene.net.n_nodes, self.scene.net.n_edges
        g = h5.create_group("trajectory")
        # Fill value NaN: a frame that never fully reached the disk (the writer failed or
        # was killed in the middle of it) reads as NaN, and readers skip it.
        g.create_dataset(
            "time", shape=(0,), maxshape=(None,), dtype="f8", chunks=(1024,), fillvalue=np.nan
        )
        shapes = {"x": (n, 3), "tension": (m,)}
        if self.velocities:
            shapes["v"] = (n, 3)
        for name in TRAJECTORY:
            if name not in shapes:
                continue
            tail = shapes[name]
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

    # --- frames ----------------------------------------------------------------------------
    def frame(self, t: float, x, v=None, tension=None) -> None:
        """Appends a frame and flushes it to disk. ``v`` None stores zeros (when the file
        keeps velocities); ``tension`` None is computed from x. Raises OutputError for a
        non-finite frame (not written). A failed write (a full disk) is remembered, and
        frames stop: the run goes on and ``result`` saves the final state elsewhere."""
        if self.every == 0 or self.error is not None:
            return
        if self._h5 is None:
            raise OutputError(f"{self.path}: the writer is not open")
        net = self.scene.net
        x = np.asarray(x, dtype=np.float64)
        if x.shape != net.nodes.shape:
            raise OutputError(f"frame x: shape {x.shape}: must be {net.nodes.shape}")
        data = {"x": x, "tension": self._stored_tension(x, tension)}
        if self.velocities:
            data["v"] = np.zeros_like(x) if v is None else np.asarray(v, dtype=np.float64)
        if not math.isfinite(float(t)):
            raise OutputError(f"refusing to write a frame at t = {t!r}: the time must be finite")
        for name, arr in data.items():
            _check_finite(name, arr, float(t))
        k = self.frames
        try:
            for name, arr in data.items():
                ds = self._datasets[name]
                ds.resize(k + 1, axis=0)
                ds[k] = arr
            ds = self._datasets["time"]
            ds.resize((k + 1,))
            ds[k] = float(t)  # last: the frame counts once its time is there
            self._h5.flush()
        except (OSError, RuntimeError) as exc:  # ENOSPC, EFBIG, EIO, quota ...
            self._fail(exc)
            return
        self.frames += 1
        self.times.append(float(t))
        if self.xdmf and time.monotonic() >= self._next_xdmf:
            self._write_sidecar()

    def _stored_tension(self, x, tension) -> np.ndarray:
        """The tensions stored with positions x: as given, else computed from the law (the
        one place where the writer derives a measure)."""
        if tension is None:
            tension = measures.tension(self.scene.net, x)
        return np.asarray(tension, dtype=np.float64)

    def _fail(self, exc: BaseException) -> None:
        self.error = exc
        log.warning(
            "%s: writing failed after %d frames (%s); the run goes on, its final state will "
            "be saved to a temporary file",
            self.path,
            self.frames,
            describe(exc),
        )
        h5, self._h5 = self._h5, None
        if h5 is not None:
            _detach(h5)
            self._datasets = {}
            try:
                h5.close()
            except Exception:  # the file is broken already
                pass

    def _write_sidecar(self) -> None:
        if not self.xdmf:
            return
        net = self.scene.net
        start = time.monotonic()
        try:
            write_xdmf(
                self.sidecar,
                self.path.name,
                n_nodes=net.n_nodes,
                n_edges=net.n_edges,
                times=self.times,
                velocities=self.velocities,
            )
        except OSError as exc:
            log.warning("%s: cannot write the XDMF sidecar: %s", self.sidecar, exc)
        now = time.monotonic()
        self._next_xdmf = now + max(XDMF_REWRITE_SECONDS, (now - start) / XDMF_SHARE)

    # --- result ----------------------------------------------------------------------------
    def result(self, res, **attrs) -> None:
        """Writes /result (final state and its attributes; ``attrs`` add to them). After a
        failed write, saves root attributes, mesh and /result to a temporary file and
        raises OutputError naming it (with ``.result`` and ``.saved_to`` set)."""
        _check_finite("x", res.x, float(getattr(res, "time", 0.0)))
        if self.error is None:
            try:
                self._reopen_for_result()
                self._write_result(self._h5, res, attrs)
                self._h5.flush()
                self._result_written = True
                return
            except (OSError, RuntimeError) as exc:
                self._fail(exc)
        # Writing failed: keep the result in a temporary file.
        first = self.error
        try:
            self.saved_to = self._save_elsewhere(res, attrs)
        except Exception as exc:
            err = OutputError(
                f"{self.path}: writing failed ({describe(first)}); saving the result to the "
                f"temporary directory {tempfile.gettempdir()} failed as well ({describe(exc)}): "
                "the result exists only in memory"
            )
            err.result = res
            err.saved_to = None
            raise err from None
        kept = f" (it keeps {self.frames} trajectory frames)" if self.frames else ""
        err = OutputError(
            f"{self.path}: writing failed ({describe(first)}){kept}; the final state was "
            f"saved to {self.saved_to} instead"
        )
        err.result = res
        err.saved_to = self.saved_to
        raise err

    def _reopen_for_result(self) -> None:
        """HDF5 creates no objects in SWMR mode: close that phase and reopen."""
        import h5py

        if self._h5 is None:
            raise OSError(errno.EBADF, "the result file is not open", str(self.path))
        if self._swmr:
            self._close_file()
            self._h5 = h5py.File(self.path, "r+", libver=LIBVER)

    def _write_result(self, h5, res, attrs: dict) -> None:
        scene = self.scene
        if "result" in h5:
            del h5["result"]
        g = h5.create_group("result")
        g.create_dataset("x", data=np.asarray(res.x, dtype=np.float64))
        g.create_dataset("tension", data=self._stored_tension(res.x, res.tension))
        reaction = res.reaction if res.reaction is not None else np.zeros_like(res.x)
        g.create_dataset("reaction", data=np.asarray(reaction, dtype=np.float64))
        v = getattr(res, "v", None)
        if self.velocities and v is not None and np.all(np.isfinite(v)):
            g.create_dataset("v", data=np.asarray(v, dtype=np.float64))
        for key, value in result_attrs(res, scene).items():
            g.attrs[key] = value
        for key, value in attrs.items():
            g.attrs[key] = value

    def _save_elsewhere(self, res, attrs: dict) -> Path:
        import h5py

        fd, name = tempfile.mkstemp(prefix=f"{self.path.stem}-", suffix=".h5")
        os.close(fd)
        tmp = Path(name)
        try:
            with h5py.File(tmp, "w", libver=LIBVER) as h5:
                self._write_header(h5)
                h5.attrs["note"] = (
                    f"saved here because writing {self.path} failed ({describe(self.error)}); "
                    f"the trajectory ({self.frames} frames) is in that file"
                )
                self._write_result(h5, res, attrs)
        except Exception:
            tmp.unlink(missing_ok=True)
            raise
        return tmp

    # --- closing ---------------------------------------------------------------------------
    def _close_file(self) -> None:
        """Flushes and closes the file. When that fails, the file is detached (see
        ``_detach``) and closed all the same, and the error re-raised."""
        h5 = self._h5
        try:
            h5.flush()
            self._datasets = {}
            h5.close()
        except (OSError, RuntimeError):
            _detach(h5)
            self._datasets = {}
            try:
                h5.close()
            except Exception:  # closed as far as it goes
                pass
            raise
        finally:
            self._h5 = None
            self._swmr = False

    def close(self) -> None:
        """Closes the file and writes the final sidecar (consistent with the file)."""
        if self._h5 is not None:
            try:
                self._close_file()
            except (OSError, RuntimeError) as exc:  # a broken file: nothing more to save
                self.error = self.error or exc
                log.warning("%s: closing failed: %s", self.path, describe(exc))
            if self.xdmf and self.error is None and (self.frames or self._result_written):
                self._write_sidecar()


def _detach(h5) -> None:
    """Points HDF5's file descriptor of a file whose writes fail at /dev/null.

    HDF5 retries the failed writes when the file and its datasets are closed; when those
    fail again, it keeps their identifiers and crashes at interpreter exit. Writing the
    rest to /dev/null lets the close succeed, while the file on disk keeps what was
    flushed before the failure (consistent, thanks to SWMR).
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
