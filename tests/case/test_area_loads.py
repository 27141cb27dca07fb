"""[[load.area]] in case files: the paper's pressure on the square net, exact totals on a
hypar cable net and on a net read from a file, node sets by region (box, near,
cable:NAME) and the nodes they reach, load steps and time histories, bad input (exit 2,
the key path named)."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from click.testing import CliRunner
from meshes import hypar_roof

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.errors import ConfigError
from catenet.run.runner import run_case

SQUARE = {
    "geometry": {"kind": "square_net", "n": 10, "alpha": 0.4, "size": 2.0, "edge_length": 0.1},
    "material": {"E": 1e6, "radius": 0.01},
}


def force(data: dict, **kw) -> np.ndarray:
    loads = build(parse_case(data, **kw)).loads
    return np.zeros(0) if loads.force is None else loads.force


def with_area(data: dict, **area) -> dict:
    out = copy.deepcopy(data)
    out.setdefault("load", {})["area"] = [area]
    return out


def problems(data: dict, **kw) -> list[str]:
    with pytest.raises(ConfigError) as info:
        build(parse_case(data, **kw))
    return info.value.problems


def test_on_the_square_net_it_is_the_papers_pressure(tmp_path):
    """load.pressure shares p L^2 equally among the nodes (contract §2); an area load
    over the whole square net does the same, on plan and normal to the flat net."""
    paper = copy.deepcopy(SQUARE)
    paper["load"] = {"pressure": 150.0}
    for direction in ("plan", "normal"):
        area = with_area(SQUARE, pressure=150.0, direction=direction)
        assert np.array_equal(force(area), force(paper))
    a = run_case(parse_case(with_area(SQUARE, pressure=150.0)), tmp_path / "a.h5")
    b = run_case(parse_case(paper), tmp_path / "b.h5")
    assert np.array_equal(a.x, b.x) and a.report.delta == b.report.delta


@pytest.mark.parametrize("half, p", [(6.0, 800.0), (0.3, 2.5), (40.0, 1200.0)])
def test_on_a_hypar_cable_net_the_total_is_pressure_times_plan_area(half, p):
    data = hypar_roof(half=half, rise=half / 4, edge_length=half / 10)
    f = force(with_area(data, pressure=p))
    assert f[:, 2].sum() == pytest.approx(-p * (2 * half) ** 2, rel=1e-12, abs=0)
    assert np.all(f[:, :2] == 0.0)
    scene = build(parse_case(data))
    made = np.arange(scene.net.n_nodes) >= len(data["geometry"]["nodes"])
    assert np.all(f[made & ~scene.net.fixed, 2] < 0)  # the nodes that split cables carry some


def test_a_net_read_from_a_file_gives_the_same_loads(tmp_path):
    """The hypar's built net written as OBJ polylines and as a VTU line mesh, read back:
    the same nodal forces as the case with cables."""
    meshio = pytest.importorskip("meshio")
    data = hypar_roof(edge_length=0.5)
    net = build(parse_case(data)).net
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in net.nodes.tolist()]
    lines += [f"l {i + 1} {j + 1}" for i, j in net.edges.tolist()]
    (tmp_path / "roof.obj").write_text("\n".join(lines) + "\n")
    meshio.Mesh(net.nodes, [("line", net.edges)]).write(tmp_path / "roof.vtu")
    expect = force(with_area(data, pressure=800.0))
    for name in ("roof.obj", "roof.vtu"):
        read = {
            "geometry": {
                "kind": "graph",
                "file": name,
                "fixed": np.flatnonzero(net.fixed).tolist(),
            },
            "material": {"EA": 1e7},
            "load": {"area": [{"pressure": 800.0}]},
        }
        got = force(read, base_dir=tmp_path)
        assert got[:, 2].sum() == pytest.approx(-800.0 * 144.0, rel=1e-12, abs=0)
        assert np.allclose(got, expect, rtol=0, atol=1e-9 * 800.0)


def test_a_normal_pressure_on_a_flat_net_equals_the_plan_load():
    data = hypar_roof(rise=0.0, edge_length=0.5)
    plan = force(with_area(data, pressure=500.0))
    normal = force(with_area(data, pressure=500.0, direction="normal"))
    assert np.array_equal(plan, normal)


def test_wind_normal_to_the_hypar_pushes_each_node_along_the_surface_normal():
    data = hypar_roof(edge_length=0.5)
    f = force(with_area(data, pressure=-300.0, direction="normal"))  # suction
    assert f[:, 2].sum() == pytest.approx(300.0 * 144.0, rel=1e-12)
    assert np.abs(f[:, :2]).max() > 0  # inclined where the surface is


def test_a_node_set_covers_its_part_and_the_nodes_that_split_its_cables():
    data = hypar_roof(edge_length=0.5)
    data["geometry"]["sets"]["west"] = {"box": [[-6, -6, -10], [0, 6, 10]]}
    f = force(with_area(data, pressure=100.0, nodes="west"))
    assert f[:, 2].sum() == pytest.approx(-100.0 * 72.0, rel=1e-12)
    scene = build(parse_case(data))
    x = scene.net.nodes[:, 0]
    assert np.all(f[x > 1e-9] == 0.0) and np.all(f[(x < -1e-9) & ~scene.net.fixed, 2] < 0)
    # given nodes only: the chains between them are covered too
    given = [i for i, p in enumerate(data["geometry"]["nodes"]) if p[0] <= 0]
    assert np.array_equal(force(with_area(data, pressure=100.0, nodes=given)), f)


def test_load_steps_and_histories_scale_it(tmp_path):
    data = with_area(hypar_roof(edge_length=1.0), pressure=800.0)
    data["solver"] = {"steps": 3}
    res = run_case(parse_case(data), tmp_path / "s.h5")
    assert res.converged and res.steps == 3
    reaction = res.reaction[:, 2].sum()
    assert reaction == pytest.approx(800.0 * 144.0, rel=1e-9)
    data["load"]["area"][0]["history"] = [[0.0, 0.0], [1.0, 1.0]]
    loads = build(parse_case(data)).loads
    ((part, history),) = loads.parts
    assert loads.force is None and history(0.5) == 0.5
    assert part[:, 2].sum() == pytest.approx(-800.0 * 144.0, rel=1e-12)


# --------------------------------------------------------------------------- node sets


def test_box_near_and_cable_sets_reach_the_nodes_that_split_cables():
    data = hypar_roof(edge_length=0.5)
    data["geometry"]["sets"].update(
        {"strip": {"box": [[-0.1, -6, -5], [0.1, 6, 5]]}, "spot": {"near": [0.26, 0.1, 9]}}
    )
    data["supports"] = {"fixed": ["border"]}
    data["load"] = {"point": [{"node": "cable:x0", "force": [0, 0, -1]}]}
    scene = build(parse_case(data))
    nodes = scene.net.nodes
    strip = np.flatnonzero(np.abs(nodes[:, 0]) <= 0.1)
    given = len(data["geometry"]["nodes"])
    assert (strip >= given).any()  # nodes of cable y0 made by splitting it
    on_x0 = np.flatnonzero(scene.loads.force[:, 2] < 0)
    x0 = scene.net.edges[scene.cables.edge == scene.cables.names.index("x0")]
    assert np.array_equal(on_x0, np.unique(x0)) and np.allclose(nodes[on_x0, 1], 0.0)
    assert (on_x0 >= given).sum() == len(x0) - 6  # its 6 segments split
    data["output"] = {"probe": "spot"}
    assert build(parse_case(data)).probe == int(
        np.argmin(np.linalg.norm(nodes - [0.26, 0.1, 9], axis=1))
    )
    data["supports"] = {"fixed": ["strip"]}
    assert np.array_equal(np.flatnonzero(build(parse_case(data)).net.fixed), strip)


def test_sets_by_region_are_written_back():
    data = hypar_roof()
    del data["material"]["prestress"]  # (a resolved case writes geometry.prestrain)
    data["geometry"]["sets"]["corner"] = {"near": [6, 6, 0]}
    data["geometry"]["sets"]["west"] = {"box": [[-6, -6, -1], [-5, 6, 1]]}
    case = parse_case(data)
    import tomllib

    again = parse_case(tomllib.loads(case.to_toml()))
    assert again == case


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "change, message",
    [
        (
            lambda d: d["load"].update(area=[{"pressure": 1.0}]),
            "load.area[0] (on the whole net): covers no area: its nodes lie on a line",
        ),
    ],
)
def test_an_area_load_on_a_single_cable_is_refused(change, message, tmp_path):
    data = {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [4, 0, 0], "nodes": 5},
        "material": {"EA": 1e4},
        "load": {},
    }
    change(data)
    assert problems(data) == [message]
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "c.h5")])
    assert r.exit_code == 2 and message in r.output


def run_bad(tmp_path, data) -> str:
    path = tmp_path / "c.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "c.h5")])
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    return r.output


def test_a_node_set_that_covers_no_area_is_refused(tmp_path):
    data = with_area(hypar_roof(edge_length=0.5), pressure=1.0, nodes="line")
    data["geometry"]["sets"]["line"] = {"box": [[-7, -0.1, -9], [7, 0.1, 9]]}
    out = run_bad(tmp_path, data)
    assert "load.area[0].nodes = 'line': covers no area: its nodes lie on a line" in out


@pytest.mark.parametrize(
    "sets, area, message",
    [
        (
            {"none": {"box": [[10, 10, 0], [11, 11, 1]]}},
            {},
            "geometry.sets.none.box = [[10, 10, 0], [11, 11, 1]]: holds no node",
        ),
        ({"odd": {"box": [[0, 0, 0]]}}, {}, "geometry.sets.odd.box = [[0, 0, 0]]: must be"),
        ({"odd": {"near": [0, 0]}}, {}, "geometry.sets.odd.near = [0, 0]: must be [x, y, z]"),
        ({"odd": {"around": 1}}, {}, "geometry.sets.odd.around: unknown key of a region"),
        ({}, {"nodes": "nowhere"}, "load.area[0].nodes = 'nowhere': must be a node index or"),
        ({}, {"nodes": [0, 1]}, "load.area[0].nodes = [0, 1]: must be a node set"),
        ({}, {"direction": "up"}, "load.area[0].direction = 'up': must be one of 'plan', 'normal'"),
        ({}, {"pressure": "heavy"}, "load.area[0].pressure = 'heavy': must be a number"),
    ],
)
def test_bad_area_loads_and_regions_name_the_key(tmp_path, sets, area, message):
    data = with_area(hypar_roof(), **{"pressure": 1.0, **area})
    data["geometry"]["sets"].update(sets)
    assert message in run_bad(tmp_path, data)


def _grid_without_corners(n: int = 5, h: float = 1.0) -> dict:
    """A flat n x n grid whose cables run from border to border, its border nodes held:
    the grid's four corner nodes are joined by no edge."""
    at = [[i * h, j * h, 0.0] for j in range(n) for i in range(n)]
    edges = [[j * n + i, j * n + i + 1] for j in range(1, n - 1) for i in range(n - 1)]
    edges += [[j * n + i, (j + 1) * n + i] for i in range(1, n - 1) for j in range(n - 1)]
    border = [j * n + i for j in range(n) for i in range(n) if i in (0, n - 1) or j in (0, n - 1)]
    return {
        "geometry": {"kind": "graph", "nodes": at, "edges": edges, "fixed": border},
        "material": {"EA": 1e6, "prestress": 1000.0},
    }


