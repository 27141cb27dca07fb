"""catenet report: its tables hold the result file's numbers (read here with h5py, as a
user's script would), per state, cable, support and node set; csv to the last digit;
html with its figures; a dynamic run's peaks; bad input exits 2 with one message."""

from __future__ import annotations

import base64
import csv
import re
import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main
from tests.conftest import CONFIGS

MAST = CONFIGS / "structures" / "mast_load_cases.toml"
GUYS = ("guy_windward", "guy_leeward", "guy_side_south", "guy_side_north")


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def mast(tmp_path_factory):
    """The bundled mast with its load cases, its guys' strand given a breaking load (the
    mast, a strut of its own material, none)."""
    d = tmp_path_factory.mktemp("mast")
    data = tomllib.loads(MAST.read_text())
    data["material"]["breaking_load"] = 150.0e3
    data["design"] = {"gamma_R": 1.0}
    case = d / "mast.toml"
    case.write_text(dumps_toml(data))
    out = d / "mast.h5"
    res = invoke("run", case, "-o", out, "-q")
    assert res.exit_code == 0, res.output
    return out


def file_states(path) -> dict:
    """Every state of a result file, read with h5py alone: name -> arrays and attrs."""
    out = {}
    with h5py.File(path) as h5:
        names = list(h5["mesh"].attrs["cable_names"])
        cable = h5["mesh/cable"][:]
        fixed = h5["mesh/fixed"][:]
        nodes = h5["mesh/nodes"][:]
        groups = {"base state": h5["result"]}
        order = [n.decode() if isinstance(n, bytes) else n for n in h5["envelope"].attrs["cases"]]
        groups.update({n: h5["cases"][n] for n in order})
        for name, g in groups.items():
            out[name] = {k: g[k][()] for k in ("x", "tension", "reaction", "utilisation")}
            out[name]["attrs"] = dict(g.attrs)
        env = {k: h5["envelope"][k][()] for k in h5["envelope"]}
    return {
        "states": out,
        "cables": names,
        "cable": cable,
        "fixed": fixed,
        "nodes": nodes,
        "env": env,
        "order": order,
    }


def sections(md: str) -> dict[str, str]:
    """The report's sections by heading (without "load case " / "combination ")."""
    parts = re.split(r"^## ", md, flags=re.M)[1:]
    out = {}
    for p in parts:
        head, _, body = p.partition("\n")
        out[re.sub(r"^(load case|combination) ", "", head)] = body
    return out


def table(body: str, title: str) -> list[list[str]]:
    """The rows of the Markdown table under ``#### title`` (the header first)."""
    block = body.split(f"#### {title}\n", 1)[1].lstrip("\n").split("\n\n", 1)[0]
    rows = [r for r in block.splitlines() if r.startswith("|") and not r.startswith("|---")]
    return [[c.strip() for c in re.split(r"(?<!\\)\|", r)[1:-1]] for r in rows]


def g6(v) -> str:
    return "n/a" if np.isnan(v) else f"{v:.6g}"


def test_markdown_report_holds_the_files_numbers_for_every_state(mast, tmp_path):
    res = invoke("report", mast, "-o", tmp_path / "mast.md")
    assert res.exit_code == 0, res.output
    assert res.output.strip() == str(tmp_path / "mast.md")
    md = (tmp_path / "mast.md").read_text()
    f = file_states(mast)
    secs = sections(md)
    assert list(secs) == ["base state", *f["order"], "envelope"]
    for name, s in f["states"].items():
        body = secs[name]
        rows = {r[0]: r for r in table(body, "Cables")[1:]}
        assert list(rows) == f["cables"]
        for k, cname in enumerate(f["cables"]):
            e = np.flatnonzero(f["cable"] == k)
            t, u = s["tension"][e], s["utilisation"][e]
            row = rows[cname]
            assert row[2] == g6(t.max()) and int(row[3]) in e  # its edge: the largest
            assert s["tension"][int(row[3])] == pytest.approx(t.max(), rel=1e-12)
            assert row[4] == g6(t.min())
            assert row[6] == g6(np.nan if np.isnan(u).all() else np.nanmax(u))
        assert rows["mast"][6] == "0"  # a strut in compression: no tension to resist
        reactions = {r[0]: r for r in table(body, "Support reactions")[1:]}
        anchors = s["reaction"][[2, 3, 4, 5]].sum(axis=0)
        assert reactions["anchors"][2:5] == [g6(c) for c in anchors]
        # the foot is a set of node 0 alone: one row, not the set's and then the node's
        assert reactions["foot"][1] == "1" and "node 0 (foot)" not in reactions
        assert reactions["foot"][5] == g6(np.linalg.norm(s["reaction"][0]))
        assert reactions["node 2 (anchors)"][5] == g6(np.linalg.norm(s["reaction"][2]))
        u = np.linalg.norm(s["x"] - f["nodes"], axis=1)
        u[f["fixed"]] = -1
        disp = table(body, "Displacements")[1]
        # the largest, its node the first within round-off of it (the mast's symmetric
        # guys tie to 1e-14: which is larger by the last bits depends on the factorisation)
        tied = np.flatnonzero(u >= u.max() * (1.0 - 1e-12))
        assert disp[:3] == ["all free nodes", g6(u.max()), str(tied[0])]
        balance = {r[0]: r for r in table(body, "Loads against reactions and contact")[1:]}
        applied = [s["attrs"][f"applied_resultant_{c}"] for c in "xyz"]
        assert balance["applied loads"][1:] == [g6(c) for c in applied]
        assert f"- **stability**: {s['attrs']['stability']}" in body
        assert "- **warnings**: none" in body
    env = {r[0]: r for r in table(secs["envelope"], "Cables over the cases")[1:]}
    e = np.flatnonzero(f["cable"] == f["cables"].index("guy_windward"))
    k = e[np.argmax(f["env"]["utilisation_max"][e])]
    assert env["guy_windward"][7:10] == [
        g6(f["env"]["utilisation_max"][k]),
        str(k),
        f["order"][f["env"]["utilisation_max_case"][k]],
    ]


