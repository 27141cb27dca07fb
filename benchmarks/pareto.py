"""Run time against error (a Pareto front) and the recommended settings.

A thin script: the study is `catenet.studies.bench.pareto` (so that `catenet bench pareto` works
from an installed package). Usage: `python benchmarks/pareto.py [-o DIR] [--quick]`, the options of
`catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.pareto import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["pareto", *sys.argv[1:]], prog_name="python benchmarks/pareto.py")
