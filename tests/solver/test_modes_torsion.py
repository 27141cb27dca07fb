"""Torsional modes (``catenet modes`` with the rods' twist angles as DOFs,
``catenet.model.torsion``): a steel shaft's first torsional frequency from its section
alone through the command line, the result file's /modes/twist, twist_share and
polar_inertia and the summary's column; coupled modes of a curved rod, which tend to the
eliminated twist's as the rotational inertia vanishes; a pinned rod's free spin named as
a zero mode with its bending frequencies unchanged; and the input refused (exit 2)."""

from __future__ import annotations

import dataclasses
import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.solver.modes import modes

R, RHO, G, L = 0.02, 7850.0, 81e9, 1.5
SHAFT = {
    "title": "steel shaft clamped at one end",
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [L, 0.0, 0.0], "nodes": 51},
    "material": {"E": 210e9, "G": G, "radius": R, "density": RHO, "EI": "section",
                 "GJ": "section"},
    "supports": {"fixed": ["start"], "clamped": ["start"]},
}  # fmt: skip


def _invoke(tmp_path, data, *args):
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    out = tmp_path / "r.h5"
    return CliRunner().invoke(main, ["modes", str(case), "-o", str(out), *args]), out


def test_a_steel_shaft_has_its_torsional_mode_from_its_section(tmp_path):
    """Clamped-free: f_1 = sqrt(G / rho) / (4 L) whatever the radius (rho J_p from the
    section, density pi r^4 / 2), within 1e-4 at 50 edges (the discrete shaft's 4e-5);
    the file's twist angles, their inertia and each mode's share of kinetic energy in
    them (with the directions' shares, 1); the summary marks the mode "tw"."""
    done, out = _invoke(tmp_path, SHAFT, "--count", "12")
    assert done.exit_code == 0, done.output
    exact = math.sqrt(G / RHO) / (4 * L)
    with h5py.File(out) as f:
        g = f["modes"]
        share = g["twist_share"][:]
        frequency = g["frequency"][:]
        twist, inertia = g["twist"][:], g["polar_inertia"][:]
        direction = g["direction_share"][:]
        rest = f["mesh/rest_length"][:]
    torsional = np.flatnonzero(share > 0.5)
    assert torsional.size == 1 and share[torsional[0]] > 1 - 1e-9
    assert frequency[torsional[0]] == pytest.approx(exact, rel=1e-4)
    assert inertia == pytest.approx(RHO * math.pi * R**4 / 2 * rest, rel=1e-12)
    assert twist.shape == (12, 50)
    assert np.einsum("e,ke->k", inertia, twist**2) == pytest.approx(share, abs=1e-12)
    assert direction.sum(axis=1) + share == pytest.approx(np.ones(12), abs=1e-9)
    assert frequency[0] < exact / 10  # bending comes first in a slender shaft
    assert "torsion      the twist angles of 50 rod edges" in done.output
    row = next(line for line in done.output.splitlines() if " tw " in line)
    assert "100.00" in row and "(twist)" in row


def _arc(polar: float | None) -> dict:
    """A quarter circle of radius 1 m (30 edges), naturally curved, clamped at one end."""
    a = np.linspace(0.0, math.pi / 2, 31)
    nodes = np.column_stack([np.sin(a), 1 - np.cos(a), 0 * a]).tolist()
    material = {"EA": 1e4, "EI": 1.0, "GJ": 0.8, "area": 1e-3, "density": 1000.0,
                "natural_curvature": "given", "tension_only": False}  # fmt: skip
    if polar is not None:
        material["polar_inertia"] = polar
    return {
        "geometry": {"kind": "graph", "nodes": nodes,
                     "cable": [{"name": "arc", "nodes": list(range(31))}]},
        "material": material,
        "supports": {"fixed": [0], "clamped": [0]},
    }  # fmt: skip


def test_a_curved_rods_modes_couple_bending_and_twist():
    """Out of its plane a curved rod bends and twists at once: with rho J_p = 0.1 kg m
    modes carry 9 % of their energy in bending and 91 % in the twist; in its plane it
    does not twist."""
    heavy = build(parse_case(_arc(0.1)))
    found = modes(heavy, k=8, x=heavy.net.nodes)
    share = found.twist_share()
    assert np.any((share > 0.5) & (share < 0.95))  # coupled
    assert np.any(share < 1e-9)  # the in-plane modes


BENT = {
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [2.0, 0.0, 0.0], "nodes": 21},
    "material": {"E": 210e9, "G": 81e9, "radius": 0.01, "EI": "section", "GJ": "section",
                 "density": 7850.0},
    "supports": {"fixed": ["start", "end"], "clamped": ["start", "end"],
                 "twist": [{"nodes": ["end"], "angle": 3.0}]},
    "load": {"point": [{"node": "midpoint", "force": [0.0, 2000.0, -3000.0]}]},
}  # fmt: skip


