"""``catenet validate`` and ``catenet plot`` from the command line (click's CliRunner)."""

from __future__ import annotations

import csv
import json
import math
import sys
import types

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.validate.table import Row, format_table, observed_order


def invoke(*args):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


# ---------------------------------------------------------------- validate


def test_validate_passes_and_writes_csv(tmp_path):
    out = tmp_path / "table.csv"
    res = invoke("validate", "-o", str(out))
    assert res.exit_code == 0, res.output
    header = res.output.splitlines()[0].split()
    assert header == [
        "case",
        "quantity",
        "N",
        "catenet",
        "analytic",
        "rel.",
        "error",
        "order",
        "tol",
        "ok",
    ]
    assert "all " in res.output and "checks passed" in res.output
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == [
        "case",
        "quantity",
        "resolution",
        "catenet",
        "analytic",
        "rel_error",
        "order",
        "tolerance",
        "pass",
    ]
    assert len(rows) >= 40
    assert {r["pass"] for r in rows} <= {"True", ""}
    midpoint = [r for r in rows if r["case"].startswith("midpoint")]
    assert midpoint and all(float(r["rel_error"]) <= 1e-9 for r in midpoint)
    assert all(int(r["resolution"]) % 2 == 1 for r in midpoint)
    elastic = [r for r in rows if r["quantity"].endswith("elastic")]
    assert elastic and all(1.8 <= float(r["order"]) <= 2.2 for r in elastic)
    eq15 = [r for r in rows if "Eq.15" in r["quantity"]]
    assert len(eq15) == 3 and all(r["pass"] == "" and float(r["rel_error"]) > 0 for r in eq15)
    oc3 = [r for r in rows if r["case"].startswith("OC3-Hywind") and r["pass"] == "True"]
    assert [r["quantity"].split()[0] for r in oc3] == ["K11", "K33", "K66"]


def test_validate_quiet_and_bad_output(tmp_path):
    res = invoke("validate", "-q", "-o", str(tmp_path / "missing" / "t.csv"))
    assert res.exit_code == 2
    assert "directory does not exist" in res.output


def test_table_helpers():
    assert observed_order([0.1, 0.05, 0.025], [1e-2, 2.5e-3, 6.25e-4]) == pytest.approx(2.0)
    assert math.isnan(observed_order([0.1, 0.05], [1e-2, 0.0]))
    rows = [
        Row("a", "q", 3, 1.0, 1.0, 0.0, tolerance=1e-9, passed=True),
        Row("bb", "quantity", 161, 2.0, 1.0, 1.0, order=2.0, tolerance=1e-3, passed=False),
        Row("c", "q", 5, 1.0, 2.0, 0.5),
    ]
    lines = format_table(rows).splitlines()
    assert len({len(line) for line in lines[:2]}) == 1  # header and rule line up
    assert lines[2].endswith("yes") and lines[3].endswith("NO") and lines[4].endswith("info")
    assert "rel. error 1 > tol 0.001" in rows[1].failure()


# ---------------------------------------------------------------- plot


def write_result(path, *, frames=1, method="static", with_result=True):
    """A small result file in the contract §5 layout: a 21-node cable sagging into a
    parabola, every frame a little lower."""
    n = 21
    s = np.linspace(-0.5, 0.5, n)
    nodes = np.column_stack([s, np.zeros(n), np.zeros(n)])
    edges = np.column_stack([np.arange(n - 1), np.arange(1, n)]).astype(np.int64)
    rest = np.full(n - 1, 1.0 / (n - 1))
    fixed = np.zeros(n, bool)
    fixed[[0, -1]] = True
    traj = []
    for k in range(1, frames + 1):
        x = nodes.copy()
        x[:, 0] *= 0.9
        x[:, 2] = -0.2 * (k / frames) * (1 - 4 * s**2)
        traj.append(x)
    traj = np.array(traj)
    length = np.linalg.norm(np.diff(traj, axis=1), axis=2)
    tension = np.maximum(3141.6 * (length / rest - 1), 0.0)
    with h5py.File(path, "w") as h5:
        h5.attrs["catenet_version"] = "test"
        h5.attrs["case"] = f'title = "plot test"\n[solver]\nmethod = "{method}"\n'
        h5["/mesh/nodes"] = nodes
        h5["/mesh/edges"] = edges
        h5["/mesh/rest_length"] = rest
        h5["/mesh/EA"] = np.full(n - 1, 3141.6)
        h5["/mesh/fixed"] = fixed
        h5["/trajectory/time"] = np.linspace(0.1, 1.0, frames)
        h5["/trajectory/x"] = traj
        h5["/trajectory/tension"] = tension
        if with_result:
            h5["/result/x"] = traj[-1]
            h5["/result/tension"] = tension[-1]
            h5["/result/reaction"] = np.zeros((n, 3))
            h5["/result"].attrs["converged"] = True
    return path


