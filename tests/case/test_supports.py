"""``[[supports.roller]]``, ``[[supports.slider]]`` and ``[[supports.spring]]`` in case
files: written as a user would from the docs, run through ``catenet run`` and ``catenet
modes``, load cases and dynamic runs, the reactions in the result file; bad input refused
with its key path, value and what is accepted (exit status 2)."""

from __future__ import annotations

import copy

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.output.supports import read_supported
from catenet.run.runner import run_case

G = 9.81

#: A cable from a pinned start to an end on a vertical wall it slides down (a roller
#: held along x) and a graph with a slider and springs.
CABLE = {
    "title": "half catenary",
    "geometry": {
        "kind": "cable",
        "start": [0.0, 0.0, 0.0],
        "end": [5.0, 0.0, 0.0],
        "length": 6.0,
        "nodes": 11,
    },
    "material": {"EA": 1e5, "density": 1000.0, "area": 0.002},
    "supports": {"fixed": ["start"], "roller": [{"nodes": "end", "normal": [1, 0, 0]}]},
    "load": {"gravity": [0, 0, -G]},
}

GRAPH = {
    "title": "a guyed post on a slider, its foot on springs",
    "geometry": {
        "kind": "graph",
        "nodes": [[0, 0, 0], [0, 0, 4], [3, 0, 0], [-2, 2, 0], [-2, -2, 0]],
        "edges": [[0, 1], [1, 2], [1, 3], [1, 4]],
        "fixed": [2, 3, 4],
        "sets": {"foot": [0]},
    },
    "material": {"EA": 2e6, "tension_only": False},
    "supports": {
        "slider": [{"nodes": [1], "direction": [0, 0, 1]}],
        "spring": [{"nodes": "foot", "stiffness": [4e4, 4e4, 1e5]}],
    },
    "load": {"point": [{"node": 1, "force": [0, 0, -500]}]},
}


def _run(tmp_path, data, *args):
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(data))
    return CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5"), *args])


def _refused(tmp_path, data) -> str:
    """The message of a case refused as bad input (exit status 2, no traceback)."""
    r = _run(tmp_path, data)
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    with pytest.raises(ConfigError):
        parse_case(copy.deepcopy(data))
    return r.output


def test_roller_case_runs_and_writes_the_reactions(tmp_path):
    """The end slides down the wall until the cable meets it horizontally: its reaction
    is along the wall's normal only, the start carries the whole weight, and reactions
    and loads sum to zero in the result file."""
    r = _run(tmp_path, CABLE)
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "out.h5") as h5:
        x, reaction = h5["result/x"][:], h5["result/reaction"][:]
        mass = h5["mesh/mass"][:]
        assert h5["mesh/supports/roller_nodes"][:].tolist() == [10]
        assert h5["mesh/supports/roller_normal"][:].tolist() == [[1.0, 0.0, 0.0]]
        assert h5["mesh/supports/slider_nodes"].shape == (0,)
        assert "spring_nodes" not in h5["mesh/supports"]
    assert x[-1, 0] == pytest.approx(5.0, abs=1e-12) and x[-1, 2] < -2.0
    weight = mass.sum() * G
    assert reaction[-1, 1:] == pytest.approx([0.0, 0.0], abs=1e-7 * weight)
    assert reaction[-1, 0] > 0.2 * weight  # the wall pushes the end back
    assert reaction[0, 2] == pytest.approx(weight, rel=1e-7)
    assert np.abs(reaction.sum(axis=0) - [0.0, 0.0, weight]).max() < 1e-7 * weight
    supported = read_supported(tmp_path / "out.h5", 11)
    assert supported is not None and np.flatnonzero(supported).tolist() == [10]
    drawn = CliRunner().invoke(main, ["plot", str(tmp_path / "out.h5")])
    assert drawn.exit_code == 0 and (tmp_path / "out.png").exists(), drawn.output
    # the end's edge is horizontal there: no vertical pull on the wall
    d = x[-1] - x[-2]
    assert abs(d[2]) < 1e-3 * np.linalg.norm(d) + (mass[-1] * G) / reaction[-1, 0]


def test_slider_and_springs_case(tmp_path):
    """A post from a foot on springs to a head on a vertical slider, three guys: the
    head goes straight down, the foot's springs take the post's force (its vertical
    spring by kz), and every reaction with the load sums to zero."""
    case = parse_case(copy.deepcopy(GRAPH))
    result = run_case(case, tmp_path / "g.h5")
    x, reaction = result.x, result.reaction
    assert np.abs(x[1, :2]).max() < 1e-12  # the slider keeps the head on the axis
    u_foot = x[0] - np.array([0.0, 0.0, 0.0])
    assert reaction[0] == pytest.approx(-np.array([4e4, 4e4, 1e5]) * u_foot, rel=1e-9)
    assert reaction[1, 2] == pytest.approx(0.0, abs=1e-6)  # free along the slider
    total = reaction.sum(axis=0) + [0.0, 0.0, -500.0]
    assert np.abs(total).max() < 1e-6 * 500.0
    assert u_foot[2] < 0.0 and abs(result.tension[0]) > 0.0
    with h5py.File(tmp_path / "g.h5") as h5:
        s = h5["mesh/supports"]
        assert s["slider_nodes"][:].tolist() == [1]
        assert s["slider_direction"][:].tolist() == [[0.0, 0.0, 1.0]]
        assert s["spring_nodes"][:].tolist() == [0]
        assert np.array_equal(s["spring_stiffness"][0], np.diag([4e4, 4e4, 1e5]))


