"""Hostile input for catenet's commands and the judge of what they do with it.

Mutations (each takes a ``random.Random``, so that hypothesis in tests/fuzz and the long
run in benchmarks/fuzz.py draw the same kinds of input):

- ``mutate_case``: a case table (an example case of configs/, or one built from the
  declared keys) with one to three changes: a value replaced by a hostile one (wrong type,
  NaN, infinities, huge, tiny, integers beyond 64 bits, dates, long or odd text, empty
  arrays and tables), a key or a table removed or emptied, an unknown key, a typo, deep
  nesting, counts that would never finish; ``render`` writes it as TOML, sometimes in an
  odd encoding (UTF-16, Latin-1 bytes, NUL bytes, a byte-order mark) or truncated.
- ``mutate_text``: a net file (JSON, CSV, OBJ) or a mesh (STL) cut, with bytes flipped,
  lines dropped, repeated or garbled, numbers replaced by hostile ones.
- ``mutate_params``: sweep values (``--param key=...``) from a small grammar of numbers,
  expressions, ranges and junk.
- ``mutate_result``: a result file truncated at a random offset, bytes flipped, datasets
  of the wrong shape or type, groups missing.

``judge(result, work)`` sorts an outcome into "ok" (exit 0, every number in the files
finite), "bad input" (exit 2: one message naming what was wrong, no NumPy reprs, nothing
left behind), "failed" (exit 1 with catenet's message), "long" (a dynamic run still
taking steps when its time was up: slow, not stuck) or a bad class: "traceback", "hang",
"exit code", "unclear message", "numpy repr", "non-finite result", "leftover".
"""

from __future__ import annotations

import contextlib
import copy
import datetime
import math
import os
import random
import re
import signal
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
CONFIGS = REPO / "configs"

GOOD = ("ok", "bad input", "failed", "long")

HOSTILE = [
    math.nan,
    math.inf,
    -math.inf,
    1e300,
    -1e300,
    1e101,
    1e99,
    -1e99,
    1e-300,
    5e-324,
    0,
    0.0,
    -1,
    -0.5,
    0.5,
    3,
    2**63 - 1,
    -(2**63),
    "",
    " ",
    "x",
    "dynamic",
    "pi/4",
    "1e400",
    "\u202e\u00e9\u4e2d",
    "a" * 5000,
    True,
    False,
    [],
    [1, 2],
    [math.nan, 0, 0],
    [1e300, 0, 0],
    [0, 0, -1e100],
    [[1, 2], [3]],
    {},
    {"a": 1},
    datetime.date(2020, 1, 1),
    datetime.time(12, 0),
]
COUNTS = ["steps", "max_iter", "nodes", "n", "every", "threads"]
HUGE_COUNTS = [10**9, 10**12, 1e300, 2**62, 10**6 + 1]
NUMPY_REPR = re.compile(r"np\.(float|int|bool|str)\w*\(|array\(\[|dtype=")
#: What catenet says when a run (or a sweep's rows) failed: exit 1.
FAILED = re.compile(r"catenet: (error|did not converge)|error:|rows failed or did not converge")
HIDDEN = re.compile(r"^\..*\.(spare|prev|copy|lock)$")


# --------------------------------------------------------------------------------------------
# Case tables
# --------------------------------------------------------------------------------------------


def paths(data, prefix=()) -> list[tuple]:
    """Every path into nested tables and arrays, containers included."""
    out = []
    items = data.items() if isinstance(data, dict) else enumerate(data)
    for k, v in items:
        p = (*prefix, k)
        out.append(p)
        if isinstance(v, (dict, list)) and len(p) < 8:
            out.extend(paths(v, p))
    return out


def _parent(data, path):
    cur = data
    for k in path[:-1]:
        cur = cur[k]
    return cur


def _deep(depth: int):
    value: object = 1
    for _ in range(depth):
        value = {"a": value}
    return value


def hostile(rng: random.Random):
    """A copy of one of HOSTILE's values: later mutations change the case in place, and
    one that changed a shared list or table would change HOSTILE itself for every later
    draw (hypothesis then finds its data generation inconsistent on a replay, and the
    failure it replays is lost)."""
    return copy.deepcopy(rng.choice(HOSTILE))


