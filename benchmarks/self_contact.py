"""What the strands' barrier (``solver.self_contact``) costs, in one run.

1. Wrapped nets, on against off: configs/contact/tether_capture.toml (short: the net
   hits the box, wraps its top and the corners swing round its sides) and
   configs/contact/folded_net.toml (a net thrown onto itself: off, it flies through
   itself, so its run does less work than the physical one). Solve time (median of
   ``--repeat`` runs, after one warm-up), Newton iterations, and their ratios.
2. Off costs nothing: no term is added, the pattern is the same and the runs are
   bit-identical with ``self_contact = false`` and without the key (checked here);
   the only work left on the path is one check per time step whether a pattern grew,
   timed against the cost of a step.
3. The candidate search by the grid against the net's size: a flat square net of 50^2
   to 200^2 cells, every node's radius 0.6 of a cell (each edge pairs with its parallel
   neighbours one cell away): time per edge should stay flat (linear cost), where all
   pairs would grow with the square.
4. The folded net to its default end: configs/contact/folded_net.toml without
   ``solver.t_end`` (10 s, 1 000 steps of a net landing on itself), as ``catenet run``
   (the fuzz harness's ``invoke``): it must end "ok" within the fuzz run's limit of 120 s
   of processor time (the long fuzz run once judged it a hang); its CPU seconds. (A test
   until it took a sixth of the suite's time: tests check answers, not time.)

Usage: ``python benchmarks/self_contact.py [--repeat K] [--quick]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from catenet.case import build, load_case
from catenet.kernels.strands import candidates
from catenet.solver import path as sv

CONTACT = Path(__file__).parents[1] / "configs" / "contact"


def solve_time(case: Path, changes: list[str], repeat: int) -> tuple[float, int, object]:
    """Median solve seconds of this process's CPU (a fresh scene and workspace per run,
    after a warm-up; CPU time, not wall time: the machine may be shared), the Newton
    iterations and the last result."""
    times, res = [], None
    for k in range(repeat + 1):
        scene = build(load_case(case, changes))
        settings = sv.Settings.of(scene.case.solver)
        start = time.process_time()
        res = sv.solve(scene, settings)
        if k:
            times.append(time.process_time() - start)
    return statistics.median(times), res.iterations, res


def wrapped(repeat: int, quick: bool) -> None:
    print("1. wrapped nets: self_contact on against off (solve CPU seconds, median)")
    print(f"{'case':34s} {'off s':>8s} {'on s':>8s} {'ratio':>6s} {'iter off':>9s} {'iter on':>8s}")
    runs = [("folded_net.toml", [])]
    if not quick:
        runs.insert(0, ("tether_capture.toml", ["solver.t_end=0.6"]))
    for name, changes in runs:
        off = solve_time(CONTACT / name, [*changes, "solver.self_contact=false"], repeat)
        on = solve_time(CONTACT / name, [*changes, "solver.self_contact=true"], repeat)
        print(f"{name:34s} {off[0]:8.2f} {on[0]:8.2f} {on[0] / off[0]:6.2f} {off[1]:9d} {on[1]:8d}")


def off_is_free(repeat: int) -> None:
    print("\n2. off: the same run, and what is left on the path")
    case, changes = CONTACT / "tether_capture.toml", ["solver.t_end=0.05"]
    _, it_plain, plain = solve_time(case, changes, 1)
    seconds, it_off, off = solve_time(case, [*changes, "solver.self_contact=false"], repeat)
    same = np.array_equal(plain.x, off.x) and it_plain == it_off
    scene = build(load_case(case, changes))
    ws = sv.workspace(scene, sv.Settings.of(scene.case.solver))
    calls = 100_000
    start = time.perf_counter()
    for _ in range(calls):
        ws.refresh()
    check = (time.perf_counter() - start) / calls
    step = seconds / max(off.steps, 1)
    print(f"bit-identical to the run without the key: {same}; pattern nnz {ws.system.nnz}")
    print(f"per time step: the pattern check {check * 1e6:.2f} us, the step {step * 1e3:.2f} ms")
    print(f"ratio {check / step:.1e} (nothing measurable)")


def grid_scaling(quick: bool) -> None:
    print("\n3. candidate pairs by the grid against the net's size")
    print(f"{'cells':>8s} {'edges':>9s} {'pairs':>8s} {'ms':>8s} {'ns/edge':>9s}")
    for n in (50, 100) if quick else (50, 100, 200):
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        rng = np.random.default_rng(0)
        nodes = np.c_[i.ravel(), j.ravel(), 0.01 * rng.normal(size=i.size)].astype(float)
        idx = i * (n + 1) + j
        edges = np.r_[
            np.c_[idx[:-1].ravel(), idx[1:].ravel()], np.c_[idx[:, :-1].ravel(), idx[:, 1:].ravel()]
        ].astype(np.int64)
        grow = np.full(len(edges), 0.6)
        candidates(nodes, edges, grow, 0.01)  # compiled
        times = []
        for _ in range(3):
            start = time.perf_counter()
            pairs = candidates(nodes, edges, grow, 0.01)
            times.append(time.perf_counter() - start)
        t = min(times)
        print(
            f"{n * n:8d} {len(edges):9d} {len(pairs):8d} {t * 1e3:8.1f} {t / len(edges) * 1e9:9.0f}"
        )


def folded_to_its_end() -> None:
    import sys
    import tempfile

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from fuzzing import CONFIGS, copy_beside, invoke, judge

    print("\n4. the folded net to its default end (10 s), as catenet run")
    source = CONFIGS / "contact" / "folded_net.toml"
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        copy_beside(source, work)
        text = source.read_text()
        case = work / "case.toml"
        case.write_text("\n".join(x for x in text.splitlines() if not x.startswith("t_end")))
        start = time.process_time()
        result = invoke(["run", case, "-o", work / "o.h5", "-q"], seconds=120, cwd=work)
        cpu = time.process_time() - start
        outcome = judge(result, work)
    print(f"outcome {outcome.kind!r} (must be 'ok'), {cpu:.1f} s of CPU (limit 120)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="the small cases only")
    args = parser.parse_args()
    wrapped(args.repeat, args.quick)
    off_is_free(args.repeat)
    grid_scaling(args.quick)
    if not args.quick:
        folded_to_its_end()


if __name__ == "__main__":
    main()