def test_load_cases_and_modes_keep_the_guides(tmp_path):
    data = copy.deepcopy(CABLE)
    data["load_case"] = [{"name": "push", "point": [{"node": 5, "force": [0, 30.0, 0]}]}]
    r = _run(tmp_path, data)
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "out.h5") as h5:
        x = h5["cases/push/x"][:]
        reaction = h5["cases/push/reaction"][:]
    assert x[-1, 0] == pytest.approx(5.0, abs=1e-12)
    assert x[-1, 1] > 1e-3  # the end follows the push along the wall
    assert abs(reaction[-1, 1]) < 1e-6 and abs(reaction[-1, 2]) < 1e-6
    path = tmp_path / "case.toml"
    out = tmp_path / "m.h5"
    m = CliRunner().invoke(main, ["modes", str(path), "-o", str(out), "--count", "4"])
    assert m.exit_code == 0, m.output
    with h5py.File(out) as h5:
        shapes = h5["modes/shape"][:]
    assert np.abs(shapes[:, -1, 0]).max() < 1e-12  # never through the wall
    assert np.abs(shapes[:, -1, 1:]).max() > 1e-3


def test_dynamic_case_on_a_roller(tmp_path):
    data = copy.deepcopy(CABLE)
    data["solver"] = {"method": "dynamic", "dt": 0.01, "t_end": 0.5, "damping": 0.0}
    data["output"] = {"every": 5}
    r = _run(tmp_path, data)
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "out.h5") as h5:
        x = h5["trajectory/x"][:]
        energy = h5["trajectory/energy"][:]
    assert np.abs(x[:, -1, 0] - 5.0).max() < 1e-13
    assert x[-1, -1, 2] < -0.5  # it fell down the wall
    assert energy[-1, -1] <= 0.0  # implicit Euler: dissipation, never energy made


def test_node_sets_and_arrays_of_nodes():
    data = copy.deepcopy(GRAPH)
    data["supports"]["roller"] = [{"nodes": [3, 4], "normal": [0, 0, 2]}]
    data["geometry"]["fixed"] = [2]
    scene = build(parse_case(data))
    guides = scene.net.guides
    assert guides is not None and sorted(guides.nodes.tolist()) == [1, 3, 4]
    assert guides.held_count == 2 + 1 + 1
    assert scene.net.springs is not None and scene.net.springs.nodes.tolist() == [0]
    written = parse_case(data).to_dict()["supports"]
    assert written["roller"] == [{"nodes": [3, 4], "normal": [0.0, 0.0, 2.0]}]
    assert parse_case(copy.deepcopy(data) | {}).supports == parse_case(data).supports


@pytest.mark.parametrize(
    ("change", "needles"),
    [
        (
            {"roller": [{"nodes": "end", "normal": [0, 0, 0]}]},
            ["supports.roller[0].normal = [0, 0, 0]", "must not be [0, 0, 0]"],
        ),
        (
            {"slider": [{"nodes": "end", "direction": [0, 0]}]},
            ["supports.slider[0].direction", "[x, y, z]"],
        ),
        (
            {"roller": [{"nodes": "end", "norml": [1, 0, 0]}]},
            ["supports.roller[0].norml: unknown key", "did you mean 'normal'"],
        ),
        (
            {"roller": [{"nodes": "start", "normal": [1, 0, 0]}]},
            ["supports.roller[0].nodes = 'start' (node 0)", "fixed already (supports.fixed)"],
        ),
        (
            {
                "roller": [{"nodes": "end", "normal": [1, 0, 0]}],
                "slider": [{"nodes": 10, "direction": [2, 0, 0]}],
            },
            ["supports.slider[0].nodes = 10", "on supports.roller[0] already"],
        ),
        (
            {"spring": [{"nodes": [3], "stiffness": [1e3, -1.0, 0]}]},
            ["supports.spring[0].stiffness", "each finite and >= 0"],
        ),
        (
            {"spring": [{"nodes": [3], "stiffness": [[1, 2, 0], [2, 1, 0], [0, 0, 1]]}]},
            ["supports.spring[0].stiffness", "positive semidefinite"],
        ),
        ({"spring": [{"nodes": [30], "stiffness": [1, 1, 1]}]}, ["supports.spring[0].nodes"]),
        ({"roller": [{"normal": [1, 0, 0]}]}, ["supports.roller[0].nodes: missing"]),
        (
            {
                "roller": [{"nodes": "end", "normal": [1, 0, 0]}],
                "move": [{"node": "end", "displacement": [0, 0, -1]}],
            },
            ["supports.move[0].node = 'end'", "is on supports.roller[0]", "does not move"],
        ),
        (  # a clamp holds its end in place: it named the geometry's fixed nodes
            {"slider": [{"nodes": "end", "direction": [1, 0, 0]}], "clamped": ["end"]},
            [
                "supports.clamped[0] = 'end' (node 10): node 10 is on supports.slider[0] too",
                "hold its direction by a stiff [[supports.rotational]]",
            ],
        ),
        (  # a spring on a clamped end held nothing, silently
            {"spring": [{"nodes": [0], "stiffness": [1, 1, 1]}], "clamped": ["start"]},
            ["supports.clamped[0] = 'start' (node 0): node 0 is on supports.spring[0] too"],
        ),
    ],
)
def test_bad_supports_are_refused(tmp_path, change, needles):
    data = copy.deepcopy(CABLE)
    data["supports"] = {"fixed": ["start"], **change}
    if "move" in change:
        data["supports"]["fixed"] = ["start"]
    out = _refused(tmp_path, data)
    for needle in needles:
        assert needle in out, out