def test_csv_report_is_one_table_per_file_to_the_last_digit(mast, tmp_path):
    res = invoke("report", mast, "--format", "csv", "-o", tmp_path / "tables")
    assert res.exit_code == 0, res.output
    f = file_states(mast)
    with open(tmp_path / "tables" / "cables.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["state"] for r in rows} == set(f["states"])
    for r in rows:
        s = f["states"][r["state"]]
        e = np.flatnonzero(f["cable"] == f["cables"].index(r["cable"]))
        assert float(r["max tension [N]"]) == s["tension"][e].max()  # exactly: repr
        assert float(r["least tension [N]"]) == s["tension"][e].min()
        u = s["utilisation"][e]
        assert float(r["max utilisation [-]"]) == np.nanmax(u)
    with open(tmp_path / "tables" / "verdicts.csv", newline="") as fh:
        verdicts = list(csv.DictReader(fh))
    assert [v["state"] for v in verdicts] == ["base state", *f["order"], "envelope"]


def test_csv_report_opens_in_pandas(mast, tmp_path):
    import pandas  # the test extras install it: the check never skips

    assert invoke("report", mast, "--format", "csv", "-o", tmp_path / "t").exit_code == 0
    frame = pandas.read_csv(tmp_path / "t" / "supports.csv")
    assert {"state", "kind", "support", "Rx [N]", "|R| [N]"} <= set(frame.columns)
    cables = pandas.read_csv(tmp_path / "t" / "cables.csv")
    assert cables["max utilisation [-]"].dtype.kind == "f"


def test_xlsx_report_is_the_csv_tables_in_one_workbook(mast, tmp_path):
    """--format xlsx (or -o NAME.xlsx): a sheet per CSV file, the same cells, numbers as
    numbers to the 15 digits a workbook keeps (pandas reads them as floats); -o -
    refused (a workbook is no text)."""
    import openpyxl
    import pandas

    assert invoke("report", mast, "--format", "csv", "-o", tmp_path / "t").exit_code == 0
    res = invoke("report", mast, "-o", tmp_path / "mast.xlsx")
    assert res.exit_code == 0, res.output
    book = openpyxl.load_workbook(tmp_path / "mast.xlsx")
    assert sorted(book.sheetnames) == sorted(p.stem for p in (tmp_path / "t").glob("*.csv"))
    for name in book.sheetnames:
        with open(tmp_path / "t" / f"{name}.csv", newline="") as fh:
            rows = list(csv.reader(fh))
        cells = [
            ["" if v is None else v for v in r] for r in book[name].iter_rows(values_only=True)
        ]
        assert len(cells) == len(rows), name
        for got, want in zip(cells, rows, strict=True):
            for g, w in zip(got, want, strict=True):
                if isinstance(g, (int, float)) and not isinstance(g, bool):  # 16 digits kept
                    assert g == pytest.approx(float(w), rel=1e-15, abs=0.0), (name, g, w)
                else:
                    assert str(g) == w, (name, g, w)
    cables = pandas.read_excel(tmp_path / "mast.xlsx", sheet_name="cables")
    assert cables["max tension [N]"].dtype.kind == "f"
    refused = invoke("report", mast, "--format", "xlsx", "-o", "-")
    assert refused.exit_code == 2 and "give a file (.xlsx)" in refused.output


def test_html_report_embeds_its_figures(mast, tmp_path):
    res = invoke("report", mast, "-o", tmp_path / "mast.html")
    assert res.exit_code == 0, res.output
    page = (tmp_path / "mast.html").read_text()
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) == 1 + 6  # the cables' bars, then the net of each state
    assert all(base64.b64decode(i)[:8] == b"\x89PNG\r\n\x1a\n" for i in images)
    assert "<h2>combination ULS_diagonal</h2>" in page and "<th>max utilisation [-]</th>" in page


def test_markdown_to_standard_output(mast):
    res = invoke("report", mast, "-o", "-")
    assert res.exit_code == 0 and res.output.startswith("# guyed mast")


