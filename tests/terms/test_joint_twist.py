"""Twist through rigid joints (``catenet.model.twist``, ``catenet.kernels.twist``): a
twisting rod that ends at a rigid joint has its twist held there against the joint's
director, so a frame's members carry torsion into each other. The exact gradient and
Hessian of the twist against finite differences with ends on joints (a portal's three
segments, an oblique corner, the T's through-line split at its joint), and the frames'
closed forms: an L-frame loaded out of its plane (its column twisted by the beam) and a
portal pushed out of its plane at one corner (a 6 x 6 stiffness problem by hand: the
columns' bending and torsion, the beam's bending in plan and torsion)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, parse_case
from catenet.cli import main
from catenet.terms import check_derivatives

EI, GJ, EA = 1.0e6, 0.8e6, 2.0e9
H, B, P = 3.0, 2.0, 10.0  # column height, beam length [m], the load [N]


def _frame(nodes, lines, joints, clamped, edge, load_node, force, fixed=None) -> dict:
    return {
        "geometry": {
            "kind": "graph",
            "nodes": nodes,
            "edge_length": edge,
            "cable": [{"name": n, "nodes": pair} for n, pair in lines],
        },
        "material": {"EA": EA, "EI": EI, "GJ": GJ, "tension_only": False},
        "supports": {
            "fixed": clamped if fixed is None else fixed,
            "clamped": clamped,
            "rigid_joints": joints,
        },
        "load": {"point": [{"node": load_node, "force": force}]},
    }


def _l_frame(edge: float) -> dict:
    nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, H], [B, 0.0, H]]
    lines = [("column", [0, 1]), ("beam", [1, 2])]
    return _frame(nodes, lines, [1], [0], edge, 2, [0.0, P, 0.0])


def _portal(edge: float, gj: float = GJ) -> dict:
    nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, H], [B, 0.0, H], [B, 0.0, 0.0]]
    lines = [("left", [0, 1]), ("beam", [1, 2]), ("right", [3, 2])]
    data = _frame(nodes, lines, [1, 2], [0, 3], edge, 1, [0.0, P, 0.0])
    data["material"]["GJ"] = gj
    return data


def _twist_term(scene):
    return next(t for t in scene.terms if t.name == "twist")


@pytest.mark.parametrize("shape", ["portal", "oblique", "tee"])
def test_the_twist_with_ends_on_joints_passes_finite_differences(shape):
    """The twist term's gradient and Hessian where its segments end on rigid joints: the
    portal's (clamp-joint, joint-joint, joint-clamp), an oblique corner (members at 60
    degrees, the partner's direction not normal to the rod), and a T whose through-line
    is split at its joint; at states shaken off the drawn geometry, the segments twisted."""
    if shape == "portal":
        data = _portal(0.5)
    elif shape == "oblique":
        nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, H], [B * 0.5, 0.3, H + B * 0.8]]
        data = _frame(nodes, [("a", [0, 1]), ("b", [1, 2])], [1], [0, 2], 0.5, 1, [0.0, P, 0.0])
    else:
        nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, H], [0.0, 0.0, 2 * H], [B, 0.0, H]]
        lines = [("post", [0, 1, 2]), ("arm", [1, 3])]
        data = _frame(nodes, lines, [1], [0, 2, 3], 0.5, 1, [0.0, P, 0.0])
    scene = build(parse_case(data))
    term = _twist_term(scene)
    held = term.twists.partner >= 0
    assert held.any() and (shape != "tee" or held.sum() >= 3)  # the post split at node 1
    rng = np.random.default_rng(len(shape))
    x0 = np.zeros((scene.net.n_nodes, 3))
    x0[: scene.net.n_nodes] = scene.net.nodes
    for shake in (0.02, 0.1):
        y = x0 + shake * rng.standard_normal(x0.shape)
        assert np.all(np.abs(term.moments(y)) > 0.0)  # twisted
        grad_err, hess_err = check_derivatives(term, y)
        assert grad_err < 1e-7 and hess_err < 1e-6, (shape, shake, grad_err, hess_err)


def _solve(tmp_path, data):
    from catenet.case import dumps_toml

    case = tmp_path / "frame.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "f.h5"), "-q"])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "f.h5") as f:
        torque = f["result/twisting_moment"][()] if "twisting_moment" in f["result"] else None
        return f["result/x"][()] - f["mesh/nodes"][()], torque


@pytest.mark.roundoff
def test_an_l_frame_loaded_out_of_its_plane_twists_its_column(tmp_path):
    """The L-frame (column clamped at its foot, beam at a rigid corner) with P across its
    plane at the tip: the tip moves P b^3 / (3 EI) + P a^3 / (3 EI) + P b^2 a / GJ (the
    beam a cantilever off the corner, the column bent by P and twisted by P b); the
    column's twisting moment is P b. Second order in the edge length (1.25e-3, 3.1e-4 at
    0.2, 0.1 m edges)."""
    by_hand = P * B**3 / (3 * EI) + P * H**3 / (3 * EI) + P * B**2 * H / GJ
    errors = []
    for edge in (0.2, 0.1):
        d, torque = _solve(tmp_path, _l_frame(edge))
        errors.append(abs(d[2, 1] / by_hand - 1.0))
        assert np.max(np.abs(torque)) == pytest.approx(P * B, rel=1e-6)
    assert errors[1] < 5e-4, errors
    assert 3.5 < errors[0] / errors[1] < 4.5, errors


def _portal_by_hand() -> tuple[float, float]:
    """The portal's top displacements across its plane (at the loaded corner, the other)
    by a 6 x 6 stiffness problem: at each top v (y), rx and rz (rotations about x and z);
    the columns cantilevers bending in y (v, rx) and twisting (rz), the beam bending in
    plan (v, rz) and twisting (rx)."""
    K = np.zeros((6, 6))
    col = EI / H**3 * np.array([[12.0, 6.0 * H], [6.0 * H, 4.0 * H * H]])  # (v, rx)
    for top in (0, 3):
        K[np.ix_([top, top + 1], [top, top + 1])] += col
        K[top + 2, top + 2] += GJ / H
    beam = (
        EI
        / B**3
        * np.array(
            [
                [12.0, 6 * B, -12.0, 6 * B],
                [6 * B, 4 * B * B, -6 * B, 2 * B * B],
                [-12.0, -6 * B, 12.0, -6 * B],
                [6 * B, 2 * B * B, -6 * B, 4 * B * B],
            ]
        )
    )
    at = [0, 2, 3, 5]  # v1, rz1, v2, rz2
    K[np.ix_(at, at)] += beam
    K[np.ix_([1, 4], [1, 4])] += GJ / B * np.array([[1.0, -1.0], [-1.0, 1.0]])
    u = np.linalg.solve(K, np.array([P, 0, 0, 0, 0, 0]))
    return float(u[0]), float(u[3])


@pytest.mark.roundoff
def test_a_portal_pushed_out_of_its_plane_shares_the_push(tmp_path):
    """The portal on clamped feet pushed across its plane at one corner: both tops move as
    the 6 x 6 stiffness problem says (the far column takes its share through the beam's
    bending in plan and the columns' torsion), to 6e-4 at 0.1 m edges, second order;
    without GJ the joint holds no twist and the far top barely moves (the beam, a link,
    swings)."""
    near, far = _portal_by_hand()
    assert far > 0.2 * near  # a share worth checking
    errors = []
    for edge in (0.2, 0.1):
        d, _ = _solve(tmp_path, _portal(edge))
        errors.append(max(abs(d[1, 1] / near - 1.0), abs(d[2, 1] / far - 1.0)))
    assert errors[1] < 1e-3, errors
    assert 3.5 < errors[0] / errors[1] < 4.5, errors
    d, _ = _solve(tmp_path, _portal(0.2, gj=0.0))
    assert abs(d[2, 1]) < 0.05 * far


def test_the_l_frames_modes_carry_the_joints_twist(tmp_path):
    """catenet modes of the L-frame of steel tubes (no roller): its twist angles with
    their rotational inertia held at the joint as the statics hold them, so its lowest
    mode, across its plane, lies within 1e-3 of the one with the twist quasistatic
    (polar_inertia = 0: the static stiffness) and below it; without the joint's hold the
    beam would swing round the column at zero frequency."""
    from catenet.case import dumps_toml

    data = _l_frame(0.1)
    data["material"] = {
        "E": 210e9, "G": 81e9, "radius": 0.05, "inner_radius": 0.045, "density": 7850.0,
        "EI": "section", "GJ": "section", "tension_only": False,
    }  # fmt: skip
    found = []
    for polar in (None, 0.0):
        if polar is not None:
            data["material"]["polar_inertia"] = polar
        case = tmp_path / "frame.toml"
        case.write_text(dumps_toml(data))
        out = tmp_path / "modes.h5"
        args = ["modes", str(case), "-o", str(out), "--count", "2", "-q"]
        done = CliRunner().invoke(main, args)
        assert done.exit_code == 0, done.output
        with h5py.File(out) as f:
            found.append(f["modes/frequency"][()])
    (turning, quasistatic) = found
    assert 1.0 < turning[0] <= quasistatic[0] < (1 + 1e-3) * turning[0], found


def test_a_joints_bending_moment_counts_what_passes_into_twist(tmp_path):
    """The L-frame loaded across its plane: the beam's moment at the corner, P b, passes
    into the column's twist; /result/bending_moment at the corner is that P b (it read
    about 3e-5 N m: only the beam's turn against the joint's was counted), and the T's
    joint carries the column's end moment into both halves of the beam it twists."""
    from catenet.case import dumps_toml

    case = tmp_path / "frame.toml"
    case.write_text(dumps_toml(_l_frame(0.1)))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "f.h5"), "-q"])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "f.h5") as f:
        corner = f["result/bending_moment"][1]
    assert corner == pytest.approx(P * B, rel=1e-3)
    nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, H], [0.0, 0.0, 2 * H], [B, 0.0, H]]
    lines = [("post", [0, 1, 2]), ("arm", [1, 3])]
    tee = _frame(nodes, lines, [1], [0, 2], 0.1, 3, [0.0, P, 0.0])
    case.write_text(dumps_toml(tee))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "t.h5"), "-q"])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "t.h5") as f:
        joint, torque = f["result/bending_moment"][1], f["result/twisting_moment"][()]
    assert joint == pytest.approx(P * B, rel=1e-3)  # the arm's root: P b
    assert np.max(np.abs(torque)) == pytest.approx(0.5 * P * B, rel=1e-3)  # each half
