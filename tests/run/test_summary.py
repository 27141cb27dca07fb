"""The numbers an engineer reads after a run (``catenet.model.summary``): the same in
``result.stats``, the /result attributes, the printed summary and the sweep table."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, load_case, parse_case
from catenet.cli import main
from catenet.run.runner import run_case
from tests.conftest import CONFIGS

MAST = CONFIGS / "structures" / "guyed_mast.toml"


def first_at_max(values) -> int:
    """The first index whose value is the largest to round-off (1e-12 relative)."""
    values = np.asarray(values)
    top = values.max()
    return int(np.flatnonzero(values >= top - 1e-12 * abs(top))[0])


def test_guyed_mast_summary_reads_as_an_engineer_expects(tmp_path):
    """The mast (configs/structures/guyed_mast.toml): the top moves most (the default
    probe of a graph, said so), its strut is reported in compression, the reactions
    balance the 10 kN load, and the file's attributes hold the same numbers."""
    case = load_case(MAST)
    scene = build(case)
    result = run_case(case, tmp_path / "m.h5")
    s = result.report.summary
    net, x = scene.net, result.x
    u = np.linalg.norm(x - net.nodes, axis=1)
    top = 1
    assert s["max_displacement_node"] == top and s["max_displacement"] == u[top]
    assert s["max_displacement_vector"] == list(x[top] - net.nodes[top])
    assert s["probe"] == top and s["probe_auto"] is True
    assert s["probe_displacement"] == s["max_displacement_vector"]
    assert s["max_displacement_vector"][0] > 1e-2  # it moves downwind
    assert s["delta"] == pytest.approx(-(x[top, 2] - net.nodes[top, 2]), rel=1e-12)
    # The strut: compression, not a negative "max tension" nor a slack cable.
    strut = int(np.flatnonzero(~net.law.tension_only)[0])
    assert s["max_compression_edge"] == strut and s["max_compression"] == -result.tension[strut]
    assert s["max_compression"] == pytest.approx(64e3, rel=1e-2)
    assert s["compressed_edges"] == 1 and s["slack_edges"] == 0
    assert s["max_tension"] == result.tension.max() > 0
    # the edge named: the first at the largest tension to round-off (symmetric guys tie)
    assert s["max_tension_edge"] == first_at_max(result.tension)
    mast = s["cables"]["mast"]
    assert mast["strut"] and mast["max_compression"] == s["max_compression"]
    assert not s["cables"]["guy_windward"]["strut"]
    # Reactions + loads = 0: the resultant is minus the 10 kN top load.
    assert np.allclose(s["reaction_resultant"], [-10e3, 0.0, 0.0], atol=1e-6 * 10e3)
    size = np.linalg.norm(result.reaction, axis=1)
    assert s["max_reaction"] == size.max() and s["max_reaction_node"] == first_at_max(size)
    assert s["contact_nodes"] == 0 and s["contact_resultant"] == [0.0, 0.0, 0.0]
    eps = np.linalg.norm(x[net.edges[:, 1]] - x[net.edges[:, 0]], axis=1) / net.rest_length - 1
    assert s["max_strain_edge"] == first_at_max(eps) and s["max_strain"] == eps.max()
    with h5py.File(tmp_path / "m.h5") as h5:
        a = dict(h5["result"].attrs)
        assert h5["result/cable_max_compression"][0] == mast["max_compression"]
        assert h5["result/cable_slack_edges"][:].tolist() == [0, 0, 0, 0, 0]
    for key in ("max_displacement", "max_displacement_node", "max_compression", "probe"):
        assert a[key] == s[key], key
    assert [a[f"reaction_resultant_{c}"] for c in "xyz"] == s["reaction_resultant"]
    assert [a[f"max_displacement_vector_{c}"] for c in "xyz"] == s["max_displacement_vector"]


def test_printed_summary_names_struts_slack_and_the_probe(tmp_path):
    r = CliRunner().invoke(main, ["run", str(MAST), "-o", str(tmp_path / "m.h5")])
    assert r.exit_code == 0, r.output
    out = r.output
    assert "(node 1, the free node that moves most;" in out
    assert "mast: a strut, compression 6" in out and "mast: max tension" not in out
    assert "compression " in out and "1 strut in compression" in out
    assert "slack        0 of 21 edges" in out
    assert "reactions    resultant [-1e+04, 0, " in out
    assert "max displ.   0.0173" in out and "m at node 1 (cable mast): [0.01736, 0, " in out
    assert "peak tension" not in out  # a static load that only grows peaks at the end


