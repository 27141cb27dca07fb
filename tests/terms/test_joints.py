"""Rigid joints where rods meet (``supports.rigid_joints``, ``catenet.terms.joints``): the
exact gradient and Hessian against finite differences (joints of 2 to 5 members in
space, a flat crossing), zero energy as drawn and under rigid motions, and the frames'
closed forms: an L-frame (a column clamped at its foot, a beam joined at its top) under
a tip load, and a T (a beam pinned at both ends, a column joined at its middle) under a
sideways load, both second order in the edge length, each held across its plane at its
free end (their rods have no GJ, so a rod could turn round another's axis there, and
from a start moved by round-off an L-frame's beam swung out of its plane); the joint's
moment; the frame's modes; the warning where a joint turns about the axis of a rod that
does not twist; the collapse's message; bad input (twist through joints:
test_joint_twist.py)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial.transform import Rotation

from catenet.cli import main
from catenet.model.joints import build_joints
from catenet.model.net import Net
from catenet.terms import check_derivatives
from catenet.terms.joints import RigidJoints

EI, EA = 1.0e6, 2.0e9


def _star(dirs: np.ndarray, EIs: np.ndarray) -> tuple[RigidJoints, np.ndarray]:
    """A joint at node 0 with a member of its own line along each of ``dirs``."""
    m = len(dirs)
    x = np.vstack([[0.0, 0.0, 0.0], 0.5 * dirs])
    edges = np.column_stack([np.zeros(m, int), np.arange(1, m + 1)])
    net = Net.from_arrays(x, edges, EA=1.0, fixed=[0], tension_only=False)
    joints = build_joints(net, EIs, np.arange(m), np.array([0]), "supports.rigid_joints")
    return RigidJoints(joints, len(x)), x


@pytest.mark.parametrize("m", [2, 3, 4, 5])
def test_a_joint_passes_finite_differences_and_is_zero_under_rigid_motions(m):
    rng = np.random.default_rng(m)
    dirs = rng.standard_normal((m, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    term, x = _star(dirs, rng.uniform(1.0, 3.0, m))
    assert term.energy(x) < 1e-25
    y = x + 0.1 * rng.standard_normal(x.shape)
    grad_err, hess_err = check_derivatives(term, y)
    assert grad_err < 1e-7 and hess_err < 1e-6, (grad_err, hess_err)
    turn = Rotation.from_rotvec(rng.standard_normal(3)).as_matrix()
    assert term.energy(x @ turn.T + 2.0) < 1e-25
    assert term.energy(y @ turn.T - 1.0) == pytest.approx(term.energy(y), rel=1e-12)


def test_a_flat_crossing_passes_finite_differences():
    """Two straight lines crossing in a plane (a square net's joint, four members)."""
    dirs = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0]])
    term, x = _star(dirs, np.full(4, 2.0))
    rng = np.random.default_rng(7)
    for shake in (0.0, 0.05):
        y = x + shake * rng.standard_normal(x.shape)
        y[1:, 2] += 0.02 * np.array([1.0, -1.0, 0.5, 0.3])  # out of the plane
        grad_err, hess_err = check_derivatives(term, y)
        assert grad_err < 1e-7 and hess_err < 1e-6, (shake, grad_err, hess_err)


def test_two_members_in_line_are_the_hinge_of_a_straight_rod():
    """Members at 160 degrees turned by a small angle against each other: the joint's
    energy is the straight rod's hinge EI / (l1 + l2) dphi^2 (as if clamped to a joint
    that turns with them), to second order, whatever their angle."""
    angle = np.radians(160.0)
    dirs = np.array([[1.0, 0, 0], [np.cos(angle), np.sin(angle), 0.0]])
    term, x = _star(dirs, np.array([EI, EI]))
    dphi = 1e-3
    y = x.copy()
    y[2] = 0.5 * np.array([np.cos(angle + dphi), np.sin(angle + dphi), 0.0])
    assert term.energy(y) == pytest.approx(EI / (0.5 + 0.5) * dphi**2, rel=1e-5)


