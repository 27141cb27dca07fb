"""Writing a result file (the layout in ``catenet.output``) while a run goes on.

``ResultWriter`` writes the mesh when it opens, takes trajectory frames as a run goes and
the final state (``/result``) at the end; the XDMF sidecar follows the file.

Crash safety: the result file is never written in place. Frames gather in memory and are
flushed in batches (after ``flush_seconds`` of wall time, ``flush_frames`` frames or
``MAX_PENDING_BYTES``, whichever comes first, and at once for the first frame) into a
hidden spare copy, a closed HDF5 file that then replaces the result file in one
``os.replace`` (``catenet.output.files``); the replaced version becomes the spare and gets
the same batch. So the result file is at every moment a complete, closed HDF5 file that any
reader opens (h5py, ParaView, meshio, also while the run goes on), and a run killed at any
point (SIGKILL, power loss) leaves every frame up to the last flush. The sidecar is
rewritten after each flush and names only frames in the file. A run that ends, fails or is
interrupted flushes what is left; /result is written with the last batch.

Nothing non-finite is ever written: a frame or result with NaN or inf is refused with
``OutputError`` and the frames before it are kept. When writing fails mid-run (a full
disk), the writer stops writing frames and, at the end, saves the final state to a file in
the system's temporary directory, naming it in the ``OutputError`` it raises.
"""

from __future__ import annotations

import contextlib
import datetime
import logging
import math
import os
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError, OutputError
from catenet.model import measures
from catenet.output.bodies import write_bodies
from catenet.output.chunks import append_frames, append_times, create_trajectory, encode
from catenet.output.files import (
    WriteLock,
    check_finite,
    check_free_space,
    check_output_path,
    copy_atomically,
    describe,
    detach,
    header_bytes,
    publish,
    remove_spares,
    spare_paths,
    utf8,
    write_image,
)
from catenet.output.history import HistoryLayout, HistoryLog
from catenet.output.metadata import environment
from catenet.output.netsets import write_net_index
from catenet.output.obstacles import Obstacles
from catenet.output.reader import LIBVER, TRAJECTORY
from catenet.output.result_group import write_result_group
from catenet.output.supports import write_supports
from catenet.output.xdmf import sidecar_path, write_views, write_xdmf
from catenet.solver.energy import COLUMNS as ENERGY_COLUMNS

if TYPE_CHECKING:
    from catenet.scene.scene import Scene
    from catenet.solver.result import Result

log = logging.getLogger(__name__)

# Frames reach the file at least this often (wall time) ...
FLUSH_SECONDS = 1.0
# ... and after this many frames or bytes held in memory, whichever comes first;
FLUSH_FRAMES = 1000
MAX_PENDING_BYTES = 64 * 2**20
# a flush (written twice, the sidecar rewritten) takes at most this share of the run's time.
FLUSH_SHARE = 0.05

__all__ = ["ResultWriter", "check_output_path"]


# --------------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------------


