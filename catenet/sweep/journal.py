"""The sweep directory: its append-only journal and the tables made from it.

``DIR/results.jsonl`` holds a header line (the base case, the parameters and their
fingerprint), then one line per finished job (or per worker crash), flushed and synced as
soon as the job returns. ``DIR/results.csv`` and ``DIR/results.h5`` are regenerated from
it by ``write_tables``; ``read_table`` reads the journal (or, lacking one, the CSV).
"""

from __future__ import annotations

import contextlib
import csv
import json
import logging
import os
import time
from pathlib import Path

from catenet.errors import ConfigError
from catenet.sweep.jobs import Sweep

log = logging.getLogger(__name__)

JOURNAL = "results.jsonl"
CSV_FILE = "results.csv"
H5_FILE = "results.h5"
FORMAT_VERSION = 1


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
def directory_lock(out: Path):
    """Hold DIR's lock file ``.lock`` while the sweep runs and remove it at the end (also
    after an error or Ctrl-C); ConfigError when another sweep holds it.

    The file is removed while still locked; a sweep that opened it just before and locks
    it just after finds it gone from DIR (another inode than ``.lock`` now names) and
    takes the lock afresh, so two sweeps never both hold it."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    path = out / ".lock"
    while True:
        fh = path.open("a")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            fh.close()
            raise ConfigError(f"{out}: another sweep is writing into this directory") from None
        try:
            current = os.stat(path).st_ino
        except FileNotFoundError:
            current = None
        if current == os.fstat(fh.fileno()).st_ino:
            break
        fh.close()  # removed by the sweep that held it: lock the new one
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            path.unlink()
        fh.close()


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


class Journal:
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


def table_rows(jobs: dict[int, dict]) -> list[dict]:
    """Rows of the table in job order, then load level."""
    rows = []
    for index in sorted(jobs):
        rows.extend(jobs[index]["rows"])
    return rows


def _cell(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(float(value))  # as Python prints it, whatever the user's spelling
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
    rows = table_rows(jobs)
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
        rows = table_rows(jobs)
        return keys, header["columns"], {c: [r.get(c) for r in rows] for c in header["columns"]}
    path = directory / CSV_FILE
    if not path.exists():
        raise ConfigError(f"{directory}: no {JOURNAL} or {CSV_FILE}: not a sweep directory")
    with path.open(newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        columns = next(reader)
        data: dict[str, list] = {c: [] for c in columns}
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
