"""Unit slips and implausible states (``catenet.run.advice.unit_slips``, ``implausible``).

A cable truss written in SI with one number in the wrong unit (E = 160 for 160 GPa, an
area in mm^2, a kN-m case given N): the run names the key, the value, the range of real
cable materials and the value it most likely meant; a state beyond the material law's
range (or moved beyond the structure's size) warns, a load case's naming the case and
the unit slip, and beyond ten times either the run or the case fails (exit 1).
The bundled cases give no such warning.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from catenet.case import build, load_case, parse_case
from catenet.cli import main
from catenet.run.advice import unit_slips

ROOT = Path(__file__).resolve().parents[2]


def truss(**material) -> dict:
    """A 20 m prestressed steel cable (E 160 GPa, 10 mm radius) under its weight, with a
    snow and a wind load case at its midpoint."""
    return {
        "title": "stay",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [20, 0, 0], "nodes": 11},
        "material": {"E": 160e9, "radius": 0.01, "density": 7850.0, "prestress": 1e3, **material},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "load_case": [
            {"name": "snow", "point": [{"node": "midpoint", "force": [0, 0, -500.0]}]},
            {"name": "wind", "point": [{"node": "midpoint", "force": [0, 300.0, 0]}]},
        ],
    }


def run(tmp_path, case: dict):
    tmp_path.mkdir(parents=True, exist_ok=True)
    path = tmp_path / "case.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    return CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])


def test_a_modulus_in_the_wrong_unit_fails_the_base_state_naming_it(tmp_path):
    """E = 160 for 160 GPa: the base state (self-weight, prestress) is strained beyond
    10x the law's range already: the run fails there (exit 1) naming the slip, and no
    load case is solved from a state no cable reaches."""
    r = run(tmp_path, truss(E=160.0))
    assert r.exit_code == 1, r.output
    head = "check units: material.E = 160 Pa (SI) is far below real cables"
    assert head in r.output and "did you mean 1.6e+11 (160 GPa)?" in r.output
    assert "catenet: error: the result is implausible (check units and supports)" in r.output
    assert "the base state is implausible: no load case is solved" in r.output
    (error,) = [line for line in r.output.splitlines() if line.startswith("catenet: error")]
    assert "did you mean 1.6e+11" in error  # the likely cause, in the error itself


def test_a_slip_in_n_mm_gives_the_real_range_in_si(tmp_path):
    """In N-mm the written E is named in MPa, the real cables' range in SI stays in Pa
    (the units' relabelling read it as MPa: a range that held the value it refused)."""
    case = truss(E=7e10, radius=10.0, density=7.85e-9)
    case["units"] = "N-mm"
    case["geometry"]["end"] = [20000, 0, 0]
    case["load"]["gravity"] = [0.0, 0.0, -9810.0]
    r = run(tmp_path, case)
    assert "check units: material.E = 7e+10 MPa (N-mm) is far above real cables" in r.output
    assert "(1e+06 to 3e+11 in SI units of Pa); did you mean 70000 (70 GPa)?" in r.output


def test_a_load_case_in_the_wrong_unit_fails_naming_itself(tmp_path):
    """A plausible base state and a snow load a million times too large (N-mm's N given
    where the case is in MN, say): that case fails (exit 1) naming itself, the wind case
    is solved and stays quiet."""
    case = truss()
    case["load_case"][0]["point"][0]["force"] = [0, 0, -5e8]
    r = run(tmp_path, case)
    assert r.exit_code == 1, r.output
    assert "load case snow: strain" in r.output and "no: implausible" in r.output
    assert "load case wind: strain" not in r.output
    assert "load case snow failed" in r.output
    import h5py

    with h5py.File(tmp_path / "out.h5") as f:  # the file says so too (it said converged)
        snow, wind = f["cases/snow"].attrs, f["cases/wind"].attrs
        assert not snow["converged"] and snow["outcome"] == "failed"
        assert str(snow["message"]).startswith("implausible")
        assert wind["converged"]


def test_the_same_truss_in_the_right_unit_says_nothing(tmp_path):
    r = run(tmp_path, truss())
    assert r.exit_code == 0, r.output
    assert "check units" not in r.output and "beyond the material law" not in r.output


@pytest.mark.parametrize(
    "units, material, key, meant",
    [
        ("SI", {"radius": None, "area": 314.0}, "material.area = 314 m^2", "314 mm^2"),
        ("SI", {"density": 7.85}, "material.density = 7.85 kg/m^3", "7850 kg/m^3"),
        ("N-mm", {"E": 160e9}, "material.E = 1.6e+11 MPa (N-mm)", "160 GPa"),
        ("kN-m", {"E": 160e9}, "material.E = 1.6e+11 kPa (kN-m)", "160 GPa"),
    ],
)
def test_slips_in_each_unit_system_are_named_with_what_was_meant(units, material, key, meant):
    case = truss(**material)
    case["material"] = {k: v for k, v in case["material"].items() if v is not None}
    case["units"] = units
    case.pop("load_case")
    parsed = parse_case(case)
    slips = unit_slips(parsed, build(parsed).net)
    assert any(key in s and f"({meant})?" in s for s in slips), slips


def test_an_implausible_state_in_n_mm_is_named_in_mm_and_its_si_hints_stay_si(tmp_path):
    """The N-mm stay with its density in kg/m^3 (7850 t/mm^3 read as written): the error
    names the move and the size in mm (they read "1.65e+09 m, more than the structure's
    size 3000 m"), the hint for the density's SI value stays in kg/m^3; with gravity
    written as in SI (9.81), the hint says 9810 is 9.81 m/s^2 in SI (it read "9.81
    mm/s^2", the value the case had written)."""
    case = truss(E=160e3, radius=10.0, density=7850.0)
    case["units"] = "N-mm"
    case["geometry"]["end"] = [20000, 0, 0]
    case["load"]["gravity"] = [0.0, 0.0, -9810.0]
    case.pop("load_case")
    r = run(tmp_path / "density", case)
    assert r.exit_code == 1, r.output
    (error,) = [line for line in r.output.splitlines() if line.startswith("catenet: error")]
    moved = re.search(
        r"moves [0-9.e+-]+ (\S+), more than the structure's size [0-9.e+-]+ (\w+)", error
    )
    assert moved is not None and moved.groups() == ("mm", "mm"), error
    assert "(7850 kg/m^3)" in error
    case["material"]["density"] = 7.85e-9
    case["load"]["gravity"] = [0.0, 0.0, -9.81]
    r = run(tmp_path / "gravity", case)
    assert "did you mean 9810 (9.81 m/s^2 in SI)?" in r.output, r.output


@pytest.mark.parametrize(
    "units, gravity, slip",
    [
        ("N-mm", -9.81, "|load.gravity| = 9.81 mm/s^2 (N-mm)"),
        ("N-mm", -9810.0, ""),
        ("SI", -9810.0, "|load.gravity| = 9810 m/s^2 (SI)"),
        ("kN-m", -9.81, ""),
    ],
)
def test_gravity_in_the_wrong_length_unit_is_a_slip(units, gravity, slip):
    """Gravity has no default: a case in N-mm that writes -9.81 asks for 9.81 mm/s^2, a
    thousandth of the Earth's (the cable then hangs a thousand times too taut)."""
    case = truss()
    case["units"] = units
    case["load"] = {"gravity": [0.0, 0.0, gravity]}
    case.pop("load_case")
    parsed = parse_case(case)
    slips = [s for s in unit_slips(parsed, build(parsed).net) if "gravity" in s]
    if slip:
        assert len(slips) == 1 and slip in slips[0], slips
    else:
        assert slips == [], slips


@pytest.mark.parametrize(
    "units, pressure, slip",
    [
        ("SI", 0.8, "load.area[0].pressure = 0.8 Pa (SI) is far below real area loads"),
        ("kN-m", 800.0, "load.area[0].pressure = 800 kPa (kN-m) is far above real area loads"),
        ("N-mm", 500.0, "load.area[0].pressure = 500 MPa (N-mm) is far above real area loads"),
        ("SI", 800.0, ""),
        ("kN-m", 0.8, ""),
        ("N-mm", 8e-4, ""),
    ],
)
def test_an_area_load_in_the_wrong_unit_is_a_slip(units, pressure, slip):
    """Snow of 0.8 kN/m^2 written 0.8 in SI (185 N on a roof, no word), or 800 in kN-m (a
    strain of 0.74, then 'use a large-strain law'): a pressure far outside 1 Pa to 100
    kPa is named before the run, with what was likely meant."""
    from meshes import hypar_roof

    case = hypar_roof(half=6.0, rise=1.5, edge_length=0.6)
    case["units"] = units
    case["load"] = {"area": [{"pressure": pressure}]}
    parsed = parse_case(case)
    slips = [s for s in unit_slips(parsed, build(parsed).net) if "pressure" in s]
    if slip:
        assert len(slips) == 1 and slip in slips[0] and "did you mean" in slips[0], slips
    else:
        assert slips == [], slips


def test_the_bundled_cases_have_no_unit_slip():
    paths = sorted((ROOT / "configs").rglob("*.toml"))
    paths.append(ROOT / "catenet" / "data" / "default.toml")
    for path in paths:
        case = load_case(path, ())
        assert unit_slips(case, build(case).net) == [], path


def test_a_drop_with_a_box_spun_beyond_its_step_is_not_an_answer(tmp_path):
    """The drop of benchmarks/peers/mujoco_drop.toml with its box spun at 1e10 rad/s: the
    steps converge only to the round-off of forces 1e12 times the loads (the spin's), so
    no digit of the answer is sure: exit 1 saying so, the start kept (it used to end
    "converged" with the box leaving at 18 m/s)."""
    import tomllib

    case = tomllib.loads((ROOT / "benchmarks" / "peers" / "mujoco_drop.toml").read_text())
    case["obstacle"][0]["angular_velocity"] = [0.0, 0.0, 1e10]
    r = run(tmp_path, case)
    assert r.exit_code == 1, r.output
    assert "the round-off of its forces" in r.output and "above the loads" in r.output
    assert "converged    yes" not in r.output
    assert "use a smaller solver.dt" in r.output  # (fixed steps)
    del case["solver"]["dt"]  # steps chosen by accuracy: they shrink to round-off
    r = run(tmp_path, case)
    assert r.exit_code == 1 and "the round-off of its forces" in r.output, r.output
    assert "the steps chosen by accuracy shrank" in r.output
    assert "use a larger solver.tolerance or solver.dt_min" in r.output


def mooring(prestrain: float) -> dict:
    """The mooring line of docs/howto/mooring-line.md (anchor on the bed, fairlead 27 m
    away and 8 m up), its rest length set by ``prestrain`` over the 28.16 m chord."""
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.005], [27.0, 0.0, 8.0]],
            "fixed": [0, 1],
            "edge_length": 0.5,
            "prestrain": prestrain,
            "cable": [{"name": "line", "nodes": [0, 1]}],
        },
        "material": {"EA": 1e6, "area": 1e-3, "density": 1019.4},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "plane", "distance": 0.01}],
    }


