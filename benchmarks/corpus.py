"""Run the untuned corpus (tests/corpus.py) through `catenet run` and tabulate what fails.

    python benchmarks/corpus.py --count N --seed S [--jobs J] [-o DIR] [--timeout T]
                                [--tol TOL] [--family F] [--in-process]

Writes models S .. S+N-1 as DIR/<family>-<seed>.toml, runs `catenet run CASE -o CASE.h5 -q`
on each in a subprocess (J at a time, each with T seconds), and prints the failure rate by
family and by kind of failure (exit code and the first line of stderr, or a traceback's
last line, numbers masked so that like failures group), then the Newton iterations and
wall times of the runs (from the result file's /result attributes). A run fails when it
exits non-zero, times out, or exits 0 with a global force imbalance above --tol. Every
run is also a row of DIR/runs.csv.
Exits 0 whatever fails.

With --in-process, J worker processes each import catenet once and call the same command
(`catenet.cli.main` with the same arguments, its exit status and stderr captured; a run
longer than T seconds is stopped by an alarm): the same outcome as a subprocess per model
without Python's and the kernels' start-up in every run, so that 10^4 models take hours
less. Each worker serves 200 models and is then replaced (no state carried further).
"""

from __future__ import annotations

import argparse
import csv
import functools
import multiprocessing
import re
import subprocess
import sys
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import h5py
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import corpus  # noqa: E402

FIELDS = [
    "seed",
    "family",
    "scale",
    "edges",
    "exit",
    "kind",
    "imbalance",
    "iterations",
    "solve_time",
    "wall_time",
    "process_time",
    "description",
    "case",
    "stderr",
]


def run_one(seed: int, out: Path, timeout: float, tol: float, family=None) -> dict:
    """Write model ``seed``, run it, and describe the outcome as one row."""
    model = corpus.generate(seed, family)
    case = corpus.write(model, out / f"{model['family']}-{seed}.toml")
    result = case.with_suffix(".h5")
    row = {k: model[k] for k in ("seed", "family", "scale", "edges", "description")}
    row |= {"case": str(case), "imbalance": "", "iterations": "", "solve_time": "", "wall_time": ""}
    command = [sys.executable, "-m", "catenet", "run", str(case), "-o", str(result), "-q"]
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        row["exit"], row["stderr"] = done.returncode, done.stderr.strip()
    except subprocess.TimeoutExpired:
        row["exit"], row["stderr"] = "timeout", f"no answer within {timeout:g} s"
    row["process_time"] = time.perf_counter() - start
    if result.exists():
        try:
            with h5py.File(result, "r") as f:
                attrs = f["result"].attrs
                row |= {k: float(attrs[k]) for k in ("iterations", "solve_time", "wall_time")}
            row["imbalance"] = corpus.check_equilibrium(result)
        except (OSError, KeyError) as exc:
            row["stderr"] = row["stderr"] or f"unreadable result: {exc}"
    row["kind"] = failure_kind(row, tol)
    return row


def run_in_process(seed: int, out: Path, timeout: float, tol: float, family=None) -> dict:
    """``run_one`` through ``catenet.cli.main`` in this process (a pool worker's)."""
    import contextlib
    import io
    import signal

    from catenet.cli import main as cli

    model = corpus.generate(seed, family)
    case = corpus.write(model, out / f"{model['family']}-{seed}.toml")
    result = case.with_suffix(".h5")
    row = {k: model[k] for k in ("seed", "family", "scale", "edges", "description")}
    row |= {"case": str(case), "imbalance": "", "iterations": "", "solve_time": "", "wall_time": ""}
    stderr = io.StringIO()

    def expire(signum, frame):
        raise TimeoutError(f"no answer within {timeout:g} s")

    signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    start = time.perf_counter()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            cli.main(["run", str(case), "-o", str(result), "-q"], prog_name="catenet")
        row["exit"] = 0
    except SystemExit as exc:
        row["exit"] = exc.code if isinstance(exc.code, int) else 1
    except TimeoutError as exc:
        row["exit"], row["stderr"] = "timeout", str(exc)
    except BaseException as exc:  # noqa: BLE001  (a traceback is a failure to report)
        row["exit"] = "traceback"
        stderr.write(f"Traceback\n{type(exc).__name__}: {exc}")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    row["process_time"] = time.perf_counter() - start
    row["stderr"] = row.get("stderr") or stderr.getvalue().strip()
    if result.exists():
        try:
            with h5py.File(result, "r") as f:
                attrs = f["result"].attrs
                row |= {k: float(attrs[k]) for k in ("iterations", "solve_time", "wall_time")}
            row["imbalance"] = corpus.check_equilibrium(result)
        except (OSError, KeyError) as exc:
            row["stderr"] = row["stderr"] or f"unreadable result: {exc}"
    if row["exit"] == 0:
        result.unlink(missing_ok=True)  # 10^4 result files would fill the disk
    row["kind"] = failure_kind(row, tol)
    return row


