"""catenet formfind says what it found: the span, the lowest and highest node, each node
set's rise or sag against the supports, the force densities and each cable's tension
range (checked on a chain whose shape is known in closed form)."""

from __future__ import annotations

import math
import re

import pytest
from click.testing import CliRunner

from catenet.cli import main

CHAIN = """
[geometry]
kind = "graph"
nodes = [[0, 0, 0], [5, 0, 0], [10, 0, 0]]
edges = []
fixed = [0, 2]
edge_length = 1.0
[geometry.sets]
middle = [1]
[[geometry.cable]]
name = "chain"
nodes = [0, 1, 2]
[material]
EA = 1.0e6
[load]
point = [{ node = "middle", force = [0, 0, -40.0] }]
[formfind]
force_density = 100.0
"""


def test_the_formfind_summary_gives_the_shape_and_forces(tmp_path):
    """Force density q = 100 N/m on 1 m edges: the horizontal force H = q dx = 100 N in
    every edge; the two straight halves hold the 40 N at the middle when 2 H z / 5 m =
    40 N, so the middle sags z = 1 m and every edge carries q L = 100 sqrt(1.04) N."""
    case = tmp_path / "chain.toml"
    case.write_text(CHAIN.replace("middle = [1]", "middle = [1]\nends = [0, 2]"))
    res = CliRunner().invoke(main, ["formfind", str(case), "-o", str(tmp_path / "c.h5")])
    assert res.exit_code == 0, res.output
    assert "ends:" not in res.output  # (a set of supports: form finding does not move it)
    lines = {line[:12].strip(): line[12:].strip() for line in res.output.splitlines()}
    t = 100.0 * math.sqrt(1.04)
    assert lines["span"].startswith("10 m")
    assert lines["height"].startswith("lowest node 1 at z = -1 m")
    assert lines["set"].startswith("middle: z = -1 .. -1 m, sag 1 m")
    assert lines["density"].startswith("100 .. 100 N/m")
    assert lines["cable"] == f"chain: tension {t:.6g} .. {t:.6g} N, q 100 .. 100 N/m"


@pytest.mark.parametrize("max_iter", [5, 100])
def test_a_target_no_force_density_reaches_fails_with_its_last_iterate_written(tmp_path, max_iter):
    """The chain's middle asked 1 m above its supports under a downward load: larger
    force densities only bring it nearer z = 0, never above, so the search runs towards
    tensions without bound (out of iterations at 5, away at 100). That is no compromise
    (a stationary least-squares point): exit 1, its last iterate written (the result
    file and OUT.toml), the error saying why and what bounds the search; with -q the
    error alone."""
    case = tmp_path / "chain.toml"
    case.write_text(CHAIN + '\n[[target]]\nnode = "middle"\nz = 1.0\n')
    out = ["-o", str(tmp_path / "c.h5"), "--set", f"formfind.max_iter={max_iter}"]
    why = (
        "did not converge within formfind.max_iter = 5 iterations"
        if max_iter == 5
        else "the force densities ran away (to "
    )
    for quiet in ([], ["-q"]):
        res = CliRunner().invoke(main, ["formfind", str(case), *out, *quiet])
        assert res.exit_code == 1, res.output
        assert res.stderr.startswith("catenet: error: ") and why in res.stderr
        assert "formfind.force_density_min / _max" in res.stderr
        assert ("a larger formfind.max_iter" in res.stderr) is (max_iter == 5)
        assert "compromise" not in res.stderr  # the warning of a stationary compromise
        assert (tmp_path / "c.h5").is_file() and (tmp_path / "c.toml").is_file()
        written = (tmp_path / "c.toml").read_text()  # its header claims no design
        assert "found no answer" in written and "reproduces the shape" not in written
        assert ("NOT met" in res.stdout) is not bool(quiet)
        assert "(catenet run" not in res.stdout  # (no answer to run)
        assert ("(the last iterate: no answer)" in res.stdout) is not bool(quiet)
        if max_iter == 100:  # which way they ran, and how far
            assert "times their start, beyond 1e+06)" in res.stderr


def test_an_unreachable_target_within_bounds_is_a_compromise(tmp_path):
    """The same target with the force densities bounded: the compromise at the bound is
    a stationary point, said with a warning (exit 0)."""
    case = tmp_path / "chain.toml"
    case.write_text(CHAIN + '\n[[target]]\nnode = "middle"\nz = 1.0\n')
    args = ["--set", "formfind.force_density_max=1e4", "-o", str(tmp_path / "c.h5")]
    res = CliRunner().invoke(main, ["formfind", str(case), *args])
    assert res.exit_code == 0, res.output
    assert "catenet: warning: the targets are not all met" in res.stderr
    assert "least-squares compromise within the bounds" in res.stdout  # (not the targets')


def test_the_formfind_summary_names_the_cases_units(tmp_path):
    """The same chain in kN-m and in N-mm: the numbers are the case's, every label names
    its units (kN, kN/m; mm, N/mm), the summary's and the written case's header's (a
    target's line), never N and m for numbers that are not in them."""
    t = 100.0 * math.sqrt(1.04)
    found = {}
    for units, target in (("kN-m", ""), ("N-mm", '[[target]]\nnode = "middle"\nz = -1.0\n')):
        case = tmp_path / f"in-{units}.toml"
        case.write_text(f'units = "{units}"\n' + CHAIN + target)
        out = tmp_path / f"{units}.h5"
        res = CliRunner().invoke(main, ["formfind", str(case), "-o", str(out)])
        assert res.exit_code == 0, res.output
        found[units] = {line[:12].strip(): line[12:].strip() for line in res.output.splitlines()}
    kn = found["kN-m"]
    assert kn["tension"] == f"{t:.6g} .. {t:.6g} kN" and kn["span"].startswith("10 m (")
    assert kn["cable"] == f"chain: tension {t:.6g} .. {t:.6g} kN, q 100 .. 100 kN/m"
    mm = found["N-mm"]
    assert mm["span"].startswith("10 mm (") and mm["density"].startswith("100 .. 100 N/mm")
    assert mm["height"].startswith("lowest node 1 at z = -1 mm") and mm["height"].endswith("mm")
    assert mm["set"].startswith("middle: z = -1 .. -1 mm, sag 1 mm")
    assert mm["target[0]"].startswith("node 'middle' z: -1 mm (target -1 mm,")
    header = (tmp_path / "N-mm.toml").read_text().split("\n\n")[0]
    assert "#   target[0] node 'middle' z: -1 mm (target -1 mm, miss" in header


def test_the_errors_name_the_cases_units(tmp_path):
    """In kN-m the search that runs away names its tensions in kN (it said "tensions up
    to ... N" under a summary in kN), and a bad key's message its unit in kN (it said
    "a tension > 0 [N]")."""
    case = tmp_path / "kn.toml"
    case.write_text('units = "kN-m"\n' + CHAIN + '\n[[target]]\nnode = "middle"\nz = 1.0\n')
    res = CliRunner().invoke(main, ["formfind", str(case), "-o", str(tmp_path / "c.h5")])
    assert res.exit_code == 1, res.output
    assert re.search(r"tensions up to [0-9.e+-]+ kN\)", res.stderr), res.stderr
    bad = ["--set", 'target=[{cable = "chain", tension = [60.0, 20.0]}]']
    res = CliRunner().invoke(main, ["formfind", str(case), "-o", str(tmp_path / "d.h5"), *bad])
    assert res.exit_code == 2, res.output
    assert "must be a tension > 0 [kN] or a range" in res.stderr, res.stderr