def test_the_modes_tend_to_the_eliminated_twists_as_the_inertia_vanishes():
    """A bar turned by 3 rad between clamps and bent by a load (its twist couples to its
    bending): the six lowest bending modes with the twist's rotational inertia rho J_p
    of its section, and a hundredth of it, differ from those of the eliminated twist by
    7e-7 and a hundred times less (the difference is of order rho J_p)."""
    from catenet.solver import path

    scene = build(parse_case(BENT))
    x = path.solve(scene, path.Settings(rtol=1e-10)).x
    eliminated = modes(dataclasses.replace(scene, torsion=None), k=6, x=x).frequency
    section = RHO * math.pi * 0.01**4 / 2
    gaps = []
    for polar in (section, section / 100):
        data = {**BENT, "material": {**BENT["material"], "polar_inertia": polar}}
        found = modes(build(parse_case(data)), k=8, x=x)
        bending = found.frequency[found.twist_share() < 0.5][:6]
        gaps.append(float(np.abs(bending / eliminated - 1).max()))
    assert 1e-7 < gaps[0] < 1e-5 and gaps[1] < gaps[0] / 50, gaps


def test_a_pinned_rod_spins_freely_and_bends_as_before():
    """Pinned at both ends (nothing holds its twist): one zero-frequency mode, the spin,
    named; the bending frequencies are those without GJ (pi^2 sqrt(EI / rho A) / (2 pi
    L^2) to the discretisation's 1e-3)."""
    data = {
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [1.0, 0.0, 0.0],
                     "nodes": 41},
        "material": {"EA": 1e5, "EI": 1.0, "GJ": 0.8, "area": 1e-3, "density": 1000.0,
                     "polar_inertia": 1e-3, "tension_only": False},
        "supports": {"fixed": ["start", "end"]},
    }  # fmt: skip
    scene = build(parse_case(data))
    assert scene.torsion.spins == 1
    found = modes(scene, k=6, x=scene.net.nodes)
    assert found.zero_modes == 1 and "turning about their own axes" in found.zero_message
    plain = build(parse_case({**data, "material": {**data["material"], "GJ": 0.0}}))
    before = modes(plain, k=4, x=plain.net.nodes)
    bending = found.frequency[found.twist_share() < 0.5][:4]
    assert bending == pytest.approx(before.frequency, rel=1e-9)
    assert bending[0] == pytest.approx(math.pi / 2, rel=1e-3)


def test_a_twisting_rod_without_its_rotational_inertia_is_refused(tmp_path):
    """GJ with an area (no radius) and no polar_inertia: exit 2 naming the key; the run
    itself needs none; polar_inertia = 0 keeps the twist eliminated (no /modes/twist);
    a negative one is refused by its key."""
    data = {**SHAFT, "material": {"EA": 1e6, "EI": 10.0, "GJ": 8.0, "area": 1e-4,
                                  "density": RHO, "tension_only": False}}  # fmt: skip
    done, _ = _invoke(tmp_path, data)
    assert done.exit_code == 2
    assert "material.polar_inertia: a rod that twists (GJ > 0) needs" in done.output
    assert "Traceback" not in done.output
    case = tmp_path / "case.toml"
    ran = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "run.h5")])
    assert ran.exit_code == 0, ran.output
    zero = {**data, "material": {**data["material"], "polar_inertia": 0.0}}
    done, out = _invoke(tmp_path, zero)
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        assert "twist" not in f["modes"] and not f["modes/twist_share"][:].any()
    bad = {**data, "material": {**data["material"], "polar_inertia": -1.0}}
    done, _ = _invoke(tmp_path, bad)
    assert done.exit_code == 2 and "material.polar_inertia" in done.output


def test_a_cables_own_material_is_named_when_its_inertia_is_missing(tmp_path):
    """In a graph, the twisting cable's own material key is named."""
    data = {
        "geometry": {"kind": "graph", "nodes": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
                     "edge_length": 0.1,
                     "cable": [{"name": "bar", "nodes": [0, 1],
                                "material": {"EI": 1.0, "GJ": 0.8}}]},
        "material": {"EA": 1e5, "area": 1e-3, "density": 1000.0},
        "supports": {"fixed": [0], "clamped": [0]},
    }  # fmt: skip
    done, _ = _invoke(tmp_path, data)
    assert done.exit_code == 2
    assert "geometry.cable[0].material.polar_inertia" in done.output
