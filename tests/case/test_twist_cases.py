"""Twisted rods from a case file: material.GJ (or "section" from G), [[supports.twist]],
which chains twist (clamped at both ends, rings; graph cables each on its own), the
results (/result/twisting_moment, the summary, catenet export), a dynamic run along a
history with its energy balance, Newton's convergence, and bad input (exit 2, one
message)."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.model.summary import twisting_moments
from catenet.solver import path

BAR = {
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [2.0, 0.0, 0.0], "nodes": 21},
    "material": {"E": 210e9, "G": 81e9, "radius": 0.01, "EI": "section", "GJ": "section"},
    "supports": {
        "fixed": ["start", "end"],
        "clamped": ["start", "end"],
        "twist": [{"nodes": ["end"], "angle": 0.5}],
    },
}
GJ_BAR = 81e9 * math.pi * 0.01**4 / 2


def _invoke(tmp_path, data, *args, command="run"):
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    return CliRunner().invoke(main, [command, str(case), "-o", str(tmp_path / "r.h5"), *args])


def test_a_bar_turned_between_clamps_carries_gj_phi_over_l(tmp_path):
    """G pi r^4 / 2 times the turn over the length on every edge, in the file, the
    summary and the exported cell data."""
    done = _invoke(tmp_path, BAR)
    assert done.exit_code == 0, done.output
    assert "twist        max moment" in done.output
    exact = GJ_BAR * 0.5 / 2.0
    with h5py.File(tmp_path / "r.h5") as f:
        moment = f["result/twisting_moment"][:]
        attrs = dict(f["result"].attrs)
    assert moment == pytest.approx(np.full(20, exact), rel=1e-12)
    assert attrs["max_twisting_moment"] == pytest.approx(exact, rel=1e-12)
    out = tmp_path / "vtu"
    done = CliRunner().invoke(
        main, ["export", str(tmp_path / "r.h5"), "--to", "vtu", "-o", str(out)]
    )
    assert done.exit_code == 0, done.output
    import meshio

    mesh = meshio.read(next(out.glob("*.vtu")))
    assert mesh.cell_data["twisting_moment"][0] == pytest.approx(moment, rel=1e-12)


def test_both_ends_turned_add_and_signs_follow_the_right_hand():
    """Turns right-handed about each end's outward tangent add up; the opposite turn at
    one end cancels the other's."""
    both = {**BAR, "supports": {**BAR["supports"], "twist": [
        {"nodes": ["start"], "angle": 0.3}, {"nodes": ["end"], "angle": 0.2}]}}  # fmt: skip
    scene = build(parse_case(both))
    m = twisting_moments(scene, scene.net.nodes)
    assert m == pytest.approx(np.full(20, GJ_BAR * 0.5 / 2.0), rel=1e-12)
    undone = {**BAR, "supports": {**BAR["supports"], "twist": [
        {"nodes": ["start"], "angle": -0.5}, {"nodes": ["end"], "angle": 0.5}]}}  # fmt: skip
    scene = build(parse_case(undone))
    assert np.abs(twisting_moments(scene, scene.net.nodes)).max() < 1e-9 * GJ_BAR


def test_a_tube_section_and_graph_cables_twist_each_on_its_own():
    """GJ = "section" of a tube, G pi (r^4 - ri^4) / 2; in a graph, a cable's own GJ
    makes it twist and leaves the others."""
    nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]
    data = {
        "geometry": {"kind": "graph", "nodes": nodes, "edge_length": 0.25, "cable": [
            {"name": "shaft", "nodes": [0, 1, 2], "material": {"GJ": "section"}},
            {"name": "arm", "nodes": [2, 3], "material": {"EI": 0.0}}]},
        "material": {"E": 200e9, "G": 80e9, "radius": 0.02, "inner_radius": 0.015,
                     "EI": "section"},
        "supports": {"fixed": [0, 2, 3], "clamped": [0, 2],
                     "twist": [{"nodes": [2], "angle": 0.1}]},
    }  # fmt: skip
    scene = build(parse_case(data))
    m = twisting_moments(scene, scene.net.nodes)
    shaft = scene.cables.edge == 0
    gj = 80e9 * math.pi * (0.02**4 - 0.015**4) / 2
    assert m[shaft] == pytest.approx(np.full(int(shaft.sum()), gj * 0.1 / 2.0), rel=1e-12)
    assert not m[~shaft].any()


def test_newton_converges_quadratically_on_a_twisted_loaded_rod():
    """A bar turned by a turn and a half under a sideways end-span load: converged,
    the residual's last steps falling quadratically."""
    data = {**BAR, "geometry": {**BAR["geometry"], "nodes": 41},
            "supports": {**BAR["supports"], "twist": [{"nodes": ["end"], "angle": 9.0}]},
            "load": {"point": [{"node": "midpoint", "force": [0.0, 2000.0, -3000.0]}]},
            "solver": {"rtol": 1e-12}}  # fmt: skip
    scene = build(parse_case(data))
    result = path.solve(scene, path.Settings(rtol=1e-12))
    assert result.converged and result.stable is not False
    first = result.history[0]
    tail = [r / first for r in result.history if r > 1e-8 * first][-3:]  # above round-off
    rates = [math.log(b) / math.log(a) for a, b in zip(tail[:-1], tail[1:], strict=True)]
    assert rates[-1] > 1.7, result.history
    x = result.x
    assert abs(x[20, 1]) > 1e-4  # the load pushes the twisted bar sideways too


