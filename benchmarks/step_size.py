"""Time against step size (paper App. B, Fig. B10).

A thin script: the study is `catenet.studies.bench.step_size` (so that `catenet bench step-size`
works from an installed package). Usage: `python benchmarks/step_size.py [-o DIR] [--quick]`, the
options of `catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.step_size import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["step-size", *sys.argv[1:]], prog_name="python benchmarks/step_size.py")