def test_slack_edges_are_counted_per_cable(tmp_path):
    """Two cables of one span: one pulled by a point load, the other's support moved 0.8 m
    towards its anchor, so that every one of its 4 edges hangs slack; the summary counts
    them, per cable too, and prints them."""
    data = {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [4, 0, 0], [0, 1, 0], [4, 1, 0]],
            "edge_length": 1.0,
            "sets": {"moved": [3]},
            "cable": [
                {"name": "taut", "nodes": [0, 1], "prestress": 100.0},
                {"name": "loose", "nodes": [2, 3]},
            ],
            "fixed": [0, 1, 2, 3],
        },
        "supports": {"move": [{"node": "moved", "displacement": [-0.8, 0, 0]}]},
        "material": {"EA": 1e5},
        "load": {"point": [{"cable": "taut", "at": 0.5, "force": [0, 0, -10.0]}]},
    }
    result = run_case(parse_case(data), tmp_path / "s.h5")
    s = result.report.summary
    assert s["slack_edges"] == 4
    assert s["cables"]["loose"]["slack_edges"] == 4 and s["cables"]["taut"]["slack_edges"] == 0
    assert s["cables"]["loose"]["slack_fraction"] == 1.0
    assert s["compressed_edges"] == 0 and s["max_compression"] == 0.0


def test_contact_totals_close_the_equilibrium(tmp_path):
    """A net pressed onto a sphere: reactions + contact forces + loads = 0, and the
    summary's resultants say so."""
    case = load_case(CONFIGS / "contact" / "net_on_sphere.toml")
    scene = build(case)
    result = run_case(case, tmp_path / "s.h5")
    s = result.report.summary
    load = scene.loads.external_force(scene.net).sum(axis=0)
    total = np.add(s["reaction_resultant"], s["contact_resultant"]) + load
    assert np.allclose(total, 0.0, atol=1e-6 * np.abs(load).max())
    assert s["contact_nodes"] > 0 and s["contact_resultant"][2] > 0.1 * abs(load[2])
    size = np.linalg.norm(result.contact_force, axis=1)
    assert s["max_contact"] == size.max() and s["max_contact_node"] == int(np.argmax(size))
    assert s["probe_auto"] is False  # a square net keeps the paper's centre node


REST = """
title = "a box resting on a net"
[geometry]
kind = "square_net"
n = 10
alpha = 0.7853981633974483
size = 1.0
edge_length = 0.05
[material]
E = 10e6
radius = 0.01
density = 1000.0
[load]
gravity = [0.0, 0.0, -9.81]
[[obstacle]]
kind = "box"
center = [0.0, 0.0, 0.052]
half_size = [0.15, 0.15, 0.05]
mass = 10.0
distance = 0.005
friction = 0.5
[solver]
method = "static"
"""


def test_a_body_resting_on_the_net_shows_its_weight_as_the_contact_on_the_net(tmp_path):
    """docs/guide/bodies.md's box at rest: the contact on the net's own nodes carries
    its 98.1 N (over every node, the body's and the net's, it cancels), and the largest
    contact is at a node of the net, not at one of the four that carry the body."""
    import tomllib

    case = parse_case(tomllib.loads(REST))
    result = run_case(case, tmp_path / "rest.h5")
    s = result.report.summary
    net = build(case).net
    assert np.allclose(s["contact_on_net"], [0.0, 0.0, -98.1], atol=1e-3)
    assert np.abs(s["contact_resultant"]).max() < 1e-6 * 98.1
    assert 0 <= s["max_contact_node"] < net.n_net and 0 < s["contact_nodes"] <= net.n_net
    (tmp_path / "rest.toml").write_text(REST)
    out = CliRunner().invoke(
        main, ["run", str(tmp_path / "rest.toml"), "-o", str(tmp_path / "r.h5")]
    )
    assert out.exit_code == 0, out.output
    line = next(ln for ln in out.output.splitlines() if ln.startswith("contact"))
    assert line.split(None, 1)[1].startswith("on the net [0, 0, -98.1"), line


def test_a_ball_gets_its_line_in_the_summary_as_a_free_body_does(tmp_path):
    """configs/contact/sphere_catch.toml to 0.4 s: the ball's line gives its first contact
    with the net (0.34 s) and its speed at the end, the centre node's (no spin: a ball is
    a point); before, only free bodies had a line."""
    out = CliRunner().invoke(
        main,
        ["run", str(CONFIGS / "contact" / "sphere_catch.toml"), "-o", str(tmp_path / "s.h5"),
         "--set", "solver.t_end=0.4"],
    )  # fmt: skip
    assert out.exit_code == 0, out.output
    (line,) = [ln for ln in out.output.splitlines() if ln.startswith("body")]
    assert "obstacle[0] (sphere): speed " in line and "first contact at t = 0.34 s" in line
    assert "spin" not in line
    with h5py.File(tmp_path / "s.h5") as f:
        node = int(f["/mesh/bodies/node"][0])  # the ball's centre
        v = f["/result/v"][node]
    speed = float(line.split("speed ")[1].split(" m/s")[0])
    assert speed == pytest.approx(float(np.linalg.norm(v)), rel=1e-3)