def mutate_case(data: dict, rng: random.Random) -> list[str]:
    """Changes ``data`` in place (one to three mutations); returns what was done."""
    notes = []
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        where = paths(data)
        if not where:
            data["geometry"] = hostile(rng)
            notes.append("geometry replaced")
            continue
        path = rng.choice(where)
        parent = _parent(data, path)
        key = path[-1]
        op = rng.randrange(10)
        shown = ".".join(map(str, path))
        if op <= 3:
            parent[key] = hostile(rng)
            notes.append(f"{shown} = {parent[key]!r:.40}")
        elif op == 4:
            del parent[key]
            notes.append(f"{shown} removed")
        elif op == 5 and isinstance(parent[key], dict):
            parent[key] = {}
            notes.append(f"{shown} emptied")
        elif op == 6 and isinstance(parent, dict):
            typo = str(key)[:-1] + rng.choice("xyz_") if str(key) else "x"
            parent[typo] = parent.pop(key)
            notes.append(f"{shown} renamed {typo!r}")
        elif op == 7 and isinstance(parent, dict):
            parent[f"unknown_{rng.randrange(100)}"] = hostile(rng)
            notes.append(f"unknown key beside {shown}")
        elif op == 8:
            parent[key] = _deep(rng.choice((3, 40, 200)))
            notes.append(f"{shown} nested deeply")
        else:
            table = data.setdefault(rng.choice(("solver", "geometry", "output")), {})
            if isinstance(table, dict):
                name = rng.choice(COUNTS)
                table[name] = rng.choice(HUGE_COUNTS)
                notes.append(f"count {name} = {table[name]!r}")
    return notes


def render(data: dict, rng: random.Random) -> bytes:
    """The case as TOML bytes; now and then in an odd encoding, with junk, or cut."""
    import tomli_w

    try:
        try:
            text = tomli_w.dumps(data)
        except Exception:  # what TOML cannot hold (e.g. a huge integer): the value as text
            text = tomli_w.dumps(_as_text(data))
    except RecursionError:  # nested deeper than tomli-w writes: nested arrays instead
        return b"title = " + b"[" * 2000 + b"]" * 2000 + b"\n"
    raw = text.encode("utf-8", "surrogateescape")
    op = rng.randrange(12)
    if op == 0:
        return text.encode("utf-16")
    if op == 1:
        return b"\xef\xbb\xbf" + raw
    if op == 2:
        return raw.replace(b"=", b"= \xff", 1)
    if op == 3 and raw:
        return raw[: rng.randrange(len(raw))]
    if op == 4:
        return raw + b"\x00\n"
    return raw


