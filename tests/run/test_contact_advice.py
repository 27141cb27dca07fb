"""A frictionless contact that pushes along a cable at a node is the discretisation's
(``catenet.run.contact_advice``): the run warns, naming the node and the share of its
tension. Found on a newcomer's model: a cord dragged round a box blade's corners by a
frictionless blade read 8.9 % above the hand tension of its path, "converged yes", no
warning."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
from click.testing import CliRunner
from contact_cases import dragged_cord

from catenet.cli import main
from catenet.run.contact_advice import WRAP_SHARE, wrap_share


def _bent(angle: float):
    """Three nodes, the cable bent by ``angle`` at node 1, which a face pushes along +y
    (its normal) with 1 kN; tensions 1000 N."""
    x = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [math.cos(angle), -math.sin(angle), 0.0]])
    net = SimpleNamespace(edges=np.array([[0, 1], [1, 2]]), n_nodes=3, EA=np.full(2, 1e6))
    contact = np.zeros((3, 3))
    contact[1] = [0.0, 1000.0, 0.0]
    return net, x, np.array([1000.0, 1000.0]), contact


def test_a_tension_at_round_off_is_not_judged():
    """A steel rod lying on the floor carries round-off's tension (7e-9 N on EA = 1.6e7
    N): a push of 1.2e-7 N along it was warned as 1630 % of its tension. Below a strain
    of TAUT no share is read; just above it, it is."""
    from catenet.model.peaks import TAUT

    net, x, _, contact = _bent(0.5)
    net.EA = np.full(2, 1.6e7)
    contact[1] *= 1.2e-7 / 1000.0
    assert wrap_share(net, x, np.array([7e-9, 7e-9]), contact) is None
    above = np.full(2, 1.01 * TAUT * 1.6e7)
    assert wrap_share(net, x, above, contact) is not None


def test_the_share_is_the_contact_force_along_the_bisector_over_the_tension():
    """A cable leaving a face at a kink of angle a at a node the face pushes along its
    normal: the push along the cable (the bisector of its edges) is F sin(a / 2); a
    straight cable pushed square to it gives none, and free nodes, none."""
    for angle in (0.1, 0.5, 1.0):
        net, x, tension, contact = _bent(angle)
        share, node, along = wrap_share(net, x, tension, contact)
        assert node == 1 and math.isclose(along, 1000.0 * math.sin(angle / 2), rel_tol=1e-12)
        assert math.isclose(share, math.sin(angle / 2), rel_tol=1e-12)
    net, x, tension, contact = _bent(0.0)
    assert wrap_share(net, x, tension, contact)[0] < 1e-15
    assert wrap_share(net, x, tension, np.zeros((3, 3))) is None
    assert WRAP_SHARE == 0.02


CORD = dragged_cord(
    nodes=41,
    box=(-0.2, -0.03),
    half=(0.01, 0.02, 0.3),
    history=[[0.0, 0.0], [0.05, 1.0], [0.4, 1.0], [0.45, 0.0]],
    post=(0.3, 0.15),
    t_end=0.5,
    post_half=0.3,
)


def test_a_cord_dragged_round_a_box_blades_corners_is_warned(tmp_path):
    """The newcomer's cord (50 mm edges) dragged 0.2 m by a frictionless box blade round a
    post: the run ends, warning that the contact at a node by the blade's corner pushes
    along the cable by more than WRAP_SHARE of its tension; with friction on the blade
    (friction pushes along the cable by design) it says nothing of it."""
    case = tmp_path / "cord.toml"
    case.write_text(CORD)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 0, done.output
    text = " ".join(done.output.split())
    assert "the frictionless contact there pushes along the cable with" in text, text
    share = float(text.split("pushes along the cable with ")[1].split(" %")[0])
    assert share > 100.0 * WRAP_SHARE
    case.write_text(CORD.replace('kind = "box"', 'kind = "box"\nfriction = 0.2'))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "f.h5")])
    assert done.exit_code == 0, done.output
    assert "pushes along the cable" not in done.output


SINKING = """
title = "10 m of 20 mm steel rope, free, sinking broadside in still water"
[geometry]
kind = "graph"
nodes = [[0.0, 0.0, -50.0], [10.0, 0.0, -50.0]]
edge_length = 1.0
[[geometry.cable]]
name = "rope"
nodes = [0, 1]
[material]
EA = 2.0e7
radius = 0.01
density = 7850.0
cd_n = 1.2
cd_t = 0.008
ca_n = 1.0
[water]
density = 1025.0
[load]
gravity = [0.0, 0.0, -9.81]
[solver]
method = "dynamic"
t_end = 3.0
"""


def test_the_waters_drag_along_a_free_rope_is_no_contact(tmp_path):
    """A free rope sinking in still water, no obstacle: the drag along it (cd_t) is no
    contact, and its tension is round-off's; a newcomer's run of it was warned that "the
    frictionless contact" pushed along the cable with 4.5 % of a 2e-10 N tension."""
    case = tmp_path / "rope.toml"
    case.write_text(SINKING)
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 0, done.output
    assert "warning:" not in done.output, done.output