def test_a_mooring_line_too_long_for_a_catenary_is_named_at_once(tmp_path):
    """36 m of line for a 27 m span and 8 m of height (27 + 7.995 = 34.995 m): it would
    hang straight down and lie slack on the bed, H = 0, in no unique shape. The run says
    so before solving (exit 2), where it used to fail after minutes advising a larger
    solver.max_iter; the how-to's 30 m line runs."""
    chord = float(np.hypot(27.0, 7.995))
    r = run(tmp_path, mooring(chord / 36.0 - 1.0))
    assert r.exit_code == 2, r.output
    assert "cable line: its unstretched length 36 m is at least the span" in r.output
    assert "no catenary holds it" in r.output and "max_iter" not in r.output
    assert run(tmp_path, mooring(-0.061372)).exit_code == 0


def test_a_rope_strained_beyond_its_law_for_an_instant_is_named(tmp_path):
    """A 10 m cable (EA 800 N, 1 % slack) dropped from its chord: its final strain is 3.4 %,
    within the linear law's 5 %, but it overshoots to about 15 % on the way: the run
    says so, with the time (it used to say nothing: only the final state was checked)."""
    case = {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, 0.0],
            "end": [10.0, 0.0, 0.0],
            "length": 10.1,
            "nodes": 11,
        },
        "material": {"EA": 800.0, "density": 7800.0, "radius": 0.005},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.5, "t_end": 3.0},
    }
    r = run(tmp_path, case)
    assert r.exit_code == 0, r.output
    assert "peak strain 0.1" in r.output and "(t = 0.8" in r.output
    assert "beyond the linear law's range" in r.output