def _as_text(v):
    if isinstance(v, dict):
        return {k: _as_text(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_as_text(x) for x in v]
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 2**63:
        return str(v)
    return v


# --------------------------------------------------------------------------------------------
# Net files, sweep values, result files
# --------------------------------------------------------------------------------------------

NUMBERS = ["nan", "inf", "-inf", "1e300", "1e400", "-0", "", "x", "1e-320", "99999999999999999999"]


def mutate_text(raw: bytes, rng: random.Random) -> bytes:
    """A text file (JSON, CSV, OBJ, ASCII STL) damaged in one to three places."""
    for _ in range(rng.choice((1, 1, 2, 3))):
        op = rng.randrange(6)
        if not raw:
            return b"\xff\xfe"
        if op == 0:
            raw = raw[: rng.randrange(len(raw))]
        elif op == 1:
            k = rng.randrange(len(raw))
            raw = raw[:k] + bytes([raw[k] ^ (1 << rng.randrange(8))]) + raw[k + 1 :]
        elif op == 2:
            lines = raw.split(b"\n")
            k = rng.randrange(len(lines))
            lines[k : k + 1] = [] if rng.random() < 0.5 else [lines[k]] * 3
            raw = b"\n".join(lines)
        else:  # a number replaced by a hostile one
            found = list(re.finditer(rb"-?\d+(\.\d+)?(e-?\d+)?", raw))
            if found:
                m = rng.choice(found)
                raw = raw[: m.start()] + rng.choice(NUMBERS).encode() + raw[m.end() :]
    return raw


VALUE_PARTS = [
    "1", "2.5", "-3", "0", "1e300", "1e400", "-1e400", "nan", "inf", "pi/4", "radians(30)",
    "9**9**9", "10**400", "2**0.5", "(-1)**0.5", "1/0", "0:1:inf", "0:1e-300:1", "1:0:5",
    "0:0.25:1", "10:8:34", "1979-05-27", '"text"', "[0, 0, -9.81]", "[", "{a = 1}", "true",
    "scipy", "sqrt(-1)", "e**1000", "1e-320", "__import__('os')", "x" * 300,
]  # fmt: skip
SWEPT = [
    "load.pressure", "geometry.alpha", "geometry.n", "material.E", "solver.method",
    "solver.dt", "load.gravity", "nonsense.key", "geometry", "a.b.c.d", "load.pressure.x",
]  # fmt: skip


def mutate_params(rng: random.Random) -> list[str]:
    """One or two ``--param key=values`` texts from the grammar above."""
    out = []
    for _ in range(rng.choice((1, 1, 2))):
        values = ",".join(rng.choice(VALUE_PARTS) for _ in range(rng.choice((1, 2, 3))))
        out.append(f"{rng.choice(SWEPT)}={values}")
    return out


def mutate_result(src: Path, dst: Path, rng: random.Random) -> str:
    """``dst``: ``src`` damaged in one way (returned)."""
    import h5py

    raw = src.read_bytes()
    op = rng.randrange(5)
    if op == 0:
        k = rng.randrange(len(raw))
        dst.write_bytes(raw[:k])
        return f"truncated at {k}"
    if op == 1:
        data = bytearray(raw)
        for _ in range(rng.choice((1, 4, 32))):
            k = rng.randrange(len(data))
            data[k] ^= 1 << rng.randrange(8)
        dst.write_bytes(bytes(data))
        return "bytes flipped"
    dst.write_bytes(raw)
    with h5py.File(dst, "a") as h5:
        names: list[str] = []
        h5.visit(names.append)
        name = rng.choice(names)
        obj = h5[name]
        if op == 2 or not hasattr(obj, "shape"):
            del h5[name]
            return f"{name} removed"
        del h5[name]
        shape = obj.shape if op == 3 else ()
        if op == 3:  # the wrong shape
            h5[name] = np.zeros(tuple(max(1, s - 1) for s in shape) + (2,))
            return f"{name} of the wrong shape"
        h5[name] = np.array([b"not", b"numbers"]) if rng.random() < 0.5 else np.float64(np.nan)
        return f"{name} of the wrong type"


# --------------------------------------------------------------------------------------------
# Running a command in this process, and the judge
# --------------------------------------------------------------------------------------------


class Hang(BaseException):
    """A command that did not end within its time (a BaseException: catenet's handlers of
    unexpected exceptions must not take it for one of the command's own)."""


class Long(Hang):
    """A dynamic run stopped at its checkpoint while still taking steps: long, not hung."""


@dataclass
class Outcome:
    kind: str
    detail: str = ""

    @property
    def good(self) -> bool:
        return self.kind in GOOD


#: A command waiting (not computing) is a hang after this many times its time limit.
WALL_FACTOR = 4.0


@dataclass
class Progress:
    """The time steps a command has taken: how many, to what time, and this process's
    processor time at the last one."""

    steps: int = 0
    t: float = 0.0
    cpu: float = -math.inf


@contextlib.contextmanager
def watching_steps():
    """Yields a Progress that every accepted time step of the command updates."""
    import pytest

    from catenet.solver.stepper import TimeStepper

    progress = Progress()
    accept = TimeStepper.accept

    def counted(stepper, *args, **kwargs):
        accept(stepper, *args, **kwargs)
        progress.steps += 1
        progress.t = stepper.t
        progress.cpu = time.process_time()

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(TimeStepper, "accept", counted)
        yield progress


@contextlib.contextmanager
def time_limit(seconds: float, long_after: float | None = None):
    """Raises Hang in the main thread after ``seconds`` of this process's processor time
    (a command computing for ever), or WALL_FACTOR times as long on the clock (one
    waiting for ever). Processor time, not the clock: on a machine shared with other
    work a long but finite run gets the processor for a share of the clock only (the long
    fuzz run's seed 11 stopped the folded net's 10 s run, 41 s of processor time, after
    120 s on a machine at a load of 7 on 2 cores). Python code only: a hang inside C code
    would outlast it, which the test's own timeout then catches.

    ``long_after``: a checkpoint (processor seconds) where a dynamic run that took a time
    step within the last quarter of it is stopped as Long: still advancing, so slow and
    not stuck (a 10 s default run of a capture takes minutes; the checkpoint bounds what
    it costs the fuzzing without calling it a hang). A run not advancing there goes on to
    ``seconds``."""
    checkpoint = long_after is not None and long_after < seconds
    watch = watching_steps() if checkpoint else contextlib.nullcontext(Progress())

    def alarm(signum, frame):
        if signum == signal.SIGALRM:
            raise Hang(f"no end after {WALL_FACTOR * seconds:g} s on the clock")
        now = time.process_time()
        if state["checkpoint"]:
            state["checkpoint"] = False
            if progress.steps and now - progress.cpu < 0.25 * long_after:
                raise Long(
                    f"still advancing after {long_after:g} s of processor time: "
                    f"t = {progress.t:.4g} s after {progress.steps} steps"
                )
            signal.setitimer(signal.ITIMER_PROF, seconds - long_after)
            return
        raise Hang(f"no end after {seconds:g} s of processor time")

    state = {"checkpoint": checkpoint}
    previous = signal.signal(signal.SIGALRM, alarm), signal.signal(signal.SIGPROF, alarm)
    try:
        with watch as progress:
            signal.setitimer(signal.ITIMER_PROF, long_after if checkpoint else seconds)
            signal.setitimer(signal.ITIMER_REAL, WALL_FACTOR * seconds)
            yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGALRM, previous[0])
        signal.signal(signal.SIGPROF, previous[1])


