"""What crash-safe result files cost: a 10^3-step dynamic run writing a frame per step,
with catenet's batched, atomically published writer against the per-frame SWMR flush it
replaced (ratio in one run; the frames of both are checked to be bitwise equal).

A thin script: the study is `catenet.studies.bench.flush` (so that `catenet bench flush`
works from an installed package). Usage: `python benchmarks/flush.py [-o DIR] [--quick]`, the
options of `catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.flush import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["flush", *sys.argv[1:]], prog_name="python benchmarks/flush.py")
