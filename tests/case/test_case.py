"""Case files: loading, overrides, validation (every problem with its key path), the memory
guard, the TOML round trip and building scenes of each geometry kind."""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import tomllib
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from catenet import case as C
from catenet.case import (
    Case,
    GeometryConfig,
    SquareNetConfig,
    apply_overrides,
    build,
    guard,
    load_case,
    parse_case,
    readme,
)
from catenet.case.keys import declared, integer, real
from catenet.case.kinds.base import Built, Topology, resolve
from catenet.errors import ConfigError
from catenet.model import builders as geo

# --------------------------------------------------------------------------- fixtures


def cable_dict() -> dict:
    return {
        "title": "a cable",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 11},
        "material": {"E": 1e9, "radius": 0.001, "density": 7800.0},
        "load": {"gravity": [0, 0, -9.81], "point": [{"node": "midpoint", "force": [0, 0, -1]}]},
        "solver": {"method": "dynamic", "dt": 0.01, "t_end": 1.0},
    }


def static_cable_dict() -> dict:
    """The cable, solved statically (where a net needs a support)."""
    return {**cable_dict(), "solver": {"method": "static"}}


def test_a_dynamic_cable_may_fly_free_with_no_support():
    """supports.fixed = [] holds no node: refused in a static run (nothing holds the
    net), accepted in a dynamic one, where a net may fly free (docs/reference/contract.md);
    its nodes then all move."""
    case = {**cable_dict(), "supports": {"fixed": []}}
    del case["load"]
    scene = build(parse_case(case))
    assert not scene.net.fixed.any()


def square_dict() -> dict:
    return {
        "geometry": {
            "kind": "square_net",
            "n": 2,
            "alpha": 0.3,
            "size": 1.0,
            "edge_length": 0.25,
        },
        "material": {"E": 10e6, "radius": 0.01},
        "load": {"pressure": 100.0},
    }


def graph_dict() -> dict:
    # A triangle pinned at two corners, plus a tail node hanging from the third.
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 1, -1]],
            "edges": [[0, 1], [1, 2], [2, 0], [2, 3]],
            "fixed": [0, 1],
        },
        "material": {"EA": 1000.0},
        "load": {"point": [{"node": 3, "force": [0, 0, -5]}]},
    }


def problems(data: dict, **kwargs) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_case(data, **kwargs)
    return info.value.problems


def one_problem(data: dict, *needles: str) -> str:
    found = problems(data)
    assert len(found) == 1, found
    for needle in needles:
        assert needle in found[0], found
    return found[0]


def mutate(data: dict, path: str, value) -> dict:
    """Set (or with value DELETE, remove) the dotted path in a copy of data."""
    out = copy.deepcopy(data)
    parts = path.split(".")
    cur = out
    for p in parts[:-1]:
        cur = cur[int(p)] if isinstance(cur, list) else cur.setdefault(p, {})
    if value is DELETE:
        del cur[parts[-1]]
    elif isinstance(cur, list):
        cur[int(parts[-1])] = value
    else:
        cur[parts[-1]] = value
    return out


class _Delete:
    """Marks a key to remove; its repr is stable, so test ids match across workers."""

    def __repr__(self):
        return "DELETE"


DELETE = _Delete()


# --------------------------------------------------------------------------- default case


def test_default_case_is_the_papers_densest_net():
    case = load_case(None)
    g = case.geometry
    assert isinstance(g, SquareNetConfig)
    assert (g.n, g.alpha, g.size, g.edge_length) == (34, math.pi / 4, 1.0, 0.01)
    m = case.material
    assert (m.E, m.radius, m.density, m.tension_only) == (10e6, 0.01, 1000.0, True)
    assert case.load.pressure == 100.0 and case.load.gravity is None
    assert case.solver.method == "static"
    assert (case.output.file, case.output.every, case.output.xdmf) == ("out/default.h5", 1, True)


def test_default_case_builds_about_9500_free_dofs():
    scene = build(load_case(None))
    net = scene.net
    free_dofs = 3 * int((~net.fixed).sum())
    assert 9000 < free_dofs < 10000
    assert scene.size == 1.0
    # The probe is the joint at the centre (m = 17 is odd).
    assert np.allclose(net.nodes[scene.probe], 0.0)
    # The pressure totals -p L^2, spread equally.
    assert np.allclose(scene.loads.force.sum(axis=0), [0, 0, -100.0])
    assert scene.loads.gravity is None and scene.loads.support_displacement is None


# --------------------------------------------------------------------------- files


