"""Parameter sweeps: a base case run over the Cartesian product of parameter values.

A sweep is a base case file and a list of parameters ``key.path = v1, v2, ...``. Keys under
``load.`` are *load keys*: for every combination of the other keys (a *job*) the load
levels (the product of the load keys' values, in the order given) are solved as one
continuation over one net and one Workspace, each level starting from the previous
equilibrium, so a whole force-displacement curve costs little more than its last point.

Jobs run in this process (``workers=1``), in a pool of spawned processes
(``concurrent.futures.ProcessPoolExecutor``; MKL, OpenMP and Numba threads per process set
to ``max(1, cores // workers)``), or on a Dask distributed cluster (``scheduler=ADDRESS``).

Everything a sweep has found is in the append-only journal ``DIR/results.jsonl``: a header
line (the base case, the parameters and their fingerprint), then one line per finished job,
flushed to disk as soon as the job returns. ``DIR/results.csv`` and ``DIR/results.h5`` are
regenerated from it. Running the same sweep into the same directory again skips the jobs
the journal already holds (resume after a crash or Ctrl-C); a journal of another base case
or other parameters is refused.

Columns of the table: the swept keys (by key path, in the order given), then ``delta``
(z-deflection of the scene's probe node, positive down) [m], ``delta_over_L``, ``F_bar``
(|sum of the external nodal forces| / EA, = p L^2 / EA for the square net), ``max_strain``,
``slack_edges`` (edges shorter than their rest length), ``iterations`` (Newton iterations
of that load level), ``wall_time`` [s] (building the net and the workspace counts towards
the first level of a job), ``converged``, ``error`` (empty on success), ``attempts`` (2
when the job was retried after its worker process died) and ``run_file`` (the level's
HDF5 file under ``runs/`` with ``save_runs``, else empty).

Test hook: with ``CATENET_TEST_CRASH=<job index>`` in the environment, a worker process
(pool or Dask, never the calling process) that starts that job exits with status 1 the
first time, leaving a marker file ``DIR/.crash-<index>`` so that the retry succeeds.
"""

from __future__ import annotations

import ast
import contextlib
import csv
import hashlib
import itertools
import json
import logging
import math
import operator
import os
import time
import tomllib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any

from catenet.errors import CatenetError, ConfigError

log = logging.getLogger(__name__)

LOAD_PREFIX = "load."
JOURNAL = "results.jsonl"
CSV_FILE = "results.csv"
H5_FILE = "results.h5"
RUNS_DIR = "runs"
RUNNING_DIR = ".running"
FORMAT_VERSION = 1
RESULT_COLUMNS = (
    "delta",
    "delta_over_L",
    "F_bar",
    "max_strain",
    "slack_edges",
    "iterations",
    "wall_time",
    "converged",
    "error",
    "attempts",
    "run_file",
)
MAX_VALUES = 100_000
MAX_VALIDATED = 5_000  # combinations checked as cases before a sweep starts
THREAD_VARIABLES = (
    "MKL_NUM_THREADS",
    "NUMBA_NUM_THREADS",
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
)
CRASH_VARIABLE = "CATENET_TEST_CRASH"


# --------------------------------------------------------------------------------------------
# Parameter values: TOML scalars, pi expressions, inclusive ranges start:step:stop
# --------------------------------------------------------------------------------------------

_OPS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.USub: operator.neg,
    ast.UAdd: operator.pos,
}
_NAMES = {"pi": math.pi, "e": math.e, "tau": math.tau}
_FUNCS = {
    "sqrt": math.sqrt,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "radians": math.radians,
    "degrees": math.degrees,
}


class _NotExpression(Exception):
    pass