@contextlib.contextmanager
def small_machine():
    """Nets beyond a few 10^4 nodes refused as on a small machine, so that a mutation
    that asks for millions of nodes is bad input, not minutes of work."""
    import pytest

    from catenet.case import guard
    from catenet.model import builders

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(guard, "MAX_NODES", 40_000)
        mp.setattr(builders, "MAX_NODES", 40_000)
        yield


def invoke(
    args: list[str], seconds: float = 60.0, cwd: Path | None = None, long_after: float | None = None
):
    """``catenet *args`` in this process (click's CliRunner), bounded in time (time_limit)."""
    from click.testing import CliRunner

    from catenet.cli import main

    here = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with small_machine(), time_limit(seconds, long_after):
            return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    except Hang as exc:  # CliRunner lets a BaseException through
        return Stopped(exc)
    finally:
        os.chdir(here)


@dataclass
class Stopped:
    """What ``invoke`` returns for a command stopped by its time limit."""

    exception: BaseException
    output: str = ""
    stderr_bytes: bytes | None = None
    stderr: str = ""
    exit_code: int | None = None


def judge(result, work: Path, before: set[Path] = frozenset()) -> Outcome:
    """The class of an outcome of ``invoke``; ``work``: the directory it wrote into,
    ``before``: the files that were there already."""
    out = result.output + (result.stderr if result.stderr_bytes is not None else "")
    exc = result.exception
    if isinstance(exc, Long):
        return Outcome("long", str(exc))
    if isinstance(exc, Hang):
        return Outcome("hang", str(exc))
    if exc is not None and not isinstance(exc, SystemExit):
        return Outcome("traceback", f"{type(exc).__name__}: {exc}"[:300])
    if "Traceback (most recent call last)" in out or "internal error:" in out:
        return Outcome("traceback", out[-300:])
    code = result.exit_code
    if code not in (0, 1, 2):
        return Outcome("exit code", f"{code}: {out[-200:]}")
    left = [p for p in work.rglob("*") if HIDDEN.match(p.name)]
    if left:
        return Outcome("leftover", ", ".join(p.name for p in left))
    new = [p for p in work.rglob("*.h5") if p not in before]
    if code == 2:
        if NUMPY_REPR.search(out):
            return Outcome("numpy repr", out[-300:])
        if "error" not in out.lower():
            return Outcome("unclear message", out[-300:])
        made = [p for p in new if p.is_file()]
        if made:
            return Outcome("leftover", f"exit 2 and {made[0].name} written")
        return Outcome("bad input", out.strip().splitlines()[-1][:200] if out.strip() else "")
    if code == 1 and not re.search(FAILED, out):
        return Outcome("unclear message", out[-300:])
    for path in new:
        bad = nonfinite(path)
        if bad:
            return Outcome("non-finite result", f"{path.name}: {bad}")
    return Outcome("ok" if code == 0 else "failed", out.strip()[-200:])


