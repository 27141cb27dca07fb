"""A sweep's row says converged only where ``catenet run`` of its combination exits 0:
a level beyond a snap-through is the collapse the run reports (each level of a bilateral
net along its own judged path; from the level before, Newton jumped to the far branch,
called stable), and an unstable or implausible equilibrium is the row's error (rows of
both said converged, with the sweep's exit 0)."""

from __future__ import annotations

import csv

from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main

#: A shallow three-bar truss: apex 0.3 m over a ring of radius 5 m, EA = 2e6 N; its limit
#: load is EA h^3 / (sqrt 3 L0^3) = 248 N (L0 the bars' length), its inverted branch at
#: 300 N lies 0.654 m below the apex.
TRIPOD = {
    "title": "a shallow tripod",
    "geometry": {
        "kind": "graph",
        "nodes": [
            [0.0, 0.0, 0.3],
            [5.0, 0.0, 0.0],
            [-2.5, 4.330127018922193, 0.0],
            [-2.5, -4.330127018922193, 0.0],
        ],
        "edges": [[0, 1], [0, 2], [0, 3]],
        "fixed": [1, 2, 3],
    },
    "material": {"EA": 2e6, "tension_only": False},
    "load": {"point": [{"node": 0, "force": [0.0, 0.0, -60.0]}]},
}
STRUT = {  # a pinned chain of bilateral struts precompressed, nothing else: unstable
    "title": "a precompressed chain",
    "geometry": {
        "kind": "graph",
        "nodes": [[float(i), 0.0, 0.0] for i in range(5)],
        "edges": [[i, i + 1] for i in range(4)],
        "fixed": [0, 4],
    },
    "material": {"EA": 1e6, "tension_only": False, "prestress": -1000.0},
}
ROLLERS = {  # both ends on rollers, a load tilted by 1e-9: nothing holds it along x
    "title": "a cable on rollers",
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [10.0, 0.0, 0.0], "nodes": 11},
    "material": {"EA": 1e6, "prestress": 1000.0},
    "supports": {"fixed": [], "roller": [{"nodes": ["start", "end"], "normal": [0, 0, 1]}]},
    "load": {"point": [{"node": "midpoint", "force": [1e-7, 0.0, -100.0]}]},
}


def sweep(tmp_path, case: dict, *params: str):
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    args = ["sweep", str(path), "-o", str(tmp_path / "s"), "--workers", "1"]
    for p in params:
        args += ["-p", p]
    done = CliRunner().invoke(main, args)
    with open(tmp_path / "s" / "results.csv", newline="") as fh:
        return done, list(csv.DictReader(fh))


def test_a_level_beyond_a_snap_through_is_the_collapse_catenet_run_reports(tmp_path):
    forces = "[0,0,-100.0],[0,0,-240.0],[0,0,-300.0],[0,0,-200.0]"
    done, rows = sweep(tmp_path, TRIPOD, f"load.point.0.force={forces}")
    assert done.exit_code == 1, done.output
    assert [r["converged"] for r in rows] == ["true", "true", "false", "true"]
    assert "collapses beyond load factor" in rows[2]["error"]
    assert float(rows[1]["delta"]) < 0.15 and float(rows[3]["delta"]) < 0.15  # not inverted
    run = CliRunner().invoke(
        main,
        ["run", str(tmp_path / "case.toml"), "-o", str(tmp_path / "r.h5"), "--set"]
        + ["load.point.0.force=[0,0,-200.0]"],
    )
    assert run.exit_code == 0 and float(rows[3]["delta"]) > 0.0
    assert f"{float(rows[3]['delta']):.6g}" in run.output  # the run's delta, to its digits


def test_an_unstable_level_is_an_error_row(tmp_path):
    done, rows = sweep(tmp_path, STRUT, "material.EA=1e6,2e6")
    assert done.exit_code == 1, done.output
    for row in rows:
        assert row["converged"] == "false"
        assert row["error"].startswith("the equilibrium found is unstable: "), row["error"]


def test_an_implausible_level_is_an_error_row(tmp_path):
    done, rows = sweep(tmp_path, ROLLERS, "material.EA=1e6,2e6")
    assert done.exit_code == 1, done.output
    for row in rows:
        assert row["converged"] == "false"
        assert row["error"].startswith("the result is implausible (check units and supports)")