def test_a_load_cases_warnings_name_it_in_the_log_file_and_report(tmp_path, caplog):
    """A wind that slackens the leeward guy, its path followed through the collapse: the
    solver's warnings in that case (the collapse followed, nodes left on slack edges at
    its end) begin with its name, in the log, in /cases/<name> and in the report. (A
    path that stops at the collapse warns of no state it did not keep.)"""
    data = tomllib.loads(MAST.read_text())
    data["load_case"] = [{"name": "storm", "point": [{"node": "top", "force": [40e3, 0, 0]}]}]
    data.pop("combination")
    data.setdefault("solver", {})["post_collapse"] = True
    case = tmp_path / "storm.toml"
    case.write_text(dumps_toml(data))
    out = tmp_path / "storm.h5"
    res = CliRunner().invoke(main, ["run", str(case), "-o", str(out), "-q"])
    assert "warning:" not in res.stderr  # -q: errors only, yet the file keeps the warnings
    with h5py.File(out) as h5:
        kept = h5["cases/storm"].attrs["warnings"].split("\n")
        assert h5["result"].attrs["warnings"] == ""
    assert kept and all(w.startswith("load case storm: ") for w in kept)
    assert any("hang on slack edges only" in w for w in kept)  # a warning, not the error
    md = invoke("report", out, "-o", "-").output
    body = sections(md)["storm"]
    assert f"- **warnings** ({len(kept)}):" in body
    assert all(w in body for w in kept)


def test_dynamic_run_reports_peaks_with_their_times(tmp_path):
    case = tmp_path / "swing.toml"
    case.write_text(
        """
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [4.0, 0.0, 0.0]
length = 4.4
nodes = 9
[material]
EA = 2.0e5
radius = 0.005
density = 7800.0
breaking_load = 4.0e3
[load]
gravity = [0.0, 0.0, -9.81]
[solver]
method = "dynamic"
dt = 0.01
damping = 0.5
t_end = 0.6
"""
    )
    out = tmp_path / "swing.h5"
    assert invoke("run", case, "-o", out, "-q").exit_code == 0
    md = invoke("report", out, "-o", "-").output
    row = table(sections(md)["base state"], "Cables")
    assert row[0][-3:] == ["peak tension [N]", "peak tension t [s]", "peak utilisation [-]"]
    with h5py.File(out) as h5:
        peak = h5["result/peak_tension"][:]
        when = h5["result/peak_tension_time"][:]
        pu = h5["result/peak_utilisation"][:]
    k = int(np.argmax(peak))
    assert row[1][0] == "cable" and row[1][-3:] == [g6(peak[k]), g6(when[k]), g6(pu.max())]
    assert pu.max() == pytest.approx(peak[k] * 1.5 / 4.0e3, rel=1e-12)
    # a file that lost a peak's times (or its peak displacements) is reported with n/a
    # there, the rest as before (a fuzzed file once gave a KeyError)
    with h5py.File(out, "a") as h5:
        del h5["result/peak_displacement_time"]
        del h5["result/peak_tension_time"]
    md = invoke("report", out, "-o", "-").output
    row = table(sections(md)["base state"], "Cables")
    assert row[1][-3:] == [g6(peak[k]), "n/a", g6(pu.max())]
    shown = table(sections(md)["base state"], "Displacements")
    assert shown[1][-1] == "n/a" and shown[1][-3] != "n/a"
    with h5py.File(out, "a") as h5:
        del h5["result/peak_displacement"]
    shown = table(sections(invoke("report", out, "-o", "-").output)["base state"], "Displacements")
    assert shown[1][-3:] == ["n/a", "n/a", "n/a"] and len(shown[1]) == len(shown[0])


def test_square_net_cables_by_name(tmp_path):
    case = tmp_path / "net.toml"
    case.write_text(
        """
[geometry]
kind = "square_net"
n = 4
alpha = 0.3
size = 1.0
edge_length = 0.1
[material]
EA = 1000.0
[load]
pressure = 50.0
"""
    )
    out = tmp_path / "net.h5"
    assert invoke("run", case, "-o", out, "-q").exit_code == 0
    md = invoke("report", out, "-o", "-").output
    rows = table(sections(md)["base state"], "Cables")[1:]
    assert [r[0] for r in rows] == ["A0", "A1", "B0", "B1"]
    with h5py.File(out) as h5:
        t = h5["result/tension"][:]
    assert sum(int(r[1]) for r in rows) == len(t)
    assert max(float(r[2]) for r in rows) == pytest.approx(t.max(), rel=1e-5)


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["missing.h5"], "missing.h5: no such file or directory"),
        (["notes.txt"], "not an HDF5 file"),
        (["other.h5"], "not a catenet result file"),
        (["MAST", "--format", "pdf"], "--format 'pdf': must be one of md, csv, html"),
        (["MAST", "--format", "csv", "-o", "t.csv"], "give a directory"),
        (["MAST", "-o", "r.html", "--format", "md"], "its suffix says html"),
    ],
)
def test_bad_input_exits_2_with_one_message(args, says, mast, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.txt").write_text("not a result file\n")
    with h5py.File(tmp_path / "other.h5", "w") as h5:
        h5["data"] = [1, 2, 3]
    res = invoke("report", *[str(mast) if a == "MAST" else a for a in args])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("catenet: error: ") and says in lines[0]
