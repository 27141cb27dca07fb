"""Static solve from 1e3 to 1e7 DOF: time split, peak memory against the memory guard's
estimate, and PARDISO's ordering and out-of-core choices at 1e6 DOF.

A thin script: the study is `catenet.studies.bench.scale` (so that `catenet bench scale` works from
an installed package). Usage: `python benchmarks/scale.py [-o DIR] [--quick]`, the options of
`catenet bench`; the table and figure go to benchmarks/results/ by default.
"""

import sys

from catenet.cli.bench import command
from catenet.studies.bench.scale import run  # noqa: F401  (importable: run(out_dir, quick=...))

if __name__ == "__main__":
    command.main(["scale", *sys.argv[1:]], prog_name="python benchmarks/scale.py")