class ResultWriter:
    """Writes a run's result file (and its XDMF sidecar) while the run goes on.

    ``every``: the run keeps every k-th step as a trajectory frame (0: only the final
    state, and the file has no /trajectory group). The writer stores what it is given:
    ``frame`` takes a frame (the caller picks which steps, see ``wants``), ``result``
    writes /result. ``velocities`` (default: dynamic cases) adds /trajectory/v and
    /result/v; ``accelerations`` (newmark runs) adds /trajectory/a and /result/a, the
    scheme's acceleration state that a restart goes on from; ``attrs`` are extra root
    attributes. ``flush_seconds`` and ``flush_frames``
    (0: no limit) say how often frames reach the file (see the module's docstring).
    ``history``: the file keeps a dynamic run's /history (``record`` takes its rows).

    ``frames`` counts the frames in the file, ``pending`` those in memory, ``flushes``
    and ``flush_time`` [s] the flushes so far and the wall time they took.

    Use it as a context manager; the file is complete and closed on exit, also when the
    block raises (frames kept, no /result unless ``result`` was called).
    """

    def __init__(
        self,
        path: str | Path,
        scene: Scene,
        *,
        every: int,
        xdmf: bool = True,
        velocities: bool | None = None,
        accelerations: bool = False,
        attrs: dict | None = None,
        flush_seconds: float = FLUSH_SECONDS,
        flush_frames: int = FLUSH_FRAMES,
        history: HistoryLayout | None = None,
    ):
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 0:
            raise ConfigError(f"output.every = {every!r}: must be an integer >= 0")
        self.path = Path(path)
        self.scene = scene
        self.every = int(every)
        self.xdmf = bool(xdmf)
        if velocities is None:
            velocities = scene.case is not None and scene.case.solver.method == "dynamic"
        self.velocities = bool(velocities)
        self.accelerations = bool(accelerations)
        # dynamic runs (they keep velocities) keep their energy balance per frame
        self.energies = self.velocities
        self._energy = np.zeros(len(ENERGY_COLUMNS))  # the last balance given
        self.attrs = dict(attrs or {})
        self.obstacles = Obstacles(scene)  # their surfaces and poses (catenet.output.obstacles)
        self.history = HistoryLog(history) if history is not None else None
        self.flush_seconds = float(flush_seconds)
        self.flush_frames = int(flush_frames)
        self.frames = 0
        self.times: list[float] = []
        self.flushes = 0
        self.flush_time = 0.0
        self.error: BaseException | None = None  # a failed write: frames stop there
        self.saved_to: Path | None = None  # where the result went instead
        self._spare, self._prev = spare_paths(self.path)
        self._lock = WriteLock(self.path)
        self._pending: list[tuple[float, dict]] = []
        self._pending_bytes = 0
        self._open = False
        self._result_written = False
        self._next_flush = -math.inf
        self._copy_rate = 1e-9  # s per byte copied, measured (a first guess: 1 GB/s)
        self._stale = False  # a write broken off: the spare is copied from the file first
        self.clock = time.monotonic  # the wall clock of the flush interval

    # --- context ---------------------------------------------------------------------------
    def __enter__(self) -> ResultWriter:
        self.open()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close()

    @property
    def has_result(self) -> bool:
        """Whether /result was written (to this file)."""
        return self._result_written

    @property
    def pending(self) -> int:
        """Frames taken but not yet in the file."""
        return len(self._pending)

    @property
    def sidecar(self) -> Path:
        return sidecar_path(self.path)

    def wants(self, step: int) -> bool:
        """Whether step ``step`` (0 = the initial state) is a trajectory frame."""
        return self.every > 0 and step % self.every == 0

    # --- opening ---------------------------------------------------------------------------
    def open(self) -> None:
        """Creates the file (and missing parent directories) with the mesh."""
        check_output_path(self.path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ConfigError(
                f"output file {str(self.path)!r}: cannot create its directory: "
                f"{exc.strerror or exc}"
            ) from None
        self._lock.acquire()  # a second writer of the same file is refused here
        remove_spares(self.path)  # left by a killed run

        def header(h5) -> None:
            self._write_header(h5)
            if self.every > 0:
                self._create_trajectory(h5)
            if self.history is not None:
                self.history.create(h5)  # /history (catenet.output.history)

        try:
            check_free_space(self.path, 2 * header_bytes(self.scene.net))
            write_image(self._spare, header, LIBVER)  # a full disk: OSError, not a crash
            copy_atomically(self._spare, self.path)
        except (OSError, RuntimeError) as exc:
            self._abandon()
            self._lock.release()
            raise OutputError(f"{self.path}: cannot be written: {describe(exc)}") from None
        self._open = True
        # A sidecar left from an earlier run of this file would now lie: remove it.
        if self.xdmf:
            self.sidecar.unlink(missing_ok=True)

    def _abandon(self) -> None:
        """Removes a file that could not even get its header."""
        remove_spares(self.path)
        self.path.unlink(missing_ok=True)

    def _write_header(self, h5) -> None:
        scene = self.scene
        net = scene.net
        env = environment()
        h5.attrs["catenet_version"] = env["catenet"]
        h5.attrs["case"] = scene.case.to_toml() if scene.case is not None else ""
        h5.attrs["created"] = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        title = scene.case.title if scene.case is not None else ""
        if title:
            h5.attrs["title"] = title
        for name, ver in env.items():
            if name != "catenet" and ver:
                h5.attrs[f"{name}_version"] = ver
        for key, value in self.attrs.items():
            h5.attrs[key] = utf8(value)
        mesh = h5.create_group("mesh")
        mesh.create_dataset("nodes", data=np.asarray(net.nodes, dtype=np.float64))
        mesh.create_dataset("edges", data=np.asarray(net.edges, dtype=np.int64))
        mesh.create_dataset("rest_length", data=np.asarray(net.rest_length, dtype=np.float64))
        mesh.create_dataset("EA", data=np.asarray(net.EA, dtype=np.float64))
        mesh.create_dataset("fixed", data=np.asarray(net.fixed, dtype=bool))
        # each node's lumped mass [kg]: rho A l0 / 2 of its edges, point masses, a body's
        mesh.create_dataset("mass", data=np.asarray(net.mass, dtype=np.float64))
        mesh.attrs["probe"] = int(scene.probe)
        mesh.attrs["size"] = float(scene.size)
        write_bodies(mesh, scene)  # moving spheres: /mesh/bodies (catenet.output.bodies)
        write_supports(mesh, net)  # rollers, sliders, springs: /mesh/supports
        self.obstacles.write_mesh(mesh)  # /mesh/obstacles
        write_net_index(mesh, scene)  # cables and node sets by name (catenet.output.netsets)

    def _create_trajectory(self, h5) -> None:
        n, m = self.scene.net.n_nodes, self.scene.net.n_edges
        shapes = {"x": (n, 3), "tension": (m,)}
        if self.velocities:
            shapes["v"] = (n, 3)
        if self.accelerations:
            shapes["a"] = (n, 3)
        if self.energies:
            shapes["energy"] = (len(ENERGY_COLUMNS),)
        g = create_trajectory(h5, {name: shapes[name] for name in TRAJECTORY if name in shapes})
        if self.energies:
            import h5py

            g["energy"].attrs["columns"] = np.array(ENERGY_COLUMNS, dtype=h5py.string_dtype())
            g["energy"].attrs["unit"] = "J"
        self.obstacles.create_trajectory(g)  # moving obstacles' poses and surfaces

    # --- frames ----------------------------------------------------------------------------
    def frame(
        self, t: float, x, v=None, tension=None, a=None, last: bool = False, energy=None
    ) -> None:
        """Takes a frame (a copy); it reaches the file with the next flush. ``v`` (``a``)
        None stores zeros when the file keeps velocities (accelerations); ``tension`` None
        is computed from x. ``last``: the run's final frame, with /result to follow at
        once: it reaches the file with /result (one write, not two), or on ``close``.
        Raises OutputError for a non-finite frame (not kept). A failed write (a full disk)
        is remembered, and frames stop: the run goes on and ``result`` saves the final
        state elsewhere."""
        if self.every == 0 or self.error is not None:
            return
        if not self._open:
            raise OutputError(f"{self.path}: the writer is not open")
        net = self.scene.net
        x = np.array(x, dtype=np.float64)  # a copy: the caller may reuse its arrays
        if x.shape != net.nodes.shape:
            raise OutputError(f"frame x: shape {x.shape}: must be {net.nodes.shape}")
        data = {"x": x, "tension": np.array(self._stored_tension(x, tension))}
        if self.velocities:
            data["v"] = np.zeros_like(x) if v is None else np.array(v, dtype=np.float64)
        if self.accelerations:
            data["a"] = np.zeros_like(x) if a is None else np.array(a, dtype=np.float64)
        if self.energies:  # None: the last balance given (a failed run's last frame)
            if energy is not None:
                self._energy = np.array(energy, dtype=np.float64)
            data["energy"] = self._energy.copy()
        if not math.isfinite(float(t)):
            raise OutputError(f"refusing to write a frame at t = {t!r}: the time must be finite")
        for name, arr in data.items():
            check_finite(name, arr, float(t))
        self._pending.append((float(t), data))
        self._pending_bytes += sum(arr.nbytes for arr in data.values())
        if not last and (
            self.clock() >= self._next_flush
            or (self.flush_frames > 0 and len(self._pending) >= self.flush_frames)
            or self._pending_bytes >= MAX_PENDING_BYTES
        ):
            self.flush()

    def record(self, t: float, row: dict) -> None:
        """Takes a row of the run's /history at time t (``HistoryLog.take``); it reaches
        the file with the next flush, at the latest ``flush_seconds`` later."""
        if self.history is None or self.error is not None or not self._open:
            return
        self.history.take(t, row)
        if (self.frames or not self.every) and self.clock() >= self._next_flush:
            self.flush()  # (a trajectory's first flush is its first frame's, at once)

    def _stored_tension(self, x, tension) -> np.ndarray:
        """The tensions stored with positions x: as given, else computed from the law (the
        one place where the writer derives a measure)."""
        if tension is None:
            tension = measures.tension(self.scene.net, x)
        return np.asarray(tension, dtype=np.float64)

    def flush(self, result: tuple | None = None) -> bool:
        """Writes the pending frames (and ``result``: (Result, attrs), /result) into the
        spare, publishes it as the result file and brings the new spare up to date.
        Returns False after a failed write (``error`` set)."""
        if self.error is not None or not self._open:
            return False
        batch = self._pending
        rows = (self.history.pending, self.history.rows) if self.history else ([], 0)
        if not batch and not rows[0] and result is None:
            return True
        try:
            return self._flush(batch, rows, result)
        except BaseException:  # e.g. Ctrl-C mid-write: the next write starts from the file
            self._stale = True
            raise

    def _flush(self, batch, rows, result) -> bool:
        start = time.perf_counter()
        n0 = self.frames
        encoded = encode(batch)  # compressed once, written twice (or copied)
        if not self._write_spare(batch, encoded, n0, result, rows=rows):
            return False
        written = time.perf_counter() - start
        try:
            publish(self._spare, self.path, self._prev)
        except OSError as exc:
            self._fail(exc)
            return False
        self._pending, self._pending_bytes = [], 0
        if self.history is not None:
            self.history.published(len(rows[0]))
        self.frames += len(batch)
        self.times.extend(t for t, _ in batch)
        if result is not None:
            self._result_written = True
        self._write_sidecar()  # right after the file: it names only frames in the file
        again = batch or rows[0]
        if result is None and again and not self._update_spare(batch, encoded, n0, written, rows):
            return False
        cost = time.perf_counter() - start
        self.flushes += 1
        self.flush_time += cost
        self._next_flush = self.clock() + max(self.flush_seconds, cost / FLUSH_SHARE)
        return True

    def _update_spare(self, batch, encoded, n0: int, written: float, rows) -> bool:
        """Brings the spare (the version just replaced) up to date: by appending the batch
        again, or, where that is predicted to take longer (small files, many frames), by
        copying the published file."""
        size = self.path.stat().st_size
        if self._copy_rate * size >= written:
            return self._write_spare(batch, encoded, n0, again=True, rows=rows)
        start = time.perf_counter()
        try:
            copy_atomically(self.path, self._spare)
        except OSError:  # try the other way before giving up
            return self._write_spare(batch, encoded, n0, again=True, rows=rows)
        self._copy_rate = (time.perf_counter() - start) / max(size, 1)
        return True

    def _write_spare(self, batch, encoded, n0: int, result=None, again=False, rows=None) -> bool:
        """Appends ``batch`` (frames n0, n0 + 1, ...; ``encoded``: see ``chunks.encode``),
        ``rows`` (the history's rows and the index of the first) and ``result`` to the spare.
        ``again``: the spare is the version just replaced; when it cannot be opened (a
        reader holds it), it is replaced by a copy of the published file."""
        import h5py

        h5 = None
        # Dataset objects live as long as the file: one closed while writes fail would make
        # HDF5 keep its identifier and crash at exit (see ``files.detach``).
        held: list = []
        try:
            if self._stale:  # a write broken off left it half done
                copy_atomically(self.path, self._spare)
                self._stale = False
            h5 = h5py.File(self._spare, "r+", libver=LIBVER, rdcc_nbytes=0)
            if batch:
                self._append(h5, batch, encoded, n0, held)
            if rows and rows[0] and self.history is not None:
                self.history.append(h5, rows[0], rows[1], held)
            if result is not None:
                self._write_result(h5, *result)
            h5.close()
            return True
        except (OSError, RuntimeError) as exc:
            failure = exc
        except BaseException:  # broken off: closed here, not when the traceback goes
            held.clear()
            if h5 is not None:
                with contextlib.suppress(Exception):
                    h5.close()
            raise
        if h5 is not None:
            detach(h5)
            held.clear()
            try:
                h5.close()
            except Exception:  # the spare is broken already: it is replaced or dropped
                pass
        if again:
            try:
                copy_atomically(self.path, self._spare)
                return True
            except OSError as exc:
                failure = exc
        self._fail(failure)
        return False

    def _append(self, h5, batch, encoded, n0: int, held: list) -> None:
        g = h5["trajectory"]
        append_frames(g, batch, encoded, n0, held)
        self.obstacles.append(g, [t for t, _ in batch], n0, held, [d for _, d in batch])
        append_times(g, [t for t, _ in batch], n0, held)  # last: then the frames count
        if self.xdmf:
            write_views(h5, n0, n0 + len(batch))

    def _fail(self, exc: BaseException) -> None:
        self.error = exc
        lost = f"; {len(self._pending)} frames not written" if self._pending else ""
        log.warning(
            "%s: writing failed after %d frames (%s)%s; the run goes on, its final state "
            "will be saved to a temporary file",
            self.path,
            self.frames,
            describe(exc),
            lost,
        )
        self._pending, self._pending_bytes = [], 0

    def _write_sidecar(self) -> None:
        if not self.xdmf or not (self.frames or self._result_written):
            return
        net = self.scene.net
        try:
            write_xdmf(
                self.sidecar,
                self.path.name,
                n_nodes=net.n_nodes,
                n_edges=net.n_edges,
                times=self.times,
                velocities=self.velocities,
                bodies=len(self.scene.bodies),  # the balls of /mesh/bodies
                obstacles=self.obstacles.grids(),
            )
        except OSError as exc:
            log.warning("%s: cannot write the XDMF sidecar: %s", self.sidecar, describe(exc))

    # --- result ----------------------------------------------------------------------------
    def result(self, res: Result, **attrs) -> None:
        """Writes /result (final state and its attributes; ``attrs`` add to them) with the
        pending frames. After a failed write, saves root attributes, mesh and /result to a
        temporary file and raises OutputError naming it (with ``.result`` and
        ``.saved_to`` set)."""
        check_finite("x", res.x, float(res.time))
        if self.error is None:
            if not self._open:
                raise OutputError(f"{self.path}: the writer is not open")
            if self.flush(result=(res, attrs)):
                return
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

    def _write_result(self, h5, res: Result, attrs: dict) -> None:
        tension = self._stored_tension(res.x, res.tension)
        group = write_result_group(
            h5, self.scene, res, tension, attrs, self.velocities, self.accelerations
        )
        self.obstacles.write_result(group, float(res.time), res)

    def _save_elsewhere(self, res: Result, attrs: dict) -> Path:
        fd, name = tempfile.mkstemp(prefix=f"{self.path.stem}-", suffix=".h5")
        os.close(fd)
        tmp = Path(name)

        def build(h5) -> None:
            self._write_header(h5)
            h5.attrs["note"] = (
                f"saved here because writing {self.path} failed ({describe(self.error)}); "
                f"the trajectory ({self.frames} frames) is in that file"
            )
            self._write_result(h5, res, attrs)

        try:
            write_image(tmp, build, LIBVER)
        except Exception:
            tmp.unlink(missing_ok=True)
            raise
        return tmp

    # --- closing ---------------------------------------------------------------------------
    def close(self) -> None:
        """Flushes the pending frames and removes the spare: the file is final."""
        if not self._open:
            return
        try:
            if self._pending:
                self.flush()
        finally:
            self._open = False
            try:
                remove_spares(self.path)
            except OSError as exc:
                log.warning("%s: cannot remove the spare copy: %s", self._spare, describe(exc))
            self._lock.release()
