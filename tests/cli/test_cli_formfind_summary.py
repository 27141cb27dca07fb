"""catenet formfind says what it found: the span, the lowest and highest node, each node
set's rise or sag against the supports, the force densities and each cable's tension
range (checked on a chain whose shape is known in closed form)."""

from __future__ import annotations

import math

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
    case.write_text(CHAIN)
    res = CliRunner().invoke(main, ["formfind", str(case), "-o", str(tmp_path / "c.h5")])
    assert res.exit_code == 0, res.output
    lines = {line[:12].strip(): line[12:].strip() for line in res.output.splitlines()}
    t = 100.0 * math.sqrt(1.04)
    assert lines["span"].startswith("10 m")
    assert lines["height"].startswith("lowest node 1 at z = -1 m")
    assert lines["set"].startswith("middle: z = -1 .. -1 m, sag 1 m")
    assert lines["density"].startswith("100 .. 100 N/m")
    assert lines["cable"] == f"chain: tension {t:.6g} .. {t:.6g} N, q 100 .. 100 N/m"
