"""Target searches from starts far off, and the ends of searches that find no answer
(models a newcomer wrote from the docs):

- a stay under its own weight by the force density method, its mid node asked 1.8 m
  down, from a force density a thousand times too small: the search crawled (its
  damping kept from the first, steep Jacobian) and ended at max_iter, exit 1, the mid
  node kilometres down; it meets the target now at the hand's force density;
- a target on the tension of a ``kind = "cable"`` stay crashed (an internal error):
  ``cable = "*"`` names its one cable, another name is refused naming the key; its one
  force density is ``vary = "cables"`` (a force density per edge ran its inner edges to
  nothing, a kink of 1e-7 m edges);
- an elastic stay asked to hang above its supports ran its rest lengths to nothing and
  ended at max_iter (the written case said it reproduced a design): it stops where the
  strains leave any cable's, exit 1, and the written case says it is no design."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main

EA, SPAN, EDGES = 5e4, 60.0, 12  # kN and m: a steel stay of 15 mm radius


def stay(units: str, q0: float, **more) -> dict:
    """The stay of 12 edges over 60 m (5e4 kN), its own weight (steel, 15 mm), its mid
    node's depth the target, by the force density method from ``q0``; in kN-m or N-mm."""
    k = 1000.0 if units == "N-mm" else 1.0  # mm per m
    case = {
        "title": "a stay's sag by its force density",
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": [[k * SPAN * i / EDGES, 0.0, 0.0] for i in range(EDGES + 1)],
            "fixed": [0, EDGES],
            "sets": {"mid": [EDGES // 2]},
            "cable": [{"name": "stay", "nodes": list(range(EDGES + 1))}],
        },
        "material": {
            "EA": EA * 1000.0 if units == "N-mm" else EA,
            "density": 7.85e-9 if units == "N-mm" else 7.85,
            "radius": 15.0 if units == "N-mm" else 0.015,
        },
        "load": {"gravity": [0.0, 0.0, -9.81 * k]},
        "formfind": {"force_density": q0, "vary": "cables"},
        "target": [{"node": "mid", "z": -1.8 * k}],
    }
    case.update(more)
    return case


def hand_force_density(sag: float) -> float:
    """The force density [kN/m] whose discrete stay sags ``sag`` at mid-span under its own
    weight lumped from its rest lengths l0 = L / (1 + q L / EA) (fixed point, bisection)."""
    w = 7.85 * 9.81 * np.pi * 0.015**2  # kN/m
    a = SPAN / EDGES

    def depth(q: float) -> float:
        z = np.zeros(EDGES + 1)
        K = 2 * q * np.eye(EDGES - 1) - q * np.eye(EDGES - 1, k=1) - q * np.eye(EDGES - 1, k=-1)
        for _ in range(500):
            length = np.hypot(a, np.diff(z))
            rest = length / (1 + q * length / EA)
            weight = np.zeros(EDGES + 1)
            weight[:-1] += w * rest / 2
            weight[1:] += w * rest / 2
            new = np.zeros(EDGES + 1)
            new[1:-1] = np.linalg.solve(K, -weight[1:-1])
            if np.abs(new - z).max() < 1e-14:
                break
            z = new
        return -new[EDGES // 2]

    lo, hi = 1.0, 1e3
    for _ in range(200):
        mid = np.sqrt(lo * hi)
        lo, hi = (lo, mid) if depth(mid) < sag else (mid, hi)
    return float(np.sqrt(lo * hi))


def run(tmp_path, case: dict, *args: str):
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    out = tmp_path / "out.h5"
    return CliRunner().invoke(main, ["formfind", str(path), "-o", str(out), *args]), out


@pytest.mark.parametrize(("units", "q0"), [("kN-m", 0.002), ("N-mm", 0.001), ("N-mm", 0.01)])
def test_a_weighing_stay_found_from_a_force_density_far_too_small(tmp_path, units, q0):
    """From q0 far below the answer (the stay first hangs kilometres deep) the search
    meets the sag at the hand's force density (2.7243 kN/m, as 2.7243 N/mm)."""
    import h5py

    r, out = run(tmp_path, stay(units, q0))
    assert r.exit_code == 0, r.output
    assert "met:" in r.output
    with h5py.File(out) as f:
        q = f["result/force_density"][()]
    assert np.allclose(q, hand_force_density(1.8), rtol=1e-6)


@pytest.mark.parametrize(
    "formfind",
    [{"method": "elastic"}, {"force_density": 1000.0, "vary": "cables"}],
    ids=["elastic", "force densities"],
)
def test_a_tension_target_on_a_single_cable_case(tmp_path, formfind):
    """A guy given as ``kind = "cable"`` with every edge's tension asked within [21, 24]
    kN: ``cable = "*"`` is its one cable, met by its one rest-length factor or its one
    force density (``vary = "cables"``, refused before on a net without named cables);
    a name is refused, exit 2."""
    case = {
        "title": "a guy's tension",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [30, 0, 40], "nodes": 11},
        "material": {"EA": 5e7, "density": 7850.0, "radius": 0.015},
        "load": {"gravity": [0, 0, -9.81]},
        "formfind": formfind,
        "target": [{"cable": "*", "tension": [21000.0, 24000.0]}],
    }
    r, _ = run(tmp_path, case)
    assert r.exit_code == 0, r.output
    assert "target[0]    cable '*' tension" in r.output and "met)" in r.output
    assert "1 rest-length factors" in r.output or "1 force densities" in r.output
    case["target"][0]["cable"] = "guy"
    r, _ = run(tmp_path, case)
    assert r.exit_code == 2, r.output
    assert "target[0].cable = 'guy': this net has no named cables" in r.output
    assert 'cable = "*"' in r.output and "internal error" not in r.output


def test_an_elastic_stay_asked_above_its_supports_stops_as_no_cables_state(tmp_path):
    """Its mid node asked 1 m above the supports: the rest lengths shrink without end.
    The search stops where the strains leave any cable's (ten times the law's range),
    exit 1 with that message, in a few iterations; the written case is no design."""
    case = {
        "title": "a stay asked to hang above its supports",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [60, 0, 0], "nodes": 13},
        "material": {"EA": 5e7, "density": 7850.0, "radius": 0.015},
        "load": {"gravity": [0, 0, -9.81]},
        "formfind": {"method": "elastic"},
        "target": [{"node": "midpoint", "z": 1.0}],
    }
    r, out = run(tmp_path, case)
    assert r.exit_code == 1, r.output
    assert "beyond 10 times its law's range" in r.output and "no cable reaches" in r.output
    assert "ran to strains no cable has" in r.output
    written = out.with_suffix(".toml").read_text()
    assert "found no answer" in written and "reproduces the shape" not in written
