"""Cold start: catenet --help and catenet run with an empty and a warm JIT cache.

A thin script: the study is `catenet.studies.bench.cold_start` (so that `catenet bench cold-start`
works from an installed package). Usage: `python benchmarks/cold_start.py [-o DIR] [--quick]`, the
options of `catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.cold_start import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["cold-start", *sys.argv[1:]], prog_name="python benchmarks/cold_start.py")