@pytest.mark.parametrize("units, h, area", [("SI", 1.0, "2 m^2"), ("N-mm", 1000.0, "2e+06 mm^2")])
def test_corner_nodes_no_edge_joins_are_said_to_take_no_load(caplog, units, h, area):
    """A grid's corners where no cable ends lie outside the loaded outline: the run says
    how much of the plan their outline encloses is loaded on no node."""
    from catenet.case.kinds import warn

    warn._WARNED.clear()
    data = with_area(_grid_without_corners(h=h), pressure=1000.0 / h**2)
    data["units"] = units
    with caplog.at_level("WARNING", logger="catenet.case"):
        f = force(data)
    assert f[:, 2].sum() == pytest.approx(-14_000.0, rel=1e-12)  # 14 of the 16 m^2
    text = " ".join(r.getMessage() for r in caplog.records)
    assert "4 nodes that no edge joins (nodes 0, 4, 20, 24)" in text
    assert f"the pressure on the {area} between them" in text and "(12.5 % of the" in text


def test_a_load_cases_area_warning_names_the_load_case(caplog):
    """The same corners under a [[load_case]]'s area load: the warning names
    load_case[0].area[0] (it said load.area[0], a key the case does not have)."""
    from catenet.case.kinds import warn

    warn._WARNED.clear()
    data = _grid_without_corners()
    data["load_case"] = [{"name": "snow", "area": [{"pressure": 1000.0}]}]
    with caplog.at_level("WARNING", logger="catenet.case"):
        build(parse_case(data))
    assert "load_case[0].area[0] (on the whole net): 4 nodes that no edge joins" in caplog.text
    assert "load.area" not in caplog.text


