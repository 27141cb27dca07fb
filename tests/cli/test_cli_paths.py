"""A path on the command line that cannot be what it must be (a missing case or
--restart file, a directory for a file, a file for a directory) is bad input: every
command says so in catenet's one line, ``catenet: error: <option> = <value>: <what is
accepted>``, exit 2 (docs/reference/errors.md), never click's three-line usage text."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from catenet.cli import main

CASE = """\
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [10.0, 0.0, 0.0]
nodes = 5
[material]
EA = 1e6
"""

BAD = [
    ("run nope.toml", "CASE.toml = 'nope.toml': no such file"),
    ("run adir", "CASE.toml = 'adir': is a directory: give a case file"),
    ("run case.toml -o adir", "--output = 'adir': is a directory: give a file path"),
    ("run case.toml --restart old.h5 -o o.h5", "--restart = 'old.h5': no such file"),
    ("run case.toml --restart adir -o o.h5", "--restart = 'adir': is a directory"),
    ("modes nope.toml", "CASE.toml = 'nope.toml': no such file"),
    ("modes case.toml --output adir", "--output = 'adir': is a directory"),
    ("formfind nope.toml", "CASE.toml = 'nope.toml': no such file"),
    ("formfind adir -o f.h5", "CASE.toml = 'adir': is a directory"),
    ("formfind case.toml -o adir", "--output = 'adir': is a directory"),
    ("formfind case.toml -o found.toml", "output file 'found.toml': is the name of the case"),
    ("sweep nope.toml -p material.EA=1,2", "nope.toml: no such case file"),
    ("sweep case.toml -p material.EA=1,2 -o afile", "--output = 'afile': is not a directory"),
    ("validate -o adir", "--output = 'adir': is a directory"),
    ("bench -o afile", "--output = 'afile': is not a directory"),
    ("report nope.h5", "nope.h5: no such file"),
    ("plot nope.h5", "nope.h5: no such file"),
    ("export nope.h5 --to vtu", "nope.h5: no such result file"),
    ("repair nope.h5", "nope.h5: no such result file"),
]


@pytest.mark.parametrize("command, message", BAD, ids=[c for c, _ in BAD])
def test_a_bad_path_is_one_line_and_exit_2(command, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "case.toml").write_text(CASE)
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("a file\n")
    res = CliRunner().invoke(main, command.split())
    assert res.exit_code == 2, res.output
    assert res.output.strip() == f"catenet: error: {message}" or (
        res.output.startswith(f"catenet: error: {message}")
        and len(res.output.strip().splitlines()) == 1
    ), res.output
    assert "Usage:" not in res.output and "Traceback" not in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "afile", "case.toml"]


def test_an_internal_error_names_where_debug_goes(tmp_path, monkeypatch):
    """A bug's one line tells how to see its traceback in a form the command line takes
    (``catenet --debug run`` is refused: --debug belongs to the command), and the
    command so written shows it."""
    import catenet.run.runner as runner

    def broken(*args, **kwargs):
        raise RuntimeError("a planted bug")

    monkeypatch.setattr(runner, "run_case", broken)
    case = tmp_path / "case.toml"
    case.write_text(CASE)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "o.h5")])
    assert done.exit_code == 1
    assert "internal error: RuntimeError: a planted bug" in done.output
    assert "'catenet run --debug ...'" in done.output
    debug = CliRunner().invoke(main, ["run", "--debug", str(case), "-o", str(tmp_path / "o.h5")])
    assert isinstance(debug.exception, RuntimeError)