def failure_kind(row: dict, tol: float) -> str:
    """'' for a pass, else the exit status and the first stderr line with numbers masked."""
    if row["exit"] == 0:
        if row["imbalance"] == "" or not row["imbalance"] <= tol:
            return f"exit 0, equilibrium imbalance > {tol:g}"
        return ""
    lines = [ln for ln in row["stderr"].splitlines() if ln.strip()]
    first = lines[0] if lines else "(no stderr)"
    if first.startswith("Traceback"):
        first = f"traceback: {lines[-1]}"
    first = re.sub(r"[-+]?\d[\d.]*(e[-+]?\d+)?", "#", first)
    first = re.sub(r"\S*\.(h5|toml)\b", "FILE", first)
    return f"exit {row['exit']}: {first[:150]}"


def percentiles(values) -> str:
    v = np.asarray([x for x in values if x != ""], float)
    if not len(v):
        return "-"
    q = np.percentile(v, [0, 50, 90, 100])
    return " / ".join(f"{x:.3g}" for x in q)


def report(rows: list[dict]) -> None:
    by_family = defaultdict(list)
    for row in rows:
        by_family[row["family"]].append(row)
    print(
        f"\n{'family':<12} {'runs':>5} {'failed':>7} {'rate':>6}   "
        f"{'iterations min/median/p90/max':<32} {'solve time [s] min/median/p90/max'}"
    )
    for family in [*corpus.FAMILIES, "all"]:
        group = rows if family == "all" else by_family.get(family, [])
        if not group:
            continue
        failed = sum(1 for r in group if r["kind"])
        print(
            f"{family:<12} {len(group):>5} {failed:>7} {failed / len(group):>6.0%}   "
            f"{percentiles(r['iterations'] for r in group):<32} "
            f"{percentiles(r['solve_time'] for r in group)}"
        )
    scales = Counter(r["scale"] for r in rows)
    print(
        "\nfailure rate by unit scale: "
        + ", ".join(
            f"{s} {sum(1 for r in rows if r['scale'] == s and r['kind'])}/{n}"
            for s, n in scales.items()
        )
    )
    kinds = Counter(r["kind"] for r in rows if r["kind"])
    print(f"\n{'count':>5}  {'families':<40} kind (first example)")
    for kind, count in kinds.most_common():
        group = [r for r in rows if r["kind"] == kind]
        families = Counter(r["family"] for r in group)
        names = ", ".join(f"{f} {n}" for f, n in families.most_common())
        print(f"{count:>5}  {names:<40} {kind}\n{'':>7}{group[0]['case']}")
    times = [r["process_time"] for r in rows]
    print(
        f"\nprocess wall time per run [s] min/median/p90/max: {percentiles(times)}; "
        f"total {sum(times):.0f} s"
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("-o", "--out", type=Path, default=Path("out/corpus"))
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--tol", type=float, default=1e-6, help="largest relative imbalance")
    parser.add_argument("--family", choices=corpus.FAMILIES, help="only this family")
    parser.add_argument(
        "--in-process", action="store_true", help="run in worker processes, not a process each"
    )
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = range(args.seed, args.seed + args.count)
    rows = []
    if args.in_process:
        # multiprocessing's Pool replaces a worker after its 200 models (concurrent.futures'
        # max_tasks_per_child can leave the pool without workers on Python 3.11)
        pool = multiprocessing.get_context("spawn").Pool(max(1, args.jobs), maxtasksperchild=200)
        run = functools.partial(
            run_in_process, out=args.out, timeout=args.timeout, tol=args.tol, family=args.family
        )
        results = pool.imap(run, seeds)
    else:
        pool = ThreadPoolExecutor(max(1, args.jobs))
        jobs = [
            pool.submit(run_one, s, args.out, args.timeout, args.tol, args.family) for s in seeds
        ]
        results = (job.result() for job in jobs)
    with pool:
        for k, row in enumerate(results, 1):
            rows.append(row)
            mark = "ok  " if not row["kind"] else "FAIL"
            print(
                f"[{k}/{args.count}] {mark} seed {row['seed']} {row['family']:<11} "
                f"{row['process_time']:6.1f} s  {row['kind'] or row['description']}"[:160],
                flush=True,
            )
    with open(args.out / "runs.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, FIELDS)
        writer.writeheader()
        writer.writerows(rows)
    report(rows)
    print(f"\nevery run: {args.out / 'runs.csv'}")
    return 0


if __name__ == "__main__":
    main()
    sys.exit(0)