def test_joined_corners_and_a_part_of_the_net_give_no_such_warning(caplog):
    from catenet.case.kinds import warn

    warn._WARNED.clear()
    grid = _grid_without_corners()
    n = 5
    grid["geometry"]["edges"] += [[0, 1], [0, n], [n - 2, n - 1], [n - 1, 2 * n - 1]]
    grid["geometry"]["edges"] += [[20, 21], [15, 20], [23, 24], [19, 24]]
    part = with_area(_grid_without_corners(), pressure=1000.0, nodes=[6, 7, 8, 11, 12, 13])
    with caplog.at_level("WARNING", logger="catenet.case"):
        whole = force(with_area(grid, pressure=1000.0))
        force(part)
        force(with_area(hypar_roof(half=6.0, rise=1.5, edge_length=0.6), pressure=800.0))
    assert whole[:, 2].sum() == pytest.approx(-16_000.0, rel=1e-12)
    assert "no edge joins" not in caplog.text


def _cables(lines, h: float, z=lambda x, y: 0.0 * x) -> dict:
    """A net of the cables ``lines`` (each a list of plan points (i, j) at (i h, j h)),
    every cable's ends held, no edge along the border: a net whose open border cells
    the area load closes."""
    pts = sorted({p for line in lines for p in line})
    index = {p: k for k, p in enumerate(pts)}
    edges = [
        [index[a], index[b]] for line in lines for a, b in zip(line[:-1], line[1:], strict=True)
    ]
    fixed = sorted({index[line[0]] for line in lines} | {index[line[-1]] for line in lines})
    nodes = [[i * h, j * h, float(z(i * h, j * h))] for i, j in pts]
    return {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges, "fixed": fixed},
        "material": {"EA": 1e7, "prestress": 1e4},
    }