def test_rods_are_named_rods_with_their_largest_bending_moment(tmp_path):
    """The L-frame of docs/howto/rods.md (a column clamped at its foot, a 2 m beam at a
    rigid corner, 100 N down at the beam's tip): each member's line says it is a rod and
    gives its largest bending moment, P b = 200 N m at the foot and at the corner (the
    beam's; to the tip's small sway), where the beam carries no axial force and was called
    "a strut, max tension 0.2 N"; the compression line counts edges, not struts."""
    frame = {
        "title": "L-frame",
        "geometry": {
            "kind": "graph",
            "nodes": [[0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [2.0, 0.0, 3.0]],
            "edge_length": 0.25,
            "sets": {"foot": [0], "corner": [1], "tip": [2]},
            "cable": [
                {"name": "column", "nodes": ["foot", "corner"]},
                {"name": "beam", "nodes": ["corner", "tip"]},
            ],
        },
        "material": {"E": 210e9, "radius": 0.05, "inner_radius": 0.045, "EI": "section"},
        "supports": {
            "fixed": ["foot"],
            "clamped": ["foot"],
            "rigid_joints": ["corner"],
            "roller": [{"nodes": ["tip"], "normal": [0.0, 1.0, 0.0]}],
        },
        "load": {"point": [{"node": "tip", "force": [0.0, 0.0, -100.0]}]},
    }
    case = tmp_path / "frame.toml"
    case.write_text(dumps_toml(frame))
    r = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "f.h5")])
    assert r.exit_code == 0, r.output
    lines = {ln.split(":")[0].split()[-1]: ln for ln in r.output.splitlines() if "cable  " in ln}
    assert "column: a rod, compression 100 N, largest bending moment 200." in lines["column"]
    assert "beam: a rod, max tension " in lines["beam"] and "strut" not in lines["beam"]
    assert "largest bending moment 200" in lines["beam"]
    assert "edges in compression)" in r.output and "struts in compression" not in r.output
    s = run_case(parse_case(frame), tmp_path / "g.h5").report.summary
    for name in ("column", "beam"):
        row = s["cables"][name]
        assert row["rod"] and row["max_bending_moment"] == pytest.approx(200.0, rel=2e-3)


@pytest.mark.parametrize("damping, said", [(None, True), (0.0, False)])
def test_a_release_with_nothing_in_time_says_it_is_damped_by_default(tmp_path, damping, said):
    """A pendulum let go from 30 degrees with only t_end given: nothing depends on time,
    so the run relaxes with the default damping of 1 1/s. The summary says so and how to
    get the free motion; it had said only "raise solver.t_end"."""
    case = {
        "geometry": {"kind": "graph", "nodes": [[0.0, 0.0, 0.0], [1.0, 0.0, -1.7320508]],
                     "edges": [[0, 1]], "fixed": [0]},
        "material": {"EA": 1e7, "area": 1e-5, "density": 1000.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "mass": [{"node": 1, "mass": 10.0}],
        "solver": {"method": "dynamic", "t_end": 1.0},
    }  # fmt: skip
    if damping is not None:
        case["solver"]["damping"] = damping
    path = tmp_path / "pendulum.toml"
    path.write_text(dumps_toml(case))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "p.h5")])
    assert r.exit_code == 0, r.output
    text = "damped by solver.damping = 1 1/s, the default; for the free motion give"
    assert (text in r.output) == said, r.output


def test_the_energy_line_gives_the_loss_against_the_motion_where_it_is_small():
    """A prestressed string's small motion: its largest energy is the prestress's, so the
    integrator's loss read -0.00 % of it; its share of the motion's energy is given
    beside it (where the motion is under a tenth of the largest; the example of
    docs/howto/dynamic-runs.md)."""
    from catenet.cli.run import _balance

    row = [3.6e-5, 0.3183, 0.0, 6.58e-5, 0.0, -7.16e-6]
    line = _balance(row, 0.3183, 4.5e-5)
    assert "(-0.00% of the run's largest energy, -15.91% of the motion's:" in line
    assert "of the motion's" not in _balance(row, 0.3183, 0.2)