def test_malformed_toml_names_file_line_and_column(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[geometry]\nkind = "cable"\nnodes = = 3\n')
    with pytest.raises(ConfigError) as info:
        load_case(path)
    (msg,) = info.value.problems
    assert str(path) in msg and "line 3" in msg and "column" in msg


def test_unterminated_toml_at_end_of_document(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('title = "never closed')
    msg = str(pytest.raises(ConfigError, load_case, path).value)
    assert str(path) in msg and "line 1" in msg


def test_missing_file_and_directory(tmp_path):
    missing = tmp_path / "nope.toml"
    assert str(missing) in str(pytest.raises(ConfigError, load_case, missing).value)
    assert "directory" in str(pytest.raises(ConfigError, load_case, tmp_path).value)


def test_a_bad_unit_system_is_named_by_its_own_key(tmp_path):
    """``units`` is a top-level key: its message names ``units``, in the file and from
    --set (never a made-up path such as SI.units)."""
    path = tmp_path / "units.toml"
    path.write_text(C.dumps_toml({**cable_dict(), "units": "kN-mm"}))
    need = "units = 'kN-mm': must be one of 'SI', 'kN-m', 'N-mm'"
    assert str(pytest.raises(ConfigError, load_case, path).value) == need
    path.write_text(C.dumps_toml(cable_dict()))
    assert str(pytest.raises(ConfigError, load_case, path, ["units=kN-mm"]).value) == need


def test_not_utf8(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'title = "caf\xe9"\n')
    msg = str(pytest.raises(ConfigError, load_case, path).value)
    assert "UTF-8" in msg and "line 1" in msg


def test_output_file_defaults_to_case_stem(tmp_path):
    path = tmp_path / "my_net.toml"
    path.write_text(C.dumps_toml(graph_dict()))
    assert load_case(path).output.file == "out/my_net.h5"
    assert parse_case(graph_dict()).output.file == "out/case.h5"


# --------------------------------------------------------------------------- overrides


def test_overrides_parse_toml_values_else_strings():
    data = apply_overrides(
        cable_dict(),
        [
            "geometry.nodes=21",
            "solver.method=static",
            "solver.rtol = 1e-6",
            "geometry.end=[2, 0, 0]",
            "material.tension_only=false",
            'title="quoted"',
            "output.file=out/x.h5",
            "load.point.0.node=3",
            "load.point.1.node=end",
            "load.point.1.force=[1,0,0]",
            "new.table.key=1",
        ],
    )
    assert data["geometry"]["nodes"] == 21
    assert data["solver"]["method"] == "static"
    assert data["solver"]["rtol"] == 1e-6
    assert data["geometry"]["end"] == [2, 0, 0]
    assert data["material"]["tension_only"] is False
    assert data["title"] == "quoted"
    assert data["output"]["file"] == "out/x.h5"
    assert data["load"]["point"][0] == {"node": 3, "force": [0, 0, -1]}
    assert data["load"]["point"][1] == {"node": "end", "force": [1, 0, 0]}
    assert data["new"] == {"table": {"key": 1}}


def test_overrides_create_arrays_of_tables():
    data = apply_overrides(
        square_dict(), ["load.point.0.node=center", "load.point.0.force=[0,0,-1]"]
    )
    assert data["load"]["point"] == [{"node": "center", "force": [0, 0, -1]}]
    assert parse_case(data).load.points[0].node == "center"


def test_an_override_may_index_an_array_of_tables_in_brackets():
    """``obstacle[1].friction`` as ``obstacle.1.friction`` (a newcomer wrote the first and
    was told the key was unknown); a bracket that is not an index stays part of the key."""
    base = {"obstacle": [{"kind": "plane"}, {"kind": "box"}]}
    data = apply_overrides(base, ["obstacle[1].friction=0.3", "obstacle[ 0 ].distance=0.01"])
    assert data["obstacle"] == [
        {"kind": "plane", "distance": 0.01},
        {"kind": "box", "friction": 0.3},
    ]
    assert apply_overrides({}, ["a[x].b=1"]) == {"a[x]": {"b": 1}}
    with pytest.raises(ConfigError, match="needs an index 0..2") as caught:
        apply_overrides(base, ["obstacle[5].friction=0.3"])
    assert "(the case's last is obstacle[1]; obstacle[2] adds a new one)" in str(caught.value)
    with pytest.raises(ConfigError, match=r"an array of 1 table: obstacle.2 needs an index 0..1"):
        apply_overrides({"obstacle": [{"kind": "plane"}]}, ["obstacle[2].friction=0.3"])


def test_an_override_past_the_last_table_says_it_added_one(tmp_path):
    """``--set 'obstacle[2].friction=0.2'`` on a case with two obstacles adds a third,
    which has no kind: the error says so and names the two the case has (a newcomer read
    only "obstacle[2].kind: missing")."""
    data = cable_dict()
    data["obstacle"] = [
        {"kind": "plane", "point": [0, 0, -1], "normal": [0, 0, 1]},
        {"kind": "plane", "point": [0, 0, -2], "normal": [0, 0, 1]},
    ]
    path = tmp_path / "c.toml"
    path.write_text(C.dumps_toml(data))
    with pytest.raises(ConfigError) as info:
        load_case(path, ["obstacle[2].friction=0.2"])
    text = str(info.value)
    assert "obstacle[2].kind" in text
    assert (
        "obstacle[2]: a new table that --set added (the case has 2, obstacle[0] to obstacle[1])"
        in text
    )
    load_case(path, ["obstacle[1].friction=0.2"])  # an existing one: no problem


def test_overrides_leave_the_input_alone():
    data = cable_dict()
    apply_overrides(data, ["geometry.nodes=3"])
    assert data == cable_dict()


def test_override_value_cannot_smuggle_keys():
    data = apply_overrides({}, ["title=1\nsolver = 2"])
    assert data == {"title": "1\nsolver = 2"}


def test_malformed_overrides_are_all_reported():
    with pytest.raises(ConfigError) as info:
        apply_overrides(
            cable_dict(), ["geometry.nodes", "title.x=1", "a..b=1", "load.point.7.node=1"]
        )
    p = info.value.problems
    assert len(p) == 4
    assert "'geometry.nodes'" in p[0] and "key.path=value" in p[0]
    assert "title" in p[1] and "not a table" in p[1] and "title.x" in p[1]
    assert "empty part" in p[2]
    assert "load.point" in p[3] and "index" in p[3]


def test_load_case_applies_overrides_before_validation(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(C.dumps_toml(cable_dict()))
    case = load_case(path, ["geometry.nodes=5", "solver.method=static"])
    assert case.geometry.nodes == 5 and case.solver.method == "static"
    with pytest.raises(ConfigError, match="solver.method = 'dynamc'"):
        load_case(path, ["solver.method=dynamc"])


# --------------------------------------------------------------------------- validation

BAD_VALUES = [
    # (base, path, value, expected text in the one message)
    (square_dict, "geometry.n", 3, "geometry.n = 3: must be an even integer >= 2"),
    (square_dict, "geometry.n", 0, "geometry.n = 0: must be an even integer >= 2"),
    (square_dict, "geometry.n", 2.5, "geometry.n = 2.5: must be an even integer"),
    (square_dict, "geometry.n", True, "geometry.n = true: must be an even integer"),
    (square_dict, "geometry.n", "34", "geometry.n = '34': must be an even integer"),
    (square_dict, "geometry.alpha", math.nan, "geometry.alpha = nan: must be finite"),
    (square_dict, "geometry.size", -1.0, "geometry.size = -1.0: must be finite and > 0"),
    (square_dict, "geometry.size", math.inf, "geometry.size = inf: must be finite and > 0"),
    (square_dict, "geometry.edge_length", 0, "geometry.edge_length = 0: must be finite and > 0"),
    (square_dict, "geometry.prestrain", -1.0, "geometry.prestrain = -1.0: must be finite and > -1"),
    (square_dict, "geometry.kind", "sqare_net", "geometry.kind = 'sqare_net': must be one of"),
    (square_dict, "geometry.kind", DELETE, "geometry.kind: missing"),
    (square_dict, "geometry.size", DELETE, "geometry.size: missing"),
    (square_dict, "geometry", DELETE, "geometry: missing"),
    (square_dict, "geometry", 3, "geometry = 3: must be a table"),
    (square_dict, "geometry.start", [0, 0, 0], "geometry.start: unknown key for kind 'square_net'"),
    (cable_dict, "geometry.start", [0, 0], "geometry.start = [0, 0]: must be [x, y, z]"),
    (cable_dict, "geometry.start", [0, 0, "a"], "geometry.start = [0, 0, 'a']: must be [x, y, z]"),
    (cable_dict, "geometry.end", [0, 0, math.inf], "geometry.end = [0, 0, inf]: must be [x, y, z]"),
    (
        cable_dict,
        "geometry.end",
        [0, 0, 0],
        "geometry.end = [0, 0, 0]: must differ from geometry.start",
    ),
    (cable_dict, "geometry.nodes", 1, "geometry.nodes = 1: must be an integer >= 2"),
    (cable_dict, "geometry.length", 0.0, "geometry.length = 0.0: must be finite and > 0"),
    (cable_dict, "geometry.prestrain", 0.1, "geometry.prestrain: unknown key for kind 'cable'"),
    (cable_dict, "material.E", -1.0, "material.E = -1.0: must be finite and > 0"),
    (cable_dict, "material.E", False, "material.E = false: must be a number"),
    (cable_dict, "material.E", "10e6", "material.E = '10e6': must be a number"),
    (cable_dict, "material.radius", DELETE, "material.E = 1000000000.0: needs a cross-section"),
    (
        cable_dict,
        "material.area",
        1e-6,
        "material.area = 1e-06: give material.radius or material.area",
    ),
    (cable_dict, "material.EA", 1e3, "material.EA = 1000.0: give material.E"),
    (cable_dict, "material.density", -1, "material.density = -1: must be finite and >= 0"),
    (
        cable_dict,
        "material.tension_only",
        "yes",
        "material.tension_only = 'yes': must be true or false",
    ),
    (cable_dict, "material", DELETE, "material: missing"),
    (
        cable_dict,
        "solver.method",
        "dynamc",
        "solver.method = 'dynamc': must be one of 'static', 'dynamic'",
    ),
    (cable_dict, "solver.dt", 0.0, "solver.dt = 0.0: must be finite and > 0"),
    (cable_dict, "solver.dt", 2.0, "solver.dt = 2.0: must be <= solver.t_end = 1.0"),
    (cable_dict, "solver.damping", -0.5, "solver.damping = -0.5: must be finite and >= 0"),
    (cable_dict, "solver.t_end", -1, "solver.t_end = -1: must be finite and > 0"),
    (cable_dict, "solver.rtol", 1.0, "solver.rtol = 1.0: must be finite and > 0 and < 1"),
    (
        cable_dict,
        "solver.linear",
        "mumps",
        "solver.linear = 'mumps': must be one of 'auto', 'pardiso', 'scipy'",
    ),
    (cable_dict, "solver.threads", 0, "solver.threads = 0: must be an integer >= 1"),
    (cable_dict, "solver.max_iter", 1.5, "solver.max_iter = 1.5: must be an integer >= 1"),
    (cable_dict, "solver.steps", 0, "solver.steps = 0: must be an integer >= 1"),
    (cable_dict, "solver", [1], "solver = [1]: must be a table"),
    (cable_dict, "output.file", "", "output.file = '': must be a non-empty string"),
    (cable_dict, "output.every", -1, "output.every = -1: must be an integer >= 0"),
    (cable_dict, "output.xdmf", 1, "output.xdmf = 1: must be true or false"),
    (cable_dict, "title", 5, "title = 5: must be a string"),
    (cable_dict, "load.gravity", [0, -9.81], "load.gravity = [0, -9.81]: must be [x, y, z]"),
    (
        cable_dict,
        "load.pressure",
        100.0,
        "load.pressure = 100.0: only for geometry.kind = 'square_net'",
    ),
    (cable_dict, "load.point", {"node": 1}, "load.point = {'node': 1}: must be an array of tables"),
    (
        cable_dict,
        "load.point.0.node",
        "center",
        "load.point[0].node = 'center': must be a node index or one of 'start', 'end', 'midpoint'",
    ),
    (cable_dict, "load.point.0.node", -1, "load.point[0].node = -1: must be a node index"),
    (cable_dict, "load.point.0.node", 11, "load.point[0].node = 11: must be a node index in 0..10"),
    (
        cable_dict,
        "load.point.0.force",
        [0, 0, math.nan],
        "load.point[0].force = [0, 0, nan]: must be [x, y, z]",
    ),
    (cable_dict, "load.point.0.force", DELETE, "load.point[0].force: missing"),
    (
        static_cable_dict,
        "supports.fixed",
        [],
        "supports.fixed = []: must be a non-empty array of nodes",
    ),
    (cable_dict, "supports.fixed", [0, "start"], "node 0 appears more than once"),
    (
        cable_dict,
        "supports.fixed",
        [0, 99],
        "supports.fixed[1] = 99: must be a node index in 0..10",
    ),
    (
        square_dict,
        "load.point",
        [{"node": "midpoint", "force": [0, 0, 1]}],
        "load.point[0].node = 'midpoint': must be a node index or one of 'center'",
    ),
    (
        square_dict,
        "load.point",
        [{"node": 10**6, "force": [0, 0, 1]}],
        "load.point[0].node = 1000000: must be a node index in 0..",
    ),
    (graph_dict, "material.EA", DELETE, "material: missing stiffness"),
    (graph_dict, "geometry.fixed", [0, 9], "geometry.fixed[1] = 9: must be a node index in 0..3"),
    (
        graph_dict,
        "geometry.fixed",
        [0, 0],
        "geometry.fixed = [0, 0]: node 0 appears more than once",
    ),
    (graph_dict, "geometry.fixed", DELETE, "geometry.fixed: missing or empty"),
    (graph_dict, "geometry.nodes.1", [1, 0], "geometry.nodes[1] = [1, 0]: must be [x, y, z]"),
    (
        graph_dict,
        "geometry.edges.3",
        [2, 2],
        "geometry.edges[3] = [2, 2]: an edge must join two different nodes",
    ),
    (
        graph_dict,
        "geometry.edges.3",
        [2, 9],
        "geometry.edges[3] = [2, 9]: node indices must be in 0..3",
    ),
    (
        graph_dict,
        "geometry.edges.3",
        [1, 0],
        "geometry.edges[3] = [1, 0]: repeats geometry.edges[0]",
    ),
    (graph_dict, "geometry.edges.3", [2, -1], "geometry.edges[3] = [2, -1]: must be [i, j]"),
    (graph_dict, "geometry.nodes.3", [0.5, 1, 0], "geometry.edges[3] = [2, 3]: zero length"),
    (
        graph_dict,
        "geometry.rest_length",
        [1, 1, 1],
        "geometry.rest_length = [1, 1, 1]: has 3 values: must have one per edge (4)",
    ),
    (graph_dict, "geometry.EA", [1, 1, 0, 1], "geometry.EA[2] = 0: must be finite and > 0"),
    (graph_dict, "geometry.n", 3, "geometry.n: unknown key for kind 'graph'"),
    (
        graph_dict,
        "load.point.0.node",
        "start",
        "load.point[0].node = 'start': must be a node index or one of 'center'",
    ),
]


@pytest.mark.parametrize(
    "base, path, value, expected",
    BAD_VALUES,
    ids=[f"{b.__name__}:{p}={v!r}"[:60] for b, p, v, _ in BAD_VALUES],
)
def test_each_mistake_gives_one_message_with_key_path_and_value(base, path, value, expected):
    one_problem(mutate(base(), path, value), expected)


@pytest.mark.parametrize(
    "base, path",
    [
        (cable_dict, "foo"),
        (cable_dict, "geometry.foo"),
        (cable_dict, "material.foo"),
        (cable_dict, "supports.foo"),
        (cable_dict, "load.foo"),
        (cable_dict, "load.point.0.foo"),
        (cable_dict, "solver.foo"),
        (cable_dict, "output.foo"),
    ],
)
def test_unknown_keys_at_every_level(base, path):
    msg = one_problem(mutate(base(), path, 1), "unknown key", "accepted:")
    shown = path.replace(".0.", "[0].")
    assert msg.startswith(f"{shown}: unknown key")


def test_unknown_key_inside_a_move_and_a_suggestion():
    data = cable_dict()
    data["supports"] = {"move": [{"node": "end", "displacement": [0, 0, 0], "durtion": 1.0}]}
    msg = one_problem(data, "supports.move[0].durtion: unknown key")
    assert "did you mean 'duration'" in msg


def test_all_mistakes_are_collected():
    data = cable_dict()
    data["material"]["E"] = -1.0
    data["solver"]["method"] = "dynamc"
    data["solver"]["rtol"] = 2
    data["output"] = {"every": -1, "colour": "red"}
    data["geometry"]["nodes"] = 1
    found = problems(data)
    assert len(found) == 6, found
    for text in [
        "material.E = -1.0",
        "solver.method = 'dynamc'",
        "solver.rtol = 2",
        "output.every = -1",
        "output.colour: unknown key",
        "geometry.nodes = 1",
    ]:
        assert any(text in p for p in found), (text, found)


def test_strings_must_be_unicode_text():
    one_problem(
        mutate(cable_dict(), "title", "caf\udce9"), "title = ", "must be valid Unicode text"
    )


def test_integral_floats_are_integers():
    case = parse_case(mutate(square_dict(), "geometry.n", 4.0))
    assert case.geometry.n == 4 and isinstance(case.geometry.n, int)


def test_material_choices():
    # EA alone is fine without mass; radius or area with E; area gives the mass.
    data = mutate(mutate(cable_dict(), "solver.method", "static"), "material", {"EA": 1e3})
    parse_case(mutate(data, "load.gravity", DELETE))
    one_problem(
        mutate(cable_dict(), "material", {"EA": 1e3, "density": 7800.0}),
        "material.density = 7800.0: mass needs a cross-section",
    )
    m = parse_case(mutate(cable_dict(), "material", {"EA": 5.0, "area": 2.0, "density": 3.0}))
    assert m.material.axial_stiffness == 5.0 and m.material.line_density == 6.0
    one_problem(
        mutate(cable_dict(), "material", {"density": 1.0, "area": 1.0}),
        "material: missing stiffness",
    )


def test_mass_is_needed_for_dynamics_and_gravity():
    data = mutate(cable_dict(), "material.density", 0.0)
    found = problems(data)
    assert len(found) == 2
    assert any(
        p.startswith("material.density = 0.0: solver.method = 'dynamic' needs mass") for p in found
    )
    assert any(p.startswith("load.gravity = [0, 0, -9.81]: gravity needs mass") for p in found)
    # no gravity, [0, 0, 0], is no load: it needs no mass (a static case, a load case)
    data = mutate(mutate(data, "load.gravity", [0, 0, 0]), "solver.method", "static")
    assert parse_case(data).material.density == 0.0
    data["load_case"] = [{"name": "none", "gravity": [0.0, 0, 0]}]
    assert parse_case(data).load_cases[0].name == "none"
    data["load_case"] = [{"name": "g", "gravity": [0, 0, -9.81]}]
    one_problem(data, "load_case[0].gravity = [0, 0, -9.81]: gravity needs mass")


def test_pressure_zero_is_accepted_for_every_kind():
    parse_case(mutate(cable_dict(), "load.pressure", 0.0))


def test_moves_must_be_of_fixed_nodes():
    data = cable_dict()
    data["supports"] = {"move": [{"node": "midpoint", "displacement": [0, 0, 1]}]}
    one_problem(data, "supports.move[0].node = 'midpoint' (node 5): is not a fixed node")
    data["supports"] = {
        "move": [
            {"node": "end", "displacement": [-0.1, 0, 0], "duration": 2.0},
            {"node": 10, "displacement": [0, 0, 0]},
        ]
    }
    one_problem(data, "supports.move[1].node = 10: node 10 already moves in supports.move[0]")
    data["supports"] = {"fixed": [0, 5], "move": [{"node": 5, "displacement": [0, 0, 1]}]}
    parse_case(data)
    data = square_dict()
    data["supports"] = {"move": [{"node": "center", "displacement": [0, 0, 1]}]}
    one_problem(data, "supports.move[0].node = 'center'", "is not a fixed node")


def test_graph_net_level_problems_carry_key_paths():
    # A node on no edge and a part without support (edge 2-3 is not pinned).
    data = graph_dict()
    data["geometry"]["nodes"].append([5, 5, 5])
    data["geometry"]["edges"] = [[0, 1], [2, 3]]
    data["load"] = {}
    found = problems(data)
    assert any("geometry: nodes [4]: belong to no edge" in p for p in found), found
    assert any("geometry: nodes [2, 3]" in p and "no support" in p for p in found), found


def test_graph_supports_fixed_replaces_geometry_fixed():
    data = graph_dict()
    data["supports"] = {"fixed": ["center", 0]}
    case = parse_case(data)
    scene = build(case)
    assert scene.net.fixed.tolist() == [True, False, True, False]


def test_prestrain_and_rest_length_exclude_each_other():
    data = graph_dict()
    data["geometry"]["rest_length"] = [1, 1, 1, 1]
    data["geometry"]["prestrain"] = 0.01
    one_problem(data, "geometry.prestrain = 0.01: give geometry.rest_length or geometry.prestrain")


def test_pardiso_unavailable_is_reported(monkeypatch):
    import catenet.solver.linear as ls

    monkeypatch.setattr(ls, "pardiso_available", lambda: False)
    one_problem(
        mutate(cable_dict(), "solver.linear", "pardiso"),
        "solver.linear = 'pardiso'",
        "not available",
    )


# --------------------------------------------------------------------------- JSON graphs


def write_graph(tmp_path, obj, name="net.json"):
    path = tmp_path / name
    path.write_text(obj if isinstance(obj, str) else json.dumps(obj))
    return path


def test_graph_from_json_relative_to_the_case_file(tmp_path):
    g = graph_dict()["geometry"]
    sub = tmp_path / "cases"
    sub.mkdir()
    write_graph(sub, {k: g[k] for k in ("nodes", "edges", "fixed")})
    case_file = sub / "g.toml"
    data = graph_dict()
    data["geometry"] = {"kind": "graph", "file": "net.json", "prestrain": 0.01}
    case_file.write_text(C.dumps_toml(data))
    case = load_case(case_file)
    assert case.geometry.file == "net.json"
    assert case.geometry.edges == ((0, 1), (1, 2), (2, 0), (2, 3))
    # The resolved case holds the data itself: it reads back without the file.
    resolved = case.to_dict()["geometry"]
    assert "file" not in resolved and resolved["nodes"][3] == [0.5, 1.0, -1.0]
    assert parse_case(tomllib.loads(case.to_toml())) == case
    scene = build(case)
    assert np.allclose(scene.net.rest_length[0], 1 / 1.01)


@pytest.mark.parametrize(
    "content, expected",
    [
        (None, "geometry.file = 'net.json': no such file"),
        ('{"nodes": [[0, 0, 0],', "geometry.file = 'net.json': not valid JSON"),
        ("[1, 2]", "geometry.file = 'net.json': must hold a JSON object"),
        (
            {"nodes": [[0, 0, 0], [1, 0, 0]], "edges": [[0, 1]], "fixed": [0], "colour": 1},
            "geometry.colour: unknown key in a graph file",
        ),
        (
            {"nodes": [[0, 0, 0], [1, 0, 0]], "edges": [[0, 0]], "fixed": [0]},
            "geometry.edges[0] = [0, 0]: an edge must join two different nodes "
            "(in geometry.file = 'net.json')",
        ),
    ],
)
def test_graph_file_problems(tmp_path, content, expected):
    if content is not None:
        write_graph(tmp_path, content)
    data = graph_dict()
    data["geometry"] = {"kind": "graph", "file": "net.json"}
    data["load"] = {}
    found = problems(data, base_dir=tmp_path)
    assert len(found) == 1 and expected in found[0], found


def test_graph_file_and_inline_data_exclude_each_other(tmp_path):
    data = graph_dict()
    data["geometry"]["file"] = "net.json"
    one_problem(data, "geometry.nodes: give the graph in geometry.file or inline, not both")


# --------------------------------------------------------------------------- memory guard


def test_memory_guard_refuses_a_net_too_fine_for_this_machine():
    data = mutate(square_dict(), "geometry.edge_length", 1e-7)
    msg = one_problem(data, "geometry.edge_length = 1e-07: the net would have about", "GiB")
    assert "this machine has" in msg


def test_memory_guard_uses_physical_memory(monkeypatch):
    monkeypatch.setattr(guard, "physical_memory", lambda: 2**12)  # 4 KiB
    one_problem(
        square_dict(), "geometry.edge_length = 0.25", "need about", "this machine has 0 GiB"
    )
    monkeypatch.setattr(guard, "physical_memory", lambda: None)  # unknown: only the hard cap
    parse_case(square_dict())


def test_hard_cap_on_nodes_before_building():
    one_problem(
        mutate(cable_dict(), "geometry.nodes", 10**12), "geometry.nodes = 1000000000000", "at most"
    )
    one_problem(
        mutate(square_dict(), "geometry.n", 2 * 10**9), "geometry.n = 2000000000", "at most"
    )


def test_estimates_follow_the_built_net():
    for n, el in [(34, 0.01), (10, 0.05), (2, 1.0)]:
        cfg = SquareNetConfig(n=n, alpha=math.pi / 4, size=1.0, edge_length=el)
        nodes, edges, _, _ = C.estimate_size(cfg)
        net = geo.square_net(n, math.pi / 4, 1.0, el, geo.Material(EA=1.0)).net
        assert net.n_edges <= edges <= 1.3 * net.n_edges + 2 * n
        assert net.n_nodes <= nodes
    # The default case needs well under a gigabyte.
    assert C.estimate_memory(*C.estimate_size(load_case(None).geometry)[:3]) < 2**30


# --------------------------------------------------------------------------- round trip


def full_graph_dict() -> dict:
    data = graph_dict()
    data["title"] = 'quotes " and \\ backslash\nnew line\ttab \x01 ünïcode'
    data["geometry"]["rest_length"] = [1.0, 1.1, 1.2, 0.9]
    data["geometry"]["EA"] = [1e3, 2e3, 3e3, 4e3]
    data["material"] = {"E": 2e11, "area": 1e-6, "density": 7850.0, "tension_only": False}
    data["supports"] = {
        "fixed": [0, 1, "center"],
        "move": [{"node": 1, "displacement": [0.1, 0, 0], "duration": 0.5}],
    }
    data["load"] = {
        "gravity": [0, 0, -9.81],
        "point": [{"node": 3, "force": [0, 0, -5]}, {"node": "center", "force": [1e-300, 0, 3]}],
    }
    data["solver"] = {"method": "dynamic", "dt": 1 / 3, "t_end": 10.0, "linear": "scipy"}
    data["output"] = {"file": "out/ü dir/g.h5", "every": 0, "xdmf": False}
    return data


@pytest.mark.parametrize("make", [cable_dict, square_dict, graph_dict, full_graph_dict])
def test_to_toml_round_trips(make):
    case = parse_case(make())
    text = case.to_toml()
    again = parse_case(tomllib.loads(text))
    assert again == case
    assert again.to_toml() == text
    assert tomllib.loads(text) == case.to_dict()


def test_round_trip_of_the_default_case():
    case = load_case(None)
    assert parse_case(tomllib.loads(case.to_toml())) == case


def test_to_dict_fills_every_default():
    d = parse_case(square_dict()).to_dict()
    # t_end: a static case has none; a dynamic one's default depends on the case
    # (tests/case/test_t_end.py): "rest" here, where nothing depends on time
    assert d["solver"] == {
        "method": "static",
        "dt": 1e-2,
        "damping": 1.0,
        "rtol": 1e-8,
        "linear": "auto",
        "threads": 1,
        "max_iter": 200,
        "steps": 1,
    }
    dynamic = {**square_dict(), "solver": {"method": "dynamic"}}
    dynamic["material"] = {**dynamic["material"], "density": 1000.0}
    assert parse_case(dynamic).to_dict()["solver"]["t_end"] == "rest"
    assert d["geometry"]["prestrain"] == 0.0
    assert d["material"] == {"E": 10e6, "radius": 0.01, "density": 0.0, "tension_only": True}
    assert d["output"] == {"file": "out/case.h5", "every": 1, "xdmf": True}
    assert d["title"] == ""
    c = parse_case(cable_dict()).to_dict()
    assert c["geometry"]["length"] == 1.0 and "pressure" not in c["load"]


# --------------------------------------------------------------------------- build


def test_build_cable():
    data = cable_dict()
    data["geometry"]["length"] = 1.2
    data["supports"] = {"move": [{"node": "end", "displacement": [-0.2, 0, 0], "duration": 0.5}]}
    data["load"]["point"].append({"node": 5, "force": [0, 0, -2]})
    scene = build(parse_case(data))
    net = scene.net
    assert (net.n_nodes, net.n_edges) == (11, 10)
    assert np.allclose(net.rest_length, 0.12)
    assert scene.probe == 5 and scene.size == 1.0
    # Two point loads on the midpoint add up.
    assert (
        np.allclose(scene.loads.force[5], [0, 0, -3]) and np.count_nonzero(scene.loads.force) == 1
    )
    assert isinstance(scene.loads.gravity, np.ndarray)
    assert np.allclose(scene.loads.gravity, [0, 0, -9.81])
    assert np.allclose(scene.loads.support_displacement[10], [-0.2, 0, 0])
    assert scene.loads.ramp_time[10] == 0.5 and scene.loads.settle_time() == 0.5
    assert np.allclose(net.mass.sum(), 7800 * math.pi * 1e-6 * 1.2)


def test_build_cable_with_even_nodes_midpoint_and_own_supports():
    data = mutate(cable_dict(), "geometry.nodes", 10)
    data["supports"] = {"fixed": ["start"]}
    scene = build(parse_case(data))
    assert scene.probe == 4
    assert scene.net.fixed.tolist() == [True] + [False] * 9


def test_build_square_net_with_prestrain_and_no_gravity():
    data = mutate(square_dict(), "geometry.prestrain", 0.01)
    plain = build(parse_case(square_dict()))
    scene = build(parse_case(data))
    assert scene.net.n_nodes == plain.net.n_nodes
    assert np.allclose(scene.net.rest_length * 1.01, plain.net.rest_length)
    assert scene.loads.gravity is None
    assert np.allclose(scene.loads.force.sum(axis=0), [0, 0, -100.0])
    assert scene.size == 1.0 and np.allclose(scene.net.nodes[scene.probe], 0)


def test_build_graph():
    scene = build(parse_case(graph_dict()))
    net = scene.net
    assert (net.n_nodes, net.n_edges) == (4, 4)
    assert net.fixed.tolist() == [True, True, False, False]
    assert np.allclose(net.EA, 1000.0)
    assert scene.probe == 2  # nearest the bounding-box centre (0.5, 0.5, -0.5)
    assert np.isclose(scene.size, math.sqrt(3))
    assert scene.loads.force[3, 2] == -5.0


def test_build_graph_with_per_edge_EA_and_mass():
    data = full_graph_dict()
    data["supports"] = {"fixed": [0, 1]}
    scene = build(parse_case(data))
    assert np.allclose(scene.net.EA, [1e3, 2e3, 3e3, 4e3])
    assert np.allclose(scene.net.rest_length, [1.0, 1.1, 1.2, 0.9])
    assert np.isclose(scene.net.mass.sum(), 7850 * 1e-6 * 4.2)
    assert scene.net.tension_only is False


# --------------------------------------------------------------------------- properties

GARBAGE = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.floats(),
    st.sampled_from([0, -1, 1, 2, 1e308, -1e-308, math.nan, math.inf, -math.inf, 10**30]),
    st.text(max_size=12),
    st.sampled_from(["", "center", "start", "end", "midpoint", "static", "dynamic", "scipy"]),
    st.lists(st.floats(), max_size=4),
    st.lists(st.integers(min_value=-3, max_value=12), max_size=4),
    st.lists(st.lists(st.integers(-2, 5), max_size=3), max_size=4),
    st.dictionaries(st.text(max_size=6), st.integers(), max_size=3),
    st.lists(st.dictionaries(st.sampled_from(["node", "force", "x"]), st.integers()), max_size=2),
)


def _paths(obj, prefix=()):
    """Every path to a value in nested dicts and lists."""
    out = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            out.append((*prefix, k))
            out.extend(_paths(v, (*prefix, k)))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out.append((*prefix, i))
            out.extend(_paths(v, (*prefix, i)))
    return out


def _tables(obj, prefix=()):
    out = [prefix] if isinstance(obj, dict) else []
    if isinstance(obj, (dict, list)):
        items = obj.items() if isinstance(obj, dict) else enumerate(obj)
        for k, v in items:
            out.extend(_tables(v, (*prefix, k)))
    return out


def _at(obj, path):
    for p in path:
        obj = obj[p]
    return obj


SOLVER_KEYS = [k.name for k in declared(C.SolverConfig)]


@st.composite
def mutated_cases(draw):
    base = draw(st.sampled_from([cable_dict, square_dict, graph_dict, full_graph_dict]))()
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["replace", "replace", "delete", "add"]))
        paths = _paths(base)
        if op in ("replace", "delete") and paths:
            path = draw(st.sampled_from(paths))
            parent = _at(base, path[:-1])
            if op == "replace":
                parent[path[-1]] = draw(GARBAGE)
            elif isinstance(parent, dict):
                del parent[path[-1]]
            else:
                parent.pop(path[-1])
        else:
            table = _at(base, draw(st.sampled_from(_tables(base))))
            key = draw(st.one_of(st.text(max_size=8), st.sampled_from(SOLVER_KEYS)))
            table[key] = draw(GARBAGE)
    return base