L_LINES = [
    [(0, 1), (1, 1), (2, 1), (3, 1), (4, 1)],
    [(0, 2), (1, 2), (2, 2)],
    [(0, 3), (1, 3), (2, 3)],
    [(1, 0), (1, 1), (1, 2), (1, 3), (1, 4)],
    [(2, 0), (2, 1), (2, 2)],
    [(3, 0), (3, 1), (3, 2)],
]


def test_an_l_shaped_nets_notch_stays_out_of_its_load():
    """A 12 x 12 m plan less its 6 x 6 m corner, cables every 3 m ending on supports, two
    of them at the notch's corner: that corner stays a corner of the outline, so the
    notch takes no load. 1 kPa on the L less the five 4.5 m^2 triangles cut between
    cable ends: 85.5 m^2 (the notch's own triangle had been loaded: 90)."""
    f = force(with_area(_cables(L_LINES, 3.0), pressure=1000.0))
    assert f[:, 2].sum() == pytest.approx(-85_500.0, rel=1e-12)


def test_posts_at_an_l_shaped_nets_corners_are_said_to_take_no_load(caplog):
    """Five posts no cable reaches at the L's corners (12 x 12 m less 6 x 6 m): the
    warning gives the five 4.5 m^2 triangles between them and the outline's nearest
    sides, 22.5 of the L's 108 m^2 (its convex hull, 126 m^2, had been measured)."""
    from catenet.case.kinds import warn

    warn._WARNED.clear()
    data = _cables(L_LINES, 3.0)
    posts = [
        [0.0, 0.0, 0.0],
        [12.0, 0.0, 0.0],
        [0.0, 12.0, 0.0],
        [12.0, 6.0, 0.0],
        [6.0, 12.0, 0.0],
    ]
    n = len(data["geometry"]["nodes"])
    data["geometry"]["nodes"] += posts
    data["geometry"]["fixed"] += list(range(n, n + 5))
    with caplog.at_level("WARNING", logger="catenet.case"):
        f = force(with_area(data, pressure=1000.0))
    assert f[:, 2].sum() == pytest.approx(-85_500.0, rel=1e-12)
    assert "5 nodes that no edge joins" in caplog.text
    assert "the 22.5 m^2 between them" in caplog.text
    assert "(20.8 % of the 108 m^2 they enclose; 85.5 m^2 is loaded)" in caplog.text