def _arc(pushes: np.ndarray, *, flip: np.ndarray | None = None):
    """A cable of len(pushes) + 2 nodes on a half circle of radius 0.1 m, tension 100 N;
    its inner nodes pushed radially (as a round solid pushes it) and along the cable by
    ``pushes`` [N] (toward the last node); ``flip``: edges given the other way round."""
    k = len(pushes) + 2
    angle = np.linspace(0.0, math.pi, k)
    x = np.column_stack([0.1 * np.cos(angle), 0.1 * np.sin(angle), np.zeros(k)])
    edges = np.array([[i, i + 1] for i in range(k - 1)])
    if flip is not None:
        edges[flip] = edges[flip][:, ::-1]
    net = SimpleNamespace(edges=edges, n_nodes=k, EA=np.full(k - 1, 1e6))
    contact = np.zeros((k, 3))
    contact[1:-1] = 100.0 * (math.pi / (k - 1)) * x[1:-1] / 0.1  # radial
    tangent = np.column_stack([-np.sin(angle), np.cos(angle), np.zeros(k)])
    contact[1:-1] += pushes[:, None] * tangent[1:-1]
    return net, x, np.full(k - 1, 100.0), contact


def test_pushes_along_a_cable_that_add_up_are_warned_where_each_is_small():
    """Each of 16 nodes pushed along the cable by 1.5 % of its tension (below WRAP_SHARE
    at each): together 24 %, the tension lost across the wrap (a rope round a cylinder's
    prisms with edge contact lost 25 %, unwarned). The run is found in either direction
    and whichever way its edges are given; pushes that cancel, or a radial push alone,
    are no run's."""
    from catenet.run.contact_advice import wrap_drift

    pushes = np.full(16, 1.5)
    net, x, tension, contact = _arc(pushes)
    assert wrap_share(net, x, tension, contact)[0] < WRAP_SHARE
    share, first, last, along = wrap_drift(net, x, tension, contact)
    assert math.isclose(along, 24.0, rel_tol=1e-9) and math.isclose(share, 0.24, rel_tol=1e-9)
    assert {first, last} == {1, 16}
    flipped = _arc(pushes, flip=np.arange(0, 17, 3))
    assert math.isclose(wrap_drift(*flipped)[3], 24.0, rel_tol=1e-9)
    assert math.isclose(wrap_drift(*_arc(-pushes))[3], 24.0, rel_tol=1e-9)
    alternating = pushes * np.where(np.arange(16) % 2, 1.0, -1.0)
    assert wrap_drift(*_arc(alternating))[0] <= 0.015 + 1e-12
    assert wrap_drift(*_arc(np.zeros(16)))[0] < 1e-12


def test_a_friction_coefficient_no_surface_has_is_warned(write_case, tmp_path):
    """``friction = 50`` (for 0.5) was taken as given, in silence: the rope stuck until
    the pull was 50 times its normal force. Above FRICTION_HIGH the run warns, naming the
    key; 0.5 is not warned."""
    text = """
title = "a rope on a rough plate"
[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.1]
end = [1.0, 0.0, 0.1]
nodes = 11
[material]
EA = 1e5
prestress = 10.0
[load]
point = [{ node = "midpoint", force = [0.0, 0.0, -50.0] }]
[[obstacle]]
kind = "plane"
point = [0.0, 0.0, 0.0]
friction = FRICTION
"""
    for mu, warned in (("50.0", True), ("0.5", False)):
        path = write_case(text.replace("FRICTION", mu))
        res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "o.h5")])
        assert res.exit_code == 0, res.output
        said = f"obstacle[0].friction = {mu}: Coulomb coefficients of real surfaces" in res.output
        assert said is warned, res.output


def _corner(t_in: float, t_out: float, pressed: float = 0.0):
    """A cable over a corner: nodes 0-1-2-3 along x, turned down by 90 degrees at node 2
    (2-3 along -z); tensions t_in on 0-1 and 1-2, t_out on 2-3; node 2 pushed by the
    contact the turn asks for (and ``pressed`` more, straight down: a load's)."""
    x = np.array([[-2.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    net = SimpleNamespace(
        edges=np.array([[0, 1], [1, 2], [2, 3]]), n_nodes=4, EA=np.full(3, 1e6), n_edges=3
    )
    contact = np.zeros((4, 3))
    contact[2] = [-t_in, 0.0, t_out + pressed]  # the corner's push, against the two pulls
    return net, x, np.array([t_in, t_in, t_out]), contact


def test_friction_holding_beyond_the_capstan_bound_is_found():
    """A rope hauled over a box's sharp edges with friction 0.3 ended at rest holding
    762 N on a 100 N load, in silence, where 100 exp(0.3 pi) = 257 N is the most Coulomb
    friction can hold. Across a run of contact the tensions may differ by exp(mu theta)
    at most, theta the cable's turn there: 3 over a right angle is found (bound 1.6),
    1.5 is not; a rope pressed by its load more than by its turn (on a floor) is not
    judged."""
    from catenet.run.contact_advice import capstan_excess

    ratio, bound, first, last = capstan_excess(*_corner(100.0, 300.0), 0.3)
    assert math.isclose(ratio, 3.0) and math.isclose(bound, math.exp(0.3 * math.pi / 2))
    assert first == last == 2
    ratio, bound, _, _ = capstan_excess(*_corner(100.0, 150.0), 0.3)
    assert ratio < bound
    assert capstan_excess(*_corner(100.0, 300.0, pressed=2000.0), 0.3) is None


def test_pushes_that_add_up_are_told_as_the_run_beside_a_large_one():
    """One node pushed along the cable by 3 % of its tension and 15 more by 1.5 % each:
    the message named the one node's 3 %, where the tension changes by 25.5 % across
    the run; the run's sum is told where it exceeds RUN_OVER times the node's."""
    from catenet.run.contact_advice import wrap_message

    pushes = np.full(16, 1.5)
    pushes[7] = 3.0
    said = wrap_message(*_arc(pushes))
    assert said is not None and said.startswith("nodes 1 to 16")
    assert "25.5 % of its tension in all" in said and "at most 3 % at one node" in said
    single = np.zeros(16)
    single[7] = 3.0
    assert wrap_message(*_arc(single)).startswith("node 8: ")
