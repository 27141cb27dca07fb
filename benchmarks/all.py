"""Every study, then the README performance section (docs/readme-performance.md).

Usage: `python benchmarks/all.py [-o DIR] [--quick]`; the same as `catenet bench all report`.
"""

import sys

from catenet.cli.bench import command

if __name__ == "__main__":
    command.main(["all", "report", *sys.argv[1:]], prog_name="python benchmarks/all.py")