L_FRAME = """
title = "L-frame"

[geometry]
kind = "graph"
nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [2.0, 0.0, 3.0]]
edge_length = EDGE

[geometry.sets]
foot = [0]
corner = [1]
tip = [2]

[[geometry.cable]]
name = "column"
nodes = ["foot", "corner"]

[[geometry.cable]]
name = "beam"
nodes = ["corner", "tip"]

[material]
EA = 2.0e9
EI = 1.0e6
tension_only = false

[supports]
fixed = ["foot"]
clamped = ["foot"]
rigid_joints = ["corner"]

[[supports.roller]]  # held across its plane: its beam would turn round the column freely
nodes = ["tip"]
normal = [0.0, 1.0, 0.0]

[[load.point]]
node = "tip"
force = FORCE
"""

FREE = (L_FRAME[L_FRAME.index("[[supports.roller]]") : L_FRAME.index("[[load.point]]")], "")

T_FRAME = """
[geometry]
kind = "graph"
nodes = [[-2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 1.5]]
edge_length = EDGE

[geometry.sets]
ends = [0, 2]
joint = [1]
tip = [3]

[[geometry.cable]]
name = "beam"
nodes = [0, "joint", 2]

[[geometry.cable]]
name = "column"
nodes = ["joint", "tip"]

[material]
EA = 2.0e9
EI = 1.0e6
tension_only = false

[supports]
fixed = ["ends"]
rigid_joints = ["joint"]

[[supports.roller]]  # held across its plane: the column would turn round the beam freely
nodes = ["tip"]
normal = [0.0, 1.0, 0.0]

[[load.point]]
node = "tip"
force = [1.0, 0.0, 0.0]
"""


def _run(tmp_path, text, *args, command="run"):
    case = tmp_path / "frame.toml"
    case.write_text(text)
    out = tmp_path / "frame.h5"
    done = CliRunner().invoke(main, [command, str(case), "-o", str(out), *args])
    return done, out


def _moved(tmp_path, text):
    done, out = _run(tmp_path, text, "-q")
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        # no sag of the chain foot-corner-tip: the chord crosses the frame's drawn corner
        assert ("sag_normal" in f["result"].attrs) == ("rigid_joints" not in text)
        return f["result/x"][()] - f["mesh/nodes"][()], f["result/bending_moment"][()]


@pytest.mark.roundoff
def test_the_l_frame_meets_its_closed_form_to_second_order(tmp_path):
    """A 1 N load down at the beam's tip (P / P_Euler of the column 4e-6): the tip drops
    P b^3 / (3 EI) + P a b^2 / EI + P a / EA (the beam a cantilever off the corner, which
    the column's moment P b turns by P b a / EI), the corner moves sideways P b a^2 /
    (2 EI); the corner's moment is P b."""
    a, b, P = 3.0, 2.0, 1.0
    drop = P * b**3 / (3 * EI) + P * a * b**2 / EI + P * a / EA
    errors = []
    for edge in (0.2, 0.1):
        text = L_FRAME.replace("EDGE", str(edge)).replace("FORCE", "[0.0, 0.0, -1.0]")
        d, moment = _moved(tmp_path, text)
        errors.append(abs(-d[2, 2] / drop - 1.0))
        assert d[1, 0] == pytest.approx(P * b * a**2 / (2 * EI), rel=1e-5)
        assert moment[1] == pytest.approx(P * b, rel=1e-3)
    assert errors[1] < 3e-4, errors
    assert 3.5 < errors[0] / errors[1] < 4.5, errors


