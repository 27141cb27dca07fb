"""`catenet run` of the paper's densest net against another revision, in one run.

Checks out REV (default: the commit before HEAD) into a temporary git worktree and times
whole `catenet run configs/fig4i_n34_alpha_pi4.toml` processes of both trees, interleaved
(A B A B ...) so that the load of a shared machine falls on both alike, after one warm-up
run of each (Numba's cache is per tree). Prints the medians and their ratio, and how far
the two trees' results differ (largest difference of /result/x and /result/tension,
relative to their largest entry), and writes benchmarks/results/revisions.csv.

Usage: python benchmarks/compare_revisions.py [--base REV] [--repeat N] [--case PATH]
       [--set KEY=VALUE ...]   (passed to both runs, e.g. --set geometry.edge_length=0.001)
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_once(tree: Path, case: Path, out: Path, sets: tuple[str, ...] = ()) -> float:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    extra = [a for kv in sets for a in ("--set", kv)]
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "catenet", "run", str(case), "-o", str(out), "-q", *extra],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"catenet run failed in {tree}:\n{proc.stderr}")
    return seconds


def _differences(a: Path, b: Path) -> dict[str, float]:
    import h5py
    import numpy as np

    out = {}
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        for key in ("x", "tension"):
            u, w = np.asarray(fa["result"][key]), np.asarray(fb["result"][key])
            out[key] = float(np.max(np.abs(u - w)) / max(np.max(np.abs(u)), 1e-300))
    return out


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
            times: dict[str, list[float]] = {name: [] for name in trees}
            for k, tree in enumerate(trees.values()):  # warm each tree's Numba cache
                run_once(tree, case, Path(tmp) / f"warm{k}.h5", tuple(args.sets))
            differ = _differences(Path(tmp) / "warm0.h5", Path(tmp) / "warm1.h5")
            for k in range(args.repeat):
                for name, tree in trees.items():
                    out_k = Path(tmp) / f"{name[:4]}{k}.h5"
                    times[name].append(run_once(tree, case, out_k, tuple(args.sets)))
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)], check=False
            )
    median = {name: statistics.median(t) for name, t in times.items()}
    ratio = median["this"] / median[args.base]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "revisions.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["tree", "revision", "median_s", "min_s", "runs", "dx_rel", "dtension_rel"])
        for name, t in times.items():
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
                [name, rev, f"{median[name]:.4f}", f"{min(t):.4f}", len(t)]
                + [f"{differ['x']:.3e}", f"{differ['tension']:.3e}"]
            )
    for name in trees:
        print(f"{name:>10}: median {median[name]:.3f} s, min {min(times[name]):.3f} s")
    print(f"ratio this / {args.base}: {ratio:.3f}")
    for key, value in differ.items():
        print(f"largest relative difference of /result/{key}: {value:.2e}")


if __name__ == "__main__":
    main()
