"""The ``catenet`` command line. Each command lives in its own module and is imported only
when it runs, so ``catenet --help`` stays instant (no NumPy, Numba or h5py at start-up).

This package is the only place that prints or exits. Exit codes: 0 success, 1 the run
failed or did not converge, 2 bad input (usage, case file, values).
"""

from __future__ import annotations

import atexit
import gc
import importlib

import click

COMMANDS = {
    "run": ("catenet.cli.run", "Run a case file (or the bundled default) and write HDF5."),
    "modes": ("catenet.cli.modes", "Natural frequencies and mode shapes about the equilibrium."),
    "sweep": ("catenet.cli.sweep", "Run a case over a grid of parameter values."),
    "formfind": ("catenet.cli.formfind", "Find a net's shape from force densities or targets."),
    "validate": ("catenet.cli.validate", "Check catenet against the analytic cable solutions."),
    "bench": ("catenet.cli.bench", "Time the n = 34 solve, backend, threads and cold start here."),
    "plot": ("catenet.cli.plot", "Draw figures from a result file or a sweep directory."),
    "report": (
        "catenet.cli.report",
        "Tables of a result file's cases: tensions, utilisation, reactions.",
    ),
    "export": ("catenet.cli.export", "Write a result file's frames as VTU, VTK or XDMF files."),
    "repair": ("catenet.cli.repair", "Make a result file open in every reader (killed runs)."),
    "info": ("catenet.cli.info", "Versions, linear-solver backend, threads, JIT cache."),
}


class LazyGroup(click.Group):
    def list_commands(self, ctx):
        return list(COMMANDS)

    def get_command(self, ctx, name):
        if name not in COMMANDS:
            return None
        module = importlib.import_module(COMMANDS[name][0])
        return module.command

    def format_commands(self, ctx, formatter):
        rows = [(name, help_) for name, (_, help_) in COMMANDS.items()]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("catenet")
    except PackageNotFoundError:  # running from a source tree
        return "unknown"


def _show_version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    """``--version``: looked up only when asked (the package metadata costs start-up)."""
    if value and not ctx.resilient_parsing:
        click.echo(f"catenet, version {_version()}")
        ctx.exit()


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.option(
    "--version",
    is_flag=True,
    expose_value=False,
    is_eager=True,
    callback=_show_version,
    help="Show the version and exit.",
)
def main():
    """catenet: static and dynamic analysis of elastic cable structures."""
    # At exit the operating system frees what is left: the interpreter's last garbage
    # collection would only walk it (mostly Numba's compiler and type objects, a fifth of
    # a `catenet run` process's CPU time). Frozen objects are skipped; exit handlers run.
    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