MAGIC = {".png": b"\x89PNG", ".pdf": b"%PDF", ".svg": b"<svg"}


@pytest.mark.parametrize(
    "suffix, frames, method",
    [(".png", 1, "static"), (".svg", 30, "dynamic"), (".pdf", 4, "static")],
)
def test_plot_writes_a_figure(tmp_path, suffix, frames, method):
    h5 = write_result(tmp_path / "out.h5", frames=frames, method=method)
    fig = tmp_path / f"fig{suffix}"
    res = invoke("plot", str(h5), "-o", str(fig))
    assert res.exit_code == 0, res.output
    assert res.output.strip() == str(fig)
    data = fig.read_bytes()
    assert len(data) > 1000 and MAGIC[suffix] in data[:2000]


def test_plot_default_output_and_probe(tmp_path):
    from catenet.output import read_result

    h5 = write_result(tmp_path / "run.h5", frames=5, method="dynamic", with_result=False)
    res = invoke("plot", str(h5))
    assert res.exit_code == 0, res.output
    assert (tmp_path / "run.png").stat().st_size > 1000
    r = read_result(h5)
    assert r.from_trajectory and r.probe == 10  # the midpoint, from the mesh
    assert r.delta == pytest.approx(0.2)
    np.testing.assert_allclose(r.series_delta, 0.2 * np.arange(1, 6) / 5)


@pytest.mark.parametrize("kind", ["missing", "text", "empty_h5", "bad_shape"])
def test_plot_bad_input_exits_2(tmp_path, kind):
    path = tmp_path / "bad.h5"
    if kind == "text":
        path.write_text("not hdf5\n")
    elif kind == "empty_h5":
        with h5py.File(path, "w") as h5:
            h5["/mesh/nodes"] = np.zeros((3, 3))
    elif kind == "bad_shape":
        write_result(path)
        with h5py.File(path, "a") as h5:
            del h5["/result/x"]
            h5["/result/x"] = np.zeros((4, 2))
    res = invoke("plot", str(path))
    assert res.exit_code == 2
    assert res.output.startswith("catenet: error:") and "Traceback" not in res.output


def test_plot_bad_format_exits_2(tmp_path):
    h5 = write_result(tmp_path / "out.h5")
    res = invoke("plot", str(h5), "-o", str(tmp_path / "fig.jpg"))
    assert res.exit_code == 2 and ".png, .svg, .pdf" in res.output


def test_plot_directory_goes_to_the_sweep_figures(tmp_path, monkeypatch):
    calls = []

    def plot_sweep(directory, out):
        calls.append((directory, out))
        return [tmp_path / "a.png", tmp_path / "b.png"]

    monkeypatch.setitem(sys.modules, "catenet.study", types.SimpleNamespace(plot_sweep=plot_sweep))
    # a sweep of the paper's square net over n and alpha (its figures and report), no rows yet
    params = [["geometry.n", [10]], ["geometry.alpha", [0.0]]]
    header = {"catenet_sweep": 1, "params": params, "columns": ["geometry.n", "geometry.alpha"]}
    header["base"] = {"geometry": {"kind": "square_net"}}
    (tmp_path / "results.jsonl").write_text(json.dumps(header) + "\n")
    res = invoke("plot", str(tmp_path))
    assert res.exit_code == 0, res.output
    assert calls == [(tmp_path, None)]
    assert res.output.split() == [str(tmp_path / "a.png"), str(tmp_path / "b.png")]
