"""What every command shares: options, logging, error handling and exit codes, progress."""

from __future__ import annotations

import contextlib
import gc
import logging
import os
import re
import stat
import sys
import time
from pathlib import Path
from typing import NoReturn

import click

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
# Every command takes -h as --help, also when called on its own (not through the group).
HELP = {"help_option_names": ["-h", "--help"]}


def verbosity_options(f):
    """-q / -v / --debug on a command; the values reach it as ``quiet``, ``verbose``, ``debug``."""
    f = click.option("--debug", is_flag=True, help="Show tracebacks and debug logging.")(f)
    f = click.option(
        "-v",
        "--verbose",
        count=True,
        help="More output (-v: catenet's log, Newton iterations; -vv: the libraries' too).",
    )(f)
    f = click.option(
        "-q", "--quiet", is_flag=True, help="Only errors: no summary, no progress, no warnings."
    )(f)
    return f


class PathParam(click.Path):
    """A path argument or option (click.Path's ``exists``, ``file_okay``, ``dir_okay``)
    whose refusal is catenet's one line on stderr with exit 2, the option and the value
    named (``catenet: error: --output = 'out': is a directory: give a file path such as
    out/run.h5``), never click's usage text; ``give``: what to give instead of a
    directory (a file path) or of a file (a directory)."""

    def __init__(self, *, give: str = "", **kwargs):
        super().__init__(path_type=Path, **kwargs)
        self.give = give

    def convert(self, value, param, ctx):
        why = self.refusal(value)
        if why and not (ctx is not None and ctx.resilient_parsing):  # (not while completing)
            fail(f"{param_name(param)} = {os.fsdecode(value)!r}: {why}", EXIT_BAD_INPUT)
        try:
            return super().convert(value, param, ctx)
        except click.BadParameter as exc:  # a refusal of click's own: its reason, one line
            if ctx is not None and ctx.resilient_parsing:
                raise
            reason = re.sub(r"^\w+ '.*' ", "", exc.message).rstrip(".")
            fail(f"{param_name(param)} = {os.fsdecode(value)!r}: {reason}", EXIT_BAD_INPUT)

    def refusal(self, value) -> str:
        """Why ``value`` is refused ("" when it is not)."""
        path = Path(os.fsdecode(value))
        kind = "file" if not self.dir_okay else "directory" if not self.file_okay else "path"
        try:
            st = path.stat()
        except (OSError, ValueError):  # missing, a parent that is a file, a NUL byte
            if not self.exists:
                return ""
            return (
                f"no such {kind}"
                if path.parent.is_dir() or not path.parent.exists()
                else (f"no such {kind} ({path.parent} is not a directory)")
            )
        if not self.dir_okay and stat.S_ISDIR(st.st_mode):
            return f"is a directory: give {self.give or 'a file'}"
        if not self.file_okay and not stat.S_ISDIR(st.st_mode):
            return f"is not a directory: give {self.give or 'a directory'}"
        if self.exists and self.readable and not os.access(path, os.R_OK):
            return f"the {kind} cannot be read (permission denied)"
        return ""


def param_name(param: click.Parameter | None) -> str:
    """How a message names a parameter: an option by its long name (``--output``), an
    argument by its metavar (``CASE.toml``)."""
    if isinstance(param, click.Option):
        return max(param.opts, key=len)
    if param is not None and param.metavar:
        return param.metavar.strip("[]")
    return (param.name or "PATH").upper() if param is not None else "PATH"


def case_options(output_help: str, example: str):
    """The -o/--output and --set options of the commands that read a case file."""

    def add(f):
        f = click.option(
            "--set",
            "overrides",
            metavar="KEY.PATH=VALUE",
            multiple=True,
            help=f"Override a case value, e.g. --set {example} (repeatable).",
        )(f)
        return click.option(
            "-o",
            "--output",
            "out",
            metavar="OUT.h5",
            type=PathParam(dir_okay=False, give="a file path such as out/run.h5"),
            default=None,
            help=output_help,
        )(f)

    return add


class _OwnLog(logging.Filter):
    """Passes catenet's own records, and other libraries' (h5py, numba, ...) only from
    ``others`` up: -v shows catenet's log lines, not h5py's DEBUG flood."""

    def __init__(self, others: int):
        super().__init__()
        self.others = others

    def filter(self, record: logging.LogRecord) -> bool:
        return _own(record) or record.levelno >= self.others


def _own(record: logging.LogRecord) -> bool:
    """Whether ``record`` is catenet's (its logger or a module's)."""
    return record.name == "catenet" or record.name.startswith("catenet.")


