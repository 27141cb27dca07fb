"""Where a run's time goes: start-up (the interpreter, imports, the case, loading the JIT
cache) against the solve (the engine: the pattern, PARDISO's phases, the Newton
iterations), as ``catenet run`` prints and stores them (/result ``startup_time`` and
``solve_time``).

Numba compiles, or loads from its cache, a kernel on its first call, inside the solve;
that time is start-up, not solving: it is measured by a listener on Numba's compiler lock
(held while a kernel is compiled or loaded, and while Numba initialises its target on the
first one) and moved from the solve to the start-up.
"""

from __future__ import annotations

import contextlib
import os
import time

_IMPORTED = time.perf_counter()  # the fallback origin where the process start is unknown


def since_process_start() -> float:
    """Seconds since this process started: from the kernel's start time of the process
    (Linux, 10 ms resolution), else since this module was imported."""
    try:
        with open("/proc/self/stat", "rb") as fh:
            fields = fh.read().rsplit(b")", 1)[1].split()
        started = int(fields[19]) / os.sysconf("SC_CLK_TCK")  # field 22: starttime
        return max(time.clock_gettime(time.CLOCK_BOOTTIME) - started, 0.0)
    except (OSError, ValueError, IndexError, AttributeError):
        return time.perf_counter() - _IMPORTED


class Clock:
    """Splits a run into start-up and solve.

    ``with clock.solving():`` wraps the engine's work; ``with clock.aside():`` inside it
    wraps what is neither (writing frames). The JIT time (compiling or loading kernels)
    within these blocks counts as start-up; before the first block, everything does.
    """

    def __init__(self):
        self.jit = 0.0  # seconds in Numba's compiler lock within the blocks
        self._depth = 0  # of the compiler lock
        self._blocks = 0  # open solving/aside blocks
        self._listening = contextlib.ExitStack()
        self._since = 0.0
        self._first: float | None = None  # process seconds when the solve began
        self._solving = 0.0
        self._jit_solving = 0.0
        self._aside = 0.0
        self._in_solve = 0

    def _on_start(self) -> None:
        if self._depth == 0:
            self._since = time.perf_counter()
        self._depth += 1

    def _on_end(self) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.jit += time.perf_counter() - self._since

    @contextlib.contextmanager
    def _listen(self):
        """Listens to Numba's compiler lock while a block is open."""
        self._blocks += 1
        if self._blocks == 1:
            try:
                from numba.core import event

                clock = self

                class Listener(event.Listener):
                    def on_start(self, ev):
                        clock._on_start()

                    def on_end(self, ev):
                        clock._on_end()

                self._listening.enter_context(
                    event.install_listener("numba:compiler_lock", Listener())
                )
            except (ImportError, AttributeError):  # another Numba: JIT time counts as solve
                pass
        try:
            yield
        finally:
            self._blocks -= 1
            if self._blocks == 0:
                self._listening.close()

    @contextlib.contextmanager
    def solving(self):
        if self._first is None:
            self._first = since_process_start()
        start, jit = time.perf_counter(), self.jit
        self._in_solve += 1
        try:
            with self._listen():
                yield self
        finally:
            self._in_solve -= 1
            self._solving += time.perf_counter() - start
            self._jit_solving += self.jit - jit

    @contextlib.contextmanager
    def aside(self):
        start, jit = time.perf_counter(), self.jit
        try:
            with self._listen():
                yield self
        finally:
            if self._in_solve:  # only what a solve block counted is taken out of it
                self._aside += (time.perf_counter() - start) - (self.jit - jit)

    @property
    def solve(self) -> float:
        """Seconds of the engine's own work (JIT and writing frames left out)."""
        return max(self._solving - self._jit_solving - self._aside, 0.0)

    @property
    def startup(self) -> float:
        """Seconds from the process start to the solve, plus the JIT time."""
        first = since_process_start() if self._first is None else self._first
        return first + self.jit