def nonfinite(path: Path) -> str:
    """The first dataset of /result, /trajectory or /mesh (a result file) or of a sweep's
    table with a non-finite number where a number is due, else '' (a utilisation is NaN
    where no breaking load or capacity is given: not checked, as documented)."""
    import h5py

    try:
        h5 = h5py.File(path, "r")
    except OSError:
        return ""
    with h5:
        if "result" in h5:
            for name, value in h5["result"].attrs.items():
                if name == "residual" and not np.isfinite(float(value)):
                    return f"/result residual = {value}"
        for group in ("result", "trajectory", "mesh"):
            if group not in h5 or not hasattr(h5[group], "items"):
                continue
            for name, ds in h5[group].items():
                if "utilisation" in name:  # NaN: no breaking load or capacity (documented)
                    continue
                if hasattr(ds, "dtype") and ds.dtype.kind == "f" and ds.size:
                    arr = ds[()]
                    if not np.all(np.isfinite(arr)):
                        return f"/{group}/{name}"
    return ""


SEEDS = Path(__file__).resolve().parent / "fuzz" / "cases"


def example_cases() -> list[Path]:
    """The bundled example cases (configs/), sweeps and form finding included, and the
    fuzzing's own seeds (tests/fuzz/cases: a mechanism, a snap-through, load cases and
    combinations with area loads, a run to rest)."""
    return sorted(CONFIGS.rglob("*.toml")) + sorted(SEEDS.glob("*.toml"))


def command_for(data: dict, rng) -> list[str]:
    """The command a mutated case goes through: ``formfind`` for most form-finding cases,
    ``modes`` for a quarter of the static ones (its equilibrium, then the modes), else
    ``run``; the arguments after the case file (besides -o and -q)."""
    if "formfind" in data and rng.random() < 0.7:
        return ["formfind"]
    solver = data.get("solver")
    method = solver.get("method", "static") if isinstance(solver, dict) else "static"
    if method == "static" and rng.random() < 0.25:
        return ["modes", "--count", str(rng.choice([1, 3, 6]))]
    return ["run"]


def small(data: dict) -> dict:
    """An example case made small enough to run in about a second: square nets of at
    most 10 cables and 10 edges a side, cables of at most 41 nodes, dynamic runs of at
    most 0.3 s, at most 5 load steps. Mutations then act on this case."""
    geo = data.get("geometry", {})
    kind = geo.get("kind")
    if kind == "square_net":
        geo["n"] = min(geo.get("n", 10), 10)
        geo["edge_length"] = max(geo.get("edge_length", 0.1), geo.get("size", 1.0) / 10)
    elif kind == "cable":
        geo["nodes"] = min(geo.get("nodes", 41), 41)
    solver = data.setdefault("solver", {})
    if solver.get("method") == "dynamic" and solver.get("t_end") == "rest":
        solver["max_steps"] = min(solver.get("max_steps", 400), 400)  # a run to rest
    elif solver.get("method") == "dynamic":
        solver["t_end"] = min(solver.get("t_end", 0.3), 0.3)
        solver["dt"] = min(solver.get("dt", 0.01), solver["t_end"])
    else:
        solver["steps"] = min(solver.get("steps", 5), 5)
    data.pop("sweep", None)
    return data


def copy_beside(case: Path, work: Path) -> None:
    """The files a case names beside it (nets, meshes) copied into ``work``."""
    import shutil

    for sibling in case.parent.iterdir():
        if sibling.suffix.lower() in (".json", ".csv", ".obj", ".stl", ".vtu", ".msh"):
            shutil.copy(sibling, work / sibling.name)


# Seeds shared by the quick tier (tests/fuzz) and the long run (benchmarks/fuzz.py).
NET_CASE = """
title = "net from a file"
[geometry]
kind = "graph"
file = "{name}"
fixed = [0, 3]
[material]
EA = 1000.0
[load]
point = [{{node = 1, force = [0.0, 0.0, -10.0]}}]
[solver]
method = "static"
"""

NET_FILES = {
    "net.json": b'{"nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], '
    b'"edges": [[0, 1], [1, 2], [2, 3]]}',
    "net.csv": b"x,y,z\n0,0,0\n1,0,0\n2,0,0\n3,0,0\n\ni,j\n0,1\n1,2\n2,3\n",
    "net.obj": b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nl 1 2 3 4\n",
}

SWEEP_CASE = """
title = "sweep"
[geometry]
kind = "square_net"
n = 4
alpha = 0.0
size = 1.0
edge_length = 0.25
[material]
E = 10e6
radius = 0.01
[load]
pressure = 10.0
[solver]
method = "static"
"""