@pytest.mark.roundoff
def test_without_the_joint_the_corner_is_a_pin(tmp_path):
    """The unloaded L-frame's modes: with the rigid joint none is free; with the corner
    pinned (no rigid_joints), the beam turning about the pin is a zero-frequency mode,
    named; rigid but without the roller, the beam turning round the column is one, said
    to be the joint's."""
    text = L_FRAME.replace("EDGE", "0.25").replace("FORCE", "[0.0, 0.0, 0.0]")
    text = text.replace("EA = 2.0e9", "EA = 2.0e9\ndensity = 7850.0\narea = 1e-3")
    done, _ = _run(tmp_path, text, "--count", "1", command="modes")
    assert done.exit_code == 0 and "zero-frequency" not in done.output, done.output
    pinned = text.replace('rigid_joints = ["corner"]', "")
    done, _ = _run(tmp_path, pinned, "--count", "1", command="modes")
    assert done.exit_code == 0, done.output
    assert "1 zero-frequency mode" in done.output and "cables beam" in done.output
    assert "rigid joint" not in done.output
    done, _ = _run(tmp_path, text.replace(*FREE), "--count", "1", command="modes")
    said = " ".join(done.output.split())  # rigid, but nothing holds the beam's turn
    assert done.exit_code == 0 and "1 zero-frequency mode" in said, said
    assert "rods turning at a rigid joint about the axis of a rod that does not twist" in said


@pytest.mark.roundoff
def test_the_t_frame_meets_its_closed_form_to_second_order(tmp_path):
    """Three members at one joint: the beam (one line through the joint, pinned at both
    ends, span L) takes the column's moment P h at its middle and turns there by
    P h L / (12 EI); the column's tip moves P h^3 / (3 EI) + P h^2 L / (12 EI) + P L /
    (4 EA) (the beam's halves carry P along it, one pulled, one pushed)."""
    h, span, P = 1.5, 4.0, 1.0
    tip = P * h**3 / (3 * EI) + P * h**2 * span / (12 * EI) + P * span / (4 * EA)
    errors = []
    for edge in (0.2, 0.1):
        d, _ = _moved(tmp_path, T_FRAME.replace("EDGE", str(edge)))
        errors.append(abs(d[3, 0] / tip - 1.0))
    assert errors[1] < 3e-3, errors
    assert 3.3 < errors[0] / errors[1] < 4.5, errors


def test_the_frames_modes_include_the_joint(tmp_path):
    """The L-frame of steel (7.85 kg/m) with 10 t at its tip: its two lowest in-plane
    modes are the tip mass's on the frame's flexibility (0.3451 and 1.0278 Hz, the
    frame's own 39 kg lowering them by up to 0.2 %)."""
    text = L_FRAME.replace("EDGE", "0.1").replace("FORCE", "[0.0, 0.0, -1.0]")
    text = text.replace("EA = 2.0e9", "EA = 2.0e9\ndensity = 7850.0\narea = 1e-3")
    text += '\n[[mass]]\nnode = "tip"\nmass = 10000.0\n'
    done, out = _run(tmp_path, text, "--count", "2", command="modes")
    assert done.exit_code == 0, done.output
    a, b, M = 3.0, 2.0, 1.0e4
    flex = np.array([[a**3 / 3, b * a**2 / 2], [b * a**2 / 2, b**3 / 3 + a * b**2]]) / EI
    expected = np.sqrt(np.linalg.eigvalsh(np.linalg.inv(flex) / M)) / (2 * np.pi)
    with h5py.File(out) as f:
        found = f["modes/frequency"][:2]
    np.testing.assert_allclose(found, expected, rtol=3e-3)
    assert found[0] < expected[0] and found[1] < expected[1]


PORTAL = """
[geometry]
kind = "graph"
nodes = [[0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [6.0, 0.0, 3.0], [6.0, 0.0, 0.0]]
edge_length = 0.25

[geometry.sets]
feet = [0, 3]
tops = [1, 2]

[[geometry.cable]]
name = "left"
nodes = [0, 1]

[[geometry.cable]]
name = "beam"
nodes = [1, 2]

[[geometry.cable]]
name = "right"
nodes = [3, 2]

[material]
EA = 2.0e9
EI = 1.0e6
tension_only = false

[supports]
fixed = ["feet"]
clamped = ["feet"]
rigid_joints = ["tops"]

[[load.point]]
node = 1
force = FORCE
"""


