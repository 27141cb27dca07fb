"""`catenet run` of the paper's densest net against another revision, in one run.

Checks out REV (default: the commit before HEAD) into a temporary git worktree and times
whole `catenet run configs/fig4i_n34_alpha_pi4.toml` processes of both trees, interleaved
(A B A B ...) so that the load of a shared machine falls on both alike, after one warm-up
run of each (Numba's cache and Python's bytecode cache are per tree: the warm-up writes
both, as installing a package does, whatever PYTHONDONTWRITEBYTECODE says). Prints the
medians of wall time and of CPU time (user + system of the process: what a busy machine
disturbs least) and their ratios, and how far the two trees' results differ (largest
difference of /result/x and /result/tension, relative to their largest entry), and writes
benchmarks/results/revisions.csv.

Usage: python benchmarks/compare_revisions.py [--base REV] [--repeat N] [--case PATH]
       [--set KEY=VALUE ...]   (passed to both runs, e.g. --set geometry.edge_length=0.001)
"""

from __future__ import annotations

import argparse
import csv
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_once(tree: Path, case: Path, out: Path, sets: tuple[str, ...] = ()) -> tuple[float, float]:
    """(wall, CPU) seconds of one whole `catenet run` process in ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # bytecode cached as an installed package's
    extra = [a for kv in sets for a in ("--set", kv)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "catenet", "run", str(case), "-o", str(out), "-q", *extra],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"catenet run failed in {tree}:\n{proc.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return seconds, cpu


def _differences(a: Path, b: Path) -> dict[str, float]:
    import h5py
    import numpy as np

    out = {}
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        for key in ("x", "tension"):
            u, w = np.asarray(fa["result"][key]), np.asarray(fb["result"][key])
            out[key] = float(np.max(np.abs(u - w)) / max(np.max(np.abs(u)), 1e-300))
    return out


#: Attributes that say when, where from and how fast a run went, not what it found.
CLOCK = {"created", "source", "wall_time", "solve_time", "startup_time"}


def _same_content(this: Path, other: Path) -> list[str]:
    """What of ``other``'s datasets and attributes ``this`` lacks or holds otherwise
    (bit for bit; the clock's attributes aside); [] when nothing."""
    import h5py
    import numpy as np

    problems: list[str] = []
    with h5py.File(this, "r") as fa, h5py.File(other, "r") as fb:

        def attrs(name: str, a, b) -> None:
            for key in b.attrs:
                if key in CLOCK:
                    continue
                if key not in a.attrs:
                    problems.append(f"attribute {key} of {name}: missing")
                elif not np.array_equal(np.asarray(a.attrs[key]), np.asarray(b.attrs[key])):
                    problems.append(f"attribute {key} of {name}: differs")

        def visit(name: str, obj) -> None:
            if name not in fa:
                problems.append(f"/{name}: missing")
                return
            if isinstance(obj, h5py.Dataset) and not np.array_equal(fa[name][()], obj[()]):
                problems.append(f"/{name}: differs")
            attrs(f"/{name}", fa[name], obj)

        attrs("/", fa, fb)
        fb.visititems(visit)
    return problems


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default="HEAD~1", help="the revision to compare with")
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--case", default="configs/fig4i_n34_alpha_pi4.toml")
    parser.add_argument("-o", "--out", default=str(ROOT / "benchmarks" / "results"))
    parser.add_argument(
        "--set", dest="sets", action="append", default=[], help="KEY=VALUE for both runs"
    )
    args = parser.parse_args()
    case = (ROOT / args.case).resolve()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(base), args.base],
            check=True,
        )
        try:
            trees = {"this": ROOT, args.base: base}
            runs: dict[str, list[tuple[float, float]]] = {name: [] for name in trees}
            for k, tree in enumerate(trees.values()):  # warm each tree's caches
                run_once(tree, case, Path(tmp) / f"warm{k}.h5", tuple(args.sets))
            differ = _differences(Path(tmp) / "warm0.h5", Path(tmp) / "warm1.h5")
            problems = _same_content(Path(tmp) / "warm0.h5", Path(tmp) / "warm1.h5")
            for k in range(args.repeat):
                for name, tree in trees.items():
                    out_k = Path(tmp) / f"{name[:4]}{k}.h5"
                    runs[name].append(run_once(tree, case, out_k, tuple(args.sets)))
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)], check=False
            )
    wall = {name: [w for w, _ in r] for name, r in runs.items()}
    cpu = {name: [c for _, c in r] for name, r in runs.items()}
    median = {name: statistics.median(t) for name, t in wall.items()}
    median_cpu = {name: statistics.median(t) for name, t in cpu.items()}
    ratio = median["this"] / median[args.base]
    ratio_cpu = median_cpu["this"] / median_cpu[args.base]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "revisions.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(
            ["tree", "revision", "case", "median_s", "min_s", "median_cpu_s", "min_cpu_s"]
            + ["runs", "dx_rel", "dtension_rel", "file_differences"]
        )
        for name in trees:
            rev = subprocess.run(
                [
                    "git",
                    "-C",
                    str(ROOT),
                    "rev-parse",
                    "--short",
                    "HEAD" if name == "this" else name,
                ],
                capture_output=True,
                text=True,
            ).stdout.strip()
            w.writerow(
                [name, rev, args.case, f"{median[name]:.4f}", f"{min(wall[name]):.4f}"]
                + [f"{median_cpu[name]:.4f}", f"{min(cpu[name]):.4f}", len(wall[name])]
                + [f"{differ['x']:.3e}", f"{differ['tension']:.3e}", "; ".join(problems) or "none"]
            )
    for name in trees:
        print(
            f"{name:>10}: wall median {median[name]:.3f} s (min {min(wall[name]):.3f}), "
            f"CPU median {median_cpu[name]:.3f} s (min {min(cpu[name]):.3f})"
        )
    print(f"ratio this / {args.base}: wall {ratio:.3f}, CPU {ratio_cpu:.3f}")
    for key, value in differ.items():
        print(f"largest relative difference of /result/{key}: {value:.2e}")
    print(
        "every dataset and attribute of the other revision's file: "
        + ("the same in this one" if not problems else "; ".join(problems))
    )


if __name__ == "__main__":
    main()
