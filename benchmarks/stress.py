"""Numerical-stability stress test (a fast subset runs in tests/solver/test_stress.py).

A thin script: the study is `catenet.studies.bench.stress` (so that `catenet bench stress` works
from an installed package). Usage: `python benchmarks/stress.py [-o DIR] [--quick]`, the options of
`catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.stress import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["stress", *sys.argv[1:]], prog_name="python benchmarks/stress.py")
