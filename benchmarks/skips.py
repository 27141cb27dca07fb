"""What each skip saves, and whether catenet skips by default.

A thin script: the study is `catenet.studies.bench.skips` (so that `catenet bench skips` works from
an installed package). Usage: `python benchmarks/skips.py [-o DIR] [--quick]`, the options of
`catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.skips import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["skips", *sys.argv[1:]], prog_name="python benchmarks/skips.py")