@settings(max_examples=150, deadline=None)
@given(mutated_cases())
def test_mutated_cases_parse_or_raise_config_error(data):
    try:
        case = parse_case(data)
    except ConfigError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
        return
    assert isinstance(case, Case)
    assert parse_case(tomllib.loads(case.to_toml())) == case


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.sampled_from(
            ["solver.method=", "geometry.n=", "x", "=", ".", "[", "1", "a.b=", "load.point.0.node="]
        ),
        max_size=6,
    ).map("".join)
)
def test_random_overrides_apply_or_raise_config_error(text):
    try:
        data = apply_overrides(square_dict(), [text])
        parse_case(data)
    except ConfigError:
        pass


@settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    st.one_of(
        st.binary(max_size=200),
        st.text(alphabet='[]="\\.,#\n abc123{}', max_size=80).map(str.encode),
    )
)
def test_garbage_files_give_config_error(tmp_path, raw):
    path = tmp_path / "garbage.toml"
    path.write_bytes(raw)
    with pytest.raises(ConfigError):
        load_case(path)


def test_a_sweep_table_is_left_to_catenet_sweep(tmp_path):
    path = tmp_path / "study.toml"
    path.write_text(
        '[geometry]\nkind = "square_net"\nn = 10\nalpha = 0.0\nsize = 1.0\nedge_length = 0.1\n'
        "[material]\nE = 10e6\nradius = 0.01\n[load]\npressure = 10.0\n"
        '[sweep]\n"geometry.n" = [10, 18]\n'
    )
    case = load_case(path)
    assert case.geometry.n == 10
    text = path.read_text().replace('[sweep]\n"geometry.n" = [10, 18]\n', "")
    path.write_text("sweep = 3\n" + text)
    with pytest.raises(ConfigError, match="sweep = 3"):
        load_case(path)


