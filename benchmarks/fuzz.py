"""The long run of the fuzzing suite: N hostile inputs (default 10^4) through catenet's
commands, in this process, each bounded in time, counted by outcome class.

    python benchmarks/fuzz.py                 # 10^4 cases, seed 0
    python benchmarks/fuzz.py -n 2000 --seed 7 --out benchmarks/results/fuzz.json

The inputs are those of tests/fuzz (tests/fuzzing.py): mutated example cases of configs/
and case files from the declared keys, net files (JSON, CSV, OBJ), mesh files (STL),
sweep values and damaged result files given to plot, export, repair, report and
--restart. The classes: ok, bad input (exit 2), failed (exit 1), and the bad ones (traceback, hang,
exit code, unclear message, numpy repr, non-finite result, leftover), each bad case
printed with its input so that it can be turned into a test. Exit status 1 when there
is any bad outcome.
"""

from __future__ import annotations

import argparse
import collections
import copy
import faulthandler
import json
import random
import sys
import tempfile
import time
import tomllib
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

import fuzzing as fz  # noqa: E402

SMALL_NET = """
title = "small"
[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 1.0
edge_length = 0.1
[material]
E = 10e6
radius = 0.01
density = 1000.0
[load]
pressure = 100.0
[solver]
method = "{method}"
dt = 0.01
t_end = 0.3
[output]
every = 1
"""


def case_input(rng, work: Path, cases, bases):
    case = rng.choice(cases)
    data = copy.deepcopy(bases[case])
    what = fz.mutate_case(data, rng)
    fz.copy_beside(case, work)
    path = work / "case.toml"
    path.write_bytes(fz.render(data, rng))
    command, *extra = fz.command_for(data, rng)
    args = [command, path, "-o", work / "out.h5", *extra]
    return [*args, "-q"], f"{case.name}: {what} ({command})"


def net_input(rng, work: Path):
    name = rng.choice(sorted(fz.NET_FILES))
    (work / name).write_bytes(fz.mutate_text(fz.NET_FILES[name], rng))
    (work / "case.toml").write_text(fz.NET_CASE.format(name=name))
    what = f"{name}: {(work / name).read_bytes()[:200]!r}"
    return ["run", work / "case.toml", "-o", work / "out.h5", "-q"], what


def sweep_input(rng, work: Path):
    (work / "case.toml").write_text(fz.SWEEP_CASE)
    params = fz.mutate_params(rng)
    args = ["sweep", work / "case.toml", "-o", work / "sw", "-j", "1", "-q"]
    for p in params:
        args += ["-p", p]
    return args, f"--param {params}"


def result_input(rng, work: Path, files):
    method = rng.choice(sorted(files))
    case, src = files[method]
    damaged = work / "damaged.h5"
    how = fz.mutate_result(src, damaged, rng)
    command = rng.choice(["plot", "export", "repair", "report", "restart"])
    if command == "plot":
        args = ["plot", damaged, "-o", work / "fig.png"]
    elif command == "export":
        args = ["export", damaged, "--to", rng.choice(["vtu", "xdmf"]), "-o", work / "ex"]
    elif command == "repair":
        args = ["repair", damaged]
    elif command == "report":
        args = ["report", damaged, "--format", rng.choice(["md", "csv", "html"])]
        args += ["-o", work / "report"]
    else:
        args = ["run", case, "--restart", damaged, "-o", work / "again.h5", "-q"]
        args += ["--set", "solver.t_end=0.6", "--set", "solver.method=dynamic"]
    return args, f"{method} file {how}, {command}"


def result_files(root: Path) -> dict:
    files = {}
    for method in ("dynamic", "static"):
        case = root / f"{method}.toml"
        case.write_text(SMALL_NET.format(method=method))
        out = root / f"{method}.h5"
        result = fz.invoke(["run", case, "-o", out, "-q"], seconds=300)
        if result.exit_code != 0:
            raise SystemExit(f"cannot make the result file to damage: {result.output}")
        files[method] = (case, out)
    return files


#: The watchdog's limit, in units of a case's time limit (``--seconds``): invoke's own
#: limit counts processor time and allows a command that waits 4x on the clock.
HANG = 10


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=10_000, help="cases (default 10^4)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seconds", type=float, default=120.0, help="time limit of one case")
    ap.add_argument("--out", type=Path, default=None, help="the counts as JSON")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    rng = random.Random(args.seed)
    cases = [p for p in fz.example_cases() if "sweeps" not in p.parts]
    bases = {p: fz.small(tomllib.loads(p.read_text())) for p in cases}
    counts: collections.Counter = collections.Counter()
    by_input: collections.Counter = collections.Counter()
    bad = []
    start = time.perf_counter()
    trail = sys.stderr  # the input under way, for the watchdog's report
    with tempfile.TemporaryDirectory(prefix="catenet-fuzz-") as tmp:
        root = Path(tmp)
        files = result_files(root)
        for k in range(args.n):
            work = root / f"c{k}"
            work.mkdir()
            kind = rng.choices(["case", "net", "sweep", "result"], weights=[5, 1, 1, 2])[0]
            if kind == "case":
                argv_k, what = case_input(rng, work, cases, bases)
            elif kind == "net":
                argv_k, what = net_input(rng, work)
            elif kind == "sweep":
                argv_k, what = sweep_input(rng, work)
            else:
                argv_k, what = result_input(rng, work, files)
            before = set(work.rglob("*.h5"))
            # A hang inside a library's C code (HDF5 reading a damaged heap, the run of
            # seed 19) holds the interpreter: invoke's limit never fires. The watchdog
            # ends the whole run then, naming the input and where it hung, instead of
            # stalling without a word.
            faulthandler.dump_traceback_later(HANG * args.seconds, exit=True)
            print(f"input {k}: {what}", file=trail, flush=True)
            result = fz.invoke(argv_k, seconds=args.seconds, cwd=work)
            faulthandler.cancel_dump_traceback_later()
            outcome = fz.judge(result, work, before)
            counts[outcome.kind] += 1
            by_input[f"{kind}: {outcome.kind}"] += 1
            if not outcome.good:
                bad.append({"case": k, "class": outcome.kind, "input": what,
                            "detail": outcome.detail})  # fmt: skip
                print(f"BAD {outcome.kind}: {what}\n    {outcome.detail}", flush=True)
            if (k + 1) % 500 == 0:
                rate = (k + 1) / (time.perf_counter() - start)
                print(f"{k + 1} cases ({rate:.1f}/s): {dict(counts)}", flush=True)
            _remove(work)
    report = {
        "cases": args.n,
        "seed": args.seed,
        "seconds": round(time.perf_counter() - start, 1),
        "counts": dict(counts),
        "by_input": dict(sorted(by_input.items())),
        "bad": bad,
    }
    print(json.dumps({k: v for k, v in report.items() if k != "bad"}, indent=2))
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(report, indent=2) + "\n")
    return 1 if bad else 0


def _remove(work: Path) -> None:
    import shutil

    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