@pytest.mark.roundoff
def test_a_joint_turned_about_a_member_is_warned(tmp_path):
    """Loaded out of its plane, the L-frame's beam swings round the column (the joint
    holds no twist): a mechanism the load drives, a collapse, whose message names the
    joint and the column it turned about; a portal frame's beam turns round a column by a
    small angle (its load no longer shared): the run warns, naming the joint and the
    column, whatever the angle; loaded in their plane (the turn's share about a member
    1e-10 and below) neither."""
    text = L_FRAME.replace("EDGE", "0.2")
    done, _ = _run(tmp_path, text.replace(*FREE).replace("FORCE", "[0.0, 10.0, 0.0]"))
    assert done.exit_code == 1, done.output
    said = " ".join(done.output.split())
    assert "the structure is a mechanism under these loads" in said
    column = 16  # the column's node next to the corner (its 14 inner nodes are 3 to 16)
    assert (
        f"the rigid joint at node 1 turned by 90 deg about the axis of its member toward "
        f"node {column}, a rod that does not twist there" in said
    )
    done, _ = _run(tmp_path, PORTAL.replace("FORCE", "[0.0, 1.0, 0.0]"))
    said = " ".join(done.output.split())
    assert done.exit_code == 0 and "(cable 'right'), 100 % of its turn" in said, said
    angle = float(said.split("turned by ")[1].split(" deg")[0])
    assert 1e-5 < angle < 1e-3  # a small turn, warned all the same
    for case, force in ((text, "[0.0, 0.0, -10.0]"), (PORTAL, "[1000.0, 0.0, -500.0]")):
        done, _ = _run(tmp_path, case.replace("FORCE", force))
        assert done.exit_code == 0 and "rigid joint" not in done.output, done.output


def test_a_collapse_with_rigid_joints_names_their_twist():
    """Where a path with rigid joints collapses, the message adds that a rod that does not
    twist turns freely about its axis at a joint, and how to hold the frame (it spoke of
    guys and prestress only); without joints it does not."""
    from types import SimpleNamespace

    from catenet.solver.stability import describe_collapse

    def message(names):
        terms = [SimpleNamespace(name=n) for n in names]
        system = SimpleNamespace(terms=terms, net=SimpleNamespace(n_nodes=4))
        judge = SimpleNamespace(
            ws=SimpleNamespace(system=system), start_unstable=False, loaded=True
        )
        return describe_collapse(judge, "the equilibrium is unstable", 0.5, np.array([1, 2]))

    said = message(["stretch", "joints"])
    assert "at a rigid joint about the axis of a rod that does not twist" in said
    assert "hold it across its plane ([[supports.roller]]), clamp its feet or give" in said
    assert "rigid joint" not in message(["stretch"])


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ('rigid_joints = ["corner"]', 'rigid_joints = ["tip"]'),
            "supports.rigid_joints: node 2 joins the rod of one line",
        ),
        (
            ('rigid_joints = ["corner"]', 'rigid_joints = ["nowhere"]'),
            "supports.rigid_joints[0]",
        ),
        (("EI = 1.0e6", "EI = 0.0"), "supports.rigid_joints = ['corner']: no edge bends"),
        (('rigid_joints = ["corner"]', "rigid_joints = []"), "must be a non-empty array"),
        (
            ("[2.0, 0.0, 3.0]]", "[0.0, 0.0, 5.0]]"),
            "node 1: its rods all lie on one straight line",
        ),
    ],
)
def test_bad_joints_exit_2_with_one_clear_message(tmp_path, change, message):
    text = L_FRAME.replace("EDGE", "0.5").replace("FORCE", "[0.0, 0.0, -1.0]")
    text = text.replace(*change)
    if change[0] == "EI = 1.0e6":
        text = text.replace('clamped = ["foot"]\n', "")
    done, out = _run(tmp_path, text, "-q")
    assert done.exit_code == 2, done.output
    assert message in done.output, done.output
    assert "Traceback" not in done.output and not out.exists()
    assert "geometry.fixed: missing" not in done.output  # the supports are given