# --------------------------------------------------------------------------- declarations


def test_readme_table_of_keys_is_generated_from_the_declarations():
    """The table of case keys in docs/reference/case-keys.md is what the declarations give
    (regenerate it with `python -m catenet.case.readme`)."""
    page = Path(__file__).resolve().parents[2] / "docs" / "reference" / "case-keys.md"
    text = page.read_text(encoding="utf-8")
    assert readme.readme_table(text) == readme.section_text()


@dataclasses.dataclass(frozen=True)
class RingConfig(GeometryConfig):
    """A toy kind for the test below: ``nodes`` nodes on a circle of ``radius`` in the
    xy-plane, joined in a loop, nodes 0 and nodes/2 pinned."""

    kind: ClassVar[str] = "ring"
    node_names: ClassVar[tuple[str, ...]] = ("top",)
    default_supports: ClassVar[str] = "nodes 0 and nodes/2"

    radius: float = real(gt=0, missing="the radius [m]", unit="m", doc="radius")
    nodes: int = integer(8, ge=4, even=True, doc="node count")

    def estimate_size(self):
        return float(self.nodes), float(self.nodes), 0.0, "geometry.nodes"

    def topology(self):
        n = self.nodes
        return Topology(n, frozenset({0, n // 2}), {"top": n // 4})

    def build(self, material, fixed):
        n = self.nodes
        t = 2 * np.pi * np.arange(n) / n
        xyz = self.radius * np.column_stack([np.cos(t), np.sin(t), np.zeros(n)])
        edges = [(i, (i + 1) % n) for i in range(n)]
        names = {"top": n // 4}
        pinned = [0, n // 2] if fixed is None else [resolve(r, names) for r in fixed]
        return Built(geo.graph(xyz, edges, pinned, material), n // 4, 2 * self.radius, names)


def test_a_new_geometry_kind_is_one_class_and_its_registration(monkeypatch):
    """What the registry promises: a kind registered by name is parsed (with the usual
    messages), guarded, written back, built and documented without any other change."""
    monkeypatch.setitem(C.KINDS, "ring", RingConfig)
    data = {
        "geometry": {"kind": "ring", "radius": 2.0},
        "material": {"EA": 100.0},
        "load": {"point": [{"node": "top", "force": [0, 0, -1]}]},
    }
    case = parse_case(data)
    assert case.geometry == RingConfig(radius=2.0, nodes=8)
    assert parse_case(tomllib.loads(case.to_toml())) == case
    assert "pressure" not in case.to_dict()["load"]
    scene = build(case)
    assert (scene.net.n_nodes, scene.probe, scene.size) == (8, 2, 4.0)
    assert scene.loads.force[2, 2] == -1.0
    one_problem(mutate(data, "geometry.nodes", 5), "geometry.nodes = 5: must be an even integer")
    one_problem(mutate(data, "geometry.radius", DELETE), "geometry.radius: missing: the radius")
    one_problem(mutate(data, "geometry.raduis", 1), "did you mean 'radius'?")
    one_problem(mutate(data, "load.point.0.node", 8), "load.point[0].node = 8: must be a node")
    one_problem(mutate(data, "load.pressure", 1.0), "only for geometry.kind = 'square_net'")
    assert "| `geometry.radius` |" in readme.keys_table()


@settings(max_examples=300, deadline=None)
@given(st.floats(allow_nan=False), st.lists(st.lists(st.floats(allow_nan=False), max_size=3)))
def test_toml_writer_keeps_every_float_bit_for_bit(x, nested):
    back = tomllib.loads(C.dumps_toml({"x": x, "t": {"nested": nested}}))
    assert math.copysign(1.0, back["x"]) == math.copysign(1.0, x) and back["x"] == x
    assert back["t"]["nested"] == nested
    assert math.isnan(tomllib.loads(C.dumps_toml({"x": math.nan}))["x"])


def test_an_array_of_tables_is_asked_for_by_its_toml_header():
    """A nested array of tables written as a table is told the TOML header that makes it
    one: [[load_case.area]] after its [[load_case]] (it said [[load_case[0].area]], no
    TOML); a top-level one by its own name."""
    from catenet.case.keys import Checker

    ck = Checker()
    assert ck.array_of_tables({"pressure": 1.0}, "load_case[0].area") == []
    assert ck.array_of_tables({"node": 1}, "load.point") == []
    assert ck.problems == [
        "load_case[0].area = {'pressure': 1.0}: must be an array of tables "
        "([[load_case.area]] after its [[load_case]])",
        "load.point = {'node': 1}: must be an array of tables ([[load.point]])",
    ]
