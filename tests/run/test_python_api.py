"""The Python face of a run: ``catenet.load_case`` and ``catenet.run_case`` give the
numbers ``catenet run`` prints; ``-v`` shows catenet's own log lines only."""

from __future__ import annotations

from click.testing import CliRunner

import catenet
from catenet.cli import main
from tests.conftest import CONFIGS

MAST = CONFIGS / "structures" / "guyed_mast.toml"


def test_load_case_and_run_case_give_the_printed_numbers(tmp_path):
    case = catenet.load_case(MAST, overrides=["solver.steps=1"])
    result = catenet.run_case(case, tmp_path / "api.h5")
    s = result.report.summary
    r = CliRunner().invoke(
        main, ["run", str(MAST), "--set", "solver.steps=1", "-o", str(tmp_path / "cli.h5")]
    )
    assert r.exit_code == 0, r.output
    printed = r.output
    assert (
        f"max displ.   {s['max_displacement']:.6g} m at node {s['max_displacement_node']}"
        in printed
    )
    assert f"max tension  {s['max_tension']:.6g} N (edge {s['max_tension_edge']})" in printed
    assert f"compression  {s['max_compression']:.6g} N" in printed
    assert f"largest {s['max_reaction']:.6g} N at node {s['max_reaction_node']}" in printed
    assert f"delta        {s['delta']:.6g} m" in printed
    assert catenet.read_result(tmp_path / "api.h5").result_attrs["max_tension"] == s["max_tension"]
    assert {"load_case", "run_case", "read_result"} <= set(dir(catenet))


def test_verbose_shows_catenets_log_lines_only(tmp_path):
    r = CliRunner().invoke(main, ["run", str(MAST), "-v", "-o", str(tmp_path / "v.h5")])
    assert r.exit_code == 0, r.output
    logged = [line for line in r.output.splitlines() if line.startswith(("DEBUG ", "INFO "))]
    assert logged and all(line.split()[1].startswith("catenet.") for line in logged), logged
    assert any(line.startswith("DEBUG catenet.solver.newton") for line in logged)
