"""A cable truss and a guyed mast with load cases, as a user writes them from the docs
(the truss of docs/howto/reports.md; the mast of docs/howto/guyed-mast.md given the load
cases and combinations that reports.md shows): `catenet report --format csv` gives per
load case and combination the cable tensions, the utilisations and the support reactions
that a hand-written h5py script reads from the result file, to the last digit; the
utilisation is EN 1993-1-11's rule worked by hand on the file's tensions."""

from __future__ import annotations

import csv
import re

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from tests.conftest import REPO

DOCS = REPO / "docs" / "howto"

# the guyed mast's load cases, written after reports.md: wind at the top, ice on the guys
MAST_CASES = """
[[load_case]]
name = "wind_x"
point = [{ node = "top", force = [10.0e3, 0, 0] }]      # N

[[load_case]]
name = "wind_y"
point = [{ node = "top", force = [0, 10.0e3, 0] }]

[[load_case]]
name = "ice"                                            # N per metre of each guy
line = [
    { cable = "windward", force = [0, 0, -40.0] },
    { cable = "leeward", force = [0, 0, -40.0] },
    { cable = "south", force = [0, 0, -40.0] },
    { cable = "north", force = [0, 0, -40.0] },
]

[[combination]]
name = "ULS_wind_x"
factors = { wind_x = 1.5, ice = 1.35 }

[[combination]]
name = "ULS_wind_y"
factors = { wind_y = 1.5 }
"""

MODELS = {
    "truss": {
        "page": "reports.md",
        "file": "truss.toml",
        "cables": ["carrier", "stabiliser"],
        "breaking": {"carrier": 1.1e6, "stabiliser": 6.0e5, "": 1.2e5},  # "": [material]'s
        "states": {"snow": "load_case", "uplift": "load_case", "ULS_snow": "combination"},
        "supports": {
            "anchors_upper": [0, 1],
            "anchors_lower": [2, 3],
            "node 0 (anchors_upper)": [0],
            "node 3 (anchors_lower)": [3],
            "all supports": [0, 1, 2, 3],
        },
    },
    "mast": {
        "page": "guyed-mast.md",
        "file": "mast.toml",
        "cables": ["mast", "windward", "leeward", "south", "north"],
        "breaking": {"": 3.0e5},  # the guys' strand; the mast, a strut, in compression
        "states": {"ice": "load_case", "ULS_wind_x": "combination", "ULS_wind_y": "combination"},
        "supports": {
            "foot": [0],  # a set of one node: its one row
            "anchors": [2, 3, 4, 5],
            "node 3 (anchors)": [3],
            "all supports": [0, 2, 3, 4, 5],
        },
    },
}


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def case_text(model: str) -> str:
    """The page's case file; the mast without its load at the top, with a breaking
    load and the load cases above."""
    m = MODELS[model]
    text = (DOCS / m["page"]).read_text(encoding="utf-8")
    found = re.search(rf"<!-- file: {m['file']} -->\n```toml\n(.*?)```", text, re.S)
    assert found is not None, f"docs/howto/{m['page']} lost its {m['file']}"
    case = found.group(1)
    if model == "mast":
        case = case[: case.index("[[load.point]]")]
        case = case.replace("EA = 2.0e7 ", "breaking_load = 3.0e5\nEA = 2.0e7 ")
        case += MAST_CASES
    return case


@pytest.fixture(scope="module", params=list(MODELS))
def model(request, tmp_path_factory):
    d = tmp_path_factory.mktemp(request.param)
    (d / "case.toml").write_text(case_text(request.param))
    res = invoke("run", d / "case.toml", "-o", d / "case.h5", "-q")
    assert res.exit_code == 0, res.output
    res = invoke("report", d / "case.h5", "--format", "csv", "-o", d / "tables")
    assert res.exit_code == 0, res.output
    return request.param, d


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def by_hand(path):
    """What a user's script reads: per state the tensions, utilisations, reactions."""
    with h5py.File(path) as h5:
        names = list(h5["mesh"].attrs["cable_names"])
        cable = h5["mesh/cable"][()]
        states = {"base state": h5["result"]}
        states.update({n: h5["cases"][n] for n in h5["envelope"].attrs["cases"]})
        kinds = {n: g.attrs.get("kind", "base") for n, g in states.items()}
        data = {
            n: {k: g[k][()] for k in ("tension", "utilisation", "reaction")}
            for n, g in states.items()
        }
    return names, cable, data, kinds


def test_every_case_and_combination_to_the_last_digit(model):
    name, d = model
    m = MODELS[name]
    names, cable, data, kinds = by_hand(d / "case.h5")
    assert names == m["cables"]
    assert {k: kinds[k] for k in m["states"]} == m["states"]
    cables = read_csv(d / "tables" / "cables.csv")
    seen = set()
    for row in cables:
        s = data[row["state"]]
        k = names.index(row["cable"]) if row["cable"] in names else -1
        e = np.flatnonzero(cable == k)
        assert float(row["max tension [N]"]) == s["tension"][e].max()
        assert float(row["least tension [N]"]) == s["tension"][e].min()
        assert float(row["max utilisation [-]"]) == np.nanmax(s["utilisation"][e])
        seen.add((row["state"], row["cable"]))
    rows_of = {c for _, c in seen}
    assert {(n, c) for n in data for c in rows_of} == seen and set(names) <= rows_of
    supports = {(r["state"], r["support"]): r for r in read_csv(d / "tables" / "supports.csv")}
    for state, s in data.items():
        r = s["reaction"]
        for support, nodes in m["supports"].items():
            row = supports[(state, support)]
            force = r[nodes].sum(axis=0)
            got = [float(row[f"R{c} [N]"]) for c in "xyz"]
            assert got == list(force) and float(row["|R| [N]"]) == np.linalg.norm(force)


def test_utilisation_is_the_documented_rule_on_the_files_tensions(model):
    """F_Ed / F_Rd = T / (F_min / (1.5 gamma_R)) with the defaults (gamma_R = 1.00, k_e =
    1, gamma_F = 1) and the breaking loads the case gives each cable."""
    name, d = model
    m = MODELS[name]
    names, cable, data, _ = by_hand(d / "case.h5")
    f_min = np.full(len(cable), m["breaking"][""])
    for k, c in enumerate(names):
        f_min[cable == k] = m["breaking"].get(c, m["breaking"][""])
    for s in data.values():
        want = np.maximum(s["tension"], 0.0) / (f_min / 1.5)
        np.testing.assert_allclose(s["utilisation"], want, rtol=1e-14, atol=0)
    if name == "truss":  # the page's number: the carrier governs under ULS_snow
        carrier = np.flatnonzero(cable == names.index("carrier"))
        assert data["ULS_snow"]["utilisation"][carrier].max() == pytest.approx(0.509, abs=5e-4)
    else:  # the mast, a strut in compression, has nothing to resist; the windward guy governs
        mast = np.flatnonzero(cable == names.index("mast"))
        assert all(s["tension"][mast].max() < 0 for s in data.values())
        u = data["ULS_wind_x"]["utilisation"]
        assert cable[np.nanargmax(u)] == names.index("windward")