def evaluate(text: str) -> float | int:
    """An arithmetic expression of numbers, ``pi``, ``e``, ``tau``, ``+ - * / **`` and
    ``sqrt sin cos tan radians degrees`` (``pi/4``, ``2*pi/3``, ``radians(30)``).
    Raises ValueError when ``text`` is not such an expression."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"not an expression: {text!r}") from exc

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return node.value
        if isinstance(node, ast.Name) and node.id in _NAMES:
            return _NAMES[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.operand))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _FUNCS
            and len(node.args) == 1
            and not node.keywords
        ):
            return _FUNCS[node.func.id](ev(node.args[0]))
        raise ValueError(f"not an expression of numbers and pi: {text!r}")

    try:
        value = ev(tree)
    except (ZeroDivisionError, OverflowError) as exc:
        raise ValueError(f"{text!r}: {exc}") from exc
    if isinstance(value, complex) or not math.isfinite(value):
        raise ValueError(f"{text!r}: not a finite real number")
    return value


def _toml_scalar(text: str):
    """``text`` read as a TOML value; raises ValueError when it is not one."""
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(str(exc)) from exc
    if _has_datetime(value):
        raise ValueError(f"{text!r}: dates and times are not parameter values")
    return value


def _has_datetime(value) -> bool:
    import datetime as dt

    if isinstance(value, (dt.date, dt.time, dt.datetime)):
        return True
    if isinstance(value, list):
        return any(_has_datetime(v) for v in value)
    if isinstance(value, dict):
        return any(_has_datetime(v) for v in value.values())
    return False


def _number(text: str):
    """A number from a TOML literal or an expression; ValueError otherwise."""
    try:
        value = _toml_scalar(text)
    except ValueError:
        return evaluate(text)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{text!r}: not a number")
    return value


def _decimal(text: str) -> Decimal | None:
    try:
        return Decimal(text.strip().replace("_", ""))
    except InvalidOperation:
        return None


def expand_range(text: str) -> list:
    """``start:step:stop``, inclusive of ``stop`` when the steps land on it (within
    1e-9 of a step): ``0:0.25:0.75`` -> [0.0, 0.25, 0.5, 0.75], ``10:8:34`` ->
    [10, 18, 26, 34], ``0:pi/8:pi/4``. Integers stay integers; decimal literals are
    stepped exactly (no 0.30000000000000004)."""
    parts = text.split(":")
    if len(parts) != 3 or not all(p.strip() for p in parts):
        raise ValueError(f"{text!r}: a range is start:step:stop (e.g. 0:0.25:0.75)")
    try:
        start, step, stop = (_number(p) for p in parts)
    except ValueError as exc:
        raise ValueError(f"{text!r}: a range is start:step:stop of numbers ({exc})") from None
    if step == 0:
        raise ValueError(f"{text!r}: the step must not be 0")
    span = (stop - start) / step
    if span < -1e-9:
        raise ValueError(f"{text!r}: the step goes away from stop (check its sign)")
    count = math.floor(span + 1e-9) + 1
    if count > MAX_VALUES:
        raise ValueError(f"{text!r}: {count} values: at most {MAX_VALUES}")
    if all(type(v) is int for v in (start, step, stop)):
        return [start + k * step for k in range(count)]
    decimals = [_decimal(p) for p in parts]
    if all(d is not None and d.is_finite() for d in decimals):
        d0, ds, _ = decimals
        return [float(d0 + k * ds) for k in range(count)]
    values = [float(start + k * step) for k in range(count)]
    if abs(values[-1] - stop) <= 1e-9 * abs(step):
        values[-1] = float(stop)
    return values


def _split_top(text: str) -> list[str]:
    """Split at commas outside brackets, braces, parentheses and quotes."""
    items, depth, quote, cur = [], 0, "", []
    for ch in text:
        if quote:
            cur.append(ch)
            if ch == quote:
                quote = ""
            continue
        if ch in "\"'":
            quote = ch
        elif ch in "[{(":
            depth += 1
        elif ch in "]})":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    items.append("".join(cur))
    return items


def parse_value(text: str) -> list:
    """One item of a value list: a list of one value, or of many for a range.

    In order: a TOML value (``10``, ``0.5``, ``true``, ``"text"``, ``[0, 0, -9.81]``);
    a range ``start:step:stop``; an expression such as ``pi/4``; a bare word (a string,
    as in ``solver.linear=scipy``). Raises ValueError otherwise."""
    item = text.strip()
    if not item:
        raise ValueError("empty value (two commas in a row, or a comma at the end?)")
    try:
        return [_toml_scalar(item)]
    except ValueError:
        pass
    if ":" in item:
        return expand_range(item)
    try:
        return [evaluate(item)]
    except ValueError:
        pass
    if item.replace("-", "_").isidentifier():
        return [item]
    raise ValueError(
        f"{item!r}: not a number, a range start:step:stop, an expression of pi, "
        "a TOML value or a word"
    )


@dataclass(frozen=True)
class Param:
    """A swept key and its values (TOML types)."""

    key: str
    values: tuple

    @property
    def is_load(self) -> bool:
        return self.key.startswith(LOAD_PREFIX)


def _check_key(key: str, where: str) -> str:
    key = key.strip()
    parts = key.split(".")
    if not key or not all(p.strip() and p == p.strip() for p in parts) or len(parts) < 2:
        raise ConfigError(
            f"{where}: key {key!r}: must be a key path such as geometry.n or load.pressure"
        )
    return key


def parse_param(text: str) -> Param:
    """``key.path=v1,v2,...`` (each item a value or a range; see ``parse_value``)."""
    where = f"--param {text}"
    if "=" not in text:
        raise ConfigError(f"{where}: must be key.path=v1,v2,... (e.g. geometry.n=10,18)")
    key, _, rest = text.partition("=")
    key = _check_key(key, where)
    if not rest.strip():
        raise ConfigError(f"{where}: no values after '='")
    values: list = []
    for item in _split_top(rest):
        try:
            values.extend(parse_value(item))
        except ValueError as exc:
            raise ConfigError(f"{where}: {exc}") from None
    return Param(key, tuple(values))


def _param_from_table(key: str, raw) -> Param:
    """A parameter from the ``[sweep]`` table of a case file: a list of values (strings in
    it may be expressions or ranges: ``"pi/4"``, ``"0:0.25:0.75"``) or one string as on
    the command line (``"10, 18, 22"``)."""
    where = f"sweep.{key}"
    if isinstance(raw, str):
        return parse_param(f"{key}={raw}")
    if not isinstance(raw, list) or not raw:
        raise ConfigError(f"{where} = {raw!r}: must be a non-empty list of values")
    values: list = []
    for item in raw:
        if isinstance(item, str):
            try:
                values.extend(_string_item(item))
            except ValueError as exc:
                raise ConfigError(f"{where}: {exc}") from None
        else:
            values.append(item)
    return Param(key, tuple(values))


def _string_item(item: str) -> list:
    text = item.strip()
    if ":" in text:
        return expand_range(text)
    try:
        return [evaluate(text)]
    except ValueError:
        return [item]


def _flatten(table: dict, prefix: str = "") -> list[tuple[str, Any]]:
    out = []
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.extend(_flatten(v, key + "."))
        else:
            out.append((key, v))
    return out


# --------------------------------------------------------------------------------------------
# The sweep: base case, parameters, jobs
# --------------------------------------------------------------------------------------------


def toml_literal(value) -> str:
    """A value as TOML text for ``apply_overrides`` (floats round-trip exactly)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_literal(v) for v in value) + "]"
    if isinstance(value, dict):
        items = (f"{json.dumps(k)} = {toml_literal(v)}" for k, v in value.items())
        return "{" + ", ".join(items) + "}"
    raise ConfigError(f"{value!r}: cannot be written as a TOML value")


