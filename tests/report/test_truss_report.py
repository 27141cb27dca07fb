"""The cable truss of docs/howto/reports.md, as a user writes it from that page: `catenet
report --format csv` gives per load case and combination the cable tensions, the
utilisations and the support reactions that a hand-written h5py script reads from the
result file, to the last digit; the utilisation is EN 1993-1-11's rule worked by hand on
the file's tensions with the page's breaking loads."""

from __future__ import annotations

import csv
import re

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from tests.conftest import REPO

PAGE = REPO / "docs" / "howto" / "reports.md"
BREAKING = {"carrier": 1.1e6, "stabiliser": 6.0e5}  # the page's, [N]
TIES = 1.2e5  # [material]'s, the ties' rods


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def truss(tmp_path_factory):
    text = PAGE.read_text(encoding="utf-8")
    case = re.search(r"<!-- file: truss.toml -->\n```toml\n(.*?)```", text, re.S)
    assert case is not None, "docs/howto/reports.md lost its truss"
    d = tmp_path_factory.mktemp("truss")
    (d / "truss.toml").write_text(case.group(1))
    res = invoke("run", d / "truss.toml", "-o", d / "truss.h5", "-q")
    assert res.exit_code == 0, res.output
    res = invoke("report", d / "truss.h5", "--format", "csv", "-o", d / "tables")
    assert res.exit_code == 0, res.output
    return d


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


def test_every_case_and_combination_to_the_last_digit(truss):
    names, cable, data, kinds = by_hand(truss / "truss.h5")
    assert names == ["carrier", "stabiliser"]
    assert [kinds[n] for n in ("snow", "uplift", "ULS_snow", "ULS_uplift")] == [
        "load_case",
        "load_case",
        "combination",
        "combination",
    ]
    cables = read_csv(truss / "tables" / "cables.csv")
    seen = set()
    for row in cables:
        s = data[row["state"]]
        k = names.index(row["cable"]) if row["cable"] in names else -1
        e = np.flatnonzero(cable == k)
        assert float(row["max tension [N]"]) == s["tension"][e].max()
        assert float(row["least tension [N]"]) == s["tension"][e].min()
        assert float(row["max utilisation [-]"]) == np.nanmax(s["utilisation"][e])
        seen.add((row["state"], row["cable"]))
    assert {(n, c) for n in data for c in (*names, "other edges")} == seen
    supports = {(r["state"], r["support"]): r for r in read_csv(truss / "tables" / "supports.csv")}
    for name, s in data.items():
        r = s["reaction"]
        for support, nodes in (
            ("anchors_upper", [0, 1]),
            ("anchors_lower", [2, 3]),
            ("node 0 (anchors_upper)", [0]),
            ("node 3 (anchors_lower)", [3]),
            ("all supports", [0, 1, 2, 3]),
        ):
            row = supports[(name, support)]
            force = r[nodes].sum(axis=0)
            got = [float(row[f"R{c} [N]"]) for c in "xyz"]
            assert got == list(force) and float(row["|R| [N]"]) == np.linalg.norm(force)


def test_utilisation_is_the_documented_rule_on_the_files_tensions(truss):
    """F_Ed / F_Rd = T / (F_min / (1.5 gamma_R)) with the defaults (gamma_R = 1.00, k_e =
    1, gamma_F = 1): the page's 1.1 MN carrier, 600 kN stabiliser, 120 kN ties."""
    names, cable, data, _ = by_hand(truss / "truss.h5")
    f_min = np.where(cable == 0, BREAKING["carrier"], TIES)
    f_min = np.where(cable == 1, BREAKING["stabiliser"], f_min)
    for s in data.values():
        want = np.maximum(s["tension"], 0.0) / (f_min / 1.5)
        np.testing.assert_allclose(s["utilisation"], want, rtol=1e-14, atol=0)
    carrier = np.flatnonzero(cable == names.index("carrier"))
    # the page's number: the carrier governs under ULS_snow
    assert data["ULS_snow"]["utilisation"][carrier].max() == pytest.approx(0.509, abs=5e-4)
