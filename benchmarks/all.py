"""Every study, then the README performance section (docs/readme-performance.md).

Usage: `python benchmarks/all.py [-o DIR] [--quick]`; the same as `catenet bench all report`.
"""

import sys

from catenet.cli.bench import command

if __name__ == "__main__":
    args = sys.argv[1:]
    if "-o" not in args and "--output" not in args:
        args += ["-o", "benchmarks/results"]  # the repository's committed results
    args += ["--docs", "docs", "--readme", "README.md"]
    command.main(["all", "report", *args], prog_name="python benchmarks/all.py")