@dataclass(frozen=True)
class Job:
    """One combination of the non-load keys and its load levels (a continuation)."""

    index: int
    settings: tuple[tuple[str, Any], ...]
    levels: tuple[tuple[tuple[str, Any], ...], ...]

    @property
    def key(self) -> str:
        return json.dumps([list(s) for s in self.settings])


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: the base case data (without ``[sweep]``), its parameters and jobs."""

    source: str
    base_dir: str
    base: dict
    params: tuple[Param, ...]
    base_toml: str = ""
    base_resolved: dict = field(default_factory=dict)

    @property
    def keys(self) -> list[str]:
        return [p.key for p in self.params]

    @property
    def columns(self) -> list[str]:
        return self.keys + list(RESULT_COLUMNS)

    @property
    def jobs(self) -> list[Job]:
        other = [p for p in self.params if not p.is_load]
        load = [p for p in self.params if p.is_load]
        levels = tuple(
            tuple(zip([p.key for p in load], combo, strict=True))
            for combo in itertools.product(*[p.values for p in load])
        )
        return [
            Job(i, tuple(zip([p.key for p in other], combo, strict=True)), levels)
            for i, combo in enumerate(itertools.product(*[p.values for p in other]))
        ]

    @property
    def n_rows(self) -> int:
        return math.prod(len(p.values) for p in self.params)

    @property
    def fingerprint(self) -> str:
        """Identity of the sweep for resuming: the resolved base case and the parameters."""
        blob = json.dumps(
            {
                "base": self.base_resolved or self.base,
                "params": [[p.key, list(p.values)] for p in self.params],
            },
            sort_keys=True,
            default=str,
        )
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def row_values(self, job: Job, level: int) -> dict:
        values = dict(job.settings)
        if job.levels:
            values.update(dict(job.levels[level]))
        return {k: values[k] for k in self.keys}


def _case_api():
    try:
        from catenet import case
    except ImportError as exc:  # pragma: no cover - during development only
        raise CatenetError(f"catenet.case is not available: {exc}") from exc
    return case


def load_sweep(path: str | Path, params: Sequence[str] = ()) -> Sweep:
    """The sweep of a case file: its ``[sweep]`` table (``key.path = [values]``), if any,
    with the ``params`` (``"key.path=v1,v2"``) added; a key given in both takes the
    command line's values. Every combination is validated as a case (ConfigError listing
    the problems) before anything runs."""
    from catenet.case import parse_toml, read_case_bytes

    path = Path(path)
    data = parse_toml(read_case_bytes(path), str(path))
    table = data.pop("sweep", None)
    merged: dict[str, Param] = {}
    if table is not None:
        if not isinstance(table, dict):
            raise ConfigError(f"{path}: sweep = {table!r}: must be a table of key.path = [values]")
        for key, raw in _flatten(table):
            merged[key] = _param_from_table(key, raw)
    seen: set[str] = set()
    for text in params:
        p = parse_param(text)
        if p.key in seen:
            raise ConfigError(f"--param {text}: {p.key} is given twice")
        seen.add(p.key)
        merged[p.key] = p
    return make_sweep(data, list(merged.values()), source=str(path), base_dir=path.parent)


def make_sweep(
    base: dict, params: Sequence[Param], *, source: str = "<dict>", base_dir: Path | str = "."
) -> Sweep:
    """A sweep from base case data (a dict as read from TOML) and parameters; validates
    the base case and every combination with ``catenet.case.parse_case``."""
    if not params:
        raise ConfigError(
            "no parameters to sweep: give --param key.path=v1,v2,... or a [sweep] table "
            "in the case file"
        )
    keys = [p.key for p in params]
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise ConfigError(f"parameters: {', '.join(dup)} given more than once")
    case_api = _case_api()
    base_dir = Path(base_dir)
    base_case = case_api.parse_case(base, source=source, base_dir=base_dir)
    sweep = Sweep(
        source=source,
        base_dir=str(base_dir.resolve()),
        base=base,
        params=tuple(params),
        base_toml=base_case.to_toml(),
        base_resolved=base_case.to_dict(),
    )
    problems: list[str] = []
    for param in params:  # each value on its own first: one message per bad value
        for value in param.values:
            _validate(case_api, base, [(param.key, value)], source, base_dir, problems)
    if not problems:  # then the combinations (a few ms each: the first MAX_VALIDATED)
        combos = (
            list(job.settings) + list(level)
            for job in sweep.jobs
            for level in (job.levels or ((),))
        )
        for settings in itertools.islice(combos, MAX_VALIDATED):
            _validate(case_api, base, settings, source, base_dir, problems)
            if len(problems) >= 20:
                break
        if sweep.n_rows > MAX_VALIDATED:
            log.info("validated the first %d of %d combinations", MAX_VALIDATED, sweep.n_rows)
    if problems:
        raise ConfigError(problems)
    return sweep


def _validate(case_api, base, settings, source, base_dir, problems) -> None:
    try:
        data = case_api.apply_overrides(base, _overrides(settings))
        case_api.parse_case(data, source=source, base_dir=base_dir)
    except ConfigError as exc:
        where = ", ".join(f"{k}={toml_literal(v)}" for k, v in settings)
        for line in exc.problems:
            msg = f"--param {where}: {line}" if len(settings) == 1 else f"[{where}] {line}"
            if msg not in problems:
                problems.append(msg)


def _overrides(settings: Iterable[tuple[str, Any]]) -> list[str]:
    return [f"{k}={toml_literal(v)}" for k, v in settings]


# --------------------------------------------------------------------------------------------
# One job, in whatever process runs it
# --------------------------------------------------------------------------------------------


def _task(
    sweep: Sweep, job: Job, out: Path, *, save_runs: bool, threads: int, crash_hook: bool
) -> dict:
    """Everything a worker needs, as plain picklable data."""
    return {
        "index": job.index,
        "base": sweep.base,
        "source": sweep.source,
        "base_dir": sweep.base_dir,
        "settings": [list(s) for s in job.settings],
        "levels": [[list(s) for s in level] for level in (job.levels or ((),))],
        "out": str(out),
        "save_runs": save_runs,
        "threads": threads,
        "crash_hook": crash_hook,
    }


def run_job(task: dict) -> dict:
    """Solve one job's load levels in turn, each from the previous equilibrium.

    Never raises for a failing case: every row carries its error. Returns
    ``{"index": ..., "rows": [...], "pid": ...}``."""
    out = Path(task["out"])
    index = task["index"]
    marker = out / RUNNING_DIR / str(index)
    if task.get("crash_hook"):
        with contextlib.suppress(OSError):
            marker.write_text(str(os.getpid()))
        _test_crash(out, index)
    try:
        from catenet.linsolve import set_threads

        set_threads(int(task["threads"]))
        rows = _solve_levels(task)
    finally:
        if task.get("crash_hook"):
            with contextlib.suppress(OSError):
                marker.unlink()
    return {"index": index, "rows": rows, "pid": os.getpid()}


def _test_crash(out: Path, index: int) -> None:
    target = os.environ.get(CRASH_VARIABLE, "")
    if target.strip() != str(index):
        return
    flag = out / f".crash-{index}"
    try:
        fd = os.open(flag, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return
    os.close(fd)
    log.warning("test hook %s=%s: this worker exits now", CRASH_VARIABLE, index)
    os._exit(1)


def _nan_row() -> dict:
    nan = float("nan")
    return {
        "delta": nan,
        "delta_over_L": nan,
        "F_bar": nan,
        "max_strain": nan,
        "slack_edges": -1,
        "iterations": 0,
        "wall_time": 0.0,
        "converged": False,
        "error": "",
        "attempts": 1,
        "run_file": "",
    }


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, ConfigError):
        return "; ".join(exc.problems)
    if isinstance(exc, CatenetError):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def _solve_levels(task: dict) -> list[dict]:
    import numpy as np

    case_api = _case_api()
    base_dir = Path(task["base_dir"])
    settings = [tuple(s) for s in task["settings"]]
    levels = [[tuple(s) for s in level] for level in task["levels"]]
    rows: list[dict] = []
    ws = None
    ws_net = None
    x_prev = None
    path: list = []  # (load level, equilibrium) of the current net, for the predictor
    reference = None  # the external force of the path's first level
    load_keys = {key for level in levels for key, _ in level}
    scenes = _Scenes(case_api, pressure_only=load_keys == {"load.pressure"})
    for k, level in enumerate(levels):
        start = time.perf_counter()
        row = _nan_row()
        values = dict(settings + level)
        try:
            data = case_api.apply_overrides(task["base"], _overrides(settings + level))
            case = case_api.parse_case(data, source=task["source"], base_dir=base_dir)
            scene = scenes.build(case)
            net = scene.net
            if ws is None or not _same_net(ws_net, net):
                from catenet.static import Workspace

                ws = Workspace(net, linear=case.solver.linear)
                ws_net, x_prev, path = net, None, []
            force = scene.loads.external_force(ws_net)
            if not path:
                reference = force
            level_of = _load_level(force, reference)
            x0 = x_prev
            if case.solver.method == "static" and level_of is not None and len(path) >= 2:
                from catenet.static import predict

                x0 = predict([x for _, x in path[-2:]], [s for s, _ in path[-2:]], level_of)
            result = _solve(case, ws_net, scene.loads, ws, x0)
            x_prev = result.x
            path = path + [(level_of, result.x)] if level_of is not None else []
            row.update(_measure(scene, ws_net, result, np))
            if task["save_runs"]:
                row["run_file"] = _save_run(Path(task["out"]), task["index"], k, scene, result)
        except (CatenetError, ArithmeticError, ValueError, MemoryError, OSError) as exc:
            row["error"] = _error_text(exc)
            state = getattr(exc, "state", None)
            if state is not None and ws_net is not None and np.shape(state) == ws_net.nodes.shape:
                x_prev = np.asarray(state)
            path = []
            row["iterations"] = int(getattr(exc, "iterations", 0) or 0)
            log.info("job %s level %s %s: %s", task["index"], k, values, row["error"])
        except Exception as exc:  # an unexpected failure of one case must not end the sweep
            row["error"] = _error_text(exc)
            log.exception("job %s level %s %s failed", task["index"], k, values)
        row["wall_time"] = time.perf_counter() - start
        rows.append(row)
    return rows


class _Scenes:
    """The scenes of a job's load levels. When the only load key is ``load.pressure`` of
    a square net, the net is built once and each level's loads are the first level's with
    the pressure part, -p L^2/N per node (SPEC section 2), computed for its p; the second
    level is also built in full once to check that this gives the same net and forces
    (else every level is built). Saves a net build per level: 10-40 % of a job."""

    def __init__(self, case_api, *, pressure_only: bool):
        self.case_api = case_api
        self.fast = pressure_only
        self.first = None
        self.other = None  # the first level's force minus its pressure part
        self.checked = False

    def build(self, case):
        import dataclasses

        import numpy as np

        from catenet.geometry import pressure_force

        if not self.fast or self.first is None or case.geometry.kind != "square_net":
            scene = self.case_api.build(case)
            if self.fast and self.first is None and case.geometry.kind == "square_net":
                self.first = scene
                force = scene.loads.force
                pressure = pressure_force(scene.net, case.load.pressure, scene.size)
                self.other = (np.zeros_like(pressure) if force is None else force) - pressure
            return scene
        first = self.first
        force = self.other + pressure_force(first.net, case.load.pressure, first.size)
        loads = dataclasses.replace(first.loads, force=force)
        scene = dataclasses.replace(first, case=case, loads=loads)
        if not self.checked:
            self.checked = True
            full = self.case_api.build(case)
            want = full.loads.external_force(full.net)
            got = loads.external_force(first.net)
            scale = float(np.max(np.abs(want), initial=0.0)) or 1.0
            if not (
                _same_net(first.net, full.net)
                and full.probe == first.probe
                and full.size == first.size
                and float(np.max(np.abs(want - got), initial=0.0)) <= 1e-14 * scale
            ):
                log.debug("pressure levels: the loads are not -p L^2/N: building every level")
                self.fast = False
                return full
        return scene


def _same_net(a, b) -> bool:
    import numpy as np

    if a is b:
        return True
    return (
        a is not None
        and a.nodes.shape == b.nodes.shape
        and a.edges.shape == b.edges.shape
        and a.tension_only == b.tension_only
        and np.array_equal(a.nodes, b.nodes)
        and np.array_equal(a.edges, b.edges)
        and np.array_equal(a.rest_length, b.rest_length)
        and np.array_equal(a.EA, b.EA)
        and np.array_equal(a.fixed, b.fixed)
        and np.array_equal(a.line_density, b.line_density)
    )


def _load_level(force, reference) -> float | None:
    """The multiple of ``reference`` that ``force`` is, or None when it is not one (then
    the levels of a job are not proportional and no equilibrium is predicted)."""
    import numpy as np

    ref2 = float(np.vdot(reference, reference))
    if ref2 == 0.0:
        return None
    level = float(np.vdot(force, reference)) / ref2
    if np.linalg.norm(force - level * reference) > 1e-9 * np.linalg.norm(force):
        return None
    return level


def _solve(case, net, loads, ws, x_prev):
    """One load level: static from the previous equilibrium (the first level in
    ``solver.steps`` load steps), or the dynamic run of the case from it."""
    solver = case.solver
    if solver.method == "dynamic":
        from catenet.dynamic import solve_dynamic

        r = solve_dynamic(
            net,
            loads,
            dt=solver.dt,
            damping=solver.damping,
            t_end=solver.t_end,
            rtol=solver.rtol,
            x0=x_prev,
            workspace=ws,
        )
        if not r.converged:
            from catenet.errors import ConvergenceError

            raise ConvergenceError(
                f"dynamic run did not converge: {r.message}",
                iterations=r.iterations,
                state=r.x,
            )
        return r
    from catenet.static import continuation, solve_static

    steps = int(getattr(solver, "steps", 1) or 1)
    if x_prev is None and steps > 1:
        results = continuation(
            net,
            loads,
            [k / steps for k in range(1, steps + 1)],
            rtol=solver.rtol,
            max_iter=solver.max_iter,
            workspace=ws,
        )
        r = results[-1]
        r.iterations = sum(s.iterations for s in results)
        return r
    return solve_static(
        net, loads, x0=x_prev, rtol=solver.rtol, max_iter=solver.max_iter, workspace=ws
    )


def _measure(scene, net, result, np) -> dict:
    probe = int(scene.probe)
    delta = -float(result.x[probe, 2] - net.nodes[probe, 2])
    force = scene.loads.external_force(net)
    EA = float(np.median(net.EA))
    e = result.x[net.edges[:, 1]] - result.x[net.edges[:, 0]]
    strain = np.linalg.norm(e, axis=1) / net.rest_length - 1.0
    return {
        "delta": delta,
        "delta_over_L": delta / float(scene.size),
        "F_bar": float(np.linalg.norm(force.sum(axis=0))) / EA,
        "max_strain": float(result.max_strain),
        "slack_edges": int(np.count_nonzero(strain < 0.0)),
        "iterations": int(result.iterations),
        "converged": bool(result.converged),
    }


def _save_run(out: Path, index: int, level: int, scene, result) -> str:
    """The level's HDF5 result file (SPEC section 5, as ``catenet run`` writes it: a
    static equilibrium is the frame at load factor 1) under DIR/runs/; its path relative
    to DIR."""
    from catenet.output import ResultWriter

    rel = Path(RUNS_DIR) / f"job{index:05d}-level{level:03d}.h5"
    case = scene.case
    attrs = {"source": str(getattr(case, "source", "")), "sweep_job": index, "sweep_level": level}
    every = int(case.output.every)
    with ResultWriter(out / rel, scene, every=every, xdmf=case.output.xdmf, attrs=attrs) as writer:
        t = float(result.time) if case.solver.method == "dynamic" else 1.0
        if not case.solver.method == "dynamic":
            result.time = t
        if every > 0:
            writer.frame(t, result.x, result.v, result.tension)
        writer.result(result)
    return str(rel)


# --------------------------------------------------------------------------------------------
# Journal and tables
# --------------------------------------------------------------------------------------------


def _header(sweep: Sweep) -> dict:
    from catenet import __version__

    return {
        "catenet_sweep": FORMAT_VERSION,
        "catenet_version": __version__,
        "fingerprint": sweep.fingerprint,
        "source": sweep.source,
        "params": [[p.key, list(p.values)] for p in sweep.params],
        "columns": sweep.columns,
        "base": sweep.base_resolved,
        "base_toml": sweep.base_toml,
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }


def read_journal(directory: Path) -> tuple[dict | None, dict[int, dict]]:
    """The header and the finished jobs (index -> record) of a sweep directory; a last
    line cut short by a crash is ignored."""
    path = Path(directory) / JOURNAL
    if not path.exists():
        return None, {}
    header = None
    jobs: dict[int, dict] = {}
    with path.open(encoding="utf-8") as fh:
        for number, line in enumerate(fh, 1):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                log.warning("%s:%d: an unreadable line (cut short?) is ignored", path, number)
                continue
            if header is None:
                if "catenet_sweep" not in rec:
                    raise ConfigError(f"{path}: not a catenet sweep journal")
                header = rec
            elif rec.get("kind") == "job":
                jobs[int(rec["index"])] = rec
    return header, jobs


class _Journal:
    """Append-only, flushed and synced per record."""

    def __init__(self, path: Path):
        with path.open("rb") as fh:  # a line cut short by a crash: start a new one
            size = fh.seek(0, os.SEEK_END)
            ragged = False
            if size > 0:
                fh.seek(-1, os.SEEK_END)
                ragged = fh.read(1) != b"\n"
        self.fh = path.open("a", encoding="utf-8")
        if ragged:
            self.fh.write("\n")

    def write(self, record: dict) -> None:
        self.fh.write(json.dumps(record, allow_nan=True) + "\n")
        self.fh.flush()
        with contextlib.suppress(OSError):
            os.fsync(self.fh.fileno())

    def close(self) -> None:
        self.fh.close()


def table_rows(sweep_or_header, jobs: dict[int, dict]) -> list[dict]:
    """Rows of the table in job order, then load level."""
    rows = []
    for index in sorted(jobs):
        rows.extend(jobs[index]["rows"])
    return rows


def _cell(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list | dict):
        return json.dumps(value)
    return str(value)


def write_tables(directory: Path) -> int:
    """Regenerate DIR/results.csv and DIR/results.h5 from the journal; the row count."""
    directory = Path(directory)
    header, jobs = read_journal(directory)
    if header is None:
        return 0
    columns = header["columns"]
    rows = table_rows(header, jobs)
    tmp = directory / (CSV_FILE + ".tmp")
    with tmp.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(row.get(c, "")) for c in columns])
    os.replace(tmp, directory / CSV_FILE)
    _write_h5(directory / H5_FILE, header, rows)
    return len(rows)


def _column_array(values: list, np):
    if values and all(isinstance(v, bool) for v in values):
        return np.array(values, dtype=bool)
    if values and all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return np.array(values, dtype=np.int64)
    if values and all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return np.array(values, dtype=np.float64)
    return np.array([_cell(v) for v in values], dtype=object)


def _write_h5(path: Path, header: dict, rows: list[dict]) -> None:
    """``/table``: one dataset per column (group attribute ``columns`` gives their order);
    numbers as float64 or int64, ``converged`` as bool, text (errors, string or list
    values) as UTF-8 strings. Root attributes: catenet_version, case (the base case as
    TOML), params (JSON), fingerprint, created."""
    import h5py
    import numpy as np

    tmp = path.with_suffix(".h5.tmp")
    with h5py.File(tmp, "w") as f:
        f.attrs["catenet_version"] = header.get("catenet_version", "")
        f.attrs["case"] = header.get("base_toml", "")
        f.attrs["params"] = json.dumps(header["params"])
        f.attrs["fingerprint"] = header["fingerprint"]
        f.attrs["created"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        g = f.create_group("table")
        g.attrs["columns"] = json.dumps(header["columns"])
        for col in header["columns"]:
            arr = _column_array([row.get(col, "") for row in rows], np)
            if arr.dtype == object:
                g.create_dataset(
                    col,
                    data=arr.astype(str).astype(object) if len(arr) else np.array([], dtype=object),
                    dtype=h5py.string_dtype(),
                )
            else:
                g.create_dataset(col, data=arr)
    os.replace(tmp, path)


def read_table(directory: Path) -> tuple[list[str], list[str], dict[str, list]]:
    """(swept keys, all columns, column -> values) of a sweep directory, from its
    journal (or, lacking one, results.csv)."""
    directory = Path(directory)
    header, jobs = read_journal(directory)
    if header is not None:
        keys = [k for k, _ in header["params"]]
        rows = table_rows(header, jobs)
        return keys, header["columns"], {c: [r.get(c) for r in rows] for c in header["columns"]}
    path = directory / CSV_FILE
    if not path.exists():
        raise ConfigError(f"{directory}: no {JOURNAL} or {CSV_FILE}: not a sweep directory")
    with path.open(newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        columns = next(reader)
        data = {c: [] for c in columns}
        for line in reader:
            for c, v in zip(columns, line, strict=False):
                data[c].append(_parse_cell(v))
    keys = columns[: columns.index("delta")] if "delta" in columns else []
    return keys, columns, data


def _parse_cell(text: str):
    if text in ("true", "false"):
        return text == "true"
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


# --------------------------------------------------------------------------------------------
# Running a sweep
# --------------------------------------------------------------------------------------------


@dataclass
class SweepSummary:
    """What a call of ``run_sweep`` did."""

    directory: Path
    total_jobs: int
    total_rows: int
    skipped_jobs: int = 0
    run_jobs: int = 0
    failed_rows: int = 0
    retried_jobs: list[int] = field(default_factory=list)
    crashed_jobs: list[int] = field(default_factory=list)
    wall_time: float = 0.0
    interrupted: bool = False


def cores() -> int:
    """Cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def threads_per_worker(workers: int) -> int:
    return max(1, cores() // max(1, workers))


def prepare_directory(sweep: Sweep, out: Path) -> dict[int, dict]:
    """Create DIR or check that its journal is this sweep's; the finished jobs."""
    out.mkdir(parents=True, exist_ok=True)
    header, done = read_journal(out)
    if header is None:
        if (out / CSV_FILE).exists():
            log.warning("%s: %s without a journal is overwritten", out, CSV_FILE)
        with (out / JOURNAL).open("w", encoding="utf-8") as fh:
            fh.write(json.dumps(_header(sweep)) + "\n")
        return {}
    if header.get("fingerprint") != sweep.fingerprint:
        theirs = ", ".join(f"{k}={len(v)} values" for k, v in header.get("params", []))
        raise ConfigError(
            f"{out}: holds a sweep of another base case or other parameters "
            f"({header.get('source')}: {theirs}); write to another directory (-o) or "
            "delete this one to start again"
        )
    keys = {job.index: job.key for job in sweep.jobs}
    return {i: rec for i, rec in done.items() if keys.get(i) == rec.get("key")}


@contextlib.contextmanager
def _lock(out: Path):
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    fh = (out / ".lock").open("w")
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(f"{out}: another sweep is writing into this directory") from None
        yield
    finally:
        fh.close()


def run_sweep(
    sweep: Sweep,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    save_runs: bool = False,
    progress: Callable[[int, int, str], None] | None = None,
) -> SweepSummary:
    """Run the jobs the journal of ``out`` does not hold yet; regenerate the tables.

    ``workers``: processes (default: all cores; 1 runs in this process). ``scheduler``:
    the address of a Dask scheduler instead. ``progress(done, total, note)`` counts the
    rows of this call (rows already in the journal are not in ``total``).
    Ctrl-C (KeyboardInterrupt) stops the workers; the finished jobs are kept and the
    tables written before it propagates."""
    out = Path(out)
    start = time.perf_counter()
    if workers is None:
        workers = cores()
    if workers < 1:
        raise ConfigError(f"--workers = {workers}: must be >= 1")
    if save_runs:
        try:
            from catenet.output import ResultWriter  # noqa: F401
        except ImportError as exc:
            raise ConfigError(f"--save-runs: needs catenet.output.ResultWriter: {exc}") from None
    jobs = sweep.jobs
    summary = SweepSummary(out, len(jobs), sweep.n_rows)
    out.mkdir(parents=True, exist_ok=True)
    with _lock(out):
        done = prepare_directory(sweep, out)
        todo = [job for job in jobs if job.index not in done]
        summary.skipped_jobs = len(jobs) - len(todo)
        if summary.skipped_jobs:
            log.info(
                "%s: %d of %d jobs already done, skipped", out, summary.skipped_jobs, len(jobs)
            )
        rows_before = sum(len(rec["rows"]) for rec in done.values())
        rows_todo = summary.total_rows - rows_before
        rows_done = 0
        if progress:
            progress(0, rows_todo, f"({rows_before} rows done before)" if rows_before else "")
        journal = _Journal(out / JOURNAL)
        running = out / RUNNING_DIR
        running.mkdir(exist_ok=True)
        for stale in running.iterdir():
            with contextlib.suppress(OSError):
                stale.unlink()

        def record(job: Job, rows: list[dict], attempts: int) -> None:
            nonlocal rows_done
            for r in rows:
                r["attempts"] = attempts
            full = [{**sweep.row_values(job, k), **r} for k, r in enumerate(rows)]
            journal.write(
                {
                    "kind": "job",
                    "index": job.index,
                    "key": job.key,
                    "attempts": attempts,
                    "rows": full,
                }
            )
            summary.run_jobs += 1
            summary.failed_rows += sum(1 for r in full if r["error"])
            if attempts > 1:
                summary.retried_jobs.append(job.index)
            rows_done += len(rows)
            if progress:
                failed = f"{summary.failed_rows} failed" if summary.failed_rows else ""
                progress(rows_done, rows_todo, failed)

        def crashed(job: Job, message: str) -> None:
            journal.write({"kind": "crash", "index": job.index, "error": message})
            log.warning("job %d (%s): %s", job.index, _describe(job), message)

        try:
            if not todo:
                pass
            elif scheduler:
                todo = _largest_first(sweep, todo)
                _run_dask(sweep, todo, out, scheduler, save_runs, record, crashed, summary)
            elif workers == 1:
                for job in todo:
                    task = _task(
                        sweep,
                        job,
                        out,
                        save_runs=save_runs,
                        threads=threads_per_worker(1),
                        crash_hook=False,
                    )
                    record(job, run_job(task)["rows"], 1)
            else:
                todo = _largest_first(sweep, todo)
                _run_pool(sweep, todo, out, workers, save_runs, record, crashed, summary)
        except KeyboardInterrupt:
            summary.interrupted = True
            raise
        finally:
            journal.close()
            write_tables(out)
            with contextlib.suppress(OSError):
                running.rmdir()  # empty unless a worker died
            summary.wall_time = time.perf_counter() - start
    return summary


def _largest_first(sweep: Sweep, jobs: list[Job]) -> list[Job]:
    """Jobs by estimated cost (nodes x load levels), largest first, so that the workers
    finish together instead of waiting for one large job at the end."""
    case_api = _case_api()
    estimate = getattr(case_api, "estimate_size", None)
    if estimate is None:
        return jobs

    def cost(job: Job) -> float:
        try:
            level = list(job.levels[0]) if job.levels else []
            data = case_api.apply_overrides(sweep.base, _overrides(list(job.settings) + level))
            case = case_api.parse_case(data, source=sweep.source, base_dir=Path(sweep.base_dir))
            return float(estimate(case.geometry)[0]) * max(1, len(job.levels))
        except Exception:  # a case that fails does so quickly
            return 0.0

    costs = {job.index: cost(job) for job in jobs}
    return sorted(jobs, key=lambda job: (-costs[job.index], job.index))


def _describe(job: Job) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in job.settings) or "base case"


