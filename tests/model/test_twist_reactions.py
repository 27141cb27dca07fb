"""The clamps of a twisted rod report the torque they hold (``/result/reaction_moment``,
``catenet.model.summary.support_moments``, ``Twist.end_moments``): about the rod's axis
the twisting moment GJ phi / L, -M at the first end and +M at the last; across it what
the clamp adds where the end edge leaves its held direction. The supports' forces and
moments balance the loads' moments to round-off (before, each clamp's torque about the
axis was missing from its moment, and the summary's largest support moment was a bending
one, 3.4 N m, beside a 159 N m torque)."""

from __future__ import annotations

import math
import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, parse_case
from catenet.cli import main
from catenet.model.summary import support_moments

G, E, R, L, PHI = 81e9, 210e9, 0.005, 3.0, 6.0
GJ = G * math.pi * R**4 / 2.0  # 79.52 N m^2

BAR = f"""
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [{L}, 0.0, 0.0]
nodes = 31

[material]
E = {E}
G = {G}
radius = {R}
density = 7850.0
EI = "section"
GJ = "section"

[supports]
fixed = ["start", "end"]
clamped = ["start", "end"]

[[supports.twist]]
nodes = ["end"]
angle = {PHI}
"""


def _run(write_case, tmp_path, text):
    out = tmp_path / "bar.h5"
    result = CliRunner().invoke(main, ["run", str(write_case(text)), "-o", str(out), "-q"])
    assert result.exit_code == 0, result.output
    with h5py.File(out) as f:
        r = f["result"]
        return (
            r["x"][()],
            r["reaction"][()],
            r["reaction_moment"][()],
            f["mesh/mass"][()],
            float(r.attrs["max_reaction_moment"]),
        )


def test_a_bar_turned_between_clamps_reports_the_torque_at_each(write_case, tmp_path):
    """Without gravity: the bar stays straight, each clamp holds exactly the twisting
    moment about the axis, -GJ phi / L at the start and +GJ phi / L at the end, nothing
    across it."""
    _, _, moment, _, largest = _run(write_case, tmp_path, BAR)
    torque = GJ * PHI / L  # 159.04 N m
    np.testing.assert_allclose(moment[0], [-torque, 0.0, 0.0], atol=1e-9 * torque)
    np.testing.assert_allclose(moment[-1], [torque, 0.0, 0.0], atol=1e-9 * torque)
    assert not np.any(moment[1:-1])
    assert largest == pytest.approx(torque, rel=1e-9)


def test_the_supports_balance_the_moments_of_a_twisted_bar_under_its_weight(write_case, tmp_path):
    """Under gravity the twisted bar bends out of its plane too (the twist turns the
    sag's moment); the clamps' moments now carry bending across the axis as well, and
    with the reactions' moments they balance the weights' to 1e-9 of the torque (without
    the clamps' torque the balance was off by 0.12 N m, M times the end edges' turn)."""
    text = BAR + "\n[load]\ngravity = [0.0, 0.0, -9.81]\n"
    x, reaction, moment, mass, _ = _run(write_case, tmp_path, text)
    torque = GJ * PHI / L
    assert np.max(np.abs(x[:, 1])) > 1e-4  # out of the plane of the sag
    loads = mass[:, None] * np.array([0.0, 0.0, -9.81])
    total = moment.sum(axis=0) + np.cross(x, reaction).sum(axis=0) + np.cross(x, loads).sum(axis=0)
    assert np.max(np.abs(total)) < 1e-9 * torque, total
    # about the axis still the twisting moment (6e-6 below GJ phi / L: the bent bar's
    # writhe takes a little of the turn)
    assert moment[0, 0] == pytest.approx(-torque, rel=1e-4)
    assert moment[-1, 0] == pytest.approx(torque, rel=1e-4)


def test_the_end_moments_are_the_energys_derivative_for_a_turned_clamp():
    """``Twist.end_moments`` against a turn of one clamp by a small angle done by hand:
    the energy's change over the angle (central differences of the whole energy with the
    clamp's tangent and director turned)."""
    case = parse_case(tomllib.loads(BAR.replace("nodes = 31", "nodes = 9")))
    scene = build(case)
    (term,) = [t for t in scene.terms if type(t).__name__ == "Twist"]
    rng = np.random.default_rng(3)
    x = scene.net.nodes + 0.02 * rng.standard_normal(scene.net.nodes.shape)
    x[[0, -1]] = scene.net.nodes[[0, -1]]
    got = term.end_moments(x)[0]
    twists = term.twists
    h = 1e-4
    for end, (tangent, director) in enumerate(
        ((twists.head, twists.head_dir), (twists.tail, twists.tail_dir))
    ):
        for axis in range(3):
            energies = []
            for sign in (1.0, -1.0):
                turn = _rotation(np.eye(3)[axis], sign * h)
                keys = ("head", "head_dir") if end == 0 else ("tail", "tail_dir")
                theta = term._angles(x, **{keys[0]: tangent @ turn.T, keys[1]: director @ turn.T})
                twist = theta - term.offset + term.imposed_twist()
                energies.append(0.5 * float(np.sum(twist**2 / twists.compliance)))
            expected = (energies[0] - energies[1]) / (2 * h)
            assert got[end, axis] == pytest.approx(expected, rel=1e-6, abs=1e-6 * GJ)


def _rotation(axis, angle):
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def test_no_twisted_rod_no_torque():
    """A rod that does not twist (no GJ): the clamps' moments are the bending ones alone."""
    text = BAR.replace('GJ = "section"\n', "").replace("[[supports.twist]]", "[x]")
    text = text.split("[x]")[0]
    scene = build(parse_case(tomllib.loads(text)))
    moments = support_moments(scene, scene.net.nodes)
    assert moments is not None and np.max(np.abs(moments)) < 1e-6  # round-off of the start
