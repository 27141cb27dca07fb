"""catenet against a plain NumPy/SciPy/pypardiso implementation (and OpenSees).

A thin script: the study is `catenet.studies.bench.baseline` (so that `catenet bench baseline` works
from an installed package). Usage: `python benchmarks/baseline.py [-o DIR] [--quick]`, the options
of `catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.baseline import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["baseline", *sys.argv[1:]], prog_name="python benchmarks/baseline.py")