def test_a_normal_load_on_half_a_saddle_is_the_pressure_times_its_vector_area():
    """Wind normal to the west half of a saddle (100 x 60 m, cables every 5 m ending on
    supports): its resultant is -p times the vector area of the half's outline, 1/2 the
    sum of r_i x r_i+1 round it: the cable between the halves (curved in 3D), then the
    supports where the cables end, the corners cut between them. No face between that
    cable and its chord is loaded (a horizontal force of 45 % more had been); the two
    halves add up to the whole, node by node."""

    def z(x, y):
        return 0.0024 * (x - 50.0) ** 2 - 0.0045 * (y - 30.0) ** 2

    lines = [[(i, j) for i in range(21)] for j in range(1, 12)]
    lines += [[(i, j) for j in range(13)] for i in range(1, 20)]
    data = _cables(lines, 5.0, z=z)
    nodes = np.asarray(data["geometry"]["nodes"])
    west = np.flatnonzero(nodes[:, 0] <= 50.0).tolist()
    east = np.flatnonzero(nodes[:, 0] >= 50.0).tolist()
    half = force(with_area(data, pressure=500.0, direction="normal", nodes=west))
    loop = [(10, j) for j in range(13)]  # up the middle cable, round the west border
    loop += [(i, 12) for i in range(9, 0, -1)] + [(0, j) for j in range(11, 0, -1)]
    loop += [(i, 0) for i in range(1, 10)]
    r = np.array([[5.0 * i, 5.0 * j, z(5.0 * i, 5.0 * j)] for i, j in loop])
    vector_area = 0.5 * np.cross(r, np.roll(r, -1, axis=0)).sum(axis=0)
    assert half.sum(axis=0) == pytest.approx(-500.0 * vector_area, rel=1e-9, abs=1e-6)
    whole = force(with_area(data, pressure=500.0, direction="normal"))
    other = force(with_area(data, pressure=500.0, direction="normal", nodes=east))
    assert np.abs(half + other - whole).max() <= 1e-9 * np.abs(whole).max()


def test_posts_at_a_sloped_nets_corners_are_measured_on_its_surface(caplog):
    """The L and its posts above on a 30 degree slope (z = x tan 30), under a pressure
    normal to it: the triangles between the posts and the outline lie on the slope, as
    the loaded area does (22.5 and 85.5 m^2 over cos 30: 25.98 and 98.73 m^2), their
    share 20.8 % as on the level. They had been summed on plan against the loaded
    surface (a newcomer's monopitch: 7.3 % where 8.3 %)."""
    from catenet.case.kinds import warn

    warn._WARNED.clear()
    slope = math.tan(math.radians(30.0))
    data = _cables(L_LINES, 3.0, z=lambda x, y: slope * x)
    posts = [[0.0, 0.0], [12.0, 0.0], [0.0, 12.0], [12.0, 6.0], [6.0, 12.0]]
    n = len(data["geometry"]["nodes"])
    data["geometry"]["nodes"] += [[x, y, slope * x] for x, y in posts]
    data["geometry"]["fixed"] += list(range(n, n + 5))
    with caplog.at_level("WARNING", logger="catenet.case"):
        force(with_area(data, pressure=1000.0, direction="normal"))
    c = math.cos(math.radians(30.0))
    assert f"the {22.5 / c:.4g} m^2 between them" in caplog.text
    assert f"(20.8 % of the {108.0 / c:.4g} m^2 they enclose; {85.5 / c:.4g} m^2" in caplog.text
