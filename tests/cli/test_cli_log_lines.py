"""How a command's log reads on stderr: catenet's warnings as its error messages do, its
other records and other libraries' with their level and logger."""

from __future__ import annotations

import logging

from catenet.cli.common import _Said


def _line(name: str, level: int, message: str) -> str:
    record = logging.LogRecord(name, level, __file__, 1, message, None, None)
    return _Said().format(record)


def test_catenets_warnings_read_as_its_error_messages():
    said = _line("catenet.run.runner", logging.WARNING, "the integrator removed 49%")
    assert said == "catenet: warning: the integrator removed 49%"


def test_a_failed_command_ends_with_one_error_line_its_logged_errors_keep_their_logger():
    said = _line("catenet.run.cases", logging.ERROR, "the base state is implausible")
    assert said == "ERROR catenet.run.cases: the base state is implausible"


def test_debug_lines_and_other_libraries_keep_their_level_and_logger():
    debug = _line("catenet.solver.newton", logging.DEBUG, "it 3")
    assert debug == "DEBUG catenet.solver.newton: it 3"
    assert _line("h5py", logging.WARNING, "odd") == "WARNING h5py: odd"
    assert _line("catenetx", logging.WARNING, "odd") == "WARNING catenetx: odd"


def test_an_interrupted_run_names_the_steps_it_finished_not_one_it_was_in():
    """Stopped at load factor 0.9375 after the first of two load steps: "1 of 2 load steps
    done" (it said "step 1 of 2", the step it had finished, at a factor inside step 2)."""
    from types import SimpleNamespace as NS

    from catenet.cli.run import _where

    static = NS(solver=NS(method="static", steps=2))
    said = _where(static, NS(time=0.9375, steps=1))
    assert said == "load factor 0.9375 (1 of 2 load steps done)"
    dynamic = NS(solver=NS(method="dynamic", steps=1))
    assert _where(dynamic, NS(time=0.25, steps=40)) == "t = 0.25 s (40 time steps done)"