def test_a_graph_held_by_rollers_and_springs_alone_is_supported(tmp_path):
    """No fixed node: the supports' check counts the rollers and springs."""
    data = copy.deepcopy(GRAPH)
    data["geometry"]["fixed"] = []
    data["supports"]["roller"] = [{"nodes": [2, 3, 4], "normal": [0, 0, 1]}]
    data["supports"]["spring"] = [{"nodes": [2, 3, 4], "stiffness": [1e4, 1e4, 0]}]
    data["geometry"].pop("fixed")
    r = _run(tmp_path, data)
    assert r.exit_code == 0, r.output


def test_form_finding_refuses_rollers_and_springs(tmp_path):
    data = copy.deepcopy(CABLE)
    data["formfind"] = {"force_density": 10.0}
    del data["geometry"]["length"]
    path = tmp_path / "ff.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["formfind", str(path), "-o", str(tmp_path / "found.h5")])
    assert r.exit_code == 2, r.output
    assert "the force density method holds fixed nodes only" in r.output


def test_a_cable_between_two_elastic_anchors_needs_no_pin(tmp_path):
    """supports.fixed = []: the cable's ends on springs only. By symmetry each anchor
    carries half the weight; the horizontal pulls are equal and opposite, and each
    anchor moves by its reaction over k. Without the springs: refused."""
    data = copy.deepcopy(CABLE)
    k = [5e3, 5e3, 2e4]
    data["supports"] = {"fixed": [], "spring": [{"nodes": ["start", "end"], "stiffness": k}]}
    r = _run(tmp_path, data)
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "out.h5") as h5:
        x, nodes = h5["result/x"][:], h5["mesh/nodes"][:]
        reaction, mass = h5["result/reaction"][:], h5["mesh/mass"][:]
        assert not h5["mesh/fixed"][:].any()
    weight = mass.sum() * G
    assert reaction[0, 2] == pytest.approx(weight / 2, rel=1e-7)
    assert reaction[-1, 2] == pytest.approx(weight / 2, rel=1e-7)
    assert reaction[0, 0] == pytest.approx(-reaction[-1, 0], rel=1e-7) and reaction[0, 0] < 0
    assert reaction[-1] == pytest.approx(-np.array(k) * (x[-1] - nodes[-1]), rel=1e-9)
    written = dumps_toml(parse_case(copy.deepcopy(data)).to_dict())
    assert "fixed = []" in written
    data["supports"] = {"fixed": []}
    out = _refused(tmp_path, data)
    assert "supports.fixed = []: must be a non-empty array of nodes ([] only where" in out
    # both ends on frictionless horizontal rollers: they slide together until the cable
    # hangs straight down from them (no horizontal tension is left to hold them apart)
    data["supports"]["roller"] = [{"nodes": ["start", "end"], "normal": [0, 0, 1]}]
    r = _run(tmp_path, data)
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "out.h5") as h5:
        x, reaction = h5["result/x"][:], h5["result/reaction"][:]
    # where they meet is not held: the cable may slide along the rollers as a whole (a
    # rigid translation the supports leave free; by symmetry the middle, 2.5 m, which
    # round-off may move along x): together, in the rollers' plane, within the span
    assert x[0] == pytest.approx(x[-1], abs=1e-6) and x[0][1:] == pytest.approx([0, 0], abs=1e-6)
    assert 0.0 < x[0, 0] < 5.0
    assert x[5, 2] == pytest.approx(-3.0, rel=1e-2)  # half the length below, stretched
    assert np.abs(reaction[[0, -1]] - [0.0, 0.0, weight / 2]).max() < 1e-6 * weight