def test_a_twist_along_a_history_keeps_the_energy_balance(tmp_path):
    """A dynamic run: the end turned along a ramp; the twist's work enters the balance
    (work in = the twist energy held, up to the integrator's loss) and the moment ends
    at GJ Phi / L."""
    data = {**BAR, "material": {**BAR["material"], "density": 7850.0},
            "supports": {**BAR["supports"], "twist": [
                {"nodes": ["end"], "angle": 0.5, "history": [[0.0, 0.0], [0.02, 1.0]]}]},
            "solver": {"method": "dynamic", "dt": 1e-3, "t_end": 0.04}}  # fmt: skip
    done = _invoke(tmp_path, data)
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "r.h5") as f:
        energy = f["trajectory/energy"][:]
        columns = list(f["trajectory/energy"].attrs["columns"])
        moment = f["result/twisting_moment"][:]
    row = dict(zip(columns, energy[-1], strict=True))
    assert energy[0][columns.index("elastic")] == pytest.approx(0.0, abs=1e-12)
    held = GJ_BAR * 0.5**2 / (2 * 2.0)
    assert row["external_work"] == pytest.approx(held, rel=2e-2)
    assert abs(row["numerical"]) < 1e-2 * held
    assert moment == pytest.approx(np.full(20, GJ_BAR * 0.5 / 2.0), rel=1e-2)


def _twist(**kw):
    return {**BAR, "supports": {**BAR["supports"], "twist": [{"nodes": ["end"], **kw}]}}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"material": {"EA": 1e6, "EI": 1.0, "GJ": -1.0}}, "material.GJ = -1.0: must be >= 0"),
        ({"material": {"EA": 1e6, "EI": 1.0, "GJ": "section"}},
         'material.GJ = "section": needs material.G'),
        ({"material": {"EA": 1e6, "GJ": 1.0}}, "material.GJ = 1.0: a rod that twists must bend"),
        ({"material": {"EA": 1e6, "EI": 1.0, "G": -1.0, "GJ": "section", "radius": 0.01}},
         "material.G = -1.0: must be finite and > 0"),
        (_twist(), "supports.twist[0].angle: missing"),
        (_twist(angle="half"), "supports.twist[0].angle = 'half': must be a number"),
        (_twist(angle=1.0, nodes=["top"]), "supports.twist[0].nodes[0] = 'top'"),
        ({**_twist(angle=1.0), "supports": {"fixed": ["start", "end"], "clamped": ["start"],
                                             "twist": [{"nodes": ["end"], "angle": 1.0}]}},
         "supports.twist[0].nodes: node 20 is not clamped"),
        ({**_twist(angle=1.0), "material": {"EA": 1e6, "EI": 1.0}},
         "supports.twist[0].nodes: no rod twists"),
        ({**_twist(angle=1.0), "supports": {"fixed": ["start", "end"],
                                             "clamped": ["start", "end"],
                                             "twist": [{"nodes": ["end"], "angle": 1.0},
                                                       {"nodes": [20], "angle": 1.0}]}},
         "supports.twist[1].nodes: node 20 is turned by supports.twist[0].nodes already"),
    ],
)  # fmt: skip
def test_bad_twist_input_exits_2_with_one_clear_message(tmp_path, change, message):
    done = _invoke(tmp_path, {**BAR, **change})
    assert done.exit_code == 2, done.output
    assert message in done.output, done.output
    assert "Traceback" not in done.output


def test_a_twist_whose_rod_has_a_free_end_is_refused(tmp_path):
    """Only the start is clamped (the end pinned): nothing holds the twist."""
    data = {**BAR, "supports": {"fixed": ["start", "end"], "clamped": ["start"],
                                "twist": [{"nodes": ["start"], "angle": 1.0}]}}  # fmt: skip
    done = _invoke(tmp_path, data)
    assert done.exit_code == 2, done.output
    assert "node 0 is a clamped end of a rod that does not twist" in done.output
    assert "clamp the rod's other end too" in done.output


def _ring_case(twist=None, closed=True, gj=0.8) -> dict:
    n = 24
    a = 2.0 * np.pi * np.arange(n) / n
    nodes = np.column_stack([np.cos(a), np.sin(a), np.zeros(n)]).tolist()
    cable = {"name": "ring", "nodes": [*range(n), 0] if closed else list(range(n))}
    if twist is not None:
        cable["twist"] = twist
    return {
        "geometry": {"kind": "graph", "nodes": nodes, "cable": [cable]},
        "material": {"EA": 1e6, "EI": 1.0, "GJ": gj, "tension_only": False},
        "supports": {"fixed": [0, 8, 16]},
    }


def test_a_ring_closed_with_a_twist_carries_gj_tw_over_its_length(tmp_path):
    """A closed cable's twist (Michell's ring, below its critical twist): the circle is
    an equilibrium and its twisting moment GJ Tw / (2 pi R) on every edge."""
    done = _invoke(tmp_path, _ring_case(twist=6.0))
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "r.h5") as f:
        moment = f["result/twisting_moment"][:]
    length = 24 * 2.0 * math.sin(math.pi / 24)  # the polygon's
    assert moment == pytest.approx(np.full(24, 0.8 * 6.0 / length), rel=1e-9)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (_ring_case(twist=1.0, closed=False), "geometry.cable[0].twist = 1.0: the cable is no "
         "twisting ring"),
        (_ring_case(twist=1.0, gj=0.0), "geometry.cable[0].twist = 1.0: the cable is no "
         "twisting ring"),
    ],
)  # fmt: skip
def test_a_twist_on_a_cable_that_is_no_ring_is_refused(tmp_path, data, message):
    done = _invoke(tmp_path, data)
    assert done.exit_code == 2, done.output
    assert message in done.output and "Traceback" not in done.output, done.output
