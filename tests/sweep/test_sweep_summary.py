"""Sweep tables carry the run summary's numbers (``catenet.model.summary``): the same
values as ``catenet run`` of each combination prints and writes."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import h5py
from click.testing import CliRunner

from catenet.cli import main
from catenet.model import summary
from catenet.sweep.jobs import SUMMARY_COLUMNS

ROOT = Path(__file__).resolve().parents[2]
MAST = ROOT / "configs" / "structures" / "guyed_mast.toml"


def test_sweep_columns_are_the_summary_columns():
    assert SUMMARY_COLUMNS == summary.COLUMNS


def test_mast_sweep_rows_equal_single_runs(tmp_path):
    """The mast swept over its top load: each row's summary columns are the /result
    attributes of `catenet run` at that load (same solve path, same numbers)."""
    r = CliRunner().invoke(
        main,
        [
            "sweep",
            str(MAST),
            "--param",
            "material.EA=2e7,3e7",
            "-o",
            str(tmp_path / "s"),
            "--workers",
            "1",
        ],
    )
    assert r.exit_code == 0, r.output
    with open(tmp_path / "s" / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2
    for row in rows:
        out = tmp_path / f"run{row['material.EA']}.h5"
        r = CliRunner().invoke(
            main, ["run", str(MAST), "-o", str(out), "--set", f"material.EA={row['material.EA']}"]
        )
        assert r.exit_code == 0, r.output
        with h5py.File(out) as h5:
            attrs = dict(h5["result"].attrs)
        for key in SUMMARY_COLUMNS:
            want = float(attrs[key])
            got = float(row[key])
            assert got == want or (math.isnan(got) and math.isnan(want)), key
    assert float(rows[1]["max_tension"]) != float(rows[0]["max_tension"])
    assert int(rows[0]["max_displacement_node"]) == 1 and float(rows[0]["max_compression"]) > 6e4


def test_sweep_reports_one_load_case(tmp_path):
    """--case NAME: every row is that combination of the mast's load cases, solved from
    the row's base state: the same numbers as `catenet run --case NAME` of the row."""
    import tomllib

    from catenet.case import dumps_toml

    data = tomllib.loads(MAST.read_text())
    data["load"] = {}
    data["load_case"] = [{"name": "wind", "point": [{"node": "top", "force": [1e4, 0, 0]}]}]
    data["combination"] = [{"name": "ULS", "factors": {"wind": 1.5}}]
    case = tmp_path / "mast.toml"
    case.write_text(dumps_toml(data))
    out = tmp_path / "s"
    r = CliRunner().invoke(
        main,
        [
            "sweep",
            str(case),
            "-p",
            "material.EA=2e7,3e7",
            "--case",
            "ULS",
            "-o",
            str(out),
            "-j",
            "1",
        ],
    )
    assert r.exit_code == 0, r.output
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    for row in rows:
        h5 = tmp_path / f"r{row['material.EA']}.h5"
        args = ["run", str(case), "--case", "ULS", "-o", str(h5), "--set"]
        r = CliRunner().invoke(main, [*args, f"material.EA={row['material.EA']}"])
        assert r.exit_code == 0, r.output
        with h5py.File(h5) as f:
            attrs = dict(f["cases/ULS"].attrs)
        assert float(row["max_displacement"]) == attrs["max_displacement"] > 0.01
        assert float(row["max_tension"]) == attrs["max_tension"]
    r = CliRunner().invoke(main, ["sweep", str(case), "-p", "material.EA=2e7", "--case", "SLS"])
    assert r.exit_code == 2 and "--case 'SLS': no [[load_case]]" in r.output