class _Said(logging.Formatter):
    """catenet's own warnings read as its error messages do (``catenet: warning: ...``);
    its other records (debug lines, an error on the way to the one ``catenet: error:``
    line a failed command ends with) and other libraries' keep their level and logger."""

    def __init__(self) -> None:
        super().__init__("%(levelname)s %(name)s: %(message)s")

    def format(self, record: logging.LogRecord) -> str:
        if _own(record) and record.levelno == logging.WARNING:
            return f"catenet: warning: {record.getMessage()}"
        return super().format(record)


def setup_logging(quiet: bool = False, verbose: int = 0, debug: bool = False) -> None:
    """Log to stderr: warnings; -v catenet's debug lines too; -vv or --debug every
    library's; -q errors only."""
    level = logging.WARNING
    if debug or verbose >= 1:
        level = logging.DEBUG
    if quiet:
        level = logging.ERROR
    others = logging.DEBUG if (debug or verbose >= 2) and not quiet else max(level, logging.WARNING)
    handler = logging.StreamHandler(sys.stderr)
    handler.addFilter(_OwnLog(others))
    handler.setFormatter(_Said())
    logging.basicConfig(level=level, handlers=[handler], force=True)
    logging.getLogger("numba").setLevel(logging.WARNING)
    logging.getLogger("matplotlib").setLevel(logging.WARNING)


def fail(message: str, code: int) -> NoReturn:
    """One clear message on stderr and the exit code."""
    click.echo(f"catenet: error: {message}", err=True)
    sys.exit(code)


@contextlib.contextmanager
def collecting_later():
    """No garbage collection inside the block (a command's imports: NumPy's, Numba's and
    catenet's modules make many objects and no garbage, and collecting while they load
    costs a `catenet run` 2 % of its CPU time); the collector as it was after it."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


@contextlib.contextmanager
def errors_to_exit_codes(debug: bool = False):
    """Maps catenet's exceptions to one line on stderr and the exit codes of the contract:
    ConfigError -> 2; ConvergenceError, OutputError, other CatenetError -> 1. With
    ``debug`` the traceback is shown as well. Unexpected exceptions are reported as
    internal errors (exit 1), never as a bare traceback."""
    from catenet.errors import CatenetError, ConfigError

    try:
        yield
    except ConfigError as exc:
        if debug:
            raise
        lines = exc.problems or [str(exc)]
        if len(lines) == 1:
            fail(lines[0], EXIT_BAD_INPUT)
        click.echo(f"catenet: error: {len(lines)} problems in the input:", err=True)
        for line in lines:
            click.echo(f"  {line}", err=True)
        sys.exit(EXIT_BAD_INPUT)
    except CatenetError as exc:
        if debug:
            raise
        fail(str(exc), EXIT_FAILED)
    except KeyboardInterrupt:
        if debug:
            raise
        fail("interrupted", 130)
    except MemoryError as exc:
        if debug:
            raise
        fail(f"out of memory: {exc}", EXIT_FAILED)
    except OSError as exc:
        if debug:
            raise
        fail(f"{exc.strerror or exc}: {exc.filename or ''}".rstrip(": "), EXIT_FAILED)
    except Exception as exc:  # a bug: one line, and how to see more
        if debug:
            raise
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        fail(
            f"{INTERNAL}: {type(exc).__name__}: {reason} (run the same command again with "
            "--debug after the command's name, e.g. 'catenet run --debug ...', for the "
            "traceback, and please report it)",
            EXIT_FAILED,
        )


#: How an unexpected exception (a bug in catenet) is reported: exit 1, never a traceback.
INTERNAL = "internal error"


class Progress:
    """A one-line progress bar with rate and ETA on a terminal; silent in pipes and with -q.

    ``update(done, total, note="", eta=True)`` (``eta=False``: the bar and the note only,
    for progress whose rate says nothing about what is left); ``close()``.
    """

    def __init__(self, label: str, *, enabled: bool | None = None, stream=None):
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.label = label
        self.start = time.perf_counter()
        self._last = 0.0
        self._shown = False

    def update(self, done: float, total: float, note: str = "", eta: bool = True) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < 0.1 and done < total:
            return
        self._last = now
        elapsed = now - self.start
        frac = min(max(done / total, 0.0), 1.0) if total > 0 else 0.0
        rate = done / elapsed if elapsed > 0 else 0.0
        left = (total - done) / rate if rate > 0 else float("nan")
        width = 24
        bar = "#" * int(frac * width) + "-" * (width - int(frac * width))
        if eta:
            eta_s = f"{left:6.1f}s" if left == left else "   ?  "
            timing = f"  {rate:8.3g}/s  ETA {eta_s}"
        else:
            timing = ""
        self.stream.write(f"\r{self.label} [{bar}] {100 * frac:5.1f}%{timing} {note}\x1b[K")
        self.stream.flush()
        self._shown = True

    def close(self) -> None:
        if self._shown:
            self.stream.write("\n")
            self.stream.flush()
            self._shown = False