def test_a_bilateral_cable_relaxed_to_rest_has_a_stability_verdict(tmp_path):
    """A run to rest ends at a static equilibrium: it carries a verdict as a static run
    does (a transient that ran its time does not)."""
    import h5py

    case = {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, 0.0],
            "end": [10.0, 0.0, 0.0],
            "length": 10.5,
            "nodes": 11,
        },
        "material": {"EA": 1e6, "density": 7800.0, "radius": 0.005, "tension_only": False},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "dynamic", "dt": 0.01, "t_end": "rest"},
    }
    r = run(tmp_path, case)
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "out.h5", "r") as f:
        assert f["result"].attrs["stability"] == "stable"
        assert f["result"].attrs["stable"] == 1
    case["solver"]["t_end"] = 0.2
    r = run(tmp_path, case)
    with h5py.File(tmp_path / "out.h5", "r") as f:
        assert f["result"].attrs["stability"] == "not judged"


def test_a_case_in_n_mm_is_summarised_in_mm_and_its_numbers_as_written(tmp_path):
    """The stay of ``truss`` written in N-mm (mm, MPa, t/mm^3, mm/s^2): the same state as
    in SI, its lengths printed in mm and its forces in N, no unit slip; the numbers are
    the case's own (the sag 1000x the SI run's, the tension the same)."""
    si = run(tmp_path / "si", truss() | {"load_case": []})
    case = truss(E=160e3, radius=10.0, density=7.85e-9, prestress=1e3)
    case["geometry"]["end"] = [20000, 0, 0]
    case["load"] = {"gravity": [0.0, 0.0, -9810.0]}
    case["units"] = "N-mm"
    case.pop("load_case")
    mm = run(tmp_path / "mm", case)
    assert si.exit_code == 0 and mm.exit_code == 0, (si.output, mm.output)
    assert "check units" not in mm.output, mm.output

    def line(output, label):
        return next(x for x in output.splitlines() if x.startswith(label))

    sag_si, sag_mm = line(si.output, "sag"), line(mm.output, "sag")
    assert re.search(r"^sag +[0-9.e+-]+ m normal", sag_si), sag_si
    assert re.search(r"^sag +[0-9.e+-]+ mm normal", sag_mm), sag_mm
    value = [float(x.split()[1]) for x in (sag_si, sag_mm)]
    assert value[1] == pytest.approx(1e3 * value[0], rel=1e-6)
    tension = [line(x.output, "max tension") for x in (si, mm)]
    assert all(re.search(r"max tension +[0-9.e+-]+ N \(edge", t) for t in tension), tension
    assert float(tension[1].split()[2]) == pytest.approx(float(tension[0].split()[2]), 1e-6)


def test_a_load_in_n_in_a_kn_m_case_is_named_as_a_cause(tmp_path):
    """A strand in kN-m whose line load is given in N/m (2000 for 2 kN/m) strains 24 %:
    beyond its law, not implausible, and the warning said only to take a large-strain
    law; it names the loads' units now. In SI, no such word."""
    case = {
        "units": "kN-m",
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [30.0, 0.0, 0.0],
                     "nodes": 61},
        "material": {"E": 1.6e8, "area": 1.0e-3, "prestress": 50.0},
        "load": {"line": [{"force": [0.0, 0.0, -2000.0]}]},
        "solver": {"steps": 4},
    }  # fmt: skip
    r = run(tmp_path / "knm", case)
    assert r.exit_code == 0, r.output
    assert "beyond the material law's range" in r.output
    assert "check that the loads are in the case's units (kN and kN/m, not N and N/m)" in r.output
    case["units"] = "SI"
    r = run(tmp_path / "si", case)
    assert "beyond the material law's range" in r.output
    assert "the case's units" not in r.output