def _failed_rows(job: Job, message: str) -> list[dict]:
    rows = []
    for _ in job.levels or ((),):
        row = _nan_row()
        row["error"] = message
        rows.append(row)
    return rows


@contextlib.contextmanager
def _worker_environment(threads: int):
    """Thread counts for spawned workers, set in this process's environment while the
    pool starts them (a spawned child reads them before MKL, OpenMP or Numba load)."""
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    for k in THREAD_VARIABLES:
        os.environ[k] = str(threads)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _init_worker(threads: int) -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    for k in THREAD_VARIABLES:
        os.environ[k] = str(threads)


def _run_pool(sweep, todo, out, workers, save_runs, record, crashed, summary) -> None:
    """A process pool; when a worker dies, the jobs it broke are run again: those that
    had not started at once, those that had started one at a time (so that a job that
    kills its worker again is known) and failed after their second crash."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: thread settings apply
    crashes: dict[int, int] = {}
    pending = list(todo)
    isolate: list[Job] = []
    running = out / RUNNING_DIR
    blind = 0  # pool breaks that no started job explains
    while pending or isolate:
        if pending:
            batch, pending = pending, []
            width = min(workers, len(batch))
        else:
            batch, isolate = [isolate[0]], isolate[1:]
            width = 1
        threads = threads_per_worker(width)
        for job in batch:
            with contextlib.suppress(OSError):
                (running / str(job.index)).unlink()
        broken: list[Job] = []
        env = _worker_environment(threads)  # processes start at submit: keep it until then
        env.__enter__()
        try:
            pool = ProcessPoolExecutor(
                width, mp_context=ctx, initializer=_init_worker, initargs=(threads,)
            )
        except BaseException:
            env.__exit__(None, None, None)
            raise
        try:
            futures = {}
            try:
                for job in batch:
                    task = _task(
                        sweep, job, out, save_runs=save_runs, threads=threads, crash_hook=True
                    )
                    futures[pool.submit(run_job, task)] = job
            finally:
                env.__exit__(None, None, None)
            for fut in as_completed(futures):
                job = futures[fut]
                try:
                    result = fut.result()
                except BrokenProcessPool:
                    broken.append(job)
                    continue
                record(job, result["rows"], crashes.get(job.index, 0) + 1)
        except BaseException:
            _terminate(pool)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        if not broken:
            continue
        started = [job for job in broken if (running / str(job.index)).exists()]
        if not started:  # a worker died outside any job (at start-up?)
            blind += 1
            if blind >= 2:
                message = "worker processes die before running a job (see the log above)"
                for job in broken:
                    summary.crashed_jobs.append(job.index)
                    crashed(job, message)
                    record(job, _failed_rows(job, message), crashes.get(job.index, 0) + 1)
                broken = []
        for job in broken:
            if job not in started:
                pending.append(job)
        for job in started:
            crashes[job.index] = crashes.get(job.index, 0) + 1
            message = "worker process died while running this job (crashed or killed)"
            crashed(job, message)
            if crashes[job.index] >= 2:
                summary.crashed_jobs.append(job.index)
                record(job, _failed_rows(job, message + ", twice: not retried again"), 2)
            else:
                isolate.append(job)


def _terminate(pool) -> None:
    for proc in list(getattr(pool, "_processes", {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()


def _run_dask(sweep, todo, out, scheduler, save_runs, record, crashed, summary) -> None:
    """The jobs on a Dask cluster, one task each (MKL and Numba threads 1 per task: a
    Dask worker runs as many tasks at once as it has threads). A task whose worker is
    lost beyond the scheduler's own retries (KilledWorker, lost connection) is run once
    more, then recorded as failed."""
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--scheduler needs Dask distributed: pip install catenet[dask]") from None
    try:
        client = Client(scheduler, timeout="20s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise CatenetError(f"--scheduler {scheduler}: cannot connect: {exc}") from None
    crashes: dict[int, int] = {}
    tag = sweep.fingerprint[:8]
    futures: dict = {}
    try:

        def submit(job: Job):
            task = _task(sweep, job, out, save_runs=save_runs, threads=1, crash_hook=True)
            attempt = crashes.get(job.index, 0)
            return client.submit(
                run_job, task, key=f"catenet-sweep-{tag}-{job.index}-{attempt}", pure=False
            )

        for job in todo:
            futures[submit(job)] = job
        ac = as_completed(list(futures), loop=client.loop)
        for fut in ac:
            job = futures.pop(fut)
            try:
                result = fut.result()
            except KeyboardInterrupt:
                raise
            except Exception as exc:
                crashes[job.index] = crashes.get(job.index, 0) + 1
                message = f"dask worker lost ({type(exc).__name__}: {exc})"
                crashed(job, message)
                if crashes[job.index] >= 2:
                    summary.crashed_jobs.append(job.index)
                    record(job, _failed_rows(job, message + ", twice: not retried again"), 2)
                else:
                    new = submit(job)
                    futures[new] = job
                    ac.add(new)
                continue
            record(job, result["rows"], crashes.get(job.index, 0) + 1)
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(list(futures))
        raise
    finally:
        with contextlib.suppress(Exception):
            client.close()
